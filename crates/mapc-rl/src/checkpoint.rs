//! Checkpoints: the trainer state plus what the policy needs to be used on a scenario (observation layout and
//! normalisation constants, N_AV, reward). JSON written atomically (temporary file, then rename).

use std::path::{Path, PathBuf};

use serde::{Deserialize, Serialize};

use crate::env::distributed::{AgentReward, DistNorm, DistributedConfig, Features};
use crate::env::obs::ObsNorm;
use crate::error::RlError;
use crate::ppo::{IterationStats, TrainerState};

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
        crate::limits::check_checkpoint(&ck).map_err(|msg| RlError::Format {
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
