//! What an urgent lane change does about the vehicles in the way (SUMO's `informLeader`, `informFollower`,
//! `saveBlockerLength`, `slowDownForBlocked`, `overtakeDistance`; Euler update): it asks the neighbour leader to
//! keep its speed or to let it fall behind, the neighbour follower to slow down (or to pass), and slows itself
//! to fall behind a leader it cannot overtake, or to let a follower pass.

use super::speed::{max2, min_next_speed, min2};
use super::{
    CUT_IN_LEFT_SPEED_THRESHOLD, HALTING_SPEED, HELP_OVERTAKE, Lc2013, Lc2013Memory,
    MAX_ONRAMP_LENGTH, MIN_FALLBEHIND, POSITION_EPS, congested,
};
use crate::models::cf::CarFollowModel;
use crate::models::lc::{Ego, Message, Other, lca};

/// Weight of the follower's deceleration assumed when it helps (`HELP_DECEL_FACTOR`).
const HELP_DECEL_FACTOR: f64 = 1.0;

/// The distance the follower must gain on the leader to pass it with a secure gap (SUMO's `overtakeDistance`;
/// lengths and speeds given separately as the roles vary).
fn overtake_distance(
    gap: f64,
    follower_length: f64,
    leader: (&crate::models::cf::CfModel, f64),
    leader_speed: f64,
    follower_speed: f64,
) -> f64 {
    let (leader_params, leader_length_with_gap) = leader;
    let d = gap
        + leader_length_with_gap
        + follower_length
        + leader_params.secure_gap(leader_speed, follower_speed);
    max2(d, 0.0)
}

impl Lc2013 {
    /// SUMO's `informLeader`: returns the speed the ego plans for the next step, or -1 when it overtakes the
    /// neighbour leader (which is asked to keep its speed).
    #[allow(clippy::too_many_arguments)]
    pub(super) fn inform_leader(
        &self,
        mem: &mut Lc2013Memory,
        ego: &Ego,
        blocked: u32,
        dir: u32,
        neigh_lead: Option<&Other>,
        remaining_seconds: f64,
        msgs: &mut Vec<Message>,
    ) -> f64 {
        let p = &ego.params;
        let dt = p.dt;
        let mut planned_speed = min2(
            ego.speed,
            p.stop_speed(
                mem.left_space - mem.leading_blocker_length,
                ego.speed,
                ego.max_speed,
            ),
        );
        for a in &mem.accel_advices {
            if *a >= -p.decel {
                planned_speed = min2(planned_speed, ego.speed + a * dt);
            }
        }
        let Some(nv) = neigh_lead else {
            return planned_speed;
        };
        let neigh_next_speed = nv.speed - dt * max2(1.0, -nv.accel(dt));
        let neigh_next_gap = nv.gap + dt * (neigh_next_speed - planned_speed);
        if blocked & lca::BLOCKED_BY_LEADER != 0 {
            // overtake the leader, or fall behind it?
            let overtake_dist = overtake_distance(
                nv.gap,
                ego.length,
                (nv.params, nv.length_with_gap()),
                nv.speed,
                ego.speed,
            );
            let dv = planned_speed - nv.speed;
            let overtake_time = if dv > 0.0 {
                overtake_dist / dv
            } else {
                remaining_seconds + 1.0
            };
            let cannot_overtake = dv < 0.0
                // no overtaking on the right on an uncongested road
                || (dir == lca::MLEFT && !congested(ego.speed) && !self.params.allow_overtaking_right)
                || mem.left_space - mem.leading_blocker_length - p.brake_gap(ego.speed, p.decel, p.tau)
                    < overtake_dist
                || remaining_seconds < overtake_time;
            if cannot_overtake {
                msgs.push(Message::SpeedAdvice {
                    to: nv.id,
                    speed: f64::MAX,
                    state: dir | lca::AMBLOCKINGLEADER,
                });
                // slow down smoothly to follow the leader, allowing for its small decelerations
                let target_speed = max2(
                    min_next_speed(p, ego.speed),
                    p.follow_speed_lc(neigh_next_gap, ego.speed, neigh_next_speed, ego.max_speed),
                );
                if target_speed < ego.speed {
                    let decel = if remaining_seconds == 0.0 {
                        p.decel
                    } else {
                        min2(
                            p.decel,
                            max2(
                                MIN_FALLBEHIND,
                                (ego.speed - target_speed) / remaining_seconds,
                            ),
                        )
                    };
                    let next_speed = min2(planned_speed, max2(0.0, ego.speed - decel * dt));
                    mem.add_speed_advice(next_speed, ego.speed, dt);
                    next_speed
                } else {
                    // the leader is fast enough anyway
                    mem.add_speed_advice(target_speed, ego.speed, dt);
                    planned_speed
                }
            } else {
                // overtaking: the leader should not accelerate
                msgs.push(Message::SpeedAdvice {
                    to: nv.id,
                    speed: nv.speed,
                    state: dir | lca::AMBLOCKINGLEADER,
                });
                -1.0
            }
        } else {
            // not blocked now: stay far enough behind the leader
            let target_speed = max2(
                min_next_speed(p, ego.speed),
                p.follow_speed_lc(neigh_next_gap, ego.speed, neigh_next_speed, ego.max_speed),
            );
            mem.add_speed_advice(target_speed, ego.speed, dt);
            min2(target_speed, planned_speed)
        }
    }

