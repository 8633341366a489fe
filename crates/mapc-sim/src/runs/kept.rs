//! Human runs kept for the rest of the process, by spec and seed, once a front end asks for it
//! ([`keep_runs`]). `mapc pipeline` runs `window` and then `eval` on one scenario, and each asks for the humans'
//! runs of the same seeds: the regime report's, the deployment rule's, the baseline's. A run is a function of its
//! spec and its seed alone, so a kept run is the same bits as a new one, and the job runs each seed once.
//!
//! Off unless asked: a long training or evaluation would otherwise keep every run it made.

use super::observed::Observation;
use crate::error::SimError;
use crate::measure::metrics::RunMetrics;
use crate::sim::Simulation;
use crate::spec::SimSpec;
use std::collections::HashMap;
use std::sync::Mutex;
use std::sync::atomic::{AtomicU64, Ordering};

/// What is kept of a run: its figures, and what the regime report observed of it when it was that report's run.
#[derive(Clone)]
pub(crate) struct KeptRun {
    pub(crate) metrics: RunMetrics,
    pub(crate) regime: Option<Observation>,
}

/// By spec (its full `Debug` text: every field, floats to the last bit) and seed.
type Store = HashMap<String, HashMap<u64, KeptRun>>;

static KEPT: Mutex<Option<Store>> = Mutex::new(None);
/// Runs taken from the store instead of run again.
static REUSED: AtomicU64 = AtomicU64::new(0);

fn store() -> std::sync::MutexGuard<'static, Option<Store>> {
    // a panic elsewhere while the lock was held leaves whole entries only: the store stays usable
    KEPT.lock().unwrap_or_else(|e| e.into_inner())
}

/// Keep every human run from now on, for the rest of the process.
pub fn keep_runs() {
    store().get_or_insert_with(HashMap::new);
}

/// How many runs were taken from the store instead of run again, so far in this process.
pub fn runs_reused() -> u64 {
    REUSED.load(Ordering::Relaxed)
}

/// The key under which `spec`'s runs are kept; `None` while runs are not kept.
pub(crate) fn key(spec: &SimSpec) -> Option<String> {
    store().as_ref()?;
    Some(format!("{spec:?}"))
}

/// The kept run of `seed` under `key`, if any (`observed`: only one the regime report observed).
pub(crate) fn get(key: Option<&str>, seed: u64, observed: bool) -> Option<KeptRun> {
    let run = store()
        .as_ref()?
        .get(key?)?
        .get(&seed)
        .filter(|r| !observed || r.regime.is_some())
        .cloned();
    if run.is_some() {
        REUSED.fetch_add(1, Ordering::Relaxed);
    }
    run
}

/// Keeps `run` of `seed` under `key` (nothing without a key); a regime observation already kept stays.
pub(crate) fn put(key: Option<&str>, seed: u64, run: KeptRun) {
    let Some(key) = key else { return };
    let mut guard = store();
    let Some(store) = guard.as_mut() else { return };
    let runs = store.entry(key.to_string()).or_default();
    match runs.get_mut(&seed) {
        Some(kept) => {
            debug_assert!(
                format!("{:?}", kept.metrics) == format!("{:?}", run.metrics),
                "seed {seed}: a run of the same spec gave other figures"
            );
            if kept.regime.is_none() {
                kept.regime = run.regime;
            }
        }
        None => {
            runs.insert(seed, run);
        }
    }
}

/// A spec's runs through the store: a seed's kept run when there is one, else a new run, kept while runs are kept.
pub struct KeptRuns<'a> {
    spec: &'a SimSpec,
    key: Option<String>,
}

impl<'a> KeptRuns<'a> {
    pub fn of(spec: &'a SimSpec) -> KeptRuns<'a> {
        KeptRuns {
            spec,
            key: key(spec),
        }
    }

    /// The run of `seed` to the horizon: its figures.
    pub fn run(&self, seed: u64) -> Result<RunMetrics, SimError> {
        if let Some(run) = get(self.key.as_deref(), seed, false) {
            return Ok(run.metrics);
        }
        let metrics = Simulation::from_spec(self.spec.clone(), seed)?.run()?;
        let run = KeptRun {
            metrics: metrics.clone(),
            regime: None,
        };
        put(self.key.as_deref(), seed, run);
        Ok(metrics)
    }
}
