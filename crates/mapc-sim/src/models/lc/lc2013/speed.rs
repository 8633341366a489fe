//! LC2013's speed side: the speed it lets its vehicle drive (`patchSpeed`), the anticipated speed on a lane
//! (`anticipateFollowSpeed`), and the kinematic helpers of SUMO's `MSCFModel` it uses (Euler update).

use super::{Lc2013, Lc2013Memory, lca};
use crate::models::cf::CarFollowModel;
use crate::models::cf::{CfModel, StopShare};
use crate::models::lc::{Ego, Other};
use crate::numeric::NUMERICAL_EPS;

/// SUMO's `MIN2` (`a < b ? a : b`), NaN cases included.
pub(super) fn min2(a: f64, b: f64) -> f64 {
    if a < b { a } else { b }
}

/// SUMO's `MAX2` (`a > b ? a : b`).
pub(super) fn max2(a: f64, b: f64) -> f64 {
    if a > b { a } else { b }
}

/// SUMO's `minNextSpeed` (Euler): the speed after one step of comfortable braking.
pub(super) fn min_next_speed(p: &CfModel, speed: f64) -> f64 {
    max2(speed - p.decel * p.dt, 0.0)
}

/// SUMO's `maximumSafeStopSpeedEuler(gap, headway)`: the highest speed from which braking `decel` per step after
/// `headway` seconds stops within `gap`.
pub(super) fn maximum_safe_stop_speed(p: &CfModel, gap: f64, headway: f64) -> f64 {
    let g = gap - NUMERICAL_EPS;
    if g <= 0.0 {
        return 0.0;
    }
    let b = p.decel * p.dt;
    let t = headway;
    let s = p.dt;
    // h = n (n - 1) b s / 2 + n b t is the distance of n braking steps; n is the largest with h <= g
    // floor_exact: the same bits as `floor`, without the library call the baseline target makes for it
    let n = crate::numeric::floor_exact(
        0.5 - (t + ((s * s) + 4.0 * ((s * (2.0 * g / b - t)) + t * t)).sqrt() * -0.5) / s,
    );
    let h = 0.5 * n * (n - 1.0) * b * s + n * b * t;
    let r = (g - h) / (n * s + t);
    n * b + r
}

/// SUMO's `maximumSafeFollowSpeed(.., onInsertion = true)`: the highest speed from which the vehicle can stop
/// behind a leader that brakes at the harder of both decelerations.
pub(super) fn maximum_safe_follow_speed(
    p: &CfModel,
    gap: f64,
    leader_speed: f64,
    leader_decel: f64,
) -> f64 {
    let leader_stop = p.brake_gap(leader_speed, max2(p.decel, leader_decel), 0.0);
    maximum_safe_stop_speed(p, gap + leader_stop, p.tau)
}

/// SUMO's `anticipateFollowSpeed` (with `lcSpeedGainLookahead` 0): the speed the ego could drive on a lane with
/// `leader`, or with a free lane of `dist` metres (the lane's best length, as SUMO passes it).
// inlined into `_wantsChange` (twice per side): the call and its arguments' spills cost a fifth of it
#[inline(always)]
pub(super) fn anticipate_follow_speed(
    ego: &Ego,
    leader: Option<&Other>,
    dist: f64,
    v_max: f64,
    accelerating_leader: bool,
    // the stop speed behind `leader` for the gap and speed asked, kept or to keep
    share: Option<&mut StopShare>,
) -> f64 {
    let p = &ego.params;
    let future_speed = if accelerating_leader {
        // the speed one second ahead (SUMO's #6562)
        let max_speed_1s = ego.speed + p.accel - p.accel * p.dt;
        match (leader, share) {
            (None, _) => p.follow_speed_lc(dist, max_speed_1s, 0.0, v_max),
            (Some(l), Some(share)) => {
                p.follow_speed_sharing(share, true, l.gap, max_speed_1s, l.speed, v_max)
            }
            (Some(l), None) => p.follow_speed_lc(l.gap, max_speed_1s, l.speed, v_max),
        }
    } else {
        // a driver who surely stops within the gap (or the free distance) at `v_max` may drive `v_max`: the
        // leader's braking distance only lengthens it
        let gap = leader.map_or(dist, |l| l.gap);
        if crate::models::cf::kinematics::surely_stops_within(p.tau, p.decel, gap, v_max) {
            debug_assert!(
                leader.map_or(maximum_safe_stop_speed(p, dist, p.tau), |l| {
                    maximum_safe_follow_speed(p, l.gap, l.speed, l.params.decel)
                }) >= v_max
            );
            return v_max;
        }
        match leader {
            None => maximum_safe_stop_speed(p, dist, p.tau),
            // (the car-following model's stop speed, shared, where the leader brakes no harder than the ego)
            Some(l) => match share.filter(|_| !(l.params.decel > p.decel)) {
                Some(share) => share.get_or_keep(l.gap, l.speed, || {
                    maximum_safe_follow_speed(p, l.gap, l.speed, l.params.decel)
                }),
                None => maximum_safe_follow_speed(p, l.gap, l.speed, l.params.decel),
            },
        }
    };
    min2(v_max, future_speed)
}

