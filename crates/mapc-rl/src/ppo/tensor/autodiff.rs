//! The reference gradient: the PPO loss of [`super::loss_and_grad`] traced by burn's autodiff (flex backend) as one
//! graph, operation by operation. Training uses the gradient written out ([`super::backprop`]); the tests compare
//! the two on random minibatches of both architectures.

use burn::tensor::{Device, Tensor, TensorData};

use super::{
    LN_2PI, LOG_STD_MAX, LOG_STD_MIN, LossCoeffs, LossStats, Minibatch, Model, TANH_INPUT_BOUND,
};

fn leaf(values: Vec<f32>, shape: [usize; 2], device: &Device) -> Tensor<2> {
    Tensor::<2>::from_data(TensorData::new(values, shape), device)
}

/// [`fast_tanh`] as elementary tensor operations.
fn tanh_chain(x: Tensor<2>) -> Tensor<2> {
    x.clamp(-TANH_INPUT_BOUND, TANH_INPUT_BOUND)
        .mul_scalar(2.0)
        .exp()
        .add_scalar(1.0)
        .recip()
        .mul_scalar(-2.0)
        .add_scalar(1.0)
}

fn burn_mlp(x: Tensor<2>, layers: &[(Tensor<2>, Tensor<2>)]) -> Tensor<2> {
    let mut h = x;
    for (l, (w, b)) in layers.iter().enumerate() {
        h = h.matmul(w.clone()) + b.clone();
        if l + 1 < layers.len() {
            h = tanh_chain(h);
        }
    }
    h
}

/// burn's flex CPU backend with autodiff.
fn update_device() -> Device {
    Device::flex().autodiff()
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

/// The PPO loss of [`super::loss_and_grad`] as one autodiff graph over both nets, and its gradient.
pub fn loss_and_grad(model: &Model, mb: &Minibatch, c: &LossCoeffs) -> (LossStats, Vec<f32>) {
    let device = &update_device();
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
