"""mapc from Python: the paper's merge-control environments on mapc's simulator, and its pipeline.

- ``make_env(scenario, reward, seed)``: a ``gymnasium.Env`` (the centralized setting of the paper).
- ``make_vec_env(scenario, num_envs)``: a ``gymnasium.vector.VectorEnv`` stepping every episode in Rust threads.
- ``parallel_env(scenario, features)``: a PettingZoo ``ParallelEnv`` for the distributed setting (needs
  ``pettingzoo``).
- ``simulate(scenario, seeds)`` and ``evaluate(policy, scenario, seeds)``: the dicts that ``mapc sim --json`` and
  ``mapc eval --json`` print, computed by the same library code.
- ``Policy(path)``: a trained policy's mean action.
- ``with_avs(scenario, share, output)``: the scenario with a share of its flows' vehicles as AVs, written as a
  scenario file (``av_share=`` of the env makers does it for them).
- ``import_map``, ``simplify``, ``window``: the scenario pipeline, writing the stages' files and returning the
  reports of ``mapc import|simplify|window --json``.
- ``mapc.rllib``: RLlib's env runners on the vector env (``env_creator`` for ``register_env``); ``mapc.export``:
  policies trained in Python written as mapc policy files.

Every error of mapc is raised as ``MapcError`` with mapc's message (the file and the place).
"""

from __future__ import annotations

import json
import os
from typing import Any, Dict, Optional, Sequence, Union

from ._mapc import MapcError, __version__
from ._mapc import Policy as _NativePolicy
from ._mapc import evaluate as _evaluate
from ._mapc import import_map as _import_map
from ._mapc import simplify as _simplify
from ._mapc import simulate as _simulate
from ._mapc import window as _window
from ._mapc import with_avs as _with_avs
from .env import MergeEnv, MergeVecEnv

__all__ = [
    "MapcError",
    "MergeEnv",
    "MergeVecEnv",
    "Policy",
    "evaluate",
    "import_map",
    "make_env",
    "make_vec_env",
    "parallel_env",
    "simplify",
    "simulate",
    "window",
    "with_avs",
    "__version__",
]

PathLike = Union[str, "os.PathLike[str]"]


def with_avs(
    scenario: PathLike,
    share: float,
    output: Optional[PathLike] = None,
    flows: Sequence[str] = (),
) -> str:
    """``scenario`` with ``share`` of each flow's vehicles (of ``flows``, by flow id or vehicle type; all when
    empty) driven as AVs, each flow split into its humans and an ``ID_av`` flow, as ``--av-share`` does. Written
    to ``output`` (a temporary file when omitted, kept for the process's life); returns its path. A scenario
    without a ``[control]`` section gets the approach to its merges and lane drops as its controlled region, with
    5 AVs controlled at once (``make_env``'s ``n_av``
    sets another)."""
    if output is None:
        import atexit
        import tempfile

        fd, output = tempfile.mkstemp(prefix="mapc_avs_", suffix=".toml")
        os.close(fd)
        atexit.register(lambda p=output: os.path.exists(p) and os.remove(p))
    return _with_avs(os.fspath(scenario), float(share), os.fspath(output), list(flows))


def _scenario_with_avs(scenario: PathLike, av_share: Optional[float], av_flows: Sequence[str]) -> str:
    if av_share is None:
        return os.fspath(scenario)
    return with_avs(scenario, av_share, flows=av_flows)


def make_env(
    scenario: PathLike = "simple_merge",
    reward: str = "outflow",
    seed: int = 0,
    n_av: Optional[int] = None,
    av_share: Optional[float] = None,
    av_flows: Sequence[str] = (),
) -> MergeEnv:
    """The centralized environment on ``scenario`` (a built-in name, a scenario file, windows included, or a
    SUMO configuration).

    ``reward`` is ``outflow``, ``flow`` or ``speed``; ``seed`` is the first episode's seed (each reset without
    a seed takes the next one); ``n_av`` defaults to the scenario's. ``av_share`` makes that share of each flow's
    vehicles (of ``av_flows``; all when empty) AVs (``with_avs``).
    """
    scenario = _scenario_with_avs(scenario, av_share, av_flows)
    return MergeEnv(scenario, reward=reward, seed=seed, n_av=n_av)


