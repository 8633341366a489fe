//! A vehicle's LC2013 memory between steps, and what the simulator tells it (moves, changes, messages).

use super::speed::max2;
use super::{LOOK_AHEAD_MIN_SPEED, lca};
use crate::models::cf::StopShare;
use crate::numeric::ceil_exact;

/// A vehicle's memory between steps (SUMO keeps it in the model instance).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Lc2013Memory {
    /// Summed relative speed gain: positive favours the left, negative the right (`mySpeedGainProbability`).
    pub speed_gain_probability: f64,
    /// Summed wish to keep right, negative (`myKeepRightProbability`).
    pub keep_right_probability: f64,
    /// The speed the strategic look-ahead uses: follows increases at once, decreases slowly (`myLookAheadSpeed`).
    pub look_ahead_speed: f64,
    /// Room (m) to keep free before the end of the lane for a vehicle that must enter it
    /// (`myLeadingBlockerLength`).
    pub leading_blocker_length: f64,
    /// Distance (m) left to the end of the usable lane during an urgent change (`myLeftSpace`).
    pub left_space: f64,
    /// State bits: the last wishes and the marks left by others (`myOwnState`).
    pub own_state: u32,
    /// Speed advices for the next step as accelerations (`myLCAccelerationAdvices`).
    pub(super) accel_advices: Vec<f64>,
    /// The stop speed behind the own leader computed for this lane's anticipated speed, for the next plan.
    pub stop_share: StopShare,
}

impl Lc2013Memory {
    /// After the vehicle moved: forget this step's advices and marks, keep a strategic wish (SUMO's
    /// `prepareStep`); the probabilities are rounded up to 1e-5 as SUMO does.
    pub fn prepare_step(&mut self) {
        self.own_state = if self.own_state & lca::STRATEGIC != 0 {
            self.own_state & lca::WANTS_LANECHANGE
        } else {
            0
        };
        self.leading_blocker_length = 0.0;
        self.left_space = 0.0;
        self.accel_advices.clear();
        // ceil_exact: the same bits as `ceil`, without the library call
        self.speed_gain_probability = ceil_exact(self.speed_gain_probability * 100000.0) * 0.00001;
        self.keep_right_probability = ceil_exact(self.keep_right_probability * 100000.0) * 0.00001;
    }

    /// After a lane change (`best_lane_offset`: the new lane's): start afresh (SUMO's `changed`).
    pub fn changed(&mut self, best_lane_offset: i32) {
        self.own_state = 0;
        self.speed_gain_probability = 0.0;
        self.keep_right_probability = 0.0;
        if best_lane_offset == 0 {
            // not yet on the best lane: there may be blockers still to make room for
            self.leading_blocker_length = 0.0;
            self.left_space = 0.0;
        }
        self.look_ahead_speed = LOOK_AHEAD_MIN_SPEED;
        self.accel_advices.clear();
    }

    /// A message from another vehicle (SUMO's `inform`); `own_speed` and `dt` are the receiver's.
    pub fn inform(&mut self, speed: f64, state: u32, own_speed: f64, dt: f64) {
        self.add_speed_advice(speed, own_speed, dt);
        self.own_state |= state;
    }

    /// Keep `length` metres free before the end of the lane (SUMO's `saveBlockerLength`).
    pub fn keep_room(&mut self, length: f64) {
        self.leading_blocker_length = max2(length, self.leading_blocker_length);
    }

    /// The speeds advised for the next step, in the order given.
    pub fn speed_advices(&self, own_speed: f64, dt: f64) -> impl Iterator<Item = f64> + '_ {
        self.accel_advices.iter().map(move |a| own_speed + a * dt)
    }

    pub(super) fn add_speed_advice(&mut self, speed: f64, own_speed: f64, dt: f64) {
        self.accel_advices.push((speed - own_speed) / dt);
    }
}
