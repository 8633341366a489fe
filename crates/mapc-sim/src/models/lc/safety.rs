//! The gap checks before a lane change, shared by the models (SUMO's `MSLaneChanger::checkChange`, the part
//! before the model is asked): the change is blocked by the new follower when its gap is below the follower's
//! secure gap behind the ego, and by the new leader when the ego's gap is below the ego's secure gap behind it.
//!
//! With an action step equal to the step (SUMO's default), the speeds extrapolated over the reaction time are
//! the current ones (`tauRemainder` = 0). Not done here: SUMO's extra look for a critical leader across the
//! next junction and its zipper-merge check, which need the lanes beyond the road.

use super::{Ego, NeighbourLane, Side, lca};
use crate::models::cf::CarFollowModel;

/// Checks the gaps for a change towards `side` whose neighbours are `lane`: the `LCA_BLOCKED_BY_*` and
/// `LCA_OVERLAPPING` bits, 0 when the change is safe. `safety_factor` scales both secure gaps (SUMO's
/// `getSafetyFactor`, 1 / lcAssertive).
pub fn check_gaps(ego: &Ego, side: Side, lane: &NeighbourLane, safety_factor: f64) -> u32 {
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
    // (a gap far above the secure one is decided by the model's bound, without the braking distances)
    if blocked & by_follower == 0
        && let Some(f) = &lane.follower
        && !f
            .params
            .surely_secure(f.gap, f.speed, ego.speed, safety_factor)
    {
        // the follower's own car-following model, at its speed, behind the ego at the ego's speed
        let secure = f.params.secure_gap(f.speed, ego.speed);
        if f.gap < secure * safety_factor {
            blocked |= by_follower;
        }
    }
    if blocked & by_leader == 0
        && let Some(l) = &lane.leader
        && !ego
            .params
            .surely_secure(l.gap, ego.speed, l.speed, safety_factor)
    {
        let secure = ego.params.secure_gap(ego.speed, l.speed);
        if l.gap < secure * safety_factor {
            blocked |= by_leader;
        }
    }
    blocked
}
