"""Policies trained in Python (RLlib, Stable-Baselines3) written as mapc policy files, so ``mapc eval`` evaluates
them over 100 seeds like any policy of ``mapc train``.

mapc's centralized policy is an MLP with tanh hidden layers whose last layer gives the means and then the
log-stds of the actions, and a separate value MLP of the same hidden sizes. A torch policy with a
state-independent log-std (both libraries' default) is written with zero log-std weights and its log-std as their
biases. Only the weights' values cross: mapc evaluates with its own forward pass.
"""

from __future__ import annotations

import os
from typing import Iterable, List, Sequence, Tuple

import numpy as np

from . import _mapc

Layer = Tuple[np.ndarray, np.ndarray]  # torch's (weight [out, in], bias [out])


def _numpy(x) -> np.ndarray:
    return x.detach().cpu().numpy() if hasattr(x, "detach") else np.asarray(x)


def linear_layers(modules: Iterable) -> List[Layer]:
    """The (weight, bias) of every ``torch.nn.Linear`` in ``modules``, in order."""
    return [(_numpy(m.weight), _numpy(m.bias)) for m in modules if type(m).__name__ == "Linear"]


def mapc_params(hidden: Sequence[Layer], mean: Layer, log_std: np.ndarray, value_hidden: Sequence[Layer],
                value_out: Layer) -> bytes:
    """The float32 bytes of a policy in mapc's layout (each layer's weights input-major, then its biases)."""
    w_mean, b_mean = (np.asarray(x, np.float32) for x in mean)
    log_std = np.asarray(log_std, np.float32).reshape(-1)
    last = (np.concatenate([w_mean, np.zeros_like(w_mean)]), np.concatenate([b_mean, log_std]))
    out: List[np.ndarray] = []
    for w, b in list(hidden) + [last] + list(value_hidden) + [value_out]:
        w, b = np.asarray(w, np.float32), np.asarray(b, np.float32).reshape(-1)
        if w.shape[0] != b.shape[0]:
            raise _mapc.MapcError(f"a layer with {w.shape[0]} outputs and {b.shape[0]} biases")
        out += [w.T.reshape(-1), b]  # torch keeps [out, in]; mapc reads w[i * n_out + j]
    return np.concatenate(out).astype("<f4").tobytes()


def save_sb3_policy(model, path: os.PathLike, scenario: str = "simple_merge", reward: str = "outflow") -> None:
    """A Stable-Baselines3 PPO ``MlpPolicy`` (separate policy and value nets, tanh) as a mapc policy file."""
    p = model.policy
    hidden = linear_layers(p.mlp_extractor.policy_net)
    value_hidden = linear_layers(p.mlp_extractor.value_net)
    params = mapc_params(hidden, linear_layers([p.action_net])[0], _numpy(p.log_std), value_hidden,
                         linear_layers([p.value_net])[0])
    n_av = linear_layers([p.action_net])[0][0].shape[0]
    _mapc.save_policy(os.fspath(path), params, scenario, reward, n_av, [w.shape[0] for w, _ in hidden])
