"""RLlib's PPO (Ray, new API stack) on mapc's environment: the centralized Simple Merge policy, sampled by N env
runners on a local Ray cluster or on an existing one, each stepping K episodes through mapc's vector env (one Rust
call per step, `mapc.rllib`), written at the end as a mapc policy file and evaluated over seeds against the humans
with mapc's own evaluation (what `mapc eval` prints).

    pip install ./python "ray[rllib]" torch
    python examples/python/rllib_ppo.py --iters 2 --env-runners 1 --eval-seeds 2          # smoke run
    python examples/python/rllib_ppo.py --iters 300 --env-runners 2 --out out/rllib         # a real run

On a cluster: `ray start --head` on one machine, `ray start --address HEAD:6379` on the others (each with the
package installed), then `python examples/python/rllib_ppo.py --address auto --env-runners 16`.
"""

import argparse
import os
import sys

import ray
from ray.rllib.algorithms.ppo import PPOConfig
from ray.rllib.core.rl_module.default_model_config import DefaultModelConfig
from ray.tune.registry import register_env

import mapc
import mapc.rllib
from mapc.export import save_rllib_policy

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from rllib_common import init_ray, runner_placement, train  # noqa: E402


def main():
    p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--scenario", default="simple_merge")
    p.add_argument("--reward", default="outflow")
    p.add_argument("--iters", type=int, default=300)
    p.add_argument("--env-runners", type=int, default=2)
    p.add_argument("--envs-per-runner", type=int, default=3,
                   help="sub-environments each runner steps in one call (mapc's vector env); batch / (runners x "
                        "this) steps of each per iteration, best a whole episode (2000 on the Simple Merge)")
    p.add_argument("--batch", type=int, default=12_000, help="env steps per iteration (mapc's fast preset)")
    p.add_argument("--seed", type=int, default=0)
    p.add_argument("--address", default=None, help="an existing Ray cluster (`auto`); default: a local one")
    p.add_argument("--eval-seeds", type=int, default=100)
    p.add_argument("--checkpoint-every", type=int, default=0,
                   help="also write the policy every N iterations (policy_iter<N>.json), for `mapc eval` later")
    p.add_argument("--torch-threads", type=int, default=1, help="the learner's torch threads (in the driver)")
    p.add_argument("--out", default="out/rllib")
    a = p.parse_args()

    init_ray(a.address, a.torch_threads)
    register_env("mapc_merge", mapc.rllib.env_creator)
    scenario = os.path.abspath(a.scenario) if os.path.exists(a.scenario) else a.scenario
    config = (
        PPOConfig()
        # normalize_actions=False: the raw Gaussian sample is the acceleration (mapc clips it to its bounds), as
        # in mapc's trainer, so the exported means are the accelerations mapc applies (RLlib would unsquash them)
        .environment("mapc_merge", env_config={"scenario": scenario, "reward": a.reward, "seed": a.seed},
                     normalize_actions=False)
        .env_runners(num_env_runners=a.env_runners, num_envs_per_env_runner=a.envs_per_runner,
                     gym_env_vectorize_mode=mapc.rllib.VECTORIZE_MODE, rollout_fragment_length="auto")
        # the paper's centralized PPO (docs/reference.md sec. 5) at mapc's fast preset's batch
        .training(lr=5e-4, gamma=0.99, lambda_=0.97, clip_param=0.3, train_batch_size_per_learner=a.batch,
                  minibatch_size=1000, num_epochs=8, kl_coeff=0.2, kl_target=0.01, entropy_coeff=0.0,
                  vf_clip_param=1e8)
        .rl_module(model_config=DefaultModelConfig(fcnet_hiddens=[100, 50, 25], fcnet_activation="tanh",
                                                   vf_share_layers=False))
        .debugging(seed=a.seed)
    )
    algo = config.build_algo()
    fragment = a.batch // (max(a.env_runners, 1) * a.envs_per_runner)
    horizon = mapc.make_env(scenario).horizon
    if fragment < horizon:
        # measured: 2 runners x 16 sub-environments (375 steps each per iteration) ended 250 iterations at -6.4 %,
        # 2 x 3 (whole episodes) passed the humans within 50
        print(f"note: each sub-environment plays {fragment} of its episode's {horizon} steps per iteration, so every "
              f"batch holds the same slice of all episodes (they start together); PPO learns slower than with "
              f"whole episodes (--envs-per-runner {max(a.batch // (max(a.env_runners, 1) * horizon), 1)})")
    for index, ip, host, pid in runner_placement(algo):
        print(f"env runner {index}: node {ip} (host {host}, pid {pid}), {a.envs_per_runner} sub-environments")

    def checkpoint(it):
        if a.checkpoint_every and it % a.checkpoint_every == 0:
            save_rllib_policy(algo.get_module(), os.path.join(a.out, f"policy_iter{it}.json"), scenario=a.scenario,
                              reward=a.reward)

    log, wall = train(algo, a.iters, a.out, checkpoint)
    policy = os.path.join(a.out, "policy.json")
    save_rllib_policy(algo.get_module(), policy, scenario=a.scenario, reward=a.reward)
    algo.stop()
    ray.shutdown()
    steps = log[-1]["env_steps"] or a.iters * a.batch
    report = mapc.evaluate(policy, a.scenario, seeds=a.eval_seeds)
    o, h = report["outflow"], report["baseline"]["outflow"]
    print(f"trained {a.iters} iterations, {steps} env-steps in {wall:.0f} s ({steps / wall:,.0f} env-steps/s) "
          f"with {a.env_runners} env runner(s)")
    print(f"mapc policy file: {policy}")
    print(f"policy outflow {o['mean']:.1f} ± {o['ci95']:.1f} veh/h, humans {h['mean']:.1f} ± {h['ci95']:.1f} "
          f"({report['comparison']['outflow_change_pct']:+.1f} %, 95 % CIs "
          f"{'disjoint' if report['comparison']['outflow_ci_disjoint'] else 'overlap'}) over {a.eval_seeds} seeds")


if __name__ == "__main__":
    main()
