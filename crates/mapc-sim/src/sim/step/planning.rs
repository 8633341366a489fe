//! Each vehicle's plan for a step (SUMO's `MSVehicle::planMoveInternal`): the safe speed from every leader and
//! limit ahead, and a request at every link where right of way is decided.

use super::*;
use crate::network::signals::SignalState;

/// Links planned ahead per vehicle.
pub(in crate::sim) const MAX_LINK_ITEMS: usize = 4;

/// Where SUMO would stop before a link it expects to have priority at: this far before the stop line (m).
const DIST_TO_STOPLINE_EXPECT_PRIORITY: f64 = 1.0;

#[derive(Clone, Copy, Debug, Default)]
pub(in crate::sim) struct Plan {
    pub(in crate::sim) v_safe: f64,
    /// `brake_gap(speed, decel, 0)` at the step's start speed once planning needed it, NaN before.
    pub(in crate::sim) stop_brake_gap: f64,
    pub(in crate::sim) n_items: u8,
    pub(in crate::sim) items: [LinkItem; MAX_LINK_ITEMS],
}

/// The speed at the next link, `speed_after_distance(dist, speed, accel).fmin(cap)` lowered by every leader
/// found on the way, with the square root taken only when a link request reads it (most lanes' pass speeds are
/// never read). `fmin` (`b < a ? b : a`) keeps the first operand that attains the minimum, so folding the leaders
/// into their own minimum and taking it with the root's last gives the same bits as the eager chain, signed zeros
/// included.
#[derive(Clone, Copy)]
pub(in crate::sim) struct LazyPassSpeed {
    pub(in crate::sim) dist: f64,
    pub(in crate::sim) speed: f64,
    pub(in crate::sim) accel: f64,
    pub(in crate::sim) cap: f64,
    pub(in crate::sim) leaders_min: f64,
}

impl LazyPassSpeed {
    #[inline]
    pub(in crate::sim) fn new(dist: f64, speed: f64, accel: f64, cap: f64) -> LazyPassSpeed {
        LazyPassSpeed {
            dist,
            speed,
            accel,
            cap,
            leaders_min: f64::INFINITY,
        }
    }

    #[inline]
    pub(in crate::sim) fn lower(&mut self, v: f64) {
        self.leaders_min = self.leaders_min.fmin(v);
    }

    #[inline]
    pub(in crate::sim) fn get(&self) -> f64 {
        kinematics::speed_after_distance(self.dist, self.speed, self.accel)
            .fmin(self.cap)
            .fmin(self.leaders_min)
    }
}

impl Simulation {
    /// The four IDM steps most plans need, whose arguments are known before planning: behind the own leader, the
    /// free speed towards the current lane's speed, and behind the last vehicles on the next two lanes of the
    /// route (gaps summed as the look-ahead in [`Self::plan`] sums them). One `next_speed_x4` call, the same bits
    /// as four calls; entries without a vehicle hold a result nobody reads.
    #[inline(always)]
    pub(in crate::sim) fn plan_idm_batch(&self, id: VehicleId, qi: usize) -> [f64; 4] {
        let v = &self.veh[id as usize];
        let p = &self.types[v.vtype as usize];
        if !p.batches_plan_speeds() {
            return crate::models::cf::BATCHED_NOT;
        }
        let des_cur = self.desired_speed(v, v.lane);
        let mut gap = [1e6; 4];
        let mut leader = [0.0; 4];
        if qi > 0 {
            // (not a closure: the optimizer kept one out of line)
            let lv = &self.veh[self.lane_veh[v.lane as usize][qi - 1] as usize];
            gap[0] = lv.pos - lv.length - v.pos - p.min_gap;
            leader[0] = lv.speed;
        }
        leader[1] = des_cur;
        let r = &self.routes[v.route as usize];
        let mut seen = self.lane_at(v.lane as usize).length - v.pos;
        for j in 1..=2 {
            let Some(&lane) = r.lanes.get(v.route_pos as usize + j) else {
                break;
            };
            let len = self.lane_at(lane as usize).length;
            seen += len;
            if let Some(&o) = self.lane_veh[lane as usize].last() {
                let ov = &self.veh[o as usize];
                gap[1 + j] = seen - len + ov.pos - ov.length - p.min_gap;
                leader[1 + j] = ov.speed;
            }
        }
        p.plan_speeds(gap, v.speed, leader, des_cur)
    }