    /// SUMO's `informFollower`: asks the neighbour follower to brake so that the ego can cut in, or to pass.
    #[allow(clippy::too_many_arguments)]
    pub(super) fn inform_follower(
        &self,
        mem: &mut Lc2013Memory,
        ego: &Ego,
        blocked: u32,
        dir: u32,
        neigh_follow: Option<&Other>,
        remaining_seconds: f64,
        planned_speed: f64,
        msgs: &mut Vec<Message>,
    ) {
        let Some(nv) = neigh_follow else { return };
        let p = &ego.params;
        let dt = p.dt;
        let np = &nv.params;
        let mut tell = |speed: f64, state: u32| {
            msgs.push(Message::SpeedAdvice {
                to: nv.id,
                speed,
                state,
            })
        };
        if blocked & lca::BLOCKED_BY_FOLLOWER != 0 {
            let planned = max2(planned_speed, 0.0);
            // fast enough to cut in without help?
            if planned - nv.speed >= HELP_OVERTAKE {
                let needed_gap = np.secure_gap(nv.speed, planned_speed);
                if (needed_gap - nv.gap) / remaining_seconds < planned - nv.speed {
                    tell(planned - HELP_OVERTAKE, dir | lca::AMBLOCKINGFOLLOWER);
                    return;
                }
            }
            // the follower is assumed to brake one second at its comfortable deceleration
            let help_decel = np.decel * HELP_DECEL_FACTOR;
            let neigh_new_speed = max2(0.0, nv.speed - help_decel * dt);
            let neigh_new_speed_1s = max2(0.0, nv.speed - help_decel);
            let dv = planned_speed - neigh_new_speed_1s;
            let decel_gap = nv.gap + dv;
            let secure_gap = np.secure_gap(max2(neigh_new_speed_1s, 0.0), planned);
            if decel_gap > 0.0 && decel_gap >= secure_gap {
                // the follower's braking opens the gap: the speed that is safe behind the ego next step, bounded
                // from above by computing it twice
                let v_safe_1 = max2(
                    neigh_new_speed,
                    np.follow_speed_lc(
                        nv.gap + planned_speed * dt,
                        nv.speed,
                        planned_speed,
                        nv.max_speed,
                    ),
                );
                let v_safe = max2(
                    neigh_new_speed,
                    np.follow_speed_lc(
                        nv.gap + dt * (planned_speed - v_safe_1),
                        nv.speed,
                        planned_speed,
                        nv.max_speed,
                    ),
                );
                tell(v_safe, dir | lca::AMBLOCKINGFOLLOWER);
            } else if dv > 0.0 && dv * remaining_seconds > secure_gap - decel_gap + POSITION_EPS {
                // braking opens the gap in the time left
                tell(neigh_new_speed, dir | lca::AMBLOCKINGFOLLOWER);
            } else if dir == lca::MRIGHT
                && !self.params.allow_overtaking_right
                && !congested(nv.speed)
            {
                // the follower may not pass on the right
                tell(
                    max2(neigh_new_speed, HELP_OVERTAKE),
                    dir | lca::AMBLOCKINGFOLLOWER,
                );
            } else {
                let mut v_help = max2(nv.speed, ego.speed + HELP_OVERTAKE);
                // SUMO's right-impatience test (waiting time > -1) always holds
                if nv.speed > ego.speed
                    && (dir == lca::MRIGHT
                        || (dir == lca::MLEFT && planned_speed > CUT_IN_LEFT_SPEED_THRESHOLD)
                        || (dir == lca::MLEFT && ego.lane_length > MAX_ONRAMP_LENGTH))
                {
                    // slow the follower so that later ones may be slow enough to help
                    v_help = max2(neigh_new_speed, ego.speed + HELP_OVERTAKE);
                    if (nv.speed - ego.speed) / help_decel < remaining_seconds {
                        tell(v_help, dir | lca::AMBLOCKINGFOLLOWER);
                        return;
                    }
                }
                tell(v_help, dir | lca::AMBLOCKINGFOLLOWER);
                // the follower passes: slow down smoothly to let it
                let overtake_dist = overtake_distance(
                    nv.gap,
                    nv.length,
                    (p, ego.length_with_gap()),
                    planned_speed,
                    v_help,
                );
                let need_dv = overtake_dist / remaining_seconds;
                mem.add_speed_advice(
                    max2(v_help - need_dv, ego.speed - p.decel * dt),
                    ego.speed,
                    dt,
                );
            }
        } else if blocked & lca::BLOCKED_BY_LEADER != 0 {
            // not blocked by the follower now: keep it that way
            let v_safe_1 = np.follow_speed_lc(
                nv.gap + dt * planned_speed,
                nv.speed,
                planned_speed,
                nv.max_speed,
            );
            let v_safe = np.follow_speed_lc(
                nv.gap + dt * (planned_speed - v_safe_1),
                nv.speed,
                planned_speed,
                nv.max_speed,
            );
            tell(v_safe, dir);
        }
    }

