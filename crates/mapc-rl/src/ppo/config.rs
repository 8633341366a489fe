//! PPO hyperparameters. Defaults are the paper's centralized setting (RLlib 1.0 PPO as configured by the original
//! code); `fast()` is the named preset that reaches the Simple Merge result in minutes on two cores.

use serde::{Deserialize, Serialize};

#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct PpoConfig {
    /// Adam learning rate.
    pub lr: f32,
    /// Discount factor.
    pub gamma: f32,
    /// GAE lambda.
    pub lambda: f32,
    /// Hidden layer sizes of both the policy and the value network (tanh).
    pub hidden: Vec<usize>,
    /// Surrogate clip parameter.
    pub clip: f32,
    /// Value-function clip (RLlib's vf_clip_param).
    pub vf_clip: f32,
    /// Weight of the value loss.
    pub vf_coeff: f32,
    /// Weight of the entropy bonus.
    pub entropy_coeff: f32,
    /// Initial KL penalty coefficient (adapted each iteration).
    pub kl_coeff: f32,
    /// Target KL divergence per iteration.
    pub kl_target: f32,
    /// Environment steps per iteration (whole episodes: rounded up to a multiple of the horizon).
    pub train_batch_size: usize,
    /// SGD minibatch size.
    pub minibatch: usize,
    /// SGD passes over each batch.
    pub epochs: usize,
    /// Training iterations.
    pub iterations: u64,
    /// Steps per episode (time-limit truncation, bootstrapped from the value function).
    pub horizon: usize,
    /// Run seed: weights, episode seeds, action noise and minibatch order all derive from it.
    pub seed: u64,
    /// Each minibatch gradient is computed in this many slices on the rayon pool (a fixed number, so the result
    /// does not depend on the thread count).
    pub grad_slices: usize,
}

impl Default for PpoConfig {
    fn default() -> Self {
        Self {
            lr: 5e-4,
            gamma: 0.99,
            lambda: 0.97,
            hidden: vec![100, 50, 25],
            clip: 0.3,
            vf_clip: 10.0,
            vf_coeff: 1.0,
            entropy_coeff: 0.0,
            kl_coeff: 0.2,
            kl_target: 0.01,
            train_batch_size: 40_000,
            minibatch: 128,
            epochs: 10,
            iterations: 500,
            horizon: 2000,
            seed: 0,
            grad_slices: 1,
        }
    }
}

impl PpoConfig {
    /// The quick preset: smaller batches and larger minibatches (96 gradient steps per iteration instead of
    /// 3 100), so an iteration costs about a second on two cores; enough for the outflow reward, not for the
    /// speed-based ones (the shipped policies use the paper preset; see docs/results.md).
    pub fn fast() -> Self {
        Self {
            train_batch_size: 12_000,
            minibatch: 1000,
            epochs: 8,
            iterations: 150,
            grad_slices: 2,
            ..Self::default()
        }
    }

    /// A named preset: `paper` (the defaults) or `fast`.
    pub fn preset(name: &str) -> Option<Self> {
        match name {
            "paper" => Some(Self::default()),
            "fast" => Some(Self::fast()),
            _ => None,
        }
    }

    pub fn episodes_per_iteration(&self) -> usize {
        self.train_batch_size.div_ceil(self.horizon).max(1)
    }
}
