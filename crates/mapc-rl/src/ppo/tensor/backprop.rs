//! The PPO loss and its gradient, written out. Each net's forward pass keeps what its backward pass needs (each
//! layer's input, and exp(2z) of each tanh); the loss's derivative with respect to the nets' outputs is one loop
//! over the minibatch's rows; the backward pass then goes layer by layer. Matrix products are [`super::matmul`]'s
//! (one fused multiply-add per term, in order); the element-wise steps are loops over slices.
//!
//! Why not burn's autodiff: on the paper's minibatches of 128 rows, recording the loss's ~80 operations as a
//! graph and replaying it cost three times the arithmetic (docs/perf.md, "The gradient written out"). The autodiff version
//! stays as the reference the tests compare this one with ([`super::autodiff`]).

use super::matmul::{self, Product};
use super::{
    Architecture, LN_2PI, LOG_STD_MAX, LOG_STD_MIN, LossCoeffs, LossStats, Minibatch, Model,
    TANH_INPUT_BOUND,
};

/// The PPO loss (RLlib's formulation) on one minibatch and its gradient with respect to every parameter, in the
/// model's parameter layout. See [`super::loss_and_grad`].
pub fn loss_and_grad(model: &Model, mb: &Minibatch, c: &LossCoeffs) -> (LossStats, Vec<f32>) {
    let arch = &model.arch;
    let (pp, vp) = model.params.split_at(arch.policy_len());
    let obs = || mb.obs[..mb.n * arch.obs_dim].to_vec();
    let policy = || {
        let net = Mlp::new(pp, arch.policy_sizes());
        let pass = net.forward(obs());
        let (terms, mut d_out) = policy_terms(&pass.out, arch, mb, c);
        let value_loss = arch.shared_value.then(|| {
            let outs = net.outputs();
            let value = pass.out_column(2 * arch.act_dim);
            let (loss, d_value) = value_term(&value, mb, c);
            for (row, d) in d_out.chunks_exact_mut(outs).zip(d_value) {
                row[2 * arch.act_dim] = d;
            }
            loss
        });
        (terms, value_loss, net.backward(&pass, d_out))
    };
    let value = || {
        if arch.shared_value {
            return None;
        }
        let net = Mlp::new(vp, arch.value_sizes());
        let pass = net.forward(obs());
        let (loss, d_value) = value_term(&pass.out, mb, c);
        Some((loss, net.backward(&pass, d_value)))
    };
    let ((terms, shared_loss, mut grad), separate) = if arch.shared_value {
        (policy(), None)
    } else {
        rayon::join(policy, value)
    };
    let value_loss = match separate {
        Some((loss, value_grad)) => {
            grad.extend_from_slice(&value_grad);
            loss
        }
        None => shared_loss.unwrap_or(0.0),
    };
    let PolicyTerms {
        policy_loss,
        kl,
        entropy,
    } = terms;
    let total = policy_loss + kl * c.kl_coeff + value_loss * c.vf_coeff - entropy * c.entropy_coeff;
    let stats = LossStats {
        total,
        policy_loss,
        value_loss,
        kl,
        entropy,
    };
    (stats, grad)
}

/// [`Model::values`]: the value net's (or the shared value column's) forward pass over all rows at once.
pub fn values(model: &Model, obs: &[f32]) -> Vec<f32> {
    let arch = &model.arch;
    let rows = obs.len() / arch.obs_dim.max(1);
    if rows == 0 {
        return Vec::new();
    }
    let x = obs[..rows * arch.obs_dim].to_vec();
    let (pp, vp) = model.params.split_at(arch.policy_len());
    if arch.shared_value {
        let pass = Mlp::new(pp, arch.policy_sizes()).forward(x);
        return pass.out_column(2 * arch.act_dim);
    }
    Mlp::new(vp, arch.value_sizes()).forward(x).out
}

