//! Trace runs: one seed to the horizon, every frame's vehicles written as CSV rows ([`crate::TRACE_HEADER`]).

use crate::metrics::RunMetrics;
use crate::sim::Simulation;
use crate::spec::SimSpec;

/// Run `seed` of `spec` to its horizon, writing the rows of the state before the first step and after every step
/// (no header). A simulation error comes back as an I/O error of kind `Other` carrying its message.
pub fn trace_run(
    spec: &SimSpec,
    seed: u64,
    out: &mut impl std::io::Write,
) -> std::io::Result<RunMetrics> {
    let mut sim = Simulation::from_spec(spec.clone(), seed).map_err(std::io::Error::other)?;
    sim.write_trace_rows(out)?;
    while !sim.is_done() {
        sim.step().map_err(std::io::Error::other)?;
        sim.write_trace_rows(out)?;
    }
    Ok(sim.metrics())
}
