//! Checkpoints: the trainer state plus what the policy needs to be used on a scenario (observation layout and
//! normalisation constants, N_AV, reward). JSON written atomically (temporary file, then rename).

use std::path::{Path, PathBuf};

use serde::{Deserialize, Serialize};

use crate::env::distributed::{AgentReward, DistNorm, DistributedConfig, Features};
use crate::env::merge::RewardKind;
use crate::env::obs::ObsNorm;
use crate::error::RlError;
// the ranges every field of a policy file is checked against (shared with `mapc train`'s flags)
use crate::limits::*;
use crate::ppo::{IterationStats, TrainerState};
use mapc_scenario::ranges::{DRIVING_SPEED_MPS, ROAD_LENGTH_M, show};

/// Current checkpoint format.
pub const FORMAT_VERSION: u32 = 1;

/// How observations and actions of the policy are laid out and normalised.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct PolicySpec {
    /// Scenario the policy was trained on.
    pub scenario: String,
    /// Reward it was trained with (`outflow`, `flow`, `speed`).
    pub reward: String,
    /// Controlled AVs (the observation holds 5 values per AV).
    pub n_av: usize,
    pub obs_dim: usize,
    pub act_dim: usize,
    /// Speed normalisation V (m/s).
    pub max_speed: f64,
    /// Distance normalisation L (m).
    pub norm_length: f64,
    /// Acceleration bounds (m/s^2).
    pub accel_min: f64,
    pub accel_max: f64,
    /// Set for a distributed policy (one shared policy per AV: `obs_dim` values in, one acceleration out; `n_av`
    /// and `reward` then do not apply); absent for a centralized one.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub distributed: Option<DistributedSpec>,
    /// A centralized policy that observes the adjacent lanes' leaders and followers too (`--features lanes`;
    /// a distributed policy says so in its features); absent: the paper's five values per AV.
    #[serde(default, skip_serializing_if = "std::ops::Not::not")]
    pub lanes: bool,
    /// The merges the policy is meant for: windows whose merge is not among them are left to the humans
    /// ([`crate::deploy`]); absent: every window.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub deploy: Option<crate::deploy::Deploy>,
}

/// What a distributed policy was trained with.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct DistributedSpec {
    pub features: Features,
    pub reward: AgentReward,
    pub dist_norm: DistNorm,
}

impl PolicySpec {
    /// A centralized policy for `n_av` controlled AVs trained on `scenario` with `reward`, in the paper's
    /// normalisation and acceleration bounds (what `mapc train` writes for a new run).
    pub fn centralized(scenario: &str, reward: &str, n_av: usize) -> PolicySpec {
        use crate::env::merge::{ACCEL_MAX, ACCEL_MIN, SIMPLE_MERGE_NORM};
        PolicySpec {
            scenario: scenario.to_string(),
            reward: reward.to_string(),
            n_av,
            obs_dim: crate::env::obs::PER_AV * n_av,
            act_dim: n_av,
            max_speed: SIMPLE_MERGE_NORM.max_speed,
            norm_length: SIMPLE_MERGE_NORM.length,
            accel_min: ACCEL_MIN,
            accel_max: ACCEL_MAX,
            distributed: None,
            lanes: false,
            deploy: None,
        }
    }

    /// This centralized policy observing the adjacent lanes too (`--features lanes`): 15 values per AV.
    pub fn with_lanes(self) -> PolicySpec {
        PolicySpec {
            lanes: true,
            obs_dim: crate::env::obs::per_av(true) * self.n_av,
            ..self
        }
    }

    /// A distributed policy (one shared policy, one acceleration per agent from its own observation with
    /// `features`) trained on `scenario` with `reward` (what `mapc train --distributed` writes for a new run).
    pub fn distributed(
        scenario: &str,
        n_av: usize,
        features: crate::env::distributed::Features,
        reward: AgentReward,
    ) -> PolicySpec {
        PolicySpec {
            obs_dim: features.obs_dim(),
            act_dim: 1,
            distributed: Some(DistributedSpec {
                features,
                reward,
                dist_norm: crate::env::distributed::SIMPLE_MERGE_DIST_NORM,
            }),
            ..PolicySpec::centralized(scenario, "distributed", n_av)
        }
    }

