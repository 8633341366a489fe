//! One step's phases, in the order [`super::Simulation::step`] runs them: every vehicle's plan (safe speed and
//! link requests, [`planning`], looking ahead with [`lookahead`]), right of way at the junctions ([`junction`]),
//! the moves front to back ([`moves`]), the lane-change pass ([`lane_change`], seeing neighbours through
//! [`side_lanes`]), and what the induction loops saw ([`detection`]).

use super::*;

pub(in crate::sim) mod active_lanes;
pub(in crate::sim) mod detection;
pub(in crate::sim) mod junction;
pub(in crate::sim) mod lane_change;
pub(in crate::sim) mod lane_change_view;
#[cfg(test)]
mod lane_change_view_tests;
pub(in crate::sim) mod lookahead;
pub(in crate::sim) mod moves;
#[cfg(test)]
mod overlap_tests;
pub(in crate::sim) mod planning;
#[cfg(test)]
mod red_light_tests;
pub(in crate::sim) mod side_lanes;
#[cfg(test)]
mod side_lanes_tests;
