//! Right of way at merges: the requests vehicles register for links (arrival and leave times and speeds) and
//! SUMO's `MSLink::opened` with impatience.

use super::*;

/// Waiting time after which impatience has grown by 1 (SUMO's default time to impatience).
pub(in crate::sim) const TIME_TO_IMPATIENCE_S: f64 = 300.0;

/// A foe must arrive this much later than ego leaves for ego to go first (SUMO's link lookahead).
pub(in crate::sim) const LINK_LOOKAHEAD_S: f64 = 1.0;

/// A zipper link's foes are those whose passage lies within this many seconds of ego's (SUMO's zipper
/// lookahead; 1 s at other links).
pub(in crate::sim) const ZIPPER_LOOKAHEAD_S: f64 = 4.0;

/// Farther than this from a zipper link, and ...
const ZIPPER_ADAPT_DIST_M: f64 = 100.0;
/// ... later than this before arriving there, a driver does not adapt to the other stream yet.
const ZIPPER_ADAPT_TIME_S: f64 = 10.0;

/// The arrival time of a foe that could stop is this much later than its normal arrival.
pub(in crate::sim) const BRAKING_ARRIVAL_DELAY_S: f64 = 30.0;

#[derive(Clone, Copy, Debug, Default)]
pub(in crate::sim) struct LinkItem {
    pub(in crate::sim) link: LinkIdx,
    pub(in crate::sim) dist: f64,
    pub(in crate::sim) v_link_pass: f64,
    /// Where the vehicle would stop for this link if it must yield (the speed to do so is computed only when it
    /// must wait). At a red or yellow light the stop point is a metre further back (`LIGHT_STOP_OFFSET_M`), taken
    /// in the move, where the light's state is known.
    pub(in crate::sim) stop_dist: f64,
    pub(in crate::sim) desired_speed: f64,
    pub(in crate::sim) arrival_time: f64,
    pub(in crate::sim) arrival_speed: f64,
    pub(in crate::sim) leave_time: f64,
    pub(in crate::sim) leave_speed: f64,
    pub(in crate::sim) arrival_time_braking: f64,
    pub(in crate::sim) arrival_speed_braking: f64,
    pub(in crate::sim) will_pass: bool,
}

#[derive(Clone, Copy, Debug)]
pub(in crate::sim) struct Approach {
    pub(in crate::sim) veh: VehicleId,
    pub(in crate::sim) arrival_time: f64,
    pub(in crate::sim) leave_time: f64,
    pub(in crate::sim) leave_speed: f64,
    pub(in crate::sim) arrival_time_braking: f64,
    pub(in crate::sim) arrival_speed_braking: f64,
    pub(in crate::sim) will_pass: bool,
    pub(in crate::sim) decel: f64,
    /// Distance to the link and speed when the request was made, and the index of the lane it came on (for the
    /// zipper's turns).
    pub(in crate::sim) dist: f64,
    pub(in crate::sim) speed: f64,
    pub(in crate::sim) lane_index: u8,
}

/// Whether a follower behind a leader at the merge could not brake in time: it can only when the leader's
/// braking distance (v^2 / b) is the longer one (SUMO's `MSLink::unsafeMergeSpeeds`).
pub(in crate::sim) fn unsafe_merge_speeds(
    leader_speed: f64,
    follower_speed: f64,
    leader_decel: f64,
    follower_decel: f64,
) -> bool {
    leader_speed * leader_speed / leader_decel <= follower_speed * follower_speed / follower_decel
}

impl Simulation {
    /// The request for entering the connection `link` at distance `seen` (SUMO's `DriveProcessItem`): arrival time
    /// and speed (a driver approaching a minor link slows so it could still stop once it sees the foes), the
    /// arrival when braking now, and the leave speed (lowered later by constraints beyond the link).
    #[allow(clippy::too_many_arguments)]
    pub(in crate::sim) fn link_request(
        &self,
        v: &Veh,
        p: &CfModel,
        tc: &TypeConsts,
        link: LinkIdx,
        seen: f64,
        vv: f64,
        v_link_pass: f64,
        des_cur: f64,
        plan: &mut Plan,
    ) -> usize {
        let lk = self.link_at(link as usize);
        let via = lk.via_lane;
        let via_lane = self.lane_at(via as usize);
        let speed = v.speed;
        let stop_dist = (seen - if lk.major { 0.0 } else { POSITION_EPS }).fmax(0.0);
        let mut arrival_speed = v_link_pass;
        if !lk.major && seen >= FOE_VISIBILITY_M && {
            if seen > tc.brake_gap_above(speed, 0.0) {
                true
            } else {
                if plan.stop_brake_gap.is_nan() {
                    plan.stop_brake_gap = p.brake_gap(speed, p.decel, 0.0);
                }
                plan.stop_brake_gap < seen
            }
        } {
            arrival_speed = arrival_speed.fmin(tc.max_arrival_from_visibility);
        }
        let arrival_time = self.time_s + p.minimal_arrival_time(seen, vv, arrival_speed);
        let mut arrival_speed_braking = 0.0;
        let mut arrival_time_braking = arrival_time + BRAKING_ARRIVAL_DELAY_S;
        // the bound decides the far case without the exact gap
        if seen < tc.brake_gap_above(vv, p.tau) && seen < p.brake_gap(vv, p.decel, p.tau) {
            arrival_speed_braking = p.minimal_arrival_speed_euler(seen, vv).fmin(arrival_speed);
            arrival_time_braking = arrival_time.fmax(
                self.time_s + seen / ((vv + arrival_speed_braking) * 0.5).fmax(NUMERICAL_EPS),
            );
        }
        let leave_speed = self
            .desired_speed(v, via)
            .fmin(kinematics::speed_after_distance(
                via_lane.length,
                arrival_speed,
                p.accel,
            ));
        let i = plan.n_items as usize;
        plan.items[i] = LinkItem {
            link,
            dist: seen,
            v_link_pass: vv,
            stop_dist,
            desired_speed: des_cur,
            arrival_time,
            arrival_speed,
            leave_time: f64::NAN,
            leave_speed,
            arrival_time_braking,
            arrival_speed_braking,
            will_pass: vv > 0.0,
        };
        plan.n_items += 1;
        i
    }

