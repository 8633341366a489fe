"""mapc from Python: the paper's merge-control environments on mapc's simulator, and its pipeline.

- ``make_env(scenario, reward, seed)``: a ``gymnasium.Env`` (the centralized setting of the paper).
- ``make_vec_env(scenario, num_envs)``: a ``gymnasium.vector.VectorEnv`` stepping every episode in Rust threads.
- ``simulate(scenario, seeds)`` and ``evaluate(policy, scenario, seeds)``: the dicts that ``mapc sim --json`` and
  ``mapc eval --json`` print, computed by the same library code.
- ``Policy(path)``: a trained centralized policy's mean action.

Every error of mapc is raised as ``MapcError`` with mapc's message (the file and the place).
"""

from __future__ import annotations

import json
import os
from typing import Any, Dict, Optional, Union

from ._mapc import MapcError, __version__
from ._mapc import Policy as _NativePolicy
from ._mapc import evaluate as _evaluate
from ._mapc import simulate as _simulate
from .env import MergeEnv, MergeVecEnv

__all__ = [
    "MapcError",
    "MergeEnv",
    "MergeVecEnv",
    "Policy",
    "evaluate",
    "make_env",
    "make_vec_env",
    "simulate",
    "__version__",
]

PathLike = Union[str, "os.PathLike[str]"]


def make_env(
    scenario: PathLike = "simple_merge",
    reward: str = "outflow",
    seed: int = 0,
    n_av: Optional[int] = None,
) -> MergeEnv:
    """The centralized environment on ``scenario`` (a built-in name or a scenario file, windows included).

    ``reward`` is ``outflow``, ``flow`` or ``speed``; ``seed`` is the first episode's seed (each reset without
    a seed takes the next one); ``n_av`` defaults to the scenario's.
    """
    return MergeEnv(os.fspath(scenario), reward=reward, seed=seed, n_av=n_av)


def make_vec_env(
    scenario: PathLike = "simple_merge",
    num_envs: int = 4,
    reward: str = "outflow",
    seed: int = 0,
    n_av: Optional[int] = None,
) -> MergeVecEnv:
    """``num_envs`` centralized environments stepped together in Rust threads, autoreset in the next step."""
    return MergeVecEnv(os.fspath(scenario), num_envs=num_envs, reward=reward, seed=seed, n_av=n_av)


def simulate(scenario: PathLike = "simple_merge", seeds: int = 100, first_seed: int = 0) -> Dict[str, Any]:
    """The all-human baseline over ``seeds`` seeds: what ``mapc sim --json`` prints."""
    return json.loads(_simulate(os.fspath(scenario), seeds, first_seed))


def evaluate(
    policy: PathLike,
    scenario: PathLike = "simple_merge",
    seeds: int = 100,
    first_seed: int = 0,
    sample: bool = False,
    baseline: bool = True,
) -> Dict[str, Any]:
    """A policy against the humans on the same seeds: what ``mapc eval --json`` prints."""
    return json.loads(
        _evaluate(os.fspath(policy), os.fspath(scenario), seeds, first_seed, sample, baseline)
    )


class Policy:
    """A trained centralized policy (a checkpoint file or a ``mapc train`` run directory)."""

    def __init__(self, path: PathLike) -> None:
        self._native = _NativePolicy(os.fspath(path))
        self.path: str = self._native.path
        self.obs_dim: int = self._native.obs_dim
        self.act_dim: int = self._native.act_dim

    def act(self, obs: Any) -> Any:
        """The mean action (what ``mapc eval`` applies) for one observation."""
        import numpy as np

        raw = self._native.act(np.ascontiguousarray(obs, dtype="<f4").tobytes())
        return np.frombuffer(raw, dtype="<f4").copy()