    /// The distributed environment's configuration of a distributed policy.
    pub fn distributed_config(&self) -> Option<DistributedConfig> {
        let d = self.distributed?;
        Some(DistributedConfig {
            features: d.features,
            reward: d.reward,
            norm: ObsNorm {
                max_speed: self.max_speed,
                length: self.norm_length,
            },
            dist_norm: d.dist_norm,
            accel_min: self.accel_min,
            accel_max: self.accel_max,
        })
    }
}

#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Checkpoint {
    pub format_version: u32,
    pub spec: PolicySpec,
    pub state: TrainerState,
    /// Set on a run's `best.json`: why this policy was chosen (absent on every other checkpoint).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub selected: Option<Selection>,
}

/// Why a run's best policy was chosen: its training rollouts scored highest by `by`.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct Selection {
    pub by: BestBy,
    /// The figure its training rollouts reached.
    pub score: f64,
    /// The log row that holds those rollouts (the policy's own iteration + 1: an iteration's row describes the
    /// rollouts collected before its update).
    pub row_iteration: u64,
}

/// What picks a run's best policy (`mapc train --best-by`), a figure of each iteration's training rollouts
/// (sampled actions): RLlib Tune's `checkpoint_score_attr`.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum BestBy {
    /// Mean outflow (veh/h): the congestion objective, whatever the reward.
    #[default]
    Outflow,
    /// Mean episode return: the objective the policy is trained for.
    Return,
    /// Mean speed (m/s).
    Speed,
}

impl BestBy {
    pub fn name(self) -> &'static str {
        match self {
            BestBy::Outflow => "outflow",
            BestBy::Return => "return",
            BestBy::Speed => "speed",
        }
    }

    /// The row's figure this criterion maximises.
    pub fn score(self, row: &IterationStats) -> f64 {
        match self {
            BestBy::Outflow => row.mean_outflow,
            BestBy::Return => row.mean_return,
            BestBy::Speed => row.mean_speed,
        }
    }
}

impl Checkpoint {
    pub fn save(&self, path: &Path) -> Result<(), RlError> {
        let text = serde_json::to_string(self).map_err(|e| RlError::Format {
            path: path.into(),
            msg: e.to_string(),
        })?;
        write_atomic(path, text.as_bytes())
    }

    pub fn load(path: &Path) -> Result<Self, RlError> {
        let bytes = mapc_graph::input::read(path).map_err(|e| RlError::Io {
            path: path.into(),
            source: e,
        })?;
        // another of mapc's files, or a map, whatever its name: say what it is rather than name a missing field
        if let Some(kind) = mapc_graph::filekind::sniff(&bytes)
            && kind != mapc_graph::MapcFile::Policy
        {
            return Err(RlError::Format {
                path: path.into(),
                msg: format!("is {}, not a policy", kind.name()),
            });
        }
        if let Some(map) = mapc_graph::filekind::sniff_map(&bytes) {
            return Err(RlError::Format {
                path: path.into(),
                msg: mapc_graph::filekind::map_given_for(map, path, mapc_graph::MapcFile::Policy),
            });
        }
        let text = String::from_utf8(bytes).map_err(|e| RlError::Io {
            path: path.into(),
            source: std::io::Error::new(std::io::ErrorKind::InvalidData, e.utf8_error()),
        })?;
        let ck: Checkpoint = serde_json::from_str(&text).map_err(|e| RlError::Format {
            path: path.into(),
            msg: format!("line {} column {}: {e}", e.line(), e.column()),
        })?;
        if ck.format_version != FORMAT_VERSION {
            return Err(RlError::Format {
                path: path.into(),
                msg: format!(
                    "checkpoint format {} (this build reads {FORMAT_VERSION})",
                    ck.format_version
                ),
            });
        }
        check_checkpoint(&ck).map_err(|msg| RlError::Format {
            path: path.into(),
            msg,
        })?;
        Ok(ck)
    }
}

