"""Gymnasium wrappers of mapc's native environments. The stepping happens in Rust; this module only turns
buffers into numpy arrays and speaks Gymnasium's API."""

from __future__ import annotations

from typing import Any, Dict, Optional, Tuple

import gymnasium
import numpy as np
from gymnasium import spaces
from gymnasium.vector import AutoresetMode, VectorEnv

from . import _mapc

F32 = np.dtype("<f4")


def _array(raw: bytes, shape: Tuple[int, ...]) -> np.ndarray:
    return np.frombuffer(raw, dtype=F32).reshape(shape).copy()


def _action_bytes(action: Any, size: int) -> bytes:
    a = np.ascontiguousarray(action, dtype=F32)
    if a.size != size:
        raise _mapc.MapcError(f"action has {a.size} values where {size} were expected")
    return a.tobytes()


def _spaces(native: Any) -> Tuple[spaces.Box, spaces.Box]:
    # observations are clipped to [-1, 1] (docs/reference.md sec. 5); actions are accelerations in m/s^2
    lo, hi = native.action_bounds
    obs = spaces.Box(-1.0, 1.0, shape=(native.obs_dim,), dtype=np.float32)
    act = spaces.Box(np.float32(lo), np.float32(hi), shape=(native.act_dim,), dtype=np.float32)
    return obs, act


class MergeEnv(gymnasium.Env):
    """The paper's centralized merge-control environment: one acceleration per controlled AV (the first N_AV in
    the control region, by entry), the five-value observation of each, and the outflow, Flow or speed reward.
    An episode is the whole simulation, the scenario's warm-up (if any) and its horizon; it ends truncated (there
    is no terminal state)."""

    metadata = {"render_modes": []}

    def __init__(self, scenario: str = "simple_merge", reward: str = "outflow", seed: int = 0,
                 n_av: Optional[int] = None) -> None:
        self._native = _mapc.Env(scenario, reward, n_av)
        self.scenario: str = self._native.scenario
        self.observation_space, self.action_space = _spaces(self._native)
        self.horizon: int = self._native.horizon
        self._next_seed = int(seed)
        self.episode_seed: Optional[int] = None

    def reset(self, *, seed: Optional[int] = None,
              options: Optional[Dict[str, Any]] = None) -> Tuple[np.ndarray, Dict[str, Any]]:
        super().reset(seed=seed)
        if seed is not None:
            self._next_seed = int(seed)
        self.episode_seed = self._next_seed
        self._next_seed += 1
        obs = _array(self._native.reset(self.episode_seed), (self._native.obs_dim,))
        return obs, {"seed": self.episode_seed}

    def step(self, action: Any) -> Tuple[np.ndarray, float, bool, bool, Dict[str, Any]]:
        raw, reward, truncated = self._native.step(_action_bytes(action, self._native.act_dim))
        info: Dict[str, Any] = {}
        if truncated:
            outflow, inflow, speed = self._native.metrics()
            info = {"seed": self.episode_seed, "outflow": outflow, "inflow": inflow, "speed": speed}
        return _array(raw, (self._native.obs_dim,)), float(reward), False, bool(truncated), info

    def metrics(self) -> Dict[str, float]:
        """The episode's outflow (veh/h), inflow (veh/h) and mean speed (m/s) so far, as ``mapc sim`` defines them."""
        outflow, inflow, speed = self._native.metrics()
        return {"outflow": outflow, "inflow": inflow, "speed": speed}


class MergeVecEnv(VectorEnv):
    """``num_envs`` MergeEnv episodes stepped in Rust threads in one call. Sub-environment k's first episode has
    seed ``seed + k``, its next ``seed + k + num_envs``, and so on. Autoreset as Gymnasium 1.x's default
    (``AutoresetMode.NEXT_STEP``): the step after an episode's end resets that sub-environment, ignores its action
    and returns reward 0; or with ``autoreset_mode=AutoresetMode.SAME_STEP`` in the step that ended it, whose
    observation is then the new episode's first and ``infos["final_obs"]`` the last. The step that ends an episode
    puts its ``outflow``, ``inflow``, ``speed`` and ``seed`` in the infos (with the ``_outflow``... masks)."""

    metadata = {"render_modes": [], "autoreset_mode": AutoresetMode.NEXT_STEP}

    def __init__(self, scenario: str = "simple_merge", num_envs: int = 4, reward: str = "outflow",
                 seed: int = 0, n_av: Optional[int] = None,
                 autoreset_mode: Any = AutoresetMode.NEXT_STEP) -> None:
        autoreset_mode = AutoresetMode(autoreset_mode)
        if autoreset_mode not in (AutoresetMode.NEXT_STEP, AutoresetMode.SAME_STEP):
            raise _mapc.MapcError(f"autoreset mode {autoreset_mode.value}: NextStep or SameStep")
        self.metadata = {**self.metadata, "autoreset_mode": autoreset_mode}
        same_step = autoreset_mode == AutoresetMode.SAME_STEP
        self._native = _mapc.VecEnv(scenario, num_envs, reward, n_av, same_step)
        self.scenario: str = self._native.scenario
        self.num_envs = self._native.num_envs
        single = _mapc.Env(scenario, reward, n_av)
        self.single_observation_space, self.single_action_space = _spaces(single)
        self.observation_space = gymnasium.vector.utils.batch_space(self.single_observation_space, self.num_envs)
        self.action_space = gymnasium.vector.utils.batch_space(self.single_action_space, self.num_envs)
        self.horizon: int = self._native.horizon
        self._next_seed = int(seed)
        self._shape = (self.num_envs, self._native.obs_dim)

    def reset(self, *, seed: Optional[int] = None,
              options: Optional[Dict[str, Any]] = None) -> Tuple[np.ndarray, Dict[str, Any]]:
        if seed is not None:
            self._next_seed = int(seed)
        first = self._next_seed
        self._next_seed += self.num_envs
        obs = _array(self._native.reset(first), self._shape)
        return obs, {"seed": np.arange(first, first + self.num_envs), "_seed": np.ones(self.num_envs, bool)}

    def step(self, actions: Any) -> Tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, Dict[str, Any]]:
        raw_obs, raw_rewards, truncated, finished = self._native.step(
            _action_bytes(actions, self.num_envs * self._native.act_dim))
        obs = _array(raw_obs, self._shape)
        rewards = _array(raw_rewards, (self.num_envs,))
        infos: Dict[str, Any] = {}
        if finished:
            mask = np.zeros(self.num_envs, bool)
            cols = {k: np.zeros(self.num_envs) for k in ("outflow", "inflow", "speed")}
            seeds = np.zeros(self.num_envs, np.int64)
            final_obs = np.full(self.num_envs, None, dtype=object)
            for i, s, outflow, inflow, speed, last in finished:
                mask[i] = True
                seeds[i] = s
                cols["outflow"][i], cols["inflow"][i], cols["speed"][i] = outflow, inflow, speed
                final_obs[i] = _array(last, (self._native.obs_dim,))
            same_step = self.metadata["autoreset_mode"] == AutoresetMode.SAME_STEP
            extra = [("final_obs", final_obs)] if same_step else []
            for k, v in list(cols.items()) + [("seed", seeds)] + extra:
                infos[k] = v
                infos["_" + k] = mask.copy()
        return obs, rewards, np.zeros(self.num_envs, bool), np.asarray(truncated, bool), infos
