"""Type stubs of mapc's native module (crates/mapc-py). Arrays cross as little-endian float32 bytes."""

from typing import List, Optional, Tuple

__version__: str

class MapcError(Exception):
    """An error of mapc: bad input, named with its file and place."""

def simulate(scenario: str, seeds: int = 100, first_seed: int = 0) -> str:
    """The all-human baseline as the JSON `mapc sim --json` prints."""

def evaluate(
    policy: str,
    scenario: str = "simple_merge",
    seeds: int = 100,
    first_seed: int = 0,
    sample: bool = False,
    baseline: bool = True,
) -> str:
    """A policy against the humans as the JSON `mapc eval --json` prints."""

def save_policy(
    path: str,
    params: bytes,
    scenario: str = "simple_merge",
    reward: str = "outflow",
    n_av: int = 5,
    hidden: List[int] = [100, 50, 25],
    features: Optional[str] = None,
    eta1: float = 0.9,
    eta2: float = 0.1,
    exit_bonus: float = 20.0,
) -> None:
    """Write float32 parameters in mapc's layout as a mapc policy file (see mapc.export); with `features`, a
    distributed one."""

def import_map(path: str, output: Optional[str] = None, highways: Optional[List[str]] = None) -> str:
    """`mapc import --json`'s summary; the graph written to `output` if given."""

def simplify(
    map: str,
    output: str,
    via: List[str] = [],
    classes: Optional[List[str]] = None,
    feeder_length: Optional[float] = None,
    keep_exits: bool = False,
) -> str:
    """`mapc simplify --json`'s report; the corridor written to `output`."""

def window(
    map: str,
    junction: str,
    output: str,
    match_: str = "simple_merge",
    main_vph: Optional[float] = None,
    merge_vph: Optional[float] = None,
    n_av: Optional[int] = None,
    via: List[str] = [],
) -> str:
    """`mapc window --json`'s report; the scenario written to `output`, its graph beside it."""

class Env:
    scenario: str
    obs_dim: int
    act_dim: int
    horizon: int
    action_bounds: Tuple[float, float]
    def __init__(self, scenario: str = "simple_merge", reward: str = "outflow", n_av: Optional[int] = None) -> None: ...
    def reset(self, seed: int) -> bytes: ...
    def step(self, action: bytes) -> Tuple[bytes, float, bool]: ...
    def metrics(self) -> Tuple[float, float, float]: ...

class VecEnv:
    scenario: str
    num_envs: int
    obs_dim: int
    act_dim: int
    horizon: int
    def __init__(
        self,
        scenario: str = "simple_merge",
        num_envs: int = 4,
        reward: str = "outflow",
        n_av: Optional[int] = None,
        same_step: bool = False,
    ) -> None: ...
    def reset(self, seed: int) -> bytes: ...
    def step(
        self, actions: bytes
    ) -> Tuple[bytes, bytes, List[bool], List[Tuple[int, int, float, float, float, bytes]]]: ...

class DistEnv:
    scenario: str
    obs_dim: int
    horizon: int
    max_agents: int
    action_bounds: Tuple[float, float]
    def __init__(
        self,
        scenario: str = "simple_merge",
        features: str = "full",
        eta1: float = 0.9,
        eta2: float = 0.1,
        exit_bonus: float = 20.0,
        count_waiting: bool = False,
        reward_share: float = 0.0,
    ) -> None: ...
    def reset(self, seed: int) -> List[Tuple[int, bytes]]: ...
    def step(
        self, actions: List[Tuple[int, float]]
    ) -> Tuple[List[Tuple[int, float, bool]], List[Tuple[int, bytes]], bool]: ...
    def metrics(self) -> Tuple[float, float, float]: ...

class Policy:
    path: str
    obs_dim: int
    act_dim: int
    features: Optional[str]
    def __init__(self, path: str) -> None: ...
    def act(self, obs: bytes) -> bytes: ...
