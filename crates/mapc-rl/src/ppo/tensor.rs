//! All tensor code of the trainer: the MLPs (policy, and value unless it is an output of the policy net), their
//! plain-`f32` forward pass used at rollout time, the PPO loss and its gradient on burn (flex CPU backend,
//! autodiff), and Adam.
//!
//! Parameters live in one flat `Vec<f32>` (policy layers then value layers, if any; per layer the weight matrix
//! row-major `[inputs][outputs]`, then the bias). Burn builds leaf tensors from that vector for each minibatch and returns the
//! gradient as a vector of the same layout, so checkpoints are plain numbers and Adam is a loop over slices.

use burn::tensor::{Device, Tensor, TensorData};
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

/// Plain forward of one MLP (`n_in` inputs, tanh `hidden` layers, `n_out` linear outputs) on one input.
fn mlp_forward(
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

    /// Policy mean, log-std and value for one observation, in plain `f32` (no burn: ~50x cheaper per sample).
    pub fn infer(&self, obs: &[f32], scratch: &mut Scratch) -> PolicyOutput {
        let a = self.arch.act_dim;
        let vp = &self.params[self.arch.policy_len()..];
        let Scratch {
            a: buf,
            b: vbuf,
            c: out,
        } = scratch;
        self.policy_forward(obs, buf, out);
        let mean = out[..a].to_vec();
        let log_std = out[a..2 * a]
            .iter()
            .map(|x| x.clamp(LOG_STD_MIN, LOG_STD_MAX))
            .collect();
        if self.arch.shared_value {
            return PolicyOutput {
                mean,
                log_std,
                value: out[2 * a],
            };
        }
        mlp_forward(vp, self.arch.obs_dim, &self.arch.hidden, 1, obs, buf, vbuf);
        PolicyOutput {
            mean,
            log_std,
            value: vbuf[0],
        }
    }

    /// Value estimate alone.
    pub fn value(&self, obs: &[f32], scratch: &mut Scratch) -> f32 {
        let Scratch { a: buf, c: out, .. } = scratch;
        if self.arch.shared_value {
            self.policy_forward(obs, buf, out);
            return out[2 * self.arch.act_dim];
        }
        let vp = &self.params[self.arch.policy_len()..];
        mlp_forward(vp, self.arch.obs_dim, &self.arch.hidden, 1, obs, buf, out);
        out[0]
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

fn leaf(values: Vec<f32>, shape: [usize; 2], device: &Device) -> Tensor<2> {
    Tensor::<2>::from_data(TensorData::new(values, shape), device)
}

/// [`fast_tanh`] on a tensor of the loss graph: one fused autodiff operation ([`fused_tanh`]) on the flex
/// autodiff backend, whose value and gradient have the bits of [`tanh_chain`]; the chain elsewhere.
fn burn_tanh(x: Tensor<2>) -> Tensor<2> {
    fused_tanh::apply(&x).unwrap_or_else(|| tanh_chain(x))
}

/// The tanh as seven elementary tensor operations, each one node of the autodiff graph (burn's clamp is two
/// masked fills): the definition [`fused_tanh`] reproduces bit for bit.
fn tanh_chain(x: Tensor<2>) -> Tensor<2> {
    x.clamp(-TANH_INPUT_BOUND, TANH_INPUT_BOUND)
        .mul_scalar(2.0)
        .exp()
        .add_scalar(1.0)
        .recip()
        .mul_scalar(-2.0)
        .add_scalar(1.0)
}

/// The hidden layers' tanh as one autodiff operation. As [`tanh_chain`] it cost seven tensor passes forward and
/// eight backward (exp computed again), each with its graph node and a fresh tensor: about 40 % of a
/// distributed training iteration. Here the forward pass is one loop that keeps exp(2x), and the backward pass one
/// loop that applies, element by element, the very operations burn's backward steps of the chain apply (the same
/// f32 operations on the same values, so the same bits): the add-scalars pass the gradient on, `mul_scalar(-2)`
/// multiplies it by -2, `recip` by -(1 / (u u)) with u = exp(2x) + 1 (flex's `powi_scalar(-2)` is the reciprocal of
/// the square), `exp` by exp(2x), `mul_scalar(2)` by 2, and the clamp's two masked fills zero it where x lay
/// beyond a bound. A test compares both, value and gradient, on random and edge inputs.
mod fused_tanh {
    use super::TANH_INPUT_BOUND;
    use burn::tensor::{Tensor, TensorData};
    use burn_autodiff::Autodiff;
    use burn_autodiff::checkpoint::base::Checkpointer;
    use burn_autodiff::checkpoint::strategy::NoCheckpointing;
    use burn_autodiff::grads::Gradients;
    use burn_autodiff::ops::{Backward, Ops, OpsKind, unary};
    use burn_backend::TensorMetadata;
    use burn_flex::{Flex, FlexTensor};

    type AutodiffFlex = Autodiff<Flex>;

    #[derive(Debug)]
    struct FusedTanh;

    impl Backward<Flex, 1> for FusedTanh {
        /// The input and exp(2 clamp(x)).
        type State = (FlexTensor, FlexTensor);

        fn backward(self, ops: Ops<Self::State, 1>, grads: &mut Gradients, _: &mut Checkpointer) {
            let (x, e) = ops.state;
            unary::<Flex, _>(ops.parents, ops.node, grads, |grad| {
                let shape = grad.shape();
                let (g, x, e) = (values(&grad), values(&x), values(&e));
                let n = g.len();
                let (x, e) = (&x[..n], &e[..n]);
                let mut out = vec![0.0f32; n];
                // branch-free over equal-length slices, so that the loop runs on vector registers (the same
                // operations in every lane)
                for i in 0..n {
                    let (x, e) = (x[i], e[i]);
                    // the masked fills' backward: zero where either mask of the forward pass was set
                    let masked = (x > TANH_INPUT_BOUND) | (clamp_max(x) < -TANH_INPUT_BOUND);
                    let u = e + 1.0;
                    let recip_grad = -(1.0 / (u * u));
                    let grad = ((g[i] * -2.0) * recip_grad) * e * 2.0;
                    out[i] = if masked { 0.0 } else { grad };
                }
                FlexTensor::from_data(TensorData::new(out, shape))
            });
        }
    }

    /// burn's clamp is `clamp_min(clamp_max(x))`, each a masked fill: `x > max` becomes max, then `< min` min
    /// (NaN stays NaN).
    fn clamp_max(x: f32) -> f32 {
        if x > TANH_INPUT_BOUND {
            TANH_INPUT_BOUND
        } else {
            x
        }
    }

    fn clamp_min(x: f32) -> f32 {
        if x < -TANH_INPUT_BOUND {
            -TANH_INPUT_BOUND
        } else {
            x
        }
    }

    /// The tensor's elements in row-major order (no copy when it is stored that way).
    fn values(t: &FlexTensor) -> std::borrow::Cow<'_, [f32]> {
        match t.as_slice::<f32>() {
            Some(s) => std::borrow::Cow::Borrowed(s),
            None => std::borrow::Cow::Owned(t.to_contiguous().as_slice::<f32>().unwrap().to_vec()),
        }
    }

    /// The fused tanh of `x` when it lives on the flex autodiff backend in f32; `None` otherwise.
    pub(super) fn apply(x: &Tensor<2>) -> Option<Tensor<2>> {
        if x.dtype() != burn::tensor::DType::F32 {
            return None;
        }
        let shape = x.shape();
        // (a clone shares the data and the graph node; the conversion consumes it)
        let ad = x.clone().try_into_primitive::<AutodiffFlex>().ok()?;
        let input = ad.primitive().clone();
        let (y, e) = {
            let xs = values(&input);
            // exp is a library call per element; the rest runs on vector registers in a second loop
            let es: Vec<f32> = xs
                .iter()
                .map(|&x| (clamp_min(clamp_max(x)) * 2.0).exp())
                .collect();
            let ys: Vec<f32> = es.iter().map(|&e| (1.0 / (e + 1.0)) * -2.0 + 1.0).collect();
            (
                FlexTensor::from_data(TensorData::new(ys, shape.clone())),
                FlexTensor::from_data(TensorData::new(es, shape)),
            )
        };
        let out = match FusedTanh
            .prepare::<NoCheckpointing>([ad.node()])
            .compute_bound()
            .stateful()
        {
            OpsKind::Tracked(prep) => prep.finish((input, e), y),
            OpsKind::UnTracked(prep) => prep.finish(y),
        };
        Some(Tensor::from_primitive::<AutodiffFlex>(out))
    }
}

fn burn_mlp(x: Tensor<2>, layers: &[(Tensor<2>, Tensor<2>)]) -> Tensor<2> {
    let mut h = x;
    for (l, (w, b)) in layers.iter().enumerate() {
        h = h.matmul(w.clone()) + b.clone();
        if l + 1 < layers.len() {
            h = burn_tanh(h);
        }
    }
    h
}

/// The autodiff CPU device used for updates.
pub fn update_device() -> Device {
    Device::flex().autodiff()
}

/// PPO loss (RLlib's formulation) on one minibatch and its gradient with respect to every parameter:
/// `mean(-min(A r, A clip(r, 1-c, 1+c)) + kl_coeff KL(old||new) + vf_coeff max((V-R)^2, (V_clipped-R)^2)
/// - entropy_coeff H)`, `r = exp(logp - old_logp)`, `V_clipped = V_old + clip(V - V_old, -vf_clip, vf_clip)`.
///
/// With a separate value net the policy's terms and the value's are two graphs that share no parameter,
/// differentiated side by side on the rayon pool ([`split_loss_and_grad`]); with a shared value, one graph
/// ([`joint_loss_and_grad`]). Both give the same bits as the one graph would (a test compares them).
pub fn loss_and_grad(
    model: &Model,
    mb: &Minibatch,
    c: &LossCoeffs,
    device: &Device,
) -> (LossStats, Vec<f32>) {
    if model.arch.shared_value {
        joint_loss_and_grad(model, mb, c, device)
    } else {
        split_loss_and_grad(model, mb, c, device)
    }
}

/// Leaf tensors (weight, bias) of the MLP with layer sizes `sizes` whose parameters start at `params[0]`.
fn layer_leaves(params: &[f32], sizes: &[usize], device: &Device) -> Vec<(Tensor<2>, Tensor<2>)> {
    let mut leaves = Vec::with_capacity(sizes.len().saturating_sub(1));
    let mut off = 0;
    for w in sizes.windows(2) {
        let (n_in, n_out) = (w[0], w[1]);
        let wt = leaf(
            params[off..off + n_in * n_out].to_vec(),
            [n_in, n_out],
            device,
        )
        .require_grad();
        off += n_in * n_out;
        let bt = leaf(params[off..off + n_out].to_vec(), [1, n_out], device).require_grad();
        off += n_out;
        leaves.push((wt, bt));
    }
    leaves
}

/// The leaves' gradients, flattened in parameter order (zeros for a leaf the loss does not reach).
fn flat_grads(
    leaves: &[(Tensor<2>, Tensor<2>)],
    grads: &burn::tensor::Gradients,
    flat: &mut Vec<f32>,
) {
    for (w, b) in leaves {
        for t in [w, b] {
            match t.grad(grads) {
                Some(g) => {
                    flat.extend_from_slice(g.into_data().as_slice::<f32>().expect("f32 gradient"))
                }
                None => flat.extend(std::iter::repeat_n(0.0, t.shape().num_elements())),
            }
        }
    }
}

/// The policy's loss terms from the policy net's output `out` (`[n, 2 act_dim (+1)]`): the minibatch means of
/// the clipped surrogate's negative, of KL(old || new) and of the entropy.
fn policy_terms(
    out: Tensor<2>,
    act_dim: usize,
    mb: &Minibatch,
    c: &LossCoeffs,
    device: &Device,
) -> (Tensor<1>, Tensor<1>, Tensor<1>) {
    let (n, a) = (mb.n, act_dim);
    let mean = out.clone().narrow(1, 0, a);
    let log_std = out.narrow(1, a, a).clamp(LOG_STD_MIN, LOG_STD_MAX);
    let actions = leaf(mb.actions.to_vec(), [n, a], device);
    let old_mean = leaf(mb.old_mean.to_vec(), [n, a], device);
    let old_log_std = leaf(mb.old_log_std.to_vec(), [n, a], device);
    let col = |v: &[f32]| leaf(v.to_vec(), [n, 1], device);
    let old_logp = col(mb.old_log_prob);
    let adv = col(mb.advantages);

    let inv_std = log_std.clone().neg().exp();
    let z = (actions - mean.clone()) * inv_std.clone();
    let logp = (z.square().mul_scalar(-0.5) - log_std.clone())
        .sum_dim(1)
        .sub_scalar(0.5 * LN_2PI * a as f32);
    // exp(20) is far past any clip range; bounding the log-ratio keeps an outlier from overflowing to inf.
    let ratio = (logp - old_logp).clamp(-20.0, 20.0).exp();
    let surr =
        (adv.clone() * ratio.clone()).min_pair(adv * ratio.clamp(1.0 - c.clip, 1.0 + c.clip));
    // KL(old || new) of diagonal Gaussians.
    let old_var = old_log_std.clone().mul_scalar(2.0).exp();
    let kl = (log_std.clone() - old_log_std
        + (old_var + (old_mean - mean).square()) * inv_std.square().mul_scalar(0.5))
    .sub_scalar(0.5)
    .sum_dim(1);
    let entropy = log_std
        .sum_dim(1)
        .add_scalar(0.5 * (LN_2PI + 1.0) * a as f32);
    (surr.neg().mean(), kl.mean(), entropy.mean())
}

/// The minibatch mean of the clipped value loss for the value estimates `value` (`[n, 1]`).
fn value_term(value: Tensor<2>, mb: &Minibatch, c: &LossCoeffs, device: &Device) -> Tensor<1> {
    let col = |v: &[f32]| leaf(v.to_vec(), [mb.n, 1], device);
    let targets = col(mb.value_targets);
    let old_value = col(mb.old_value);
    let vf1 = (value.clone() - targets.clone()).square();
    let vf_clipped = old_value.clone() + (value - old_value).clamp(-c.vf_clip, c.vf_clip);
    let vf2 = (vf_clipped - targets).square();
    vf1.max_pair(vf2).mean()
}

fn scalar(t: Tensor<1>) -> f32 {
    t.into_scalar::<f32>()
}

/// The loss as one autodiff graph over both nets (needed when they share layers).
pub fn joint_loss_and_grad(
    model: &Model,
    mb: &Minibatch,
    c: &LossCoeffs,
    device: &Device,
) -> (LossStats, Vec<f32>) {
    let arch = &model.arch;
    let (pp, vp) = model.params.split_at(arch.policy_len());
    let mut leaves = layer_leaves(pp, &arch.policy_sizes(), device);
    let n_policy_layers = leaves.len();
    leaves.extend(layer_leaves(vp, &arch.value_sizes(), device));
    let obs = leaf(mb.obs.to_vec(), [mb.n, arch.obs_dim], device);
    let out = burn_mlp(obs.clone(), &leaves[..n_policy_layers]);
    let shared_value = arch
        .shared_value
        .then(|| out.clone().narrow(1, 2 * arch.act_dim, 1));
    let (policy_loss, kl_mean, ent_mean) = policy_terms(out, arch.act_dim, mb, c, device);
    let value = match shared_value {
        Some(v) => v,
        None => burn_mlp(obs, &leaves[n_policy_layers..]),
    };
    let vf_mean = value_term(value, mb, c, device);
    let total = policy_loss.clone()
        + kl_mean.clone().mul_scalar(c.kl_coeff)
        + vf_mean.clone().mul_scalar(c.vf_coeff)
        - ent_mean.clone().mul_scalar(c.entropy_coeff);
    let stats = LossStats {
        total: scalar(total.clone()),
        policy_loss: scalar(policy_loss),
        value_loss: scalar(vf_mean),
        kl: scalar(kl_mean),
        entropy: scalar(ent_mean),
    };
    let grads = total.backward();
    let mut flat = Vec::with_capacity(model.params.len());
    flat_grads(&leaves, &grads, &mut flat);
    (stats, flat)
}

/// The loss of a model with a separate value net as two graphs, the policy's and the value's, differentiated in
/// parallel. No parameter is in both, so each gradient is that of the joint graph, bit for bit: the joint
/// total `((policy + kl_coeff kl) + vf_coeff vf) - entropy_coeff entropy` passes each term's gradient on
/// unchanged (+1 or -1 times its coefficient), whichever terms sit beside it; and the total itself is formed
/// from the terms' values with the same f32 operations in the same order.
fn split_loss_and_grad(
    model: &Model,
    mb: &Minibatch,
    c: &LossCoeffs,
    device: &Device,
) -> (LossStats, Vec<f32>) {
    let arch = &model.arch;
    let (pp, vp) = model.params.split_at(arch.policy_len());
    let obs = || leaf(mb.obs.to_vec(), [mb.n, arch.obs_dim], device);
    let policy = || {
        let leaves = layer_leaves(pp, &arch.policy_sizes(), device);
        let (policy_loss, kl_mean, ent_mean) =
            policy_terms(burn_mlp(obs(), &leaves), arch.act_dim, mb, c, device);
        let total = policy_loss.clone() + kl_mean.clone().mul_scalar(c.kl_coeff)
            - ent_mean.clone().mul_scalar(c.entropy_coeff);
        let grads = total.backward();
        let mut flat = Vec::with_capacity(model.params.len());
        flat_grads(&leaves, &grads, &mut flat);
        (scalar(policy_loss), scalar(kl_mean), scalar(ent_mean), flat)
    };
    let value = || {
        let leaves = layer_leaves(vp, &arch.value_sizes(), device);
        let vf_mean = value_term(burn_mlp(obs(), &leaves), mb, c, device);
        let grads = vf_mean.clone().mul_scalar(c.vf_coeff).backward();
        let mut flat = Vec::with_capacity(vp.len());
        flat_grads(&leaves, &grads, &mut flat);
        (scalar(vf_mean), flat)
    };
    let ((policy_loss, kl, entropy, mut flat), (value_loss, value_flat)) =
        rayon::join(policy, value);
    flat.extend_from_slice(&value_flat);
    let total = policy_loss + kl * c.kl_coeff + value_loss * c.vf_coeff - entropy * c.entropy_coeff;
    let stats = LossStats {
        total,
        policy_loss,
        value_loss,
        kl,
        entropy,
    };
    (stats, flat)
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
        let step = |p: &mut [f32], g: &[f32], m: &mut [f32], v: &mut [f32]| {
            for (((p, &g), m), v) in p.iter_mut().zip(g).zip(m.iter_mut()).zip(v.iter_mut()) {
                *m = b1 * *m + (1.0 - b1) * g;
                *v = b2 * *v + (1.0 - b2) * g * g;
                let mh = *m / bc1;
                let vh = *v / bc2;
                *p -= lr * mh / (vh.sqrt() + eps);
            }
        };
        if p1.is_empty() {
            step(p0, g0, m0, v0);
        } else {
            rayon::join(|| step(p0, g0, m0, v0), || step(p1, g1, m1, v1));
        }
    }
}

/// Parameter count from which Adam's step runs as two halves in parallel (below it, the fork costs more).
const ADAM_PARALLEL_LEN: usize = 8192;

#[cfg(test)]
#[path = "tensor_tests.rs"]
mod tests;
