//! Runs built on the simulator: a scenario turned into a simulation spec and run over many seeds
//! ([`scenario`]), the merges' regimes ([`regime`]), traces ([`trace`]) and replays of SUMO's states
//! ([`replay`]).

pub mod regime;
pub mod replay;
pub mod scenario;
pub mod trace;
