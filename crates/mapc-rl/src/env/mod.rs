pub mod distributed;
pub mod merge;
pub mod obs;
pub mod windows;

use mapc_sim::{SimSpec, Simulation, VehicleId};

use crate::error::RlError;

/// A problem of `spec` (or of building a simulation from it), reported against the scenario's file.
pub(crate) fn scenario_error(spec: &SimSpec, e: impl std::fmt::Display) -> RlError {
    RlError::Scenario {
        scenario: spec.graph.source.file.clone(),
        msg: e.to_string(),
    }
}

/// `spec` checked for the simulator, its problems reported against the scenario's file.
pub(crate) fn validate_spec(spec: &SimSpec) -> Result<(), RlError> {
    spec.validate().map_err(|e| scenario_error(spec, e))
}

/// An error of the running simulation (a bad command, a broken invariant).
pub(crate) fn sim_error(e: impl std::fmt::Display) -> RlError {
    RlError::Scenario {
        scenario: "simulation".into(),
        msg: e.to_string(),
    }
}

/// A new episode's simulation of `spec` (invariant checks off: the environments step it millions of times).
pub(crate) fn episode_simulation(spec: &SimSpec, seed: u64) -> Result<Simulation, RlError> {
    let mut sim = Simulation::from_spec(spec.clone(), seed).map_err(|e| scenario_error(spec, e))?;
    sim.set_invariant_checks(false);
    Ok(sim)
}

/// Give AV `id` a policy's acceleration for the next step, clamped to `[lo, hi]` (a non-finite one is 0: the
/// network's output is never trusted to be a number).
pub(crate) fn apply_action(
    sim: &mut Simulation,
    id: VehicleId,
    a: f32,
    (lo, hi): (f64, f64),
) -> Result<(), RlError> {
    let a = if a.is_finite() {
        (a as f64).clamp(lo, hi)
    } else {
        0.0
    };
    sim.set_acceleration(id, a).map_err(sim_error)
}