    /// SUMO's link leaders at a merge (`MSLink::getLeaderInfo`, `MSVehicle::getSafeFollowSpeed`), under SUMO's
    /// junction rules: a vehicle that has left a foe's connection into the same lane but whose back still lies on
    /// it leads ego through its minor link, and ego's speed on leaving the connection is what lets it stop about
    /// the distance to the link. The leave time grows with it, so a foe approaching next blocks the link until the
    /// junction is clear. (A foe still inside the junction leads ego by the plan's link leaders, as in SUMO: ego
    /// may follow it in; it once zeroed the leave speed, and a driver at a minor stop line of RESCO's cologne3
    /// waited two steps longer than SUMO's.)
    pub(in crate::sim) fn lower_leave_speeds_for_merging_foes(
        &self,
        plan: &mut Plan,
        p: &CfModel,
        speed: f64,
        desired: f64,
    ) {
        for it in &mut plan.items[..plan.n_items as usize] {
            let lk = self.link_at(it.link as usize);
            if lk.major || lk.zipper {
                continue;
            }
            for &f in &lk.foes {
                let fl = self.link_at(f as usize);
                let Some(&o) = self.lane_veh[fl.to_lane as usize].last() else {
                    continue;
                };
                let ov = &self.veh[o as usize];
                // its back still on the foe's connection
                let back_on_foe = ov.pos < ov.length
                    && ov.route_pos > 0
                    && self.routes[ov.route as usize].lanes[ov.route_pos as usize - 1]
                        == fl.via_lane;
                if back_on_foe {
                    it.leave_speed = it.leave_speed.fmin(p.stop_speed(it.dist, speed, desired));
                }
            }
        }
    }

    /// SUMO's `MSLink::opened` for a minor link: blocked by any foe approach that conflicts in time. With
    /// `crossing` (a yielding green, an unsignalised minor link), also by a vehicle approaching a link that crosses
    /// it by the net's request table, where their passages overlap: the foe neither through before ego arrives nor
    /// arriving (as an impatient driver expects it) after ego has left and the look-ahead (`blockedByFoe` for a
    /// foe into another lane).
    pub(in crate::sim) fn link_opened(
        &self,
        id: VehicleId,
        it: &LinkItem,
        can_brake: bool,
        crossing: bool,
    ) -> bool {
        let lk = self.link_at(it.link as usize);
        if crossing && !lk.crossing_foes.is_empty() {
            let impatience = self.impatience(id, can_brake);
            let crossed = lk.crossing_foes.iter().any(|&foe| {
                self.approaches[foe as usize].iter().any(|a| {
                    a.veh != id
                        && a.will_pass
                        && !(a.leave_time < it.arrival_time)
                        && !((1.0 - impatience) * a.arrival_time
                            + impatience * a.arrival_time_braking
                            > it.leave_time + LINK_LOOKAHEAD_S)
                })
            });
            if crossed {
                return false;
            }
        }
        if lk.major {
            return true;
        }
        let mut blocked = false;
        self.blocking_approaches(id, it, can_brake, LINK_LOOKAHEAD_S, &mut |_| {
            blocked = true;
        });
        !blocked
    }

    /// How far a waiting driver expects a foe to brake for it: its type's impatience, growing with its waiting time;
    /// a driver who can no longer stop takes any gap.
    fn impatience(&self, id: VehicleId, can_brake: bool) -> f64 {
        if !can_brake {
            return 1.0;
        }
        let v = &self.veh[id as usize];
        let tc = &self.type_consts[v.vtype as usize];
        (tc.impatience + v.waiting_s / TIME_TO_IMPATIENCE_S).clamp(0.0, 1.0)
    }

