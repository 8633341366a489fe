"""The distributed setting as a PettingZoo ParallelEnv: every AV in the control region is an agent that sees its
own sensors and chooses its own acceleration. Agents appear as their AVs enter the region, named ``av_0``,
``av_1``, ... in order of appearance, and are done (terminated) when they leave it; at the horizon every agent
left is truncated. While no AV is in the region the simulation runs on by itself, so ``env.agents`` is empty
only once the episode is over."""

from __future__ import annotations

import functools
from typing import Any, Dict, List, Optional, Tuple

import numpy as np
from gymnasium import spaces
from pettingzoo import ParallelEnv

from . import _mapc

F32 = np.dtype("<f4")


class MergeParallelEnv(ParallelEnv):
    metadata = {"render_modes": [], "name": "mapc_merge_v0", "is_parallelizable": True}

    def __init__(self, scenario: str = "simple_merge", features: str = "full", seed: int = 0,
                 eta1: float = 0.9, eta2: float = 0.1, exit_bonus: float = 20.0, count_waiting: bool = False,
                 reward_share: float = 0.0) -> None:
        self._native = _mapc.DistEnv(scenario, features, eta1, eta2, exit_bonus, count_waiting, reward_share)
        self.scenario: str = self._native.scenario
        self.horizon: int = self._native.horizon
        self.possible_agents: List[str] = [f"av_{i}" for i in range(self._native.max_agents)]
        self.agents: List[str] = []
        lo, hi = self._native.action_bounds
        # the distributed observation is not clipped (docs/reference.md sec. 5)
        self._obs_space = spaces.Box(-np.inf, np.inf, shape=(self._native.obs_dim,), dtype=np.float32)
        self._act_space = spaces.Box(np.float32(lo), np.float32(hi), shape=(1,), dtype=np.float32)
        self._next_seed = int(seed)
        self._name_of: Dict[int, str] = {}
        self._vehicle_of: Dict[str, int] = {}
        self.episode_seed: Optional[int] = None

    @functools.lru_cache(maxsize=None)
    def observation_space(self, agent: str) -> spaces.Box:
        return self._obs_space

    @functools.lru_cache(maxsize=None)
    def action_space(self, agent: str) -> spaces.Box:
        return self._act_space

    def _name(self, vehicle: int) -> str:
        name = self._name_of.get(vehicle)
        if name is None:
            name = f"av_{len(self._name_of)}"
            if len(self._name_of) >= len(self.possible_agents):
                raise _mapc.MapcError(f"more agents than the {len(self.possible_agents)} this scenario can hold")
            self._name_of[vehicle] = name
            self._vehicle_of[name] = vehicle
        return name

    def _observations(self, present: List[Tuple[int, bytes]]) -> Dict[str, np.ndarray]:
        return {self._name(v): np.frombuffer(raw, dtype=F32).copy() for v, raw in present}

    def reset(self, seed: Optional[int] = None,
              options: Optional[Dict[str, Any]] = None) -> Tuple[Dict[str, np.ndarray], Dict[str, Dict]]:
        if seed is not None:
            self._next_seed = int(seed)
        self.episode_seed = self._next_seed
        self._next_seed += 1
        self._name_of.clear()
        self._vehicle_of.clear()
        present, _ = self._until_agents(self._native.reset(self.episode_seed), False)
        obs = self._observations(present)
        self.agents = list(obs)
        return obs, {a: {} for a in self.agents}

    def _until_agents(self, present: List[Tuple[int, bytes]], at_horizon: bool) -> Tuple[List, bool]:
        # Steps with no AV in the control region have nobody to act: the humans drive on until an AV enters (or
        # the horizon comes), so an episode only ends at its horizon.
        while not present and not at_horizon:
            _, present, at_horizon = self._native.step([])
        return present, at_horizon

    def step(self, actions: Dict[str, Any]) -> Tuple[Dict[str, np.ndarray], Dict[str, float], Dict[str, bool],
                                                     Dict[str, bool], Dict[str, Dict]]:
        unknown = [a for a in actions if a not in self.agents]
        if unknown:
            raise _mapc.MapcError(f"actions for agents that are not acting now: {', '.join(sorted(unknown))}")
        acting = [a for a in self.agents if a in actions]
        native_actions = [(self._vehicle_of[a], float(np.asarray(actions[a], dtype=F32).reshape(-1)[0]))
                          for a in acting]
        try:
            acted, present, at_horizon = self._native.step(native_actions)
        except _mapc.MapcError as e:
            # mapc refuses an action that is not a finite number and says which one: name its agent
            index = getattr(e, "action_index", None)
            if index is None:
                raise
            raise _mapc.MapcError(f"agent {acting[index]}: {e}") from None
        present, at_horizon = self._until_agents(present, at_horizon)
        obs = self._observations(present)
        rewards: Dict[str, float] = {}
        terminations: Dict[str, bool] = {}
        for vehicle, reward, done in acted:
            name = self._name_of[vehicle]
            rewards[name] = float(reward)
            terminations[name] = bool(done)
        # agents that appeared in this step have acted in none yet
        for name in obs:
            rewards.setdefault(name, 0.0)
            terminations.setdefault(name, False)
        truncations = {name: at_horizon and not terminations[name] for name in terminations}
        infos: Dict[str, Dict] = {name: {} for name in terminations}
        for name, done in terminations.items():
            # a finished agent's last observation is its observation before leaving
            if done and name not in obs:
                obs[name] = np.zeros(self._obs_space.shape, np.float32)
        if at_horizon:
            outflow, inflow, speed = self._native.metrics()
            for info in infos.values():
                info.update(outflow=outflow, inflow=inflow, speed=speed)
            self.agents = []
        else:
            self.agents = [name for name in obs if not terminations[name]]
        return obs, rewards, terminations, truncations, infos

    def metrics(self) -> Dict[str, float]:
        outflow, inflow, speed = self._native.metrics()
        return {"outflow": outflow, "inflow": inflow, "speed": speed}
