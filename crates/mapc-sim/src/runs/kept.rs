//! The regime report's human runs kept for the rest of the process, by spec and seed, once a front end asks for
//! it ([`keep_runs`]). `mapc pipeline` runs `window` and then `eval` on one scenario, and each asks for the
//! humans' runs of the same seeds: the window's regime report, the deployment rule's, the baseline's. A run is a
//! function of its spec and its seed alone, so a kept run is the same bits as a new one, and the job runs each
//! seed once.
//!
//! Only the report's runs are kept (a few seeds per scenario), and only when asked: whatever the number of seeds
//! evaluated or simulated, the store stays small.

use super::observed::Observation;
use crate::error::SimError;
use crate::measure::metrics::RunMetrics;
use crate::sim::Simulation;
use crate::spec::SimSpec;
use std::collections::HashMap;
use std::sync::Mutex;
use std::sync::atomic::{AtomicU64, Ordering};

/// A kept run: its figures, and what the regime report observed of it.
#[derive(Clone)]
pub(crate) struct KeptRun {
    pub(crate) metrics: RunMetrics,
    pub(crate) regime: Observation,
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

/// Keep the regime report's runs from now on, for the rest of the process.
pub fn keep_runs() {
    store().get_or_insert_with(HashMap::new);
}

/// The seeds the job will run of the scenarios it keeps runs of, in its order (set by [`will_run`]).
static LATER: Mutex<Vec<u64>> = Mutex::new(Vec::new());

/// Tells the store which seeds the job will run later (the evaluation's, `mapc sim`'s): a regime report whose own
/// seeds leave threads idle in their last round runs the first of these there, and keeps them. The job then runs
/// the same number of runs in fewer rounds.
pub fn will_run(seeds: &[u64]) {
    *LATER.lock().unwrap_or_else(|e| e.into_inner()) = seeds.to_vec();
}

/// Seeds of [`will_run`] to run beside `seeds` under `key`: as many as fill the last round of `threads`, none kept
/// yet and none among `seeds` (none while runs are not kept).
pub(crate) fn fill_round(key: Option<&str>, seeds: &[u64], threads: usize) -> Vec<u64> {
    let Some(key) = key else { return Vec::new() };
    let threads = threads.max(1);
    let new = seeds.iter().filter(|&&s| !is_kept(key, s)).count();
    let idle = (threads - new % threads) % threads;
    if new == 0 || idle == 0 {
        return Vec::new();
    }
    let later = LATER.lock().unwrap_or_else(|e| e.into_inner()).clone();
    later
        .into_iter()
        .filter(|s| !seeds.contains(s) && !is_kept(key, *s))
        .take(idle)
        .collect()
}

fn is_kept(key: &str, seed: u64) -> bool {
    store()
        .as_ref()
        .and_then(|s| s.get(key))
        .is_some_and(|runs| runs.contains_key(&seed))
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

/// The kept run of `seed` under `key`, if any.
pub(crate) fn get(key: Option<&str>, seed: u64) -> Option<KeptRun> {
    let run = store().as_ref()?.get(key?)?.get(&seed).cloned();
    if run.is_some() {
        REUSED.fetch_add(1, Ordering::Relaxed);
    }
    run
}

/// Keeps `run` of `seed` under `key` (nothing without a key).
pub(crate) fn put(key: Option<&str>, seed: u64, run: KeptRun) {
    let Some(key) = key else { return };
    if let Some(store) = store().as_mut() {
        store
            .entry(key.to_string())
            .or_default()
            .entry(seed)
            .or_insert(run);
    }
}

/// A spec's runs through the store: a seed's kept run when there is one, else a new run (not kept: only the
/// regime report keeps its runs).
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

    /// Whether `seed`'s run is kept (its [`Self::run`] runs nothing).
    pub fn is_kept(&self, seed: u64) -> bool {
        self.key.as_deref().is_some_and(|k| is_kept(k, seed))
    }

    /// The run of `seed` to the horizon: its figures.
    pub fn run(&self, seed: u64) -> Result<RunMetrics, SimError> {
        match get(self.key.as_deref(), seed) {
            Some(run) => Ok(run.metrics),
            None => Simulation::from_spec(self.spec.clone(), seed)?.run(),
        }
    }
}
