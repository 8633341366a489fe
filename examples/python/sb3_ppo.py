"""Stable-Baselines3's PPO on mapc's vector env (one machine): the centralized Simple Merge policy, trained with
the outflow reward, then evaluated over seeds against the humans from Python.

    pip install ./python stable-baselines3          # torch comes with it
    python examples/python/sb3_ppo.py --timesteps 20000 --eval-seeds 2    # smoke run (docs/python.md)
    python examples/python/sb3_ppo.py --timesteps 3000000 --out out/sb3   # a real run

Stable-Baselines3 has its own vector-env interface (reset at once when an episode ends, the last observation in
``terminal_observation``); ``Sb3VecEnv`` adapts mapc's vector env in its same-step autoreset mode to it, so the
K episodes still step in Rust threads in one call.
"""

import argparse
import math
import os
import time

import numpy as np
from gymnasium.vector import AutoresetMode
from stable_baselines3 import PPO
from stable_baselines3.common.vec_env import VecEnv

import mapc


class Sb3VecEnv(VecEnv):
    """mapc's vector env behind Stable-Baselines3's VecEnv interface."""

    def __init__(self, scenario: str, num_envs: int, reward: str, seed: int) -> None:
        self.venv = mapc.make_vec_env(scenario, num_envs=num_envs, reward=reward, seed=seed,
                                      autoreset_mode=AutoresetMode.SAME_STEP)
        super().__init__(num_envs, self.venv.single_observation_space, self.venv.single_action_space)
        self._actions = None
        self._seed = seed

    def reset(self):
        obs, _ = self.venv.reset(seed=self._seed)
        return obs

    def step_async(self, actions):
        self._actions = actions

    def step_wait(self):
        obs, rewards, terminated, truncated, infos = self.venv.step(self._actions)
        dones = terminated | truncated
        out = [{} for _ in range(self.num_envs)]
        for i in np.flatnonzero(dones):
            out[i] = {"terminal_observation": infos["final_obs"][i], "TimeLimit.truncated": bool(truncated[i]),
                      "episode": {"r": float("nan"), "l": self.venv.horizon}, "outflow": infos["outflow"][i]}
        return obs, rewards, dones, out

    def close(self):
        pass

    def get_attr(self, attr_name, indices=None):
        return [getattr(self.venv, attr_name)] * len(self._indices(indices))

    def set_attr(self, attr_name, value, indices=None):
        setattr(self.venv, attr_name, value)

    def env_method(self, method_name, *args, indices=None, **kwargs):
        raise NotImplementedError("mapc's sub-environments live in Rust")

    def env_is_wrapped(self, wrapper_class, indices=None):
        return [False] * len(self._indices(indices))

    def _indices(self, indices):
        if indices is None:
            return range(self.num_envs)
        return [indices] if isinstance(indices, int) else indices


def evaluate(model, scenario: str, seeds: int, first_seed: int):
    """Deterministic actions over `seeds` seeds; mean and 95 % CI of the outflow, against the humans."""
    from scipy import stats

    env = mapc.make_env(scenario)
    outflows = []
    for seed in range(first_seed, first_seed + seeds):
        obs, _ = env.reset(seed=seed)
        truncated = False
        while not truncated:
            action, _ = model.predict(obs, deterministic=True)
            obs, _, _, truncated, info = env.step(action)
        outflows.append(info["outflow"])
    mean = float(np.mean(outflows))
    ci = float(stats.t.ppf(0.975, seeds - 1) * np.std(outflows, ddof=1) / math.sqrt(seeds)) if seeds > 1 else None
    humans = mapc.simulate(scenario, seeds=seeds, first_seed=first_seed)["outflow"]
    return mean, ci, humans


def main():
    p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--scenario", default="simple_merge")
    p.add_argument("--reward", default="outflow")
    p.add_argument("--timesteps", type=int, default=3_000_000)
    p.add_argument("--num-envs", type=int, default=8)
    p.add_argument("--seed", type=int, default=0)
    p.add_argument("--eval-seeds", type=int, default=100)
    p.add_argument("--out", default=None, help="folder for the trained model: SB3's zip and a mapc policy file")
    a = p.parse_args()
    env = Sb3VecEnv(a.scenario, a.num_envs, a.reward, seed=1000 + a.seed)
    # the paper's centralized PPO where SB3 has the knob (docs/reference.md sec. 5): [100, 50, 25] tanh, separate
    # value net, lr 5e-4, gamma 0.99, lambda 0.97, clip 0.3, 10 epochs; a smaller batch, as mapc's fast preset
    model = PPO("MlpPolicy", env, learning_rate=5e-4, n_steps=1500, batch_size=1000, n_epochs=8, gamma=0.99,
                gae_lambda=0.97, clip_range=0.3, ent_coef=0.0, seed=a.seed, verbose=0, device="cpu",
                policy_kwargs={"net_arch": {"pi": [100, 50, 25], "vf": [100, 50, 25]},
                               "activation_fn": __import__("torch").nn.Tanh})
    start = time.perf_counter()
    model.learn(total_timesteps=a.timesteps)
    wall = time.perf_counter() - start
    if a.out:
        from mapc.export import save_sb3_policy

        os.makedirs(a.out, exist_ok=True)
        model.save(os.path.join(a.out, "sb3_model"))
        policy = os.path.join(a.out, "policy.json")
        save_sb3_policy(model, policy, scenario=a.scenario, reward=a.reward)
        print(f"mapc policy file: {policy} (mapc eval --policy {policy} --scenario {a.scenario})")
    mean, ci, humans = evaluate(model, a.scenario, a.eval_seeds, 0)
    ci_text = f" ± {ci:.1f}" if ci is not None else ""
    print(f"trained {a.timesteps} env-steps in {wall:.0f} s ({a.timesteps / wall:,.0f} env-steps/s)")
    print(f"policy outflow {mean:.1f}{ci_text} veh/h over {a.eval_seeds} seeds; humans {humans['mean']:.1f}"
          f" ({100 * (mean / humans['mean'] - 1):+.1f} %)")


if __name__ == "__main__":
    main()
