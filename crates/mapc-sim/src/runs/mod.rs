//! Runs built on the simulator: a scenario turned into a simulation spec and run over many seeds
//! ([`scenario`]), the merges' regimes ([`regime`]), traces ([`trace`]), replays of SUMO's states
//! ([`replay`]), and ramp metering by ALINEA ([`alinea`]); human runs kept for a job's later steps ([`kept`]).

pub mod alinea;
pub mod kept;
mod observed;
pub mod regime;
pub mod replay;
pub mod scenario;
pub mod trace;
