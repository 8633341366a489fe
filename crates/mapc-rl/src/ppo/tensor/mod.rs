//! All tensor code of the trainer: the MLPs (policy, and value unless it is an output of the policy net), their
//! plain-`f32` forward pass used at rollout time, the PPO loss and its gradient (written out: [`backprop`], its matrix
//! products [`matmul`]'s; burn's autodiff traces the same loss in the tests: `autodiff`), and Adam.
//!
//! Parameters live in one flat `Vec<f32>` (policy layers then value layers, if any; per layer the weight matrix
//! row-major `[inputs][outputs]`, then the bias). The gradient comes back as a vector of the same layout, so
//! checkpoints are plain numbers and Adam is a loop over slices.

mod backprop;
mod matmul;
mod simd;

#[cfg(test)]
mod autodiff;

/// The PPO loss (RLlib's formulation) on one minibatch and its gradient with respect to every parameter:
/// `mean(-min(A r, A clip(r, 1-c, 1+c)) + kl_coeff KL(old||new) + vf_coeff max((V-R)^2, (V_clipped-R)^2) -
/// entropy_coeff H)`, `r = exp(logp - old_logp)`, `V_clipped = V_old + clip(V - V_old, -vf_clip, vf_clip)`.
/// With a separate value net, the policy's and the value's gradients are computed side by side on the rayon pool
/// (they share no parameter).
pub use backprop::loss_and_grad;
pub use matmul::kernel_name as matrix_kernel_name;

use serde::{Deserialize, Serialize};

use crate::rng::Rng;

/// The tanh written as `1 - 2 / (exp(2x) + 1)`: the same function, measured 1.6x faster than flex's tanh.
/// `x` is bounded to ±[`TANH_INPUT_BOUND`] first, which changes no f32 output (tanh(±15) rounds to ±1) but keeps
/// exp(2x) finite: past x ≈ 44 it overflows, and the loss graph's gradient becomes inf / inf = NaN.
#[inline]
pub fn fast_tanh(x: f32) -> f32 {
    let x = x.clamp(-TANH_INPUT_BOUND, TANH_INPUT_BOUND);
    1.0 - 2.0 / ((2.0 * x).exp() + 1.0)
}

pub const TANH_INPUT_BOUND: f32 = 15.0;

/// Bounds of the policy's log standard deviation, as the rollout and the loss see it. Without them a collapsing
/// head drives exp(-log_std) to infinity and every later gradient is NaN; mean actions are unaffected.
pub const LOG_STD_MIN: f32 = -5.0;
pub const LOG_STD_MAX: f32 = 2.0;

const LN_2PI: f32 = 1.837_877_1;

/// Sizes of the networks. The policy net ends in `2 * act_dim` outputs (means then log-stds: the log-std is
/// state-dependent), the value net in one output. With `shared_value` there is no value net: the value is one more
/// output of the policy net's last layer (RLlib's `vf_share_layers`: the value branch reads the last hidden layer),
/// so the value loss also trains the hidden layers the policy uses.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Architecture {
    pub obs_dim: usize,
    pub act_dim: usize,
    pub hidden: Vec<usize>,
    #[serde(default, skip_serializing_if = "std::ops::Not::not")]
    pub shared_value: bool,
}

impl Architecture {
    fn policy_sizes(&self) -> Vec<usize> {
        let mut s = vec![self.obs_dim];
        s.extend(&self.hidden);
        s.push(2 * self.act_dim + usize::from(self.shared_value));
        s
    }
    /// The separate value net's sizes (none with `shared_value`).
    fn value_sizes(&self) -> Vec<usize> {
        if self.shared_value {
            return Vec::new();
        }
        let mut s = vec![self.obs_dim];
        s.extend(&self.hidden);
        s.push(1);
        s
    }
    fn count(sizes: &[usize]) -> usize {
        if sizes.len() < 2 {
            return 0;
        }
        sizes.windows(2).map(|w| w[0] * w[1] + w[1]).sum()
    }
    pub fn policy_len(&self) -> usize {
        Self::count(&self.policy_sizes())
    }
    pub fn param_len(&self) -> usize {
        self.policy_len() + Self::count(&self.value_sizes())
    }
}

