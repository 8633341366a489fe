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

    /// Policy mean, log-std and value for one observation, in plain `f32` (no burn: ~50x cheaper per sample).
    pub fn infer(&self, obs: &[f32], scratch: &mut Scratch) -> PolicyOutput {
        let a = self.arch.act_dim;
        let (pp, vp) = self.params.split_at(self.arch.policy_len());
        let Scratch {
            a: buf,
            b: vbuf,
            c: out,
        } = scratch;
        mlp_forward(
            pp,
            self.arch.obs_dim,
            &self.arch.hidden,
            self.policy_outputs(),
            obs,
            buf,
            out,
        );
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
mod tests {
    use super::*;

    /// The paper's clip, KL and value coefficients, with the given entropy coefficient.
    fn test_coeffs(entropy_coeff: f32) -> LossCoeffs {
        LossCoeffs {
            clip: 0.3,
            kl_coeff: 0.2,
            vf_coeff: 1.0,
            vf_clip: 10.0,
            entropy_coeff,
        }
    }

    fn arch() -> Architecture {
        Architecture {
            obs_dim: 3,
            act_dim: 2,
            hidden: vec![4, 3],
            shared_value: false,
        }
    }

    fn shared_arch() -> Architecture {
        Architecture {
            shared_value: true,
            ..arch()
        }
    }

    /// A model whose hidden weights are zero outputs its last biases: mean and log-std are then known by hand.
    fn constant_model(mean: [f32; 2], log_std: [f32; 2], value: f32) -> Model {
        let arch = arch();
        let mut m = Model::new(arch.clone(), 1);
        m.params.iter_mut().for_each(|p| *p = 0.0);
        // Policy output bias sits at the end of the policy block; value output bias at the very end.
        let pl = arch.policy_len();
        m.params[pl - 4..pl].copy_from_slice(&[mean[0], mean[1], log_std[0], log_std[1]]);
        let n = m.params.len();
        m.params[n - 1] = value;
        m
    }

    #[test]
    fn plain_inference_matches_hand_values() {
        let m = constant_model([0.5, -1.0], [0.0, -0.5], 2.0);
        let out = m.infer(&[0.3, -0.2, 0.9], &mut Scratch::default());
        assert_eq!(out.mean, vec![0.5, -1.0]);
        assert_eq!(out.log_std, vec![0.0, -0.5]);
        assert_eq!(out.value, 2.0);
        // log N(1; 0.5, 1) + log N(-1; -1, e^-0.5) = (-0.125 - 0.9189385) + (0.5 - 0.9189385)
        let lp = gaussian_log_prob(&[1.0, -1.0], &out.mean, &out.log_std);
        assert!((lp - (-1.462_877)).abs() < 1e-5, "{lp}");
    }

    #[test]
    fn ppo_loss_matches_hand_computation() {
        // New policy: mean (0.5, -1), log-std (0, -0.5); value 2.
        let m = constant_model([0.5, -1.0], [0.0, -0.5], 2.0);
        let action = [1.0, -1.0];
        let new_lp = -1.462_877_f32;
        // Old log-prob chosen so the ratio is e^0.5 = 1.6487 (clipped to 1.3 with clip 0.3).
        let old_lp = new_lp - 0.5;
        let c = test_coeffs(0.01);
        let mb = Minibatch {
            n: 1,
            obs: &[0.3, -0.2, 0.9],
            actions: &action,
            old_log_prob: &[old_lp],
            old_mean: &[0.0, -1.0],
            old_log_std: &[0.0, 0.0],
            old_value: &[1.0],
            advantages: &[2.0],
            value_targets: &[3.5],
        };
        let (s, g) = loss_and_grad(&m, &mb, &c, &update_device());
        // Surrogate: min(2 * 1.6487, 2 * 1.3) = 2.6 -> policy loss -2.6.
        assert!((s.policy_loss + 2.6).abs() < 1e-5, "{:?}", s);
        // KL: dim 1: 0 - 0 + (1 + 0.25)/2 - 0.5 = 0.125; dim 2: -0.5 - 0 + (1 + 0) / (2 e^-1) - 0.5 = e/2 - 1.
        let kl = 0.125 + std::f32::consts::E / 2.0 - 1.0;
        assert!((s.kl - kl).abs() < 1e-5, "{:?} vs {kl}", s);
        // Value: V = 2, target 3.5: (1.5)^2 = 2.25 (the clipped branch is the same: |2 - 1| < 10).
        assert!((s.value_loss - 2.25).abs() < 1e-5);
        // Entropy: sum(log_std) + (ln 2pi + 1) = -0.5 + 2.837877.
        assert!((s.entropy - 2.337_877).abs() < 1e-5);
        let total = -2.6 + 0.2 * kl + 2.25 - 0.01 * 2.337_877;
        assert!((s.total - total).abs() < 1e-5);
        // The clipped surrogate passes no gradient; the value bias gets d/dV (V - 3.5)^2 = -3.
        let n = g.len();
        assert!((g[n - 1] + 3.0).abs() < 1e-5, "{}", g[n - 1]);
        assert_eq!(g.len(), m.params.len());
    }

    #[test]
    fn a_shared_value_is_the_policy_nets_last_output() {
        let separate = arch();
        let arch = shared_arch();
        // no value net: the policy net with one more output column (3 weights and a bias)
        assert_eq!(arch.param_len(), arch.policy_len());
        assert_eq!(arch.policy_len(), separate.policy_len() + 3 + 1);
        let mut m = Model::new(arch.clone(), 1);
        m.params.iter_mut().for_each(|p| *p = 0.0);
        let pl = arch.policy_len();
        m.params[pl - 5..pl].copy_from_slice(&[0.5, -1.0, 0.0, -0.5, 2.0]);
        let mut sc = Scratch::default();
        let out = m.infer(&[0.3, -0.2, 0.9], &mut sc);
        assert_eq!(out.mean, vec![0.5, -1.0]);
        assert_eq!(out.log_std, vec![0.0, -0.5]);
        assert_eq!(out.value, 2.0);
        assert_eq!(m.value(&[0.3, -0.2, 0.9], &mut sc), 2.0);
        // the value loss reaches the hidden layers the policy uses
        let mut m = Model::new(arch, 3);
        let o = m.infer(&[0.3, -0.2, 0.9], &mut sc);
        let lp = gaussian_log_prob(&[0.0, 0.0], &o.mean, &o.log_std);
        let mb = Minibatch {
            n: 1,
            obs: &[0.3, -0.2, 0.9],
            actions: &[0.0, 0.0],
            old_log_prob: &[lp],
            old_mean: &o.mean,
            old_log_std: &o.log_std,
            old_value: &[o.value],
            advantages: &[0.0],
            value_targets: &[o.value + 1.0],
        };
        let c = LossCoeffs {
            clip: 0.3,
            kl_coeff: 0.0,
            vf_coeff: 1.0,
            vf_clip: 10.0,
            entropy_coeff: 0.0,
        };
        let (_, g) = loss_and_grad(&m, &mb, &c, &update_device());
        assert!(
            g[..3 * 4].iter().any(|x| x.abs() > 1e-6),
            "first layer: {:?}",
            &g[..12]
        );
        m.params[0] += 1.0;
        assert_ne!(m.infer(&[0.3, -0.2, 0.9], &mut sc).value, o.value);
    }

    #[test]
    fn gradient_matches_finite_differences() {
        gradient_matches_finite_differences_for(arch());
        gradient_matches_finite_differences_for(shared_arch());
    }

    fn gradient_matches_finite_differences_for(arch: Architecture) {
        let m = Model::new(arch, 5);
        let obs = [0.3, -0.2, 0.9, -0.7, 0.1, 0.4];
        let actions = [0.1, -0.3, 0.05, 0.2];
        let mut sc = Scratch::default();
        let o1 = m.infer(&obs[..3], &mut sc);
        let o2 = m.infer(&obs[3..], &mut sc);
        let old_lp = [
            gaussian_log_prob(&actions[..2], &o1.mean, &o1.log_std) - 0.05,
            gaussian_log_prob(&actions[2..], &o2.mean, &o2.log_std) + 0.05,
        ];
        let old_mean = [o1.mean[0] + 0.01, o1.mean[1], o2.mean[0], o2.mean[1] - 0.02];
        let old_ls = [
            o1.log_std[0],
            o1.log_std[1] + 0.03,
            o2.log_std[0],
            o2.log_std[1],
        ];
        let mb = Minibatch {
            n: 2,
            obs: &obs,
            actions: &actions,
            old_log_prob: &old_lp,
            old_mean: &old_mean,
            old_log_std: &old_ls,
            old_value: &[o1.value, o2.value],
            advantages: &[1.0, -0.5],
            value_targets: &[0.7, -0.4],
        };
        let c = test_coeffs(0.01);
        let dev = update_device();
        let (_, g) = loss_and_grad(&m, &mb, &c, &dev);
        // (with a shared value, `policy_len() + 3` lies past the parameters: skipped)
        for i in [
            0usize,
            7,
            20,
            m.arch.policy_len() - 1,
            m.arch.policy_len() + 3,
            m.params.len() - 1,
        ]
        .into_iter()
        .filter(|&i| i < m.params.len())
        {
            let h = 1e-2;
            let mut p = m.clone();
            p.params[i] += h;
            let (sp, _) = loss_and_grad(&p, &mb, &c, &dev);
            p.params[i] -= 2.0 * h;
            let (sm, _) = loss_and_grad(&p, &mb, &c, &dev);
            let fd = (sp.total - sm.total) / (2.0 * h);
            assert!(
                (fd - g[i]).abs() < 2e-3 + 0.02 * g[i].abs(),
                "param {i}: fd {fd} vs {}",
                g[i]
            );
        }
    }

    /// A random minibatch of `n` rows for `m`, with old outputs near the model's own (as after a few updates).
    fn random_minibatch(m: &Model, n: usize, rng: &mut Rng) -> OwnedRows {
        let (d, a) = (m.arch.obs_dim, m.arch.act_dim);
        let mut r = OwnedRows::default();
        let mut sc = Scratch::default();
        for _ in 0..n {
            let o: Vec<f32> = (0..d).map(|_| (rng.uniform() * 2.0 - 1.0) as f32).collect();
            let out = m.infer(&o, &mut sc);
            let act: Vec<f32> = (0..a).map(|_| (rng.normal() * 0.5) as f32).collect();
            r.old_log_prob.push(
                gaussian_log_prob(&act, &out.mean, &out.log_std) + (rng.normal() * 0.1) as f32,
            );
            r.old_mean
                .extend(out.mean.iter().map(|x| x + (rng.normal() * 0.05) as f32));
            r.old_log_std
                .extend(out.log_std.iter().map(|x| x + (rng.normal() * 0.05) as f32));
            r.old_value.push(out.value + (rng.normal() * 0.2) as f32);
            r.advantages.push(rng.normal() as f32);
            r.value_targets.push(out.value + rng.normal() as f32);
            r.obs.extend(o);
            r.actions.extend(act);
        }
        r
    }

    #[derive(Default)]
    struct OwnedRows {
        obs: Vec<f32>,
        actions: Vec<f32>,
        old_log_prob: Vec<f32>,
        old_mean: Vec<f32>,
        old_log_std: Vec<f32>,
        old_value: Vec<f32>,
        advantages: Vec<f32>,
        value_targets: Vec<f32>,
    }

    impl OwnedRows {
        fn view(&self) -> Minibatch<'_> {
            Minibatch {
                n: self.advantages.len(),
                obs: &self.obs,
                actions: &self.actions,
                old_log_prob: &self.old_log_prob,
                old_mean: &self.old_mean,
                old_log_std: &self.old_log_std,
                old_value: &self.old_value,
                advantages: &self.advantages,
                value_targets: &self.value_targets,
            }
        }
    }

    fn stats_bits(s: &LossStats) -> [u32; 5] {
        [s.total, s.policy_loss, s.value_loss, s.kl, s.entropy].map(f32::to_bits)
    }

    #[test]
    fn split_graphs_give_the_joint_graphs_bits() {
        let mut rng = Rng::new(17);
        for (seed, n, entropy_coeff) in [(1, 128, 0.0), (2, 37, 0.01), (3, 1, 0.0)] {
            let mut m = Model::new(
                Architecture {
                    obs_dim: 25,
                    act_dim: 5,
                    hidden: vec![100, 50, 25],
                    shared_value: false,
                },
                seed,
            );
            // weights away from the initial ones (the output layers start 100 times smaller)
            for p in m.params.iter_mut() {
                *p += (rng.normal() * 0.05) as f32;
            }
            let rows = random_minibatch(&m, n, &mut rng);
            let c = test_coeffs(entropy_coeff);
            let dev = update_device();
            let (s_joint, g_joint) = joint_loss_and_grad(&m, &rows.view(), &c, &dev);
            let (s_split, g_split) = split_loss_and_grad(&m, &rows.view(), &c, &dev);
            assert_eq!(
                stats_bits(&s_split),
                stats_bits(&s_joint),
                "{s_split:?} vs {s_joint:?}"
            );
            let bits = |v: &[f32]| v.iter().map(|f| f.to_bits()).collect::<Vec<_>>();
            assert_eq!(bits(&g_split), bits(&g_joint), "seed {seed}");
            assert!(g_joint.iter().any(|&g| g != 0.0));
        }
    }

    #[test]
    fn burn_forward_matches_plain_inference() {
        // (the value loss below is zero only if burn reads the same value output as `infer`)
        for shared_value in [false, true] {
            burn_forward_matches_plain_inference_for(shared_value);
        }
    }

    fn burn_forward_matches_plain_inference_for(shared_value: bool) {
        let m = Model::new(
            Architecture {
                obs_dim: 4,
                act_dim: 2,
                hidden: vec![100, 50, 25],
                shared_value,
            },
            9,
        );
        let obs = [0.5, -0.25, 0.75, 0.1];
        let plain = m.infer(&obs, &mut Scratch::default());
        // Loss with zero coefficients except entropy exposes the log-std mean; check the policy via the KL term
        // against itself: identical old and new distributions give KL = 0 and ratio 1.
        let lp = gaussian_log_prob(&[0.0, 0.0], &plain.mean, &plain.log_std);
        let mb = Minibatch {
            n: 1,
            obs: &obs,
            actions: &[0.0, 0.0],
            old_log_prob: &[lp],
            old_mean: &plain.mean,
            old_log_std: &plain.log_std,
            old_value: &[plain.value],
            advantages: &[1.0],
            value_targets: &[plain.value],
        };
        let c = test_coeffs(0.0);
        let (s, _) = loss_and_grad(&m, &mb, &c, &update_device());
        assert!(s.kl.abs() < 1e-6, "{:?}", s);
        assert!((s.policy_loss + 1.0).abs() < 1e-5, "{:?}", s);
        assert!(s.value_loss < 1e-10, "{:?}", s);
    }

    #[test]
    fn adam_first_step_moves_by_lr() {
        let mut p = vec![1.0, -2.0];
        let mut a = Adam::new(2);
        a.step(&mut p, &[0.5, -3.0], 0.1);
        assert!(
            (p[0] - 0.9).abs() < 1e-6 && (p[1] + 1.9).abs() < 1e-6,
            "{p:?}"
        );
    }

    /// Value and gradient of `tanh` at `x` under the upstream gradient `w` (the gradient of sum(w * tanh(x))).
    /// With `transposed`, `x` is stored as its transpose and `tanh` sees a non-contiguous view of it.
    fn tanh_value_and_grad(
        tanh: fn(Tensor<2>) -> Tensor<2>,
        x: &[f32],
        w: &[f32],
        transposed: bool,
    ) -> (Vec<f32>, Vec<f32>) {
        let device = update_device();
        let shape = [x.len() / 4, 4];
        let (xt, input) = if transposed {
            let xt = leaf(x.to_vec(), [4, x.len() / 4], &device).require_grad();
            (xt.clone(), xt.transpose())
        } else {
            let xt = leaf(x.to_vec(), shape, &device).require_grad();
            (xt.clone(), xt)
        };
        let wt = leaf(w.to_vec(), shape, &device);
        let y = tanh(input);
        let grads = (y.clone() * wt).sum().backward();
        let values = |t: Tensor<2>| t.into_data().try_to_vec::<f32>().unwrap();
        (values(y), values(xt.grad(&grads).unwrap()))
    }

    #[test]
    fn fused_tanh_has_the_chains_bits_in_value_and_gradient() {
        let mut rng = Rng::new(11);
        let mut x: Vec<f32> = (0..40_000)
            .map(|i| {
                let scale = [0.01, 1.0, 5.0, 20.0][i % 4];
                (rng.normal() * scale) as f32
            })
            .collect();
        let edges = [
            0.0f32,
            -0.0,
            15.0,
            -15.0,
            15.000001,
            -15.000001,
            14.999999,
            -14.999999,
            44.0,
            -44.0,
            100.0,
            -100.0,
            1e-30,
            -1e-30,
            f32::MIN_POSITIVE,
            0.5,
        ];
        x[..edges.len()].copy_from_slice(&edges);
        let w: Vec<f32> = (0..x.len()).map(|_| (rng.normal() * 3.0) as f32).collect();
        // the loss graph's tensors take the fused path (not the chain as a fallback)
        let on_update_device = leaf(x[..4].to_vec(), [1, 4], &update_device()).require_grad();
        assert!(fused_tanh::apply(&on_update_device).is_some());
        let bits = |v: &[f32]| v.iter().map(|f| f.to_bits()).collect::<Vec<_>>();
        for transposed in [false, true] {
            let (y_chain, g_chain) = tanh_value_and_grad(tanh_chain, &x, &w, transposed);
            let (y_fused, g_fused) = tanh_value_and_grad(burn_tanh, &x, &w, transposed);
            assert_eq!(
                bits(&y_fused),
                bits(&y_chain),
                "values, transposed {transposed}"
            );
            assert_eq!(
                bits(&g_fused),
                bits(&g_chain),
                "gradients, transposed {transposed}"
            );
        }
        let (y_fused, _) = tanh_value_and_grad(burn_tanh, &x, &w, false);
        for (&x, &y) in x.iter().zip(&y_fused) {
            assert_eq!(y.to_bits(), fast_tanh(x).to_bits(), "x = {x}");
        }
    }

    #[test]
    fn tanh_is_unchanged_by_its_input_bound_and_its_gradient_stays_finite() {
        for x in [
            -100.0f32, -44.5, -15.0, -9.0, -0.3, 0.0, 0.7, 9.0, 15.0, 44.5, 100.0,
        ] {
            let unbounded = 1.0 - 2.0 / ((2.0 * x).exp() + 1.0);
            let unbounded = if unbounded.is_nan() {
                x.signum()
            } else {
                unbounded
            };
            assert_eq!(fast_tanh(x), unbounded, "x = {x}");
            assert!((fast_tanh(x) - x.tanh()).abs() < 1e-6, "x = {x}");
        }
        let device = update_device();
        let x = Tensor::<2>::from_data(
            burn::tensor::TensorData::new(vec![60.0f32, -60.0, 0.5], [1, 3]),
            &device,
        )
        .require_grad();
        let grads = burn_tanh(x.clone()).sum().backward();
        let g: Vec<f32> = x
            .grad(&grads)
            .unwrap()
            .into_data()
            .try_to_vec::<f32>()
            .unwrap();
        assert!(g.iter().all(|v| v.is_finite()), "{g:?}");
        assert!((g[2] - (1.0 - 0.5f32.tanh().powi(2))).abs() < 1e-5, "{g:?}");
    }
}