/// exp(x) for |x| ≤ 2 [`TANH_INPUT_BOUND`] as straight-line arithmetic, so that the tanh's loop runs on vector
/// registers: glibc's `expf` is one call per element, and took a fifth of a training iteration. Cody and Waite's
/// range reduction (x = k ln 2 + r, ln 2 in two parts) and the degree-6 polynomial of the Cephes library's
/// `expf`; within 2 ulp of `f32::exp` over that range (a test checks it). Plain f32 operations, so the same bits on
/// every machine. (Rollout-time inference keeps [`super::fast_tanh`]: the shipped policies' runs do not move.)
#[inline(always)]
pub(super) fn exp_straight(x: f32) -> f32 {
    const LN2_HI: f32 = 0.693_359_4;
    const LN2_LO: f32 = -2.121_944_4e-4;
    // adding and subtracting 1.5 * 2^23 rounds to the nearest integer without a rounding instruction
    const ROUND: f32 = 12_582_912.0;
    let t = x * std::f32::consts::LOG2_E + ROUND;
    let k = t - ROUND;
    let r = (x - k * LN2_HI) - k * LN2_LO;
    let p = 1.987_569_1e-4_f32;
    let p = p * r + 1.398_199_9e-3;
    let p = p * r + 8.333_452e-3;
    let p = p * r + 4.166_579_6e-2;
    let p = p * r + 1.666_666_5e-1;
    let p = p * r + 0.5;
    let y = p * (r * r) + r + 1.0;
    // t's last bits hold k (|k| < 2^22), so 2^k is built with integer operations, no conversion
    let k_bits = t.to_bits().wrapping_sub(ROUND.to_bits());
    y * f32::from_bits(k_bits.wrapping_add(127) << 23)
}

super::simd::wide_fn! {
    /// `z` replaced by its tanh, computed as [`super::fast_tanh`] does, with exp(2z) kept in `e`.
    pub(super) fn tanh_keeping_exp(z: &mut [f32], e: &mut [f32]) = tanh_keeping_exp_lanes;
}

/// Branch-free over slices of equal length, so that it runs on vector registers.
#[inline(always)]
pub(super) fn tanh_keeping_exp_lanes(z: &mut [f32], e: &mut [f32]) {
    let e = &mut e[..z.len()];
    for (v, e) in z.iter_mut().zip(e.iter_mut()) {
        *e = exp_straight(2.0 * v.clamp(-TANH_INPUT_BOUND, TANH_INPUT_BOUND));
        *v = 1.0 - 2.0 / (*e + 1.0);
    }
}

super::simd::wide_fn! {
    /// `d` times the tanh's slope, d tanh(z) / dz = 4 e / (e + 1)^2 with e = exp(2z).
    pub(super) fn times_tanh_slope(d: &mut [f32], e: &[f32]) = times_tanh_slope_lanes;
}

#[inline(always)]
pub(super) fn times_tanh_slope_lanes(d: &mut [f32], e: &[f32]) {
    let e = &e[..d.len()];
    for (d, &e) in d.iter_mut().zip(e) {
        let u = e + 1.0;
        *d *= 4.0 * e / (u * u);
    }
}

/// One MLP (tanh hidden layers, linear outputs) over its slice of the parameters.
struct Mlp<'a> {
    params: &'a [f32],
    sizes: Vec<usize>,
}

/// What a forward pass keeps for the backward pass.
struct Pass {
    rows: usize,
    /// Each layer's input, `[rows, inputs]` row-major.
    inputs: Vec<Vec<f32>>,
    /// exp(2z) of each hidden unit, z its (bounded) pre-activation, for the tanh's derivative.
    exps: Vec<Vec<f32>>,
    /// The last layer's output, `[rows, outputs]` row-major.
    out: Vec<f32>,
    outputs: usize,
}

impl Pass {
    /// Column `k` of the output (the shared value's, for one).
    fn out_column(&self, k: usize) -> Vec<f32> {
        self.out
            .iter()
            .skip(k)
            .step_by(self.outputs)
            .copied()
            .collect()
    }
}

impl<'a> Mlp<'a> {
    fn new(params: &'a [f32], sizes: Vec<usize>) -> Self {
        Self { params, sizes }
    }

    fn outputs(&self) -> usize {
        *self.sizes.last().expect("an MLP has layers")
    }

    fn layers(&self) -> usize {
        self.sizes.len() - 1
    }

    /// Where layer `l`'s weights start in the parameters (its bias follows them).
    fn weight_offset(&self, l: usize) -> usize {
        self.sizes
            .windows(2)
            .take(l)
            .map(|w| w[0] * w[1] + w[1])
            .sum()
    }

