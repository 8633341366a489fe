"""Policies trained in Python (RLlib, Stable-Baselines3) written as mapc policy files, so ``mapc eval`` evaluates
them over 100 seeds like any policy of ``mapc train``.

mapc's centralized policy is an MLP with tanh hidden layers whose last layer gives the means and then the
log-stds of the actions, and a separate value MLP of the same hidden sizes. A torch policy with a
state-independent log-std (both libraries' default) is written with zero log-std weights and its log-std as their
biases. Only the weights' values cross: mapc evaluates with its own forward pass.
"""

from __future__ import annotations

import os
from typing import Iterable, List, Optional, Sequence, Tuple

import numpy as np

from . import _mapc

Layer = Tuple[np.ndarray, np.ndarray]  # torch's (weight [out, in], bias [out])


def _numpy(x) -> np.ndarray:
    return x.detach().cpu().numpy() if hasattr(x, "detach") else np.asarray(x)


def linear_layers(modules: Iterable) -> List[Layer]:
    """The (weight, bias) of every ``torch.nn.Linear`` in ``modules``, in order."""
    return [(_numpy(m.weight), _numpy(m.bias)) for m in modules if type(m).__name__ == "Linear"]


def gaussian_head(mean: Layer, log_std: np.ndarray) -> Layer:
    """A last layer giving means then log-stds from a mean layer and a state-independent log-std."""
    w, b = (np.asarray(x, np.float32) for x in mean)
    log_std = np.asarray(log_std, np.float32).reshape(-1)
    return np.concatenate([w, np.zeros_like(w)]), np.concatenate([b.reshape(-1), log_std])


def mapc_params(hidden: Sequence[Layer], last: Layer, value_hidden: Sequence[Layer] = (),
                value_out: Optional[Layer] = None) -> bytes:
    """The float32 bytes of a policy in mapc's layout (each layer's weights input-major, then its biases).
    ``last`` gives the means then the log-stds of the actions (``gaussian_head`` makes one), and for a policy
    whose value shares its layers (mapc's distributed policies) the value as one more output; a centralized
    policy's separate value net follows as ``value_hidden`` and ``value_out``."""
    layers = list(hidden) + [last] + (list(value_hidden) + [value_out] if value_out is not None else [])
    out: List[np.ndarray] = []
    for w, b in layers:
        w, b = np.asarray(w, np.float32), np.asarray(b, np.float32).reshape(-1)
        if w.shape[0] != b.shape[0]:
            raise _mapc.MapcError(f"a layer with {w.shape[0]} outputs and {b.shape[0]} biases")
        out += [w.T.reshape(-1), b]  # torch keeps [out, in]; mapc reads w[i * n_out + j]
    return np.concatenate(out).astype("<f4").tobytes()


def save_policy(path: os.PathLike, hidden: Sequence[Layer], last: Layer, value_hidden: Sequence[Layer],
                value_out: Layer, scenario: str = "simple_merge", reward: str = "outflow") -> None:
    """Write a centralized policy's layers as a mapc policy file (atomically)."""
    params = mapc_params(hidden, last, value_hidden, value_out)
    n_av = np.asarray(last[0]).shape[0] // 2
    _mapc.save_policy(os.fspath(path), params, scenario, reward, n_av, [np.asarray(w).shape[0] for w, _ in hidden])


def save_distributed_policy(path: os.PathLike, hidden: Sequence[Layer], last: Layer, features: str = "full",
                            scenario: str = "simple_merge", eta1: float = 0.9, eta2: float = 0.1,
                            exit_bonus: float = 20.0) -> None:
    """Write a distributed policy (one acceleration per agent; ``last`` gives its mean, log-std and value) as a
    mapc policy file, for agents seeing ``features``."""
    params = mapc_params(hidden, last)
    _mapc.save_policy(os.fspath(path), params, scenario, "distributed", 5, [np.asarray(w).shape[0] for w, _ in hidden],
                      features, eta1, eta2, exit_bonus)


def save_sb3_policy(model, path: os.PathLike, scenario: str = "simple_merge", reward: str = "outflow") -> None:
    """A Stable-Baselines3 PPO ``MlpPolicy`` (separate policy and value nets, tanh) as a mapc policy file."""
    p = model.policy
    last = gaussian_head(linear_layers([p.action_net])[0], _numpy(p.log_std))
    save_policy(path, linear_layers(p.mlp_extractor.policy_net), last, linear_layers(p.mlp_extractor.value_net),
                linear_layers([p.value_net])[0], scenario, reward)


def save_rllib_policy(module, path: os.PathLike, scenario: str = "simple_merge", reward: str = "outflow") -> None:
    """An RLlib PPO torch RLModule (new API stack; tanh encoders, ``vf_share_layers=False``, no head hidden
    layers) as a mapc policy file. Its policy head gives means then log-stds, as mapc's last layer does. An
    env runner's module is inference-only (no critic): its value net is then written as zeros, which no
    evaluation reads."""
    enc = module.encoder
    actor, pi = linear_layers(enc.actor_encoder.modules()), linear_layers(module.pi.modules())
    if len(pi) != 1:
        raise _mapc.MapcError("the policy head must be a single layer (head_fcnet_hiddens=[])")
    critic = getattr(enc, "critic_encoder", None)
    vf = getattr(module, "vf", None)
    if critic is not None and vf is not None:
        value_hidden, value_out = linear_layers(critic.modules()), linear_layers(vf.modules())[0]
    else:
        value_hidden = [(np.zeros_like(w), np.zeros_like(b)) for w, b in actor]
        value_out = (np.zeros((1, actor[-1][0].shape[0]), np.float32), np.zeros(1, np.float32))
    save_policy(path, actor, pi[0], value_hidden, value_out, scenario, reward)


def save_rllib_distributed_policy(module, path: os.PathLike, features: str = "full", scenario: str = "simple_merge",
                                  eta1: float = 0.9, eta2: float = 0.1, exit_bonus: float = 20.0) -> None:
    """An RLlib PPO torch RLModule with shared value layers (``vf_share_layers=True``, tanh, single-layer heads)
    trained on mapc's PettingZoo env as a mapc distributed policy file. An env runner's inference-only module has
    no value head: the value output is then written as zeros, which no evaluation reads."""
    hidden = linear_layers(module.encoder.encoder.modules())
    pi = linear_layers(module.pi.modules())
    vf = linear_layers(module.vf.modules()) if getattr(module, "vf", None) is not None else []
    if len(pi) != 1 or len(vf) > 1:
        raise _mapc.MapcError("the policy and value heads must be single layers (head_fcnet_hiddens=[])")
    value = vf[0] if vf else (np.zeros((1, pi[0][0].shape[1]), np.float32), np.zeros(1, np.float32))
    last = (np.concatenate([pi[0][0], value[0]]), np.concatenate([pi[0][1], value[1]]))
    save_distributed_policy(path, hidden, last, features, scenario, eta1, eta2, exit_bonus)
