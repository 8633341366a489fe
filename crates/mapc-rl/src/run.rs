//! A training run on disk: `checkpoint.json` (written atomically every `checkpoint_every` iterations and at the
//! end), `progress.csv` (rewritten atomically after every iteration) and `best.json`, the policy whose training
//! rollouts scored highest so far (rewritten atomically whenever an iteration beats it). `--resume` reloads them
//! and continues exactly: the next iteration's episodes, noise and minibatch order are those the uninterrupted run
//! would use, and `best.json` ends as the uninterrupted run's.

use std::path::{Path, PathBuf};

use crate::checkpoint::{
    BestBy, Checkpoint, FORMAT_VERSION, PolicySpec, Selection, best_path, checkpoint_path,
};
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
    /// What picks `best.json`, and the best row so far by it.
    best_by: BestBy,
    best: Option<Selection>,
    /// The run's `best.json` already says what picks it (a resumed run keeps that).
    best_by_fixed: bool,
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
            best_by: BestBy::default(),
            best: None,
            best_by_fixed: false,
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
        let mut run = Self {
            dir: dir.into(),
            spec: ck.spec,
            state: ck.state,
            log,
            checkpoint_every: checkpoint_every.max(1),
            keep_checkpoints: false,
            best_by: BestBy::default(),
            best: None,
            best_by_fixed: false,
        };
        // the criterion the run started with, and the best row so far by it; a run from before `best.json`
        // existed has no policy of its earlier rows to keep, so its `best.json` starts with the rows to come
        let bp = best_path(dir);
        if bp.exists()
            && let Some(sel) = Checkpoint::load(&bp)?.selected
        {
            run.best_by = sel.by;
            run.best_by_fixed = true;
            run.best = run.best_of_log();
        }
        Ok(run)
    }

    /// What picks `best.json`. A new run takes any; a resumed run keeps the one its `best.json` names.
    pub fn set_best_by(&mut self, by: BestBy) -> Result<(), RlError> {
        if by == self.best_by {
            return Ok(());
        }
        if self.best_by_fixed {
            return Err(RlError::Config(format!(
                "{} chose its best policy by {}; resume it with --best-by {}",
                self.dir.display(),
                self.best_by.name(),
                self.best_by.name()
            )));
        }
        self.best_by = by;
        Ok(())
    }

    /// The best row so far (`best.json` holds its policy).
    pub fn best(&self) -> Option<Selection> {
        self.best
    }

    /// The first row with the highest score in the log. On a resumed run `best.json` may still hold the policy of
    /// a better row that was logged after the checkpoint; the run produces that row again, bit for bit, and
    /// rewrites the same file.
    fn best_of_log(&self) -> Option<Selection> {
        let mut best = None;
        for row in &self.log.rows {
            offer(&mut best, self.best_by, row);
        }
        best
    }

    pub fn done(&self) -> bool {
        self.state.iteration >= self.state.config.iterations
    }

    pub fn checkpoint(&self) -> Checkpoint {
        Checkpoint {
            format_version: FORMAT_VERSION,
            spec: self.spec.clone(),
            state: self.state.clone(),
            selected: None,
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

    /// One iteration, then the log, `best.json` when the iteration's rollouts beat the best so far, and every
    /// `checkpoint_every` iterations or at the end, the checkpoint.
    pub fn step(&mut self, factory: &EnvFactory) -> Result<IterationStats, RlError> {
        let before = self.state.clone();
        let stats = self.state.iterate(factory)?;
        self.record(stats, before)
    }

    /// [`Self::step`] for a distributed policy.
    pub fn step_agents(&mut self, factory: &AgentsEnvFactory) -> Result<IterationStats, RlError> {
        let before = self.state.clone();
        let stats = self.state.iterate_agents(factory)?;
        self.record(stats, before)
    }

    /// `before`: the state the iteration started from, whose policy collected the row's rollouts.
    fn record(
        &mut self,
        stats: IterationStats,
        before: TrainerState,
    ) -> Result<IterationStats, RlError> {
        self.log.rows.push(stats.clone());
        self.log.write(&log_path(&self.dir))?;
        if offer(&mut self.best, self.best_by, &stats) {
            Checkpoint {
                format_version: FORMAT_VERSION,
                spec: self.spec.clone(),
                state: before,
                selected: self.best,
            }
            .save(&best_path(&self.dir))?;
        }
        if self.state.iteration.is_multiple_of(self.checkpoint_every) || self.done() {
            self.save()?;
        }
        Ok(stats)
    }
}

/// Makes `row` the best so far when its score by `by` is strictly higher (the first of equal rows stays; a NaN
/// score never counts); returns whether it did.
fn offer(best: &mut Option<Selection>, by: BestBy, row: &IterationStats) -> bool {
    let score = by.score(row);
    if score.is_nan() || best.is_some_and(|b| score <= b.score) {
        return false;
    }
    *best = Some(Selection {
        by,
        score,
        row_iteration: row.iteration,
    });
    true
}

#[cfg(test)]
mod tests {
    use super::*;

    fn row(iteration: u64, mean_outflow: f64) -> IterationStats {
        IterationStats {
            iteration,
            mean_outflow,
            ..Default::default()
        }
    }

    #[test]
    fn only_a_strictly_higher_number_beats_the_best() {
        let mut best = None;
        assert!(
            !offer(&mut best, BestBy::Outflow, &row(1, f64::NAN)),
            "no best from a NaN row"
        );
        assert!(offer(&mut best, BestBy::Outflow, &row(2, -1.0)));
        assert!(offer(&mut best, BestBy::Outflow, &row(3, 1500.0)));
        assert!(
            !offer(&mut best, BestBy::Outflow, &row(4, 1500.0)),
            "the first of equal rows stays"
        );
        assert!(!offer(&mut best, BestBy::Outflow, &row(5, f64::NAN)));
        assert!(!offer(&mut best, BestBy::Outflow, &row(6, 1499.0)));
        assert_eq!(best.map(|b| (b.row_iteration, b.score)), Some((3, 1500.0)));
        // the criterion picks the column
        assert!(!offer(
            &mut best,
            BestBy::Outflow,
            &IterationStats {
                iteration: 7,
                mean_return: 9e9,
                ..row(7, 0.0)
            }
        ));
    }
}