    /// Layer `l`'s weights `[inputs, outputs]` row-major, then its bias.
    fn layer(&self, l: usize) -> (&'a [f32], &'a [f32]) {
        let (n_in, n_out) = (self.sizes[l], self.sizes[l + 1]);
        let w = &self.params[self.weight_offset(l)..];
        (&w[..n_in * n_out], &w[n_in * n_out..][..n_out])
    }

    /// `x`: `[rows, inputs]` row-major.
    fn forward(&self, x: Vec<f32>) -> Pass {
        let rows = x.len() / self.sizes[0].max(1);
        let layers = self.layers();
        let mut inputs = Vec::with_capacity(layers);
        let mut exps = Vec::with_capacity(layers - 1);
        let mut h = x;
        for l in 0..layers {
            let (n_in, n_out) = (self.sizes[l], self.sizes[l + 1]);
            let (w, bias) = self.layer(l);
            // z = bias + h w, the bias as the products' starting value
            let mut z: Vec<f32> = Vec::with_capacity(rows * n_out);
            for _ in 0..rows {
                z.extend_from_slice(bias);
            }
            let product = Product {
                rows,
                cols: n_out,
                terms: n_in,
                a: &h,
                a_row: n_in,
                a_term: 1,
                b: w,
            };
            matmul::accumulate(product, &mut z);
            inputs.push(h);
            if l + 1 < layers {
                let mut e = vec![0.0f32; z.len()];
                tanh_keeping_exp(&mut z, &mut e);
                exps.push(e);
            }
            h = z;
        }
        Pass {
            rows,
            inputs,
            exps,
            out: h,
            outputs: self.outputs(),
        }
    }

    /// The gradient of the loss with respect to this net's parameters, given its derivative `d_out` with
    /// respect to the net's outputs (`[rows, outputs]`).
    fn backward(&self, pass: &Pass, d_out: Vec<f32>) -> Vec<f32> {
        let rows = pass.rows;
        let mut grad = vec![0.0f32; self.params.len()];
        let mut g = d_out;
        for l in (0..self.layers()).rev() {
            let (n_in, n_out) = (self.sizes[l], self.sizes[l + 1]);
            let w_off = self.weight_offset(l);
            let (d_w, d_b) = grad[w_off..][..n_in * n_out + n_out].split_at_mut(n_in * n_out);
            // d_w = input^T g: term t is row t of both
            let product = Product {
                rows: n_in,
                cols: n_out,
                terms: rows,
                a: &pass.inputs[l],
                a_row: 1,
                a_term: n_in,
                b: &g,
            };
            matmul::accumulate(product, d_w);
            for row in g.chunks_exact(n_out) {
                for (d, &x) in d_b.iter_mut().zip(row) {
                    *d += x;
                }
            }
            if l == 0 {
                break;
            }
            // through the weights (d_h = g w^T), then the tanh: d tanh(z) / dz = 4 e / (e + 1)^2, e = exp(2z)
            let (w, _) = self.layer(l);
            let mut w_t = vec![0.0f32; n_in * n_out];
            for (i, w_row) in w.chunks_exact(n_out).enumerate() {
                for (j, &x) in w_row.iter().enumerate() {
                    w_t[j * n_in + i] = x;
                }
            }
            let mut d_h = vec![0.0f32; rows * n_in];
            let product = Product {
                rows,
                cols: n_in,
                terms: n_out,
                a: &g,
                a_row: n_out,
                a_term: 1,
                b: &w_t,
            };
            matmul::accumulate(product, &mut d_h);
            times_tanh_slope(&mut d_h, &pass.exps[l - 1]);
            g = d_h;
        }
        grad
    }
}

/// The policy's loss terms, each a minibatch mean.
struct PolicyTerms {
    policy_loss: f32,
    kl: f32,
    entropy: f32,
}

