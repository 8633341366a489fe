//! From a resolved scenario to a [`SimSpec`], and the scenario-level entry points.

use crate::SimError;
use crate::metrics::{RunMetrics, run_baseline_spec};
use crate::spec::SimSpec;

/// Placeholder until the scenario model is wired: the spec is taken as is.
pub fn spec_from_scenario(spec: &SimSpec) -> Result<SimSpec, SimError> {
    Ok(spec.clone())
}

/// All-human baseline over `seeds` (parallel, results in seed order).
pub fn run_baseline(spec: &SimSpec, seeds: &[u64]) -> Result<Vec<RunMetrics>, SimError> {
    run_baseline_spec(spec, seeds)
}