impl Lc2013Memory {
    /// The speed for the next step (SUMO's `patchSpeed`), between `min` and `max` (the car-following bounds),
    /// `wanted` being the car-following speed: the lowest speed advice wins; else a blocked strategic wish
    /// drives between `wanted` and `max` to find a gap, a blocked cooperative one adjusts slightly.
    /// `desired_speed` is the vehicle's highest speed on its lane, `best_lane_offset` that of its lane.
    #[allow(clippy::too_many_arguments)]
    // inlined into the move (one call per vehicle and step), whose live values the call spilled (-1 % instructions)
    #[inline]
    pub fn patch_speed(
        &mut self,
        model: &Lc2013,
        speed: f64,
        params: &CfModel,
        desired_speed: f64,
        road_has_lane_changer: bool,
        best_lane_offset: i32,
        min: f64,
        wanted: f64,
        max: f64,
    ) -> f64 {
        let min = max2(min, 0.0);
        let state = self.own_state;
        let mut n_v_safe = wanted;
        let mut got_one = false;
        if self.leading_blocker_length != 0.0 {
            // keep room before the end of the lane for a vehicle that must enter ahead
            let magic_offset = 1.0;
            let space =
                self.left_space - self.leading_blocker_length - magic_offset - params.min_gap;
            if space > 0.0 {
                let safe = params.stop_speed(space, speed, desired_speed);
                if safe < wanted {
                    n_v_safe = max2(min, safe);
                    got_one = true;
                }
            }
        }
        let coop_weight = max2(0.0, min2(1.0, model.params.cooperative_speed));
        for a in &self.accel_advices {
            let v = speed + a * params.dt;
            if v >= min && v <= max {
                n_v_safe = min2(v * coop_weight + (1.0 - coop_weight) * wanted, n_v_safe);
                got_one = true;
            }
        }
        if got_one {
            return n_v_safe;
        }
        if state & lca::WANTS_LANECHANGE != 0 && state & lca::BLOCKED != 0 {
            if state & lca::STRATEGIC != 0 {
                // speed up to find a gap; needed braking comes as advices
                return (max + wanted) / 2.0;
            } else if state & lca::COOPERATIVE != 0 {
                if state & lca::BLOCKED_BY_LEADER != 0 {
                    return if wanted >= 0.0 {
                        (max2(0.0, min) + wanted) / 2.0
                    } else {
                        wanted
                    };
                }
                if state & lca::BLOCKED_BY_FOLLOWER != 0 {
                    return (max + wanted) / 2.0;
                }
            }
        }
        if state & lca::AMBLOCKINGLEADER != 0 {
            // a vehicle behind wants to enter before the end of the lane: let it fall behind
            return (max + wanted) / 2.0;
        }
        if !road_has_lane_changer {
            self.changed(best_lane_offset);
        }
        wanted
    }
}