    /// One vehicle's plan for this step, as SUMO's `MSVehicle::planMoveInternal` builds it: walk the lanes of the
    /// route ahead, adapting the safe speed to the last vehicle on every lane, to vehicles on merging connections,
    /// and to each next lane's speed (IDM's free speed); at every link where right of way is decided, record the
    /// request (arrival and leave times and speeds) that foes check.
    pub(in crate::sim) fn plan(
        &mut self,
        id: VehicleId,
        qi: usize,
        pre: [f64; 4],
        plan: &mut Plan,
    ) {
        let dt = self.spec.step_s;
        let v = &self.veh[id as usize];
        let p = &self.types[v.vtype as usize];
        let tc = self.type_consts[v.vtype as usize];
        let speed = v.speed;
        let des_cur = self.desired_speed(v, v.lane);
        let max_next = (speed + p.accel * dt).fmin(tc.max_speed);
        let min_comfortable = (speed - p.decel * dt).fmax(0.0);
        let mut vv = max_next.fmin(des_cur);
        let r = &self.routes[v.route as usize];
        let cur = self.lane_at(v.lane as usize);
        let mut seen = cur.length - v.pos;
        // the speed at the next link: an upper bound, lowered by every leader
        let mut v_link_pass = LazyPassSpeed::new(seen, vv, p.accel, des_cur);
        plan.n_items = 0;
        plan.stop_brake_gap = f64::NAN;
        // the request whose leave speed later constraints lower (SUMO's `lastLink`); none before the first link
        // and after an exit link (those carry no request)
        let mut last_item: Option<usize> = None;
        // under SUMO's rules, the speed at which the vehicle could still stop at the last link entering a junction
        // ahead (SUMO's `myVLinkWait` of the link before): a leader found on a connection merging with that
        // junction's never lowers the speed below it, priority or not. Kept as (speed planned then, distance to
        // stop at), the stop speed computed only when a leader is found.
        let mut entry_wait: Option<(f64, f64)> = None;

        // `pre`: most of the plan's IDM steps, computed together ([`Self::plan_idm_batch`])
        let pre_has_free = speed <= des_cur;

        // Leader on the own lane.
        if qi > 0 {
            let lv = &self.veh[self.lane_veh[v.lane as usize][qi - 1] as usize];
            let gap = lv.pos - lv.length - v.pos - p.min_gap;
            let vs = if !pre[0].is_nan() {
                pre[0]
            } else if let Some(rec) = v.lc.as_ref() {
                // the lane changer's stop speed behind the same leader, kept since the last pass
                // (a copy: the move changes the positions, the plan keeps nothing for later)
                let mut share = rec.mem.stop_share;
                p.follow_speed_sharing(&mut share, false, gap, speed, lv.speed, des_cur)
            } else {
                p.follow_speed(gap, speed, lv.speed, des_cur)
            };
            debug_assert_eq!(
                vs.to_bits(),
                p.follow_speed(gap, speed, lv.speed, des_cur).to_bits()
            );
            vv = vv.fmin(vs);
            v_link_pass.lower(vs);
        }
        if let LaneKind::Via(_) = cur.kind {
            // inside a junction (behind others on the connection or not): vehicles on merging connections closer
            // to the merge point lead (SUMO checks the exit link's leaders for every vehicle on the connection)
            let mut m = f64::INFINITY;
            self.junction_foe_leaders(id, v.lane, seen, false, &mut |o, gap| {
                m = m.fmin(p.follow_speed(
                    gap - p.min_gap,
                    speed,
                    self.veh[o as usize].speed,
                    des_cur,
                ));
            });
            vv = vv.fmin(m);
            v_link_pass.lower(m);
        }
        if let LaneKind::Via(link) = cur.kind {
            let y = self.yield_inside_junction(id, link, p, des_cur);
            vv = vv.fmin(y);
            v_link_pass.lower(y);
        }
        if qi == 0 && !matches!(cur.kind, LaneKind::Via(_)) {
            // tails of vehicles that entered a connection out of this road still reach back onto it: they lead
            // on this road (before any link is considered)
            for &k in &cur.out_links {
                let via = self.link_at(k as usize).via_lane;
                if let Some(&o) = self.lane_veh[via as usize].last() {
                    let ov = &self.veh[o as usize];
                    if ov.pos < ov.length {
                        let gap = seen + ov.pos - ov.length - p.min_gap;
                        let vs = p.follow_speed(gap, speed, ov.speed, des_cur);
                        vv = vv.fmin(vs);
                        v_link_pass.lower(vs);
                    }
                }
            }
        }

        // IDM's free speed towards a lane's limit: below the limit it does not depend on the distance, and
        // consecutive lanes mostly share a limit, so the IDM integration is kept for the last limit seen
        let mut free_cache = if pre_has_free {
            (des_cur, pre[1])
        } else {
            (f64::NAN, f64::NAN)
        };
        let mut free_speed = |seen: f64, max_speed: f64| -> f64 {
            if speed <= max_speed {
                if free_cache.0 != max_speed {
                    free_cache = (
                        max_speed,
                        p.free_speed_below_limit(speed, max_speed, des_cur),
                    );
                }
                p.free_speed_given(free_cache.1, speed, seen, max_speed, des_cur)
            } else {
                p.free_speed(speed, seen, max_speed, des_cur)
            }
        };
        // SUMO's look-ahead: continue while links are near (`dist`), and at least past one exit link and 5
        // vehicle lengths of roads after it
        // (the brake distance is computed only when that rule is reached; the bound above it decides far lanes)
        let beyond_look_dist = |seen: f64| {
            seen > max_next * dt + tc.brake_gap_above(max_next, p.tau)
                || seen > max_next * dt + p.brake_gap(max_next, p.decel, p.tau)
        };
        let free_at_least_limit = p.free_speed_at_least_limit();
        let mut had_non_internal = false;
        let mut seen_non_internal = 0.0;
        let mut k = v.route_pos as usize;
        let mut lane = v.lane;
        loop {
            let lane_ref = self.lane_at(lane as usize);
            if k > v.route_pos as usize {
                // the last vehicle on a lane ahead
                if let Some(&o) = self.lane_veh[lane as usize].last() {
                    let ov = &self.veh[o as usize];
                    let gap = seen - lane_ref.length + ov.pos - ov.length - p.min_gap;
                    let ahead = k - v.route_pos as usize;
                    let vs = if ahead <= 2 && !pre[1 + ahead].is_nan() {
                        debug_assert_eq!(
                            pre[1 + ahead].to_bits(),
                            p.follow_speed(gap, speed, ov.speed, des_cur).to_bits()
                        );
                        pre[1 + ahead]
                    } else {
                        p.follow_speed(gap, speed, ov.speed, des_cur)
                    };
                    vv = vv.fmin(vs);
                    v_link_pass.lower(vs);
                    if let Some(i) = last_item {
                        let it = &mut plan.items[i];
                        it.leave_speed = it.leave_speed.fmin(vs);
                    }
                }
            }
            if k + 1 >= r.lanes.len() && r.dead_end {
                // a lane that does not continue on the route: stop at its end (until a lane change); SUMO drives
                // up to the end itself, mapc's own scenarios were measured stopping a margin before it
                let margin = if self.spec.sumo_junction_lane_changes {
                    0.0
                } else {
                    POSITION_EPS
                };
                let vs = p.stop_speed(seen - margin, speed, des_cur).fmax(0.0);
                vv = vv.fmin(vs);
                if let Some(i) = last_item {
                    let it = &mut plan.items[i];
                    it.leave_speed = it.leave_speed.fmin(vs);
                }
                break;
            }
            if k + 1 >= r.lanes.len() {
                // final lane: drive out at the lane's speed (SUMO's arrival handling)
                let lane_max = self.desired_speed(v, lane);
                // (a model whose free speed never falls below the limit lowers nothing at or below it)
                let lowers_nothing = free_at_least_limit
                    && lane_max >= vv
                    && last_item.is_none_or(|i| lane_max >= plan.items[i].leave_speed);
                if !lowers_nothing {
                    let va = free_speed(seen - lane_max * dt, lane_max).fmax(NUMERICAL_EPS);
                    vv = vv.fmin(va);
                    if let Some(i) = last_item {
                        let it = &mut plan.items[i];
                        it.leave_speed = it.leave_speed.fmin(va);
                    }
                }
                break;
            }
            let next = r.lanes[k + 1];
            let next_ref = self.lane_at(next as usize);
            if let LaneKind::Via(cur_link) = lane_ref.kind {
                // the exit link of a junction: vehicles on merging connections closer to the merge point lead
                let cur_major = self.link_at(cur_link as usize).major;
                if k > v.route_pos as usize && !self.link_at(cur_link as usize).foes.is_empty() {
                    // under SUMO's rules, a driver still before its minor link meets its link leaders apart
                    // ([`Self::minor_entry_leaders`])
                    let before_minor = self.spec.sumo_junction_lane_changes
                        && !cur_major
                        && k == v.route_pos as usize + 1
                        && !matches!(cur.kind, LaneKind::Via(_));
                    let (m, behind_stop) = if before_minor {
                        self.minor_entry_leaders(id, lane, seen, lane_ref.length, speed, des_cur)
                    } else {
                        let mut m = f64::INFINITY;
                        self.junction_foe_leaders(id, lane, seen, false, &mut |o, gap| {
                            m = m.fmin(p.follow_speed(
                                gap - p.min_gap,
                                speed,
                                self.veh[o as usize].speed,
                                des_cur,
                            ));
                        });
                        (m, f64::INFINITY)
                    };
                    if m.is_finite() {
                        // (the pass speed is reset on the next lane)
                        vv = vv.fmin(m);
                        if let Some(i) = last_item {
                            let it = &mut plan.items[i];
                            it.leave_speed = it.leave_speed.fmin(m);
                            // not yet inside: a driver without right of way may still drive up to the stop
                            // line (a driver with right of way gets no such floor: SUMO's FCD shows those
                            // drivers keep slowing for the lane ahead)
                            if !cur_major {
                                let wait = it.v_link_pass.fmin(p.stop_speed(
                                    it.stop_dist,
                                    speed,
                                    it.desired_speed,
                                ));
                                vv = vv.fmax(wait);
                            }
                        }
                        if cur_major && let Some((planned, stop_dist)) = entry_wait {
                            vv = vv.fmax(planned.fmin(p.stop_speed(stop_dist, speed, des_cur)));
                        }
                    }
                    vv = vv.fmin(behind_stop);
                }
                had_non_internal = true;
                last_item = None;
            } else if let LaneKind::Via(link) = next_ref.kind {
                let lk = self.link_at(link as usize);
                if self.spec.sumo_junction_lane_changes {
                    // SUMO stops a metre before a link it expects to have priority at, just before any other
                    let stop_offset = if lk.major {
                        DIST_TO_STOPLINE_EXPECT_PRIORITY
                    } else {
                        POSITION_EPS
                    };
                    entry_wait = Some((vv, (seen - stop_offset).fmax(0.0)));
                }
                // only links where right of way is decided need a request: minor links, and major links with
                // minor foes
                if (plan.n_items as usize) < MAX_LINK_ITEMS
                    && (!lk.major || self.link_takes_requests[link as usize] || lk.signal.is_some())
                {
                    let i = self.link_request(
                        v,
                        p,
                        &tc,
                        link,
                        seen,
                        vv,
                        v_link_pass.get(),
                        des_cur,
                        plan,
                    );
                    last_item = Some(i);
                } else {
                    last_item = None;
                }
            }
            if had_non_internal
                && seen_non_internal > (5.0 * v.length).fmax(v.length + vv)
                && (vv <= 0.0 || beyond_look_dist(seen))
            {
                break;
            }
            // onto the next lane: arrive there no faster than its speed allows (IDM's free speed), but limits
            // are no emergencies
            let next_max = self.desired_speed(v, next);
            // (a model whose free speed never falls below the limit needs it only for a limit below the speed
            // planned so far)
            if !(free_at_least_limit && next_max >= vv) {
                let va = free_speed(seen, next_max).fmax(min_comfortable);
                vv = vv.fmin(va);
            }
            if !matches!(next_ref.kind, LaneKind::Via(_)) {
                seen_non_internal += next_ref.length;
            }
            seen += next_ref.length;
            v_link_pass = LazyPassSpeed::new(next_ref.length, vv, p.accel, next_max);
            lane = next;
            k += 1;
        }
        plan.v_safe = vv;
        if self.spec.sumo_junction_lane_changes {
            self.lower_leave_speeds_for_merging_foes(plan, p, speed, des_cur);
        }
        let own_lane_index = self.lane_at(v.lane as usize).index;
        let light_time = self.time_s - self.spec.start_time_s;
        // leave times from the final leave speeds; register approaches on links that minor foes check
        for it in &mut plan.items[..plan.n_items as usize] {
            let via_len = self
                .lane_at(self.link_at(it.link as usize).via_lane as usize)
                .length;
            it.leave_time = it.arrival_time
                + (via_len + v.length)
                    / (0.5 * (it.arrival_speed + it.leave_speed)).fmax(NUMERICAL_EPS);
            if self.link_takes_requests[it.link as usize] {
                // a driver who stops for its light (red, or yellow where it can still brake) makes no request
                // (SUMO's `setRequest` false): it must not hold a foe's yielding green
                let lk = self.link_at(it.link as usize);
                let held = lk.signal.is_some()
                    && match self.signal_of(lk, light_time) {
                        Some(SignalState::Red) => true,
                        // (as the move decides it)
                        Some(SignalState::Yellow) => super::moves::can_brake_before(
                            p,
                            &tc,
                            speed,
                            it.dist,
                            plan.stop_brake_gap,
                            dt,
                        ),
                        _ => false,
                    };
                self.approaches[it.link as usize].push(Approach {
                    veh: id,
                    arrival_time: it.arrival_time,
                    leave_time: it.leave_time,
                    leave_speed: it.leave_speed,
                    arrival_time_braking: it.arrival_time_braking,
                    arrival_speed_braking: it.arrival_speed_braking,
                    will_pass: it.will_pass && !held,
                    decel: p.decel,
                    dist: it.dist,
                    speed: v.speed,
                    lane_index: own_lane_index,
                });
            }
        }
    }
}
