"""A mapc policy file driven outside mapc: the MLP's forward pass in numpy, the centralized observation and the
FIFO controlled set, as crates/mapc-rl computes them (env/obs.rs, env/merge.rs, ppo/tensor/mod.rs)."""
import json

import numpy as np

PER_AV = 5


class Policy:
    """A centralized mapc checkpoint (policies/*.json): [obs] -> accelerations of the first N_AV controlled AVs."""

    def __init__(self, path):
        with open(path) as f:
            ckpt = json.load(f)
        spec = ckpt["spec"]
        if spec.get("distributed"):
            raise SystemExit("%s: a distributed policy; sumo_check drives centralized ones" % path)
        self.n_av = spec["n_av"]
        self.max_speed = spec["max_speed"]
        self.norm_length = spec["norm_length"]
        self.accel_min = spec["accel_min"]
        self.accel_max = spec["accel_max"]
        model = ckpt["state"]["model"]
        arch = model["arch"]
        if arch.get("shared_value"):
            raise SystemExit("%s: a shared-value model; sumo_check reads separate policy nets" % path)
        self.act_dim = arch["act_dim"]
        sizes = [arch["obs_dim"]] + list(arch["hidden"]) + [2 * self.act_dim]
        params = np.asarray(model["params"], dtype=np.float32)
        # Layer by layer: weights row-major [n_in][n_out], then the biases (ppo/tensor/mod.rs, mlp_forward).
        self.layers = []
        off = 0
        for n_in, n_out in zip(sizes[:-1], sizes[1:]):
            w = params[off:off + n_in * n_out].reshape(n_in, n_out)
            off += n_in * n_out
            b = params[off:off + n_out]
            off += n_out
            self.layers.append((w, b))
        self.obs_dim = arch["obs_dim"]
        if self.obs_dim != PER_AV * self.n_av:
            raise SystemExit("%s: observation of %d values, not 5 per AV" % (path, self.obs_dim))

    def mean_action(self, obs):
        x = np.asarray(obs, dtype=np.float32)
        for i, (w, b) in enumerate(self.layers):
            x = x @ w + b
            if i + 1 < len(self.layers):
                x = np.tanh(x)
        return x[:self.act_dim]

    def observe(self, views):
        """views: per controlled AV (speed, leader (speed, gap) or None, follower (speed, gap) or None)."""
        v_max, length = self.max_speed, self.norm_length
        out = np.zeros(PER_AV * self.n_av, dtype=np.float32)
        for k, (speed, leader, follower) in enumerate(views[:self.n_av]):
            lead_v, lead_gap = leader if leader is not None else (v_max, length)
            fol_v, fol_gap = follower if follower is not None else (0.0, length)
            vals = [speed / v_max, (lead_v - speed) / v_max, lead_gap / length,
                    (speed - fol_v) / v_max, fol_gap / length]
            out[k * PER_AV:(k + 1) * PER_AV] = np.clip(vals, -1.0, 1.0)
        return out

    def clamp(self, a):
        """The environment's clamp: non-finite actions do nothing, the rest lie in [accel_min, accel_max]."""
        a = float(a)
        if not np.isfinite(a):
            return 0.0
        return min(max(a, self.accel_min), self.accel_max)


class ControlQueue:
    """AVs in FIFO order of entry into the control region; one that has left is never controlled again."""

    def __init__(self):
        self.order = []
        self.left = set()

    def update(self, present, n_av):
        now = set(present)
        kept = []
        for v in self.order:
            if v in now:
                kept.append(v)
            else:
                self.left.add(v)
        self.order = kept
        known = set(kept)
        for v in present:
            if v not in self.left and v not in known:
                self.order.append(v)
                known.add(v)
        return self.order[:n_av]