/// Policy and value networks with their parameters.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Model {
    pub arch: Architecture,
    pub params: Vec<f32>,
}

/// Fills one MLP's weights with RLlib's "normc" scheme: each output unit's incoming weights are Gaussian, scaled to
/// L2 norm `std` (1.0 for hidden layers, 0.01 for the output layer so initial actions are near zero). Biases 0.
fn normc_init(sizes: &[usize], rng: &mut Rng, out: &mut Vec<f32>) {
    let layers = sizes.len() - 1;
    for (l, w) in sizes.windows(2).enumerate() {
        let (n_in, n_out) = (w[0], w[1]);
        let std = if l + 1 == layers { 0.01 } else { 1.0 };
        let mut m: Vec<f32> = (0..n_in * n_out).map(|_| rng.normal() as f32).collect();
        for j in 0..n_out {
            let norm = (0..n_in)
                .map(|i| m[i * n_out + j].powi(2))
                .sum::<f32>()
                .sqrt()
                .max(1e-12);
            for i in 0..n_in {
                m[i * n_out + j] *= std / norm;
            }
        }
        out.extend(m);
        out.extend(std::iter::repeat_n(0.0, n_out));
    }
}

/// The (inputs, outputs) of each layer of an MLP reading `n_in` inputs through `hidden` to `n_out` outputs.
fn layer_dims(
    n_in: usize,
    hidden: &[usize],
    n_out: usize,
) -> impl Iterator<Item = (usize, usize)> + '_ {
    let ins = std::iter::once(n_in).chain(hidden.iter().copied());
    let outs = hidden.iter().copied().chain(std::iter::once(n_out));
    ins.zip(outs)
}

simd::wide_fn! {
    /// Plain forward of one MLP (`n_in` inputs, tanh `hidden` layers, `n_out` linear outputs) on one input.
    fn mlp_forward(
        params: &[f32],
        n_in: usize,
        hidden: &[usize],
        n_out: usize,
        x: &[f32],
        buf: &mut Vec<f32>,
        out: &mut Vec<f32>,
    ) = mlp_forward_lanes;
}

#[inline(always)]
fn mlp_forward_lanes(
    params: &[f32],
    n_in: usize,
    hidden: &[usize],
    n_out: usize,
    x: &[f32],
    buf: &mut Vec<f32>,
    out: &mut Vec<f32>,
) {
    out.clear();
    out.extend_from_slice(x);
    let mut off = 0;
    let layers = hidden.len() + 1;
    for (l, (n_in, n_out)) in layer_dims(n_in, hidden, n_out).enumerate() {
        let weights = &params[off..off + n_in * n_out];
        let bias = &params[off + n_in * n_out..off + n_in * n_out + n_out];
        off += n_in * n_out + n_out;
        buf.clear();
        buf.extend_from_slice(bias);
        for (i, &xi) in out.iter().enumerate() {
            if xi == 0.0 {
                continue;
            }
            let row = &weights[i * n_out..(i + 1) * n_out];
            for (b, &wij) in buf.iter_mut().zip(row) {
                *b += xi * wij;
            }
        }
        if l + 1 < layers {
            for b in buf.iter_mut() {
                *b = fast_tanh(*b);
            }
        }
        std::mem::swap(out, buf);
    }
}

/// What the policy says about one observation.
#[derive(Clone, Debug, PartialEq)]
pub struct PolicyOutput {
    pub mean: Vec<f32>,
    pub log_std: Vec<f32>,
    pub value: f32,
}

/// The policy's Gaussian for one observation.
#[derive(Clone, Debug, PartialEq)]
pub struct ActionDist {
    pub mean: Vec<f32>,
    pub log_std: Vec<f32>,
}

/// Reusable buffers for rollout-time inference (one per worker).
#[derive(Default)]
pub struct Scratch {
    a: Vec<f32>,
    b: Vec<f32>,
    c: Vec<f32>,
}

impl Model {
    /// A freshly initialised model (deterministic in `seed`).
    pub fn new(arch: Architecture, seed: u64) -> Self {
        let mut rng = Rng::new(seed);
        let mut params = Vec::with_capacity(arch.param_len());
        normc_init(&arch.policy_sizes(), &mut rng, &mut params);
        if !arch.shared_value {
            normc_init(&arch.value_sizes(), &mut rng, &mut params);
        }
        Self { arch, params }
    }

