"""RLlib's env runners on mapc's vector env: each runner steps its K sub-environments in one Rust call per step,
instead of K Python environments one after the other.

    from ray.tune.registry import register_env
    import mapc.rllib

    register_env("mapc_merge", mapc.rllib.env_creator)
    config = (PPOConfig()
              .environment("mapc_merge", env_config={"scenario": "simple_merge", "reward": "outflow"},
                           normalize_actions=False)
              .env_runners(num_envs_per_env_runner=64, gym_env_vectorize_mode=mapc.rllib.VECTORIZE_MODE)
              .debugging(seed=0))

RLlib's new API stack (Ray 2.40 and later) registers the creator with Gymnasium as both the single env's entry
point and the vector env's (``vector_entry_point``, called with ``num_envs`` added to the env config); the
``vector_entry_point`` vectorize mode makes the runner take the creator's vector env as it is. The runner steps it
with Gymnasium's default autoreset (the step after an episode's end resets it), which mapc's vector env follows.

Seeds: a runner resets its vector env once, with ``config.seed + worker_index``, and then only autoresets.
The env config's ``seed`` is where episodes start when RLlib gives no seed (``config.seed`` unset). Each runner
gets its own range of episode seeds: a reset with seed ``s`` plays episodes ``s * SEED_STRIDE``, ``s *
SEED_STRIDE + 1``, ..., so runners' episodes never repeat each other's for the first ``SEED_STRIDE`` episodes of
each. Nothing here imports Ray.
"""

from __future__ import annotations

import os
from typing import Any, Dict, Mapping, Optional, Tuple, Union

import numpy as np

from . import _mapc
from .env import MergeEnv, MergeVecEnv

# gymnasium.VectorizeMode.VECTOR_ENTRY_POINT's value: the runner uses the registered vector env as it is
VECTORIZE_MODE = "vector_entry_point"

# episodes per runner before its seeds reach the next runner's first one
SEED_STRIDE = 1_000_000

_KEYS = ("scenario", "reward", "seed", "n_av", "num_envs")


def _settings(config: Mapping[str, Any]) -> Dict[str, Any]:
    unknown = sorted(k for k in config if k not in _KEYS)
    if unknown:
        raise _mapc.MapcError(f"env config: unknown key(s) {', '.join(unknown)}; known: {', '.join(_KEYS)}")
    scenario = config.get("scenario", "simple_merge")
    return {
        "scenario": os.fspath(scenario),
        "reward": config.get("reward", "outflow"),
        "seed": int(config.get("seed", 0)),
        "n_av": config.get("n_av"),
    }


class RLlibMergeVecEnv(MergeVecEnv):
    """mapc's vector env with a runner's seed range: ``reset(seed=s)`` plays episodes from ``s * SEED_STRIDE``
    (sub-environment k plays ``s * SEED_STRIDE + k``, then ``+ num_envs`` per episode)."""

    def reset(self, *, seed: Optional[int] = None,
              options: Optional[Dict[str, Any]] = None) -> Tuple[np.ndarray, Dict[str, Any]]:
        if seed is not None:
            if seed < 0:
                raise _mapc.MapcError(f"seed {seed}: RLlib's seeds must be 0 or more")
            seed = int(seed) * SEED_STRIDE
        return super().reset(seed=seed, options=options)


def env_creator(config: Mapping[str, Any]) -> Union[MergeEnv, RLlibMergeVecEnv]:
    """The env for ``ray.tune.registry.register_env``: with ``num_envs`` in ``config`` (RLlib adds it when it
    calls the vector entry point) a vector env of that many sub-environments, without it a single env.
    ``config`` holds ``scenario`` (a built-in name or a scenario file), ``reward``, ``seed`` and ``n_av``, as
    ``mapc.make_env`` takes them; any other key is refused."""
    s = _settings(config)
    if "num_envs" in config:
        return RLlibMergeVecEnv(s["scenario"], num_envs=int(config["num_envs"]), reward=s["reward"], seed=s["seed"],
                                n_av=s["n_av"])
    return MergeEnv(s["scenario"], reward=s["reward"], seed=s["seed"], n_av=s["n_av"])
