"""Env steps per second sampled by RLlib's env runners on mapc's vector env (docs/python.md, "RLlib on Ray").

    python examples/python/bench_rllib_sampling.py --env-runners 2 --envs-per-runner 64

Builds RLlib's PPO as rllib_ppo.py does (the paper's networks, untrained), then has every env runner sample whole
episodes on each of its K sub-environments (K x 2000 env steps on the Simple Merge) at once, with exploration, as
a training iteration does: RLlib's RLModule forward pass, its connectors and its episode bookkeeping for every
step, mapc's stepping of K episodes in one call. A short warm-up round comes first. The figure is all runners'
steps over the round's wall time; each runner's CPU time (its process: user and system, mapc's threads included)
is printed beside it, and the steps per CPU second of one runner, which is what a core free for it would give.
"""

import argparse
import json
import os
import sys
import time

import ray
from ray.rllib.algorithms.ppo import PPOConfig
from ray.rllib.core.rl_module.default_model_config import DefaultModelConfig
from ray.tune.registry import register_env

import mapc.rllib

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from rllib_common import init_ray  # noqa: E402


def sample(runner, steps):
    """One runner's sampling of `steps` env steps: (steps taken, wall s, user+system CPU s of its process)."""
    cpu, start = time.process_time(), time.perf_counter()
    episodes = runner.sample(num_timesteps=steps, explore=True)
    return sum(len(e) for e in episodes), time.perf_counter() - start, time.process_time() - cpu


def main():
    p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--scenario", default="simple_merge")
    p.add_argument("--env-runners", type=int, default=2)
    p.add_argument("--envs-per-runner", type=int, default=64)
    p.add_argument("--episodes", type=int, default=1, help="whole episodes per sub-environment in the timed round")
    p.add_argument("--address", default=None, help="an existing Ray cluster (`auto`); default: a local one")
    a = p.parse_args()

    init_ray(a.address)
    register_env("mapc_merge", mapc.rllib.env_creator)
    scenario = os.path.abspath(a.scenario) if os.path.exists(a.scenario) else a.scenario
    config = (
        PPOConfig()
        .environment("mapc_merge", env_config={"scenario": scenario}, normalize_actions=False)
        .env_runners(num_env_runners=a.env_runners, num_envs_per_env_runner=a.envs_per_runner,
                     gym_env_vectorize_mode=mapc.rllib.VECTORIZE_MODE)
        .rl_module(model_config=DefaultModelConfig(fcnet_hiddens=[100, 50, 25], fcnet_activation="tanh",
                                                   vf_share_layers=False))
        .debugging(seed=0)
    )
    algo = config.build_algo()
    group = algo.env_runner_group
    horizon = group.foreach_env_runner(lambda r: r.env.unwrapped.horizon, local_env_runner=False)[0]
    for name, steps_per_runner in (("warm-up", 10 * a.envs_per_runner),
                                   ("timed", a.episodes * horizon * a.envs_per_runner)):
        # the warm-up round starts every runner's episodes; the timed round then plays them whole
        start = time.perf_counter()
        per_runner = group.foreach_env_runner(lambda r, n=steps_per_runner: sample(r, n), local_env_runner=False)
        wall = time.perf_counter() - start
        steps, cpu = sum(s for s, _, _ in per_runner), [c for _, _, c in per_runner]
        row = {"round": name, "env_steps": steps, "wall_s": round(wall, 2), "env_steps_per_s": round(steps / wall),
               "runner_cpu_s": [round(c, 2) for c in cpu], "load_1min": os.getloadavg()[0]}
        print(json.dumps(row), flush=True)
    per_cpu = steps / sum(cpu)
    print(f"{a.env_runners} env runner(s) x {a.envs_per_runner} sub-environments: {steps / wall:,.0f} env-steps/s "
          f"sampled by RLlib over whole episodes ({steps:,} steps in {wall:.1f} s wall; the runners' CPU "
          f"{sum(cpu):.1f} s: {per_cpu:,.0f} env-steps per CPU second each; load average {os.getloadavg()[0]:.1f})")
    algo.stop()
    ray.shutdown()


if __name__ == "__main__":
    main()
