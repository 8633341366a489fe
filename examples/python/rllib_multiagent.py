"""RLlib's PPO (Ray, new API stack) on the distributed setting: every AV in the control region is an agent of
mapc's PettingZoo environment, and all agents share one policy (the paper's Table 4 setting), sampled by N env
runners on a local Ray cluster or an existing one (--address).

    pip install ./python "ray[rllib]" torch pettingzoo
    python examples/python/rllib_multiagent.py --iters 2 --env-runners 1 --batch 4000 --eval-seeds 2  # smoke
    python examples/python/rllib_multiagent.py --iters 100 --env-runners 2         # a longer run

It prints each iteration's mean episode return and the env steps sampled, writes the shared policy as a mapc
distributed policy file and evaluates it with mapc's evaluation (what `mapc eval` prints).
"""

import argparse
import os
import sys

import gymnasium as gym
import ray
from ray.rllib.algorithms.ppo import PPOConfig
from ray.rllib.core.rl_module.default_model_config import DefaultModelConfig
from ray.rllib.env.wrappers.pettingzoo_env import ParallelPettingZooEnv
from ray.tune.registry import register_env

import mapc
from mapc.export import save_rllib_distributed_policy

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from rllib_common import init_ray, runner_seed, train  # noqa: E402


class MapcAgents(ParallelPettingZooEnv):
    """RLlib's PettingZoo wrapper takes the agents' spaces from the agents present after a reset; mapc's agents
    come and go with their AVs, so every possible agent's spaces are declared."""

    def __init__(self, env):
        super().__init__(env)
        self._agent_ids = set(env.possible_agents)
        self.possible_agents = list(env.possible_agents)
        self.observation_space = gym.spaces.Dict({a: env.observation_space(a) for a in env.possible_agents})
        self.action_space = gym.spaces.Dict({a: env.action_space(a) for a in env.possible_agents})


def make_env(cfg):
    return MapcAgents(mapc.parallel_env(cfg["scenario"], features=cfg["features"], seed=runner_seed(cfg)))


def main():
    p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--scenario", default="simple_merge")
    p.add_argument("--features", default="full")
    p.add_argument("--iters", type=int, default=100)
    p.add_argument("--env-runners", type=int, default=2)
    p.add_argument("--batch", type=int, default=60_000, help="agent steps per iteration (the paper's)")
    p.add_argument("--seed", type=int, default=0)
    p.add_argument("--address", default=None, help="an existing Ray cluster (`auto`); default: a local one")
    p.add_argument("--eval-seeds", type=int, default=100)
    p.add_argument("--out", default="out/rllib_multiagent")
    a = p.parse_args()

    init_ray(a.address)
    register_env("mapc_merge_agents", make_env)
    scenario = os.path.abspath(a.scenario) if os.path.exists(a.scenario) else a.scenario
    config = (
        PPOConfig()
        # raw accelerations, as mapc applies the exported means (RLlib would otherwise unsquash them)
        .environment("mapc_merge_agents",
                     env_config={"scenario": scenario, "features": a.features, "seed": a.seed},
                     normalize_actions=False)
        .env_runners(num_env_runners=a.env_runners, rollout_fragment_length="auto")
        # one policy shared by every agent
        .multi_agent(policies={"shared"}, policy_mapping_fn=lambda agent_id, episode, **kw: "shared")
        # the paper's distributed PPO (docs/reference.md sec. 5)
        .training(lr=5e-4, gamma=0.998, lambda_=0.95, clip_param=0.2, entropy_coeff=1e-3,
                  train_batch_size_per_learner=a.batch, minibatch_size=min(4096, a.batch), num_epochs=10, kl_coeff=0.01,
                  vf_loss_coeff=0.5)
        .rl_module(model_config=DefaultModelConfig(fcnet_hiddens=[100, 50, 25], fcnet_activation="tanh",
                                                   vf_share_layers=True))
        .debugging(seed=a.seed)
    )
    algo = config.build_algo()
    train(algo, a.iters, a.out)
    policy = os.path.join(a.out, "policy.json")
    save_rllib_distributed_policy(algo.get_module("shared"), policy, features=a.features, scenario=a.scenario)
    algo.stop()
    ray.shutdown()
    report = mapc.evaluate(policy, a.scenario, seeds=a.eval_seeds)
    o, h = report["outflow"], report["baseline"]["outflow"]
    print(f"mapc policy file: {policy}")
    print(f"policy outflow {o['mean']:.1f} ± {o['ci95']:.1f} veh/h, humans {h['mean']:.1f} ± {h['ci95']:.1f} "
          f"({report['comparison']['outflow_change_pct']:+.1f} %) over {a.eval_seeds} seeds")


if __name__ == "__main__":
    main()
