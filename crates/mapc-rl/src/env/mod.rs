pub mod distributed;

use mapc_sim::{SimSpec, Simulation};

use crate::error::RlError;

/// A new episode's simulation of `spec` (invariant checks off: the environments step it millions of times).
pub(crate) fn episode_simulation(spec: &SimSpec, seed: u64) -> Result<Simulation, RlError> {
    let mut sim = Simulation::from_spec(spec.clone(), seed).map_err(|e| RlError::Scenario {
        scenario: spec.graph.source.file.clone(),
        msg: e.to_string(),
    })?;
    sim.set_invariant_checks(false);
    Ok(sim)
}
pub mod merge;
pub mod obs;