    /// SUMO's `saveBlockerLength`: a neighbour that wants to change the other way (into the ego's lane) is given
    /// room before the lane's end when the ego can still brake for it, otherwise it is asked to give room.
    pub(super) fn save_blocker_length(
        &self,
        mem: &mut Lc2013Memory,
        ego: &Ego,
        blocker: Option<&Other>,
        counter_wish: u32,
        msgs: &mut Vec<Message>,
    ) {
        let Some(b) = blocker.filter(|b| b.lc_state & counter_wish != 0) else {
            return;
        };
        let p = &ego.params;
        let potential = mem.left_space - p.brake_gap(ego.speed, p.decel, 0.0);
        if b.length_with_gap() <= potential {
            mem.leading_blocker_length = max2(b.length_with_gap(), mem.leading_blocker_length);
        } else {
            msgs.push(Message::KeepRoom {
                to: b.id,
                length: ego.length_with_gap(),
            });
        }
    }

    /// SUMO's `slowDownForBlocked`: a nearly halted ego lets a blocked vehicle ahead (which wants into its lane)
    /// in by following it.
    // inlined: `_wantsChange` calls it for every vehicle, mostly with no blocked vehicle, and the call's spills of
    // the many live values around it cost more than the test (-1 % instructions)
    #[inline(always)]
    pub(super) fn slow_down_for_blocked(
        &self,
        mem: &mut Lc2013Memory,
        ego: &Ego,
        blocked: Option<&Other>,
        mut state: u32,
    ) -> u32 {
        let Some(b) = blocked else { return state };
        let p = &ego.params;
        if b.gap > POSITION_EPS && ego.speed < p.decel * p.dt {
            state |= if b.speed < HALTING_SPEED {
                lca::AMBACKBLOCKER_STANDING
            } else {
                lca::AMBACKBLOCKER
            };
            let v = p.follow_speed_lc(b.gap - POSITION_EPS, ego.speed, b.speed, ego.max_speed);
            mem.add_speed_advice(v, ego.speed, p.dt);
        }
        state
    }
}