/// A policy argument as a file: a checkpoint file as it is, a run directory's last checkpoint.
pub fn policy_file(p: &Path) -> PathBuf {
    if p.is_dir() {
        checkpoint_path(p)
    } else {
        p.to_path_buf()
    }
}

/// The checkpoint file inside a run directory.
pub fn checkpoint_path(dir: &Path) -> PathBuf {
    dir.join("checkpoint.json")
}

/// The best policy of a run so far (see [`BestBy`]), a checkpoint like the others.
pub fn best_path(dir: &Path) -> PathBuf {
    dir.join("best.json")
}

/// Writes `bytes` to `path` through a temporary file in the same directory and a rename (the workspace's one
/// atomic writer, `mapc_graph::write_atomically`).
pub fn write_atomic(path: &Path, bytes: &[u8]) -> Result<(), RlError> {
    mapc_graph::write_atomically(path, bytes).map_err(|e| RlError::Io {
        path: path.into(),
        source: e,
    })
}

/// The policy's layout and normalisation: sizes consistent with its AVs or features, bounds the right way round.
fn check_spec(s: &PolicySpec) -> Result<(), String> {
    number("spec.max_speed", s.max_speed, DRIVING_SPEED_MPS)?;
    number("spec.norm_length", s.norm_length, ROAD_LENGTH_M)?;
    number("spec.accel_min", s.accel_min, ACCEL_BOUND_MPS2)?;
    number("spec.accel_max", s.accel_max, ACCEL_BOUND_MPS2)?;
    if s.accel_min >= s.accel_max {
        return Err(format!(
            "spec.accel_min: {} is not below spec.accel_max ({})",
            show(s.accel_min),
            show(s.accel_max)
        ));
    }
    let Some(d) = &s.distributed else {
        s.reward
            .parse::<RewardKind>()
            .map_err(|e| format!("spec.reward: {e}"))?;
        count("spec.n_av", s.n_av as u64, N_AV)?;
        let per_av = crate::env::obs::per_av(s.lanes);
        if s.obs_dim != per_av * s.n_av || s.act_dim != s.n_av {
            return Err(format!(
                "spec.obs_dim, spec.act_dim: a centralized policy for {} AVs reads {} values and sets {} \
                 accelerations, but its spec says {} and {}",
                s.n_av,
                per_av * s.n_av,
                s.n_av,
                s.obs_dim,
                s.act_dim
            ));
        }
        return Ok(());
    };
    // a distributed policy drives every AV it finds: its n_av is only the training scenario's
    count("spec.n_av", s.n_av as u64, 0..=*N_AV.end())?;
    if d.features.obs_dim() != s.obs_dim || s.act_dim != 1 {
        return Err(format!(
            "spec.obs_dim, spec.act_dim: a distributed policy with features `{}` reads {} values and sets 1 \
             acceleration, but its spec says {} and {}",
            d.features.name(),
            d.features.obs_dim(),
            s.obs_dim,
            s.act_dim
        ));
    }
    let key = |k: &str| format!("spec.distributed.{k}");
    number(&key("reward.eta1"), d.reward.eta1, REWARD_WEIGHT)?;
    number(&key("reward.eta2"), d.reward.eta2, REWARD_WEIGHT)?;
    number(&key("reward.exit_bonus"), d.reward.exit_bonus, EXIT_BONUS)?;
    number(&key("reward.share"), d.reward.share, REWARD_SHARE)?;
    number(
        &key("dist_norm.junction"),
        d.dist_norm.junction,
        ROAD_LENGTH_M,
    )?;
    number(&key("dist_norm.merge"), d.dist_norm.merge, ROAD_LENGTH_M)
}