    /// Every foe approach that blocks ego's request `it` (SUMO's `MSLink::blockedByFoe` over the link's foes):
    /// its passage overlaps ego's within `lookahead` seconds, or one of them could not brake for the other.
    fn blocking_approaches(
        &self,
        id: VehicleId,
        it: &LinkItem,
        can_brake: bool,
        lookahead: f64,
        f: &mut impl FnMut(&Approach),
    ) {
        let lk = self.link_at(it.link as usize);
        let v = &self.veh[id as usize];
        let impatience = self.impatience(id, can_brake);
        // the spec's deceleration, which the IDM parameters carry unchanged
        let decel = self.types[v.vtype as usize].decel;
        for &foe in &lk.foes {
            for a in &self.approaches[foe as usize] {
                if a.veh == id || !a.will_pass {
                    continue;
                }
                let blocks = if a.leave_time < it.arrival_time {
                    // ego would follow the foe
                    it.arrival_time - a.leave_time < lookahead
                        || unsafe_merge_speeds(a.leave_speed, it.arrival_speed, a.decel, decel)
                } else if (1.0 - impatience) * a.arrival_time + impatience * a.arrival_time_braking
                    > it.leave_time + lookahead
                {
                    // (the left side is the foe's arrival as an impatient driver expects it)
                    // ego would lead the foe
                    unsafe_merge_speeds(it.leave_speed, a.arrival_speed_braking, decel, a.decel)
                } else {
                    true
                };
                if blocks {
                    f(a);
                }
            }
        }
    }

    /// The speed at which ego takes its turn at a zipper link (SUMO's `MSLink::getZipperSpeed`): every foe of
    /// the other stream that blocks ego's passage and reaches the merge first becomes a virtual leader, projected
    /// onto ego's lane at its own distance to the merge. Far from the merge ego opens the gap smoothly; near it,
    /// it follows the virtual leader as it would a real one. Never a stop at the link: the streams alternate.
    pub(in crate::sim) fn zipper_speed(
        &self,
        id: VehicleId,
        it: &LinkItem,
        can_brake: bool,
    ) -> f64 {
        let dt = self.spec.step_s;
        let v = &self.veh[id as usize];
        let p = &self.types[v.vtype as usize];
        let mut v_safe = f64::INFINITY;
        if it.arrival_time - self.time_s > ZIPPER_ADAPT_TIME_S && it.dist > ZIPPER_ADAPT_DIST_M {
            return v_safe;
        }
        let own_lane_index = self.lane_at(v.lane as usize).index;
        // a follower that could brake for a second and stay behind the leader (SUMO's `couldBrakeForLeader`)
        let could_brake_for_leader = |follow_dist: f64,
                                      follow_speed: f64,
                                      follow_decel: f64,
                                      leader_dist: f64,
                                      leader_speed: f64| {
            follow_dist > leader_dist
                && follow_dist - leader_dist > follow_speed - follow_decel - leader_speed
        };
        let v_max_lane = self.desired_speed(v, v.lane);
        self.blocking_approaches(id, it, can_brake, ZIPPER_LOOKAHEAD_S, &mut |a| {
            let foe = &self.veh[a.veh as usize];
            let fp = &self.types[foe.vtype as usize];
            let ego_leads = (a.arrival_time > it.arrival_time
                && !could_brake_for_leader(it.dist, v.speed, p.decel, a.dist, a.speed))
                || could_brake_for_leader(a.dist, a.speed, a.decel, it.dist, v.speed)
                || (a.arrival_time == it.arrival_time
                    && a.dist == it.dist
                    && own_lane_index < a.lane_index);
            if ego_leads {
                return;
            }
            let step_ceil = |t: f64| ((t / dt).ceil() * dt).fmax(1.0);
            let u_end = self
                .desired_speed(foe, foe.lane)
                .fmin(kinematics::speed_after_distance(a.dist, a.speed, fp.accel));
            let u_avg = 0.5 * (a.speed + u_end);
            let tf = step_ceil(a.dist / u_avg.fmax(NUMERICAL_EPS));
            let v_end = v_max_lane
                .fmin(kinematics::speed_after_distance(it.dist, v.speed, p.accel))
                .fmin(u_end);
            let v_avg = 0.5 * (v.speed + v_end);
            let te = step_ceil(it.dist / v_avg.fmax(NUMERICAL_EPS));
            let gap = it.dist - foe.length - p.min_gap - a.dist;
            let safe_gap = p.secure_gap(v_end, u_end);
            let delta_gap = gap + tf * u_avg - safe_gap - v_avg * tf;
            let v_safe_gap = v.speed + 2.0 * delta_gap / (tf * tf) * dt;
            let v_follow = p.follow_speed(gap, v.speed, a.speed, it.desired_speed);
            let w = (te / ZIPPER_ADAPT_TIME_S).fmin(1.0);
            let max_decel = w * p.decel + (1.0 - w) * p.emergency_decel;
            let v_zipper = v_follow
                .fmax(v.speed - max_decel * dt)
                .fmax(w * v_safe_gap + (1.0 - w) * v_follow);
            v_safe = v_safe.fmin(v_zipper);
        });
        v_safe
    }
}
