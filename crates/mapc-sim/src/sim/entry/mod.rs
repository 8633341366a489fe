//! Vehicles entering the road: departures inserted where SUMO would insert them ([`insertion`]), the lane chosen
//! at insertion for `random` and `free` flows ([`lane_choice`]), and jammed vehicles taken off and brought back
//! further along their route ([`teleport`]).

use super::*;

#[cfg(test)]
mod depart_lane_tests;
pub(in crate::sim) mod flow_schedule;
pub(in crate::sim) mod insertion;
pub(in crate::sim) mod lane_choice;
pub(in crate::sim) mod teleport;