def make_vec_env(
    scenario: PathLike = "simple_merge",
    num_envs: int = 4,
    reward: str = "outflow",
    seed: int = 0,
    n_av: Optional[int] = None,
    autoreset_mode: Any = "NextStep",
) -> MergeVecEnv:
    """``num_envs`` centralized environments stepped together in Rust threads; a finished episode's
    sub-environment resets in the next step (Gymnasium's default), or in the same step with
    ``autoreset_mode=gymnasium.vector.AutoresetMode.SAME_STEP``."""
    return MergeVecEnv(os.fspath(scenario), num_envs=num_envs, reward=reward, seed=seed, n_av=n_av,
                       autoreset_mode=autoreset_mode)


def parallel_env(
    scenario: PathLike = "simple_merge",
    features: str = "full",
    seed: int = 0,
    eta1: float = 0.9,
    eta2: float = 0.1,
    exit_bonus: float = 20.0,
    count_waiting: bool = False,
    reward_share: float = 0.0,
    av_share: Optional[float] = None,
    av_flows: Sequence[str] = (),
):
    """The distributed setting as a PettingZoo ``ParallelEnv``: one agent per AV in the control region.

    ``features`` is ``full``, ``none`` or a list of ``dist``, ``congestion``, ``merge`` (the paper's Table 4);
    the reward is ``0.1 (-eta1 + eta2 * mean speed / V)`` per step and ``exit_bonus`` when the agent leaves;
    ``av_share`` and ``av_flows`` as in ``make_env``.
    """
    from .parallel import MergeParallelEnv

    scenario = _scenario_with_avs(scenario, av_share, av_flows)
    return MergeParallelEnv(scenario, features=features, seed=seed, eta1=eta1, eta2=eta2,
                            exit_bonus=exit_bonus, count_waiting=count_waiting, reward_share=reward_share)


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
    deploy: Optional[str] = None,
) -> Dict[str, Any]:
    """A policy against the humans on the same seeds: what ``mapc eval --json`` prints. ``deploy`` overrides
    where the policy drives (``"everywhere"``, ``"main-road-yields"``, ``"main-road-yields-congested"`` or
    ``"simple-merge-regime"``, as ``mapc eval --deploy``)."""
    return json.loads(
        _evaluate(os.fspath(policy), os.fspath(scenario), seeds, first_seed, sample, baseline, deploy)
    )


def import_map(path: PathLike, output: Optional[PathLike] = None,
               highways: Optional[Sequence[str]] = None) -> Dict[str, Any]:
    """Read an OSM (.osm, .osm.pbf) or SUMO (.net.xml) map into a lane graph, written to ``output`` if given."""
    out = os.fspath(output) if output is not None else None
    return json.loads(_import_map(os.fspath(path), out, list(highways) if highways is not None else None))


def simplify(map: PathLike, output: PathLike, via: Sequence[str] = (), classes: Optional[Sequence[str]] = None,
             feeder_length: Optional[float] = None, keep_exits: bool = False) -> Dict[str, Any]:
    """Reduce a map to a single-lane corridor with its merging roads (``via``: ids the main road passes, in
    order, as ``mapc simplify --via``), written to ``output``."""
    return json.loads(_simplify(os.fspath(map), os.fspath(output), list(via),
                                list(classes) if classes is not None else None, feeder_length, keep_exits))


def window(map: PathLike, junction: str, output: PathLike, match: PathLike = "simple_merge",
           main_vph: Optional[float] = None, merge_vph: Optional[float] = None, n_av: Optional[int] = None,
           via: Sequence[str] = ()) -> Dict[str, Any]:
    """Cut a window around the merge ``junction`` of a corridor (or a map) matched to the ``match`` scenario's
    lengths, and write it as a scenario at ``output`` (its graph beside it)."""
    return json.loads(_window(os.fspath(map), junction, os.fspath(output), os.fspath(match), main_vph, merge_vph,
                              n_av, list(via)))


class Policy:
    """A trained policy (a checkpoint file or a ``mapc train`` run directory): centralized (one acceleration per
    controlled AV) or distributed (``features`` set: one acceleration for the agent whose observation it is)."""

    def __init__(self, path: PathLike) -> None:
        self._native = _NativePolicy(os.fspath(path))
        self.path: str = self._native.path
        self.obs_dim: int = self._native.obs_dim
        self.act_dim: int = self._native.act_dim
        self.features: Optional[str] = self._native.features

    def act(self, obs: Any) -> Any:
        """The mean action (what ``mapc eval`` applies) for one observation."""
        import numpy as np

        raw = self._native.act(np.ascontiguousarray(obs, dtype="<f4").tobytes())
        return np.frombuffer(raw, dtype="<f4").copy()