/// The policy's terms of the loss from the policy net's output (`[n, outputs]`: means, raw log-stds, and the
/// shared value if any), and the derivative of `policy_loss + kl_coeff kl - entropy_coeff entropy` with respect to
/// that output (zero in the value's column).
fn policy_terms(
    out: &[f32],
    arch: &Architecture,
    mb: &Minibatch,
    c: &LossCoeffs,
) -> (PolicyTerms, Vec<f32>) {
    let (n, a) = (mb.n, arch.act_dim);
    let outs = 2 * a + usize::from(arch.shared_value);
    let inv_n = 1.0 / n as f32;
    let mut d_out = vec![0.0f32; n * outs];
    let (mut surr_sum, mut kl_sum, mut entropy_sum) = (0.0f32, 0.0f32, 0.0f32);
    let mut z = vec![0.0f32; a];
    for i in 0..n {
        let row = &out[i * outs..][..outs];
        let (mean, raw_log_std) = (&row[..a], &row[a..2 * a]);
        let actions = &mb.actions[i * a..][..a];
        let old_mean = &mb.old_mean[i * a..][..a];
        let old_log_std = &mb.old_log_std[i * a..][..a];

        let mut logp = -0.5 * LN_2PI * a as f32;
        let mut kl = 0.0f32;
        let mut log_std_sum = 0.0f32;
        for j in 0..a {
            let ls = raw_log_std[j].clamp(LOG_STD_MIN, LOG_STD_MAX);
            let inv_std = (-ls).exp();
            z[j] = (actions[j] - mean[j]) * inv_std;
            logp += -0.5 * z[j] * z[j] - ls;
            let old_var = (2.0 * old_log_std[j]).exp();
            let dm = old_mean[j] - mean[j];
            kl += ls - old_log_std[j] + 0.5 * (old_var + dm * dm) * inv_std * inv_std - 0.5;
            log_std_sum += ls;
        }
        // exp(20) is far past any clip range; bounding the log-ratio keeps an outlier from overflowing to inf
        let log_ratio = logp - mb.old_log_prob[i];
        let ratio = log_ratio.clamp(-20.0, 20.0).exp();
        let adv = mb.advantages[i];
        let unclipped = adv * ratio;
        let clipped = adv * ratio.clamp(1.0 - c.clip, 1.0 + c.clip);
        surr_sum += unclipped.min(clipped);
        kl_sum += kl;
        entropy_sum += log_std_sum + 0.5 * (LN_2PI + 1.0) * a as f32;

        // d(-surrogate)/d logp: through the unclipped term only (the clipped one is flat where it is the min)
        let ratio_live = unclipped <= clipped && (-20.0..=20.0).contains(&log_ratio);
        let d_logp = if ratio_live {
            -adv * ratio * inv_n
        } else {
            0.0
        };
        let d_row = &mut d_out[i * outs..][..outs];
        for j in 0..a {
            let ls = raw_log_std[j].clamp(LOG_STD_MIN, LOG_STD_MAX);
            let inv_var = (-2.0 * ls).exp();
            let old_var = (2.0 * old_log_std[j]).exp();
            let dm = old_mean[j] - mean[j];
            let inv_std = (-ls).exp();
            d_row[j] = d_logp * z[j] * inv_std - c.kl_coeff * inv_n * dm * inv_var;
            let d_ls = d_logp * (z[j] * z[j] - 1.0)
                + c.kl_coeff * inv_n * (1.0 - (old_var + dm * dm) * inv_var)
                - c.entropy_coeff * inv_n;
            let inside = (LOG_STD_MIN..=LOG_STD_MAX).contains(&raw_log_std[j]);
            d_row[a + j] = if inside { d_ls } else { 0.0 };
        }
    }
    let terms = PolicyTerms {
        policy_loss: -surr_sum * inv_n,
        kl: kl_sum * inv_n,
        entropy: entropy_sum * inv_n,
    };
    (terms, d_out)
}

/// The minibatch mean of the clipped value loss `max((V-R)^2, (V_clipped-R)^2)` and its derivative, times
/// `vf_coeff`, with respect to each value estimate.
fn value_term(value: &[f32], mb: &Minibatch, c: &LossCoeffs) -> (f32, Vec<f32>) {
    let inv_n = 1.0 / mb.n as f32;
    let mut sum = 0.0f32;
    let mut d = Vec::with_capacity(mb.n);
    let rows = value.iter().zip(mb.value_targets).zip(mb.old_value);
    for ((&v, &target), &old) in rows.take(mb.n) {
        let step = v - old;
        let clipped = old + step.clamp(-c.vf_clip, c.vf_clip);
        let (e1, e2) = (v - target, clipped - target);
        let (l1, l2) = (e1 * e1, e2 * e2);
        sum += l1.max(l2);
        let slope = if l1 >= l2 {
            2.0 * e1
        } else if (-c.vf_clip..=c.vf_clip).contains(&step) {
            2.0 * e2
        } else {
            0.0
        };
        d.push(c.vf_coeff * inv_n * slope);
    }
    (sum * inv_n, d)
}
