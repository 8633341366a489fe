//! The gap checks before a lane change, shared by the models (SUMO's `MSLaneChanger::checkChange`, the part
//! before the model is asked): the change is blocked by the new follower when its gap is below the follower's
//! secure gap behind the ego, and by the new leader when the ego's gap is below the ego's secure gap behind it.
//!
//! With an action step equal to the step (SUMO's default), the speeds extrapolated over the reaction time are
//! the current ones (`tauRemainder` = 0). Not done here: SUMO's extra look for a critical leader across the
//! next junction and its zipper-merge check, which need the lanes beyond the road.

use super::{Ego, NeighbourLane, Side, lca};
use crate::models::cf::CarFollowModel;

/// The result of the gap check towards one side.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct GapCheck {
    /// `LCA_BLOCKED_BY_*` and `LCA_OVERLAPPING` bits; 0 when the change is safe.
    pub blocked: u32,
    /// The gap the new follower needs behind the ego (m), when there is one that does not overlap.
    pub secure_back_gap: Option<f64>,
    /// The gap the ego needs behind the new leader (m), likewise.
    pub secure_front_gap: Option<f64>,
}

/// Checks the gaps for a change towards `side` whose neighbours are `lane`. `safety_factor` scales both secure
/// gaps (SUMO's `getSafetyFactor`, 1 / lcAssertive).
pub fn check_gaps(ego: &Ego, side: Side, lane: &NeighbourLane, safety_factor: f64) -> GapCheck {
    let by_leader = side.blocked_by_leader();
    let by_follower = side.blocked_by_follower();
    let mut blocked = 0;
    if let Some(f) = &lane.follower
        && f.gap < 0.0
    {
        blocked |= by_follower | lca::OVERLAPPING;
    }
    if let Some(l) = &lane.leader
        && l.gap < 0.0
    {
        blocked |= by_leader | lca::OVERLAPPING;
    }
    let mut secure_back_gap = None;
    if blocked & by_follower == 0
        && let Some(f) = &lane.follower
    {
        // the follower's own car-following model, at its speed, behind the ego at the ego's speed
        let secure = f.params.secure_gap(f.speed, ego.speed);
        secure_back_gap = Some(secure);
        if f.gap < secure * safety_factor {
            blocked |= by_follower;
        }
    }
    let mut secure_front_gap = None;
    if blocked & by_leader == 0
        && let Some(l) = &lane.leader
    {
        let secure = ego.params.secure_gap(ego.speed, l.speed);
        secure_front_gap = Some(secure);
        if l.gap < secure * safety_factor {
            blocked |= by_leader;
        }
    }
    GapCheck {
        blocked,
        secure_back_gap,
        secure_front_gap,
    }
}