    /// The policy net's outputs: means, log-stds (and the value when it is shared).
    fn policy_outputs(&self) -> usize {
        2 * self.arch.act_dim + usize::from(self.arch.shared_value)
    }

    /// The policy net's forward pass for one observation into `out` (`buf`: the hidden layers' scratch).
    fn policy_forward(&self, obs: &[f32], buf: &mut Vec<f32>, out: &mut Vec<f32>) {
        let pp = &self.params[..self.arch.policy_len()];
        mlp_forward(
            pp,
            self.arch.obs_dim,
            &self.arch.hidden,
            self.policy_outputs(),
            obs,
            buf,
            out,
        );
    }

    /// Policy mean, log-std and value for one observation, in plain `f32` (one row: no tensor library in the way).
    pub fn infer(&self, obs: &[f32], scratch: &mut Scratch) -> PolicyOutput {
        let ActionDist { mean, log_std } = self.action_dist(obs, scratch);
        let value = if self.arch.shared_value {
            // the policy net's own last output, still in the scratch
            scratch.c[2 * self.arch.act_dim]
        } else {
            self.value_net(obs, &mut scratch.a, &mut scratch.b)
        };
        PolicyOutput {
            mean,
            log_std,
            value,
        }
    }

    /// The action distribution alone: what acting needs (the value net is not run).
    pub fn action_dist(&self, obs: &[f32], scratch: &mut Scratch) -> ActionDist {
        let a = self.arch.act_dim;
        let Scratch { a: buf, c: out, .. } = scratch;
        self.policy_forward(obs, buf, out);
        ActionDist {
            mean: out[..a].to_vec(),
            log_std: out[a..2 * a]
                .iter()
                .map(|x| x.clamp(LOG_STD_MIN, LOG_STD_MAX))
                .collect(),
        }
    }

    /// The separate value net's forward pass for one observation.
    fn value_net(&self, obs: &[f32], buf: &mut Vec<f32>, out: &mut Vec<f32>) -> f32 {
        let vp = &self.params[self.arch.policy_len()..];
        mlp_forward(vp, self.arch.obs_dim, &self.arch.hidden, 1, obs, buf, out);
        out[0]
    }

    /// Value estimates of many observations (`obs`: row-major, `obs_dim` each) in one batched forward pass, as
    /// the update computes them (within about 1e-6 of [`Model::value`]'s).
    pub fn values(&self, obs: &[f32]) -> Vec<f32> {
        backprop::values(self, obs)
    }

    /// Value estimate alone.
    pub fn value(&self, obs: &[f32], scratch: &mut Scratch) -> f32 {
        let Scratch { a: buf, c: out, .. } = scratch;
        if self.arch.shared_value {
            self.policy_forward(obs, buf, out);
            return out[2 * self.arch.act_dim];
        }
        self.value_net(obs, buf, out)
    }
}

/// Log-density of `action` under the diagonal Gaussian (summed over action dimensions).
pub fn gaussian_log_prob(action: &[f32], mean: &[f32], log_std: &[f32]) -> f32 {
    action
        .iter()
        .zip(mean)
        .zip(log_std)
        .map(|((&x, &m), &ls)| {
            let z = (x - m) / ls.exp();
            -0.5 * z * z - ls - 0.5 * LN_2PI
        })
        .sum()
}

/// One minibatch, row-major: `obs` is `n * obs_dim`, `actions`, `old_mean`, `old_log_std` are `n * act_dim`.
pub struct Minibatch<'a> {
    pub n: usize,
    pub obs: &'a [f32],
    pub actions: &'a [f32],
    pub old_log_prob: &'a [f32],
    pub old_mean: &'a [f32],
    pub old_log_std: &'a [f32],
    pub old_value: &'a [f32],
    pub advantages: &'a [f32],
    pub value_targets: &'a [f32],
}

/// Coefficients of the PPO loss.
#[derive(Clone, Copy, Debug)]
pub struct LossCoeffs {
    pub clip: f32,
    pub kl_coeff: f32,
    pub vf_coeff: f32,
    pub vf_clip: f32,
    pub entropy_coeff: f32,
}

