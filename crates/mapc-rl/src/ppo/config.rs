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
    /// Piecewise-linear learning rate over simulation steps, `[[steps, lr], ...]` (RLlib's `lr_schedule`);
    /// empty: the constant `lr`.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub lr_schedule: Vec<(u64, f32)>,
    /// The value is one more output of the policy net instead of a net of its own (RLlib's `vf_share_layers`,
    /// which the paper's distributed runs used).
    #[serde(default, skip_serializing_if = "std::ops::Not::not")]
    pub shared_value: bool,
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
            lr_schedule: Vec::new(),
            shared_value: false,
        }
    }
}

impl PpoConfig {
    /// The hyperparameters a TOML text sets over `base`: keys the text lacks keep `base`'s values, and a constant
    /// `lr` without an `lr_schedule` replaces `base`'s schedule (as `--lr` does). Their ranges are
    /// [`crate::limits::check_config`]'s.
    pub fn from_toml_over(text: &str, base: &PpoConfig) -> Result<PpoConfig, String> {
        let mut table: toml::Table = toml::from_str(text).map_err(|e| e.to_string())?;
        if table.contains_key("lr") && !table.contains_key("lr_schedule") {
            table.insert("lr_schedule".into(), toml::Value::Array(Vec::new()));
        }
        let base = toml::Table::try_from(base).map_err(|e| e.to_string())?;
        for (k, v) in base {
            table.entry(k).or_insert(v);
        }
        table
            .try_into()
            .map_err(|e: toml::de::Error| format!("invalid hyperparameters: {e}"))
    }

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

    /// The paper's distributed hyperparameters (its appendix A.2): gamma 0.998, lambda 0.95, clip 0.2, entropy
    /// 1e-3, minibatch 4096, 60 000 simulation steps (30 episodes) per iteration, value loss 0.5, KL 0.01, and
    /// the original code's learning rate 5e-4 -> 1e-4 at 1M steps -> 1e-5 at 4M -> 1e-6 at 8M (docs/reference.md
    /// sec. 5; the paper says only "piecewise linearly decreasing"), and the value as one more output of the
    /// policy net (its shared value layers).
    pub fn distributed() -> Self {
        Self {
            gamma: 0.998,
            lambda: 0.95,
            clip: 0.2,
            vf_clip: 1e8,
            vf_coeff: 0.5,
            entropy_coeff: 1e-3,
            kl_coeff: 0.01,
            kl_target: 0.01,
            train_batch_size: 60_000,
            minibatch: 4096,
            epochs: 10,
            iterations: 500,
            lr_schedule: vec![
                (0, 5e-4),
                (1_000_000, 1e-4),
                (4_000_000, 1e-5),
                (8_000_000, 1e-6),
            ],
            shared_value: true,
            ..Self::default()
        }
    }

    /// The distributed setting on a small budget: 4 episodes per iteration (about 30 000 agent-steps), the
    /// learning rate falling to 1e-4 over 1.6M simulation steps (200 iterations), gradients in 2 slices.
    pub fn distributed_fast() -> Self {
        Self {
            train_batch_size: 8_000,
            iterations: 200,
            grad_slices: 2,
            lr_schedule: vec![(0, 5e-4), (1_600_000, 1e-4)],
            ..Self::distributed()
        }
    }

    /// A named preset of the distributed setting: `paper` or `fast`.
    pub fn distributed_preset(name: &str) -> Option<Self> {
        match name {
            "paper" => Some(Self::distributed()),
            "fast" => Some(Self::distributed_fast()),
            _ => None,
        }
    }

    /// The learning rate after `steps` simulation steps: `lr`, or the schedule interpolated linearly (held at
    /// its first and last values outside it).
    pub fn lr_at(&self, steps: u64) -> f32 {
        let s = &self.lr_schedule;
        let Some(&(first_t, first_lr)) = s.first() else {
            return self.lr;
        };
        if steps <= first_t {
            return first_lr;
        }
        for w in s.windows(2) {
            let ((t0, l0), (t1, l1)) = (w[0], w[1]);
            if steps < t1 {
                let f = (steps - t0) as f64 / (t1 - t0).max(1) as f64;
                return (l0 as f64 + f * (l1 as f64 - l0 as f64)) as f32;
            }
        }
        s.last().map_or(self.lr, |&(_, l)| l)
    }

    pub fn episodes_per_iteration(&self) -> usize {
        self.train_batch_size.div_ceil(self.horizon).max(1)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn learning_rate_schedule_is_piecewise_linear() {
        let mut c = PpoConfig::default();
        assert_eq!(c.lr_at(123), c.lr);
        c.lr_schedule = vec![(0, 5e-4), (1_000_000, 1e-4), (4_000_000, 1e-5)];
        assert_eq!(c.lr_at(0), 5e-4);
        assert!((c.lr_at(500_000) - 3e-4).abs() < 1e-9);
        assert!((c.lr_at(2_500_000) - 5.5e-5).abs() < 1e-9);
        assert_eq!(c.lr_at(9_000_000), 1e-5);
        // the presets: the paper's distributed schedule, none for the centralized ones
        let d = PpoConfig::distributed();
        assert_eq!(d.lr_at(8_000_000), 1e-6);
        assert!(PpoConfig::default().lr_schedule.is_empty());
        assert!(PpoConfig::fast().lr_schedule.is_empty());
        // the value net: shared in the distributed presets (as the paper's), separate in the centralized ones
        assert!(
            PpoConfig::distributed().shared_value && PpoConfig::distributed_fast().shared_value
        );
        assert!(!PpoConfig::default().shared_value && !PpoConfig::fast().shared_value);
    }

    #[test]
    fn a_centralized_config_serialises_as_before() {
        // no `lr_schedule` key when there is none: checkpoints of centralized runs keep their bytes
        let json = serde_json::to_string(&PpoConfig::default()).unwrap();
        assert!(!json.contains("lr_schedule"), "{json}");
        let back: PpoConfig = serde_json::from_str(&json).unwrap();
        assert_eq!(back, PpoConfig::default());
        let d: PpoConfig =
            serde_json::from_str(&serde_json::to_string(&PpoConfig::distributed()).unwrap())
                .unwrap();
        assert_eq!(d, PpoConfig::distributed());
    }
}
