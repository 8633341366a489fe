//! A training run on disk: `checkpoint.json` (written atomically every `checkpoint_every` iterations and at the
//! end) and `progress.csv` (rewritten atomically after every iteration). `--resume` reloads both and continues
//! exactly: the next iteration's episodes, noise and minibatch order are those the uninterrupted run would use.

use std::path::{Path, PathBuf};

use crate::checkpoint::{Checkpoint, FORMAT_VERSION, PolicySpec, checkpoint_path};
use crate::error::RlError;
use crate::log::TrainingLog;
use crate::ppo::{IterationStats, PpoConfig, TrainerState};
use crate::rollout::{AgentsEnvFactory, EnvFactory};

/// The CSV log inside a run directory.
pub fn log_path(dir: &Path) -> PathBuf {
    dir.join("progress.csv")
}

pub struct TrainRun {
    pub dir: PathBuf,
    pub spec: PolicySpec,
    pub state: TrainerState,
    pub log: TrainingLog,
    pub checkpoint_every: u64,
    /// Also keep every checkpoint written as `checkpoints/iteration-NNNNN.json` (to evaluate earlier policies).
    pub keep_checkpoints: bool,
}

/// Where a kept checkpoint of iteration `it` goes inside a run directory.
pub fn kept_checkpoint_path(dir: &Path, it: u64) -> PathBuf {
    dir.join("checkpoints")
        .join(format!("iteration-{it:05}.json"))
}

impl TrainRun {
    /// A new run in `dir` (created; an existing checkpoint there is an error: resume it or pick another dir).
    pub fn create(
        dir: &Path,
        spec: PolicySpec,
        config: PpoConfig,
        checkpoint_every: u64,
    ) -> Result<Self, RlError> {
        if checkpoint_path(dir).exists() {
            return Err(RlError::Config(format!(
                "{} already holds a run; continue it with --resume {} or choose another -o",
                dir.display(),
                dir.display()
            )));
        }
        std::fs::create_dir_all(dir).map_err(|e| RlError::Io {
            path: dir.into(),
            source: e,
        })?;
        let state = TrainerState::new(config, spec.obs_dim, spec.act_dim);
        Ok(Self {
            dir: dir.into(),
            spec,
            state,
            log: TrainingLog::default(),
            checkpoint_every: checkpoint_every.max(1),
            keep_checkpoints: false,
        })
    }

    /// Reopens a run; the log is cut back to the checkpoint's iteration (rows written after the last checkpoint
    /// will be produced again, identically).
    pub fn resume(dir: &Path, checkpoint_every: u64) -> Result<Self, RlError> {
        let ck = Checkpoint::load(&checkpoint_path(dir))?;
        let lp = log_path(dir);
        let mut log = if lp.exists() {
            TrainingLog::read(&lp)?
        } else {
            TrainingLog::default()
        };
        log.rows.retain(|r| r.iteration <= ck.state.iteration);
        Ok(Self {
            dir: dir.into(),
            spec: ck.spec,
            state: ck.state,
            log,
            checkpoint_every: checkpoint_every.max(1),
            keep_checkpoints: false,
        })
    }

    pub fn done(&self) -> bool {
        self.state.iteration >= self.state.config.iterations
    }

    pub fn checkpoint(&self) -> Checkpoint {
        Checkpoint {
            format_version: FORMAT_VERSION,
            spec: self.spec.clone(),
            state: self.state.clone(),
        }
    }

    pub fn save(&self) -> Result<(), RlError> {
        let ck = self.checkpoint();
        ck.save(&checkpoint_path(&self.dir))?;
        if self.keep_checkpoints {
            // (the atomic writer creates `checkpoints/`)
            ck.save(&kept_checkpoint_path(&self.dir, self.state.iteration))?;
        }
        Ok(())
    }

    /// One iteration, then the log (and every `checkpoint_every` iterations or at the end, the checkpoint).
    pub fn step(&mut self, factory: &EnvFactory) -> Result<IterationStats, RlError> {
        let stats = self.state.iterate(factory)?;
        self.record(stats)
    }

    /// [`Self::step`] for a distributed policy.
    pub fn step_agents(&mut self, factory: &AgentsEnvFactory) -> Result<IterationStats, RlError> {
        let stats = self.state.iterate_agents(factory)?;
        self.record(stats)
    }

    fn record(&mut self, stats: IterationStats) -> Result<IterationStats, RlError> {
        self.log.rows.push(stats.clone());
        self.log.write(&log_path(&self.dir))?;
        if self.state.iteration.is_multiple_of(self.checkpoint_every) || self.done() {
            self.save()?;
        }
        Ok(stats)
    }
}