/// Minibatch means of the loss terms.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct LossStats {
    pub total: f32,
    pub policy_loss: f32,
    pub value_loss: f32,
    pub kl: f32,
    pub entropy: f32,
}

/// Adam on the flat parameter vector (its state is checkpointed with the model, so a resumed run is exact).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Adam {
    pub m: Vec<f32>,
    pub v: Vec<f32>,
    pub t: u64,
    pub beta1: f32,
    pub beta2: f32,
    pub eps: f32,
}

impl Adam {
    pub fn new(n: usize) -> Self {
        Self {
            m: vec![0.0; n],
            v: vec![0.0; n],
            t: 0,
            beta1: 0.9,
            beta2: 0.999,
            eps: 1e-8,
        }
    }

    pub fn step(&mut self, params: &mut [f32], grad: &[f32], lr: f32) {
        self.t += 1;
        let bc1 = 1.0 - self.beta1.powi(self.t as i32);
        let bc2 = 1.0 - self.beta2.powi(self.t as i32);
        let (b1, b2, eps) = (self.beta1, self.beta2, self.eps);
        // each element on its own, so the halves run on two threads with the same bits
        let half = if params.len() >= ADAM_PARALLEL_LEN {
            params.len() / 2
        } else {
            params.len()
        };
        let (p0, p1) = params.split_at_mut(half);
        let (g0, g1) = grad.split_at(half);
        let (m0, m1) = self.m.split_at_mut(half);
        let (v0, v1) = self.v.split_at_mut(half);
        let k = AdamStep {
            b1,
            b2,
            bc1,
            bc2,
            eps,
            lr,
        };
        if p1.is_empty() {
            adam_step(p0, g0, m0, v0, &k);
        } else {
            rayon::join(
                || adam_step(p0, g0, m0, v0, &k),
                || adam_step(p1, g1, m1, v1, &k),
            );
        }
    }
}

/// One Adam step's constants.
struct AdamStep {
    b1: f32,
    b2: f32,
    bc1: f32,
    bc2: f32,
    eps: f32,
    lr: f32,
}

/// Gradients below this are taken as zero, and moments below [`ADAM_MOMENT_FLOOR`] become zero: otherwise the
/// moments of a parameter whose gradient stays (near) zero, such as the weights of an input that is always 0,
/// decay into f32's subnormal range, where the CPU computes each operation about a hundred times slower (a quarter
/// of a late training iteration went there). The step such values would make is below 1e-7 lr. The floors keep
/// every product of the step normal: ((1 - b2) g) g >= 1e-3 * 1e-30, lr * m >= 1e-4 * 1e-30.
const ADAM_GRAD_FLOOR: f32 = 1e-15;
const ADAM_MOMENT_FLOOR: f32 = 1e-30;

simd::wide_fn! {
    fn adam_step(p: &mut [f32], g: &[f32], m: &mut [f32], v: &mut [f32], k: &AdamStep) = adam_step_lanes;
}

/// Each element on its own (so that halves run on two threads with the same bits), branch-free.
#[inline(always)]
fn adam_step_lanes(p: &mut [f32], g: &[f32], m: &mut [f32], v: &mut [f32], k: &AdamStep) {
    let n = p.len();
    let (g, m, v) = (&g[..n], &mut m[..n], &mut v[..n]);
    for i in 0..n {
        let g = if g[i].abs() < ADAM_GRAD_FLOOR {
            0.0
        } else {
            g[i]
        };
        let mi = k.b1 * m[i] + (1.0 - k.b1) * g;
        let vi = k.b2 * v[i] + (1.0 - k.b2) * g * g;
        m[i] = if mi.abs() < ADAM_MOMENT_FLOOR {
            0.0
        } else {
            mi
        };
        v[i] = if vi < ADAM_MOMENT_FLOOR { 0.0 } else { vi };
        let mh = m[i] / k.bc1;
        let vh = v[i] / k.bc2;
        p[i] -= k.lr * mh / (vh.sqrt() + k.eps);
    }
}

/// Parameter count from which Adam's step runs as two halves in parallel (below it, the fork costs more).
const ADAM_PARALLEL_LEN: usize = 8192;

#[cfg(test)]
mod tests;