/// Every field of a policy file within its range and consistent with the others, the network's parameters and
/// the optimiser's moments finite.
pub fn check_checkpoint(ck: &Checkpoint) -> Result<(), String> {
    check_spec(&ck.spec)?;
    let state = &ck.state;
    check_config(&state.config, "state.config.")?;
    let arch = &state.model.arch;
    if arch.obs_dim != ck.spec.obs_dim
        || arch.act_dim != ck.spec.act_dim
        || arch.hidden != state.config.hidden
        || arch.shared_value != state.config.shared_value
    {
        return Err(format!(
            "state.model.arch: {} values in, {} out, hidden {:?}{}, but the spec and state.config say {}, {}, \
             {:?}{}",
            arch.obs_dim,
            arch.act_dim,
            arch.hidden,
            if arch.shared_value { " shared" } else { "" },
            ck.spec.obs_dim,
            ck.spec.act_dim,
            state.config.hidden,
            if state.config.shared_value {
                " shared"
            } else {
                ""
            },
        ));
    }
    let params = state.model.params.len();
    for (key, len) in [
        ("state.model.params", params),
        ("state.adam.m", state.adam.m.len()),
        ("state.adam.v", state.adam.v.len()),
    ] {
        if len != arch.param_len() {
            return Err(format!(
                "{key}: {len} values, but the network's sizes need {} (parameter count does not match the \
                 network sizes)",
                arch.param_len()
            ));
        }
    }
    all_finite("state.model.params", &state.model.params)?;
    all_finite("state.adam.m", &state.adam.m)?;
    all_finite("state.adam.v", &state.adam.v)?;
    if let Some(i) = state.adam.v.iter().position(|&v| v < 0.0) {
        return Err(format!(
            "state.adam.v[{i}]: {} is negative (a mean of squares)",
            show(state.adam.v[i] as f64)
        ));
    }
    number(
        "state.adam.beta1",
        state.adam.beta1 as f64,
        closed(0.0, 0.999_999, ""),
    )?;
    number(
        "state.adam.beta2",
        state.adam.beta2 as f64,
        closed(0.0, 0.999_999, ""),
    )?;
    number(
        "state.adam.eps",
        state.adam.eps as f64,
        closed(1e-30, 1.0, ""),
    )?;
    // adapted every iteration, so wider than the initial coefficient's range
    number("state.kl_coeff", state.kl_coeff as f64, NON_NEGATIVE)?;
    number("state.wall_s", state.wall_s, NON_NEGATIVE)?;
    if let Some(sel) = &ck.selected {
        number("selected.score", sel.score, FINITE)?;
        if state.iteration.checked_add(1) != Some(sel.row_iteration) {
            return Err(format!(
                "selected.row_iteration: {} is not the row of this policy's rollouts ({}, its iteration + 1)",
                sel.row_iteration,
                state.iteration.saturating_add(1)
            ));
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn policy(name: &str) -> Checkpoint {
        let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
            .join("../../policies")
            .join(name);
        serde_json::from_str(&std::fs::read_to_string(path).unwrap()).unwrap()
    }

    /// The error `edit` makes `check_checkpoint` find in the shipped centralized (or distributed) policy.
    fn refusal(distributed: bool, edit: impl FnOnce(&mut Checkpoint)) -> String {
        let mut ck = policy(if distributed {
            "simple_merge_distributed.json"
        } else {
            "simple_merge_outflow.json"
        });
        edit(&mut ck);
        check_checkpoint(&ck).expect_err("the edit is refused")
    }

    #[test]
    fn every_shipped_policy_is_within_the_ranges() {
        let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../../policies");
        let mut files = vec![];
        for sub in [dir.clone(), dir.join("table5")] {
            for entry in std::fs::read_dir(sub).unwrap() {
                let path = entry.unwrap().path();
                if path.extension().is_some_and(|e| e == "json") {
                    files.push(path);
                }
            }
        }
        assert!(files.len() > 10, "{files:?}");
        for path in files {
            let ck: Checkpoint =
                serde_json::from_str(&std::fs::read_to_string(&path).unwrap()).unwrap();
            assert_eq!(check_checkpoint(&ck), Ok(()), "{}", path.display());
        }
    }

    #[test]
    fn acceleration_bounds_the_wrong_way_round_are_refused() {
        let e = refusal(false, |ck| ck.spec.accel_min = 3.0);
        assert_eq!(e, "spec.accel_min: 3 is not below spec.accel_max (2.6)");
        let e = refusal(true, |ck| ck.spec.accel_max = f64::NAN);
        assert!(e.starts_with("spec.accel_max: NaN is outside"), "{e}");
    }

    #[test]
    fn normalisation_constants_must_be_positive() {
        for (bad, field) in [
            (-1.0, "max_speed"),
            (0.0, "max_speed"),
            (-1.0, "norm_length"),
        ] {
            let e = refusal(false, |ck| match field {
                "max_speed" => ck.spec.max_speed = bad,
                _ => ck.spec.norm_length = bad,
            });
            assert!(
                e.starts_with(&format!("spec.{field}: {bad} is outside")),
                "{e}"
            );
        }
    }

    #[test]
    fn n_av_must_match_the_observation_and_stay_in_range() {
        let e = refusal(false, |ck| ck.spec.n_av = 0);
        assert!(
            e.starts_with("spec.n_av: 0 is outside the allowed range [1, 1000]"),
            "{e}"
        );
        let e = refusal(false, |ck| ck.spec.n_av = 4_294_967_296);
        assert!(e.starts_with("spec.n_av: 4294967296 is outside"), "{e}");
        let e = refusal(false, |ck| ck.spec.n_av = 4);
        assert!(e.contains("for 4 AVs reads 20 values"), "{e}");
        let e = refusal(true, |ck| ck.spec.n_av = 1_000_000);
        assert!(e.starts_with("spec.n_av: 1000000 is outside"), "{e}");
    }

    #[test]
    fn the_reward_and_the_distributed_constants_are_checked() {
        let e = refusal(false, |ck| ck.spec.reward = "speedy".into());
        assert!(e.starts_with("spec.reward: "), "{e}");
        let e = refusal(true, |ck| {
            ck.spec.distributed.as_mut().unwrap().reward.share = 2.0
        });
        assert!(
            e.starts_with("spec.distributed.reward.share: 2 is outside"),
            "{e}"
        );
        let e = refusal(true, |ck| {
            ck.spec.distributed.as_mut().unwrap().dist_norm.merge = 0.0
        });
        assert!(
            e.starts_with("spec.distributed.dist_norm.merge: 0 is outside"),
            "{e}"
        );
    }

    #[test]
    fn parameters_and_hyperparameters_must_be_finite_numbers_in_range() {
        let e = refusal(false, |ck| ck.state.model.params[7] = f32::INFINITY);
        assert_eq!(e, "state.model.params[7]: inf is not a finite number");
        let e = refusal(false, |ck| ck.state.adam.v[0] = -1.0);
        assert!(e.starts_with("state.adam.v[0]: -1 is negative"), "{e}");
        let e = refusal(false, |ck| ck.state.config.gamma = 2.0);
        assert!(
            e.starts_with("state.config.gamma: 2 is outside the allowed range [0, 1]"),
            "{e}"
        );
        let e = refusal(false, |ck| ck.state.config.hidden[1] = 0);
        assert!(e.starts_with("state.config.hidden[1]: 0 is outside"), "{e}");
        let e = refusal(false, |ck| ck.state.model.arch.hidden = vec![100, 50]);
        assert!(e.starts_with("state.model.arch: "), "{e}");
        let e = refusal(true, |ck| ck.selected.as_mut().unwrap().row_iteration = 0);
        assert!(
            e.starts_with("selected.row_iteration: 0 is not the row"),
            "{e}"
        );
    }
}
