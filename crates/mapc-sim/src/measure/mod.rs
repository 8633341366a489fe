//! What a run measures: [`metrics`] holds a run's figures and their summary over seeds (mean and 95 % CI),
//! [`points`] the measurement points (merges and the corridor's end) and the passages counted at them,
//! [`detectors`] the induction loops (SUMO's E1). Each
//! metric is computed in one place: the simulator accumulates, these types define and summarize.

pub mod detectors;
pub mod metrics;
pub mod points;
