//! The move of a step: every vehicle's next speed from its plan and the links, the moves front to back never
//! into a leader, then the passage onto the next lane of the route and arrivals.

use super::*;
use crate::network::signals::SignalState;

/// Below this speed a vehicle counts as halting (its waiting time grows).
pub(in crate::sim) const HALTING_SPEED: f64 = 0.1;

/// `1 / d` where multiplying by it gives the bits of dividing by `d`: when `d` is a power of two (0.5 s, 0.25 s,
/// 1 s), `1 / d` is exact and both operations round the same real number; `None` otherwise. The move's cap is on the
/// chain from each moved leader to its follower, and a division is several times a multiplication's latency.
pub(in crate::sim) fn exact_reciprocal(d: f64) -> Option<f64> {
    const MANTISSA: u64 = (1 << 52) - 1;
    (d.is_normal() && d.to_bits() & MANTISSA == 0).then(|| 1.0 / d)
}

/// SUMO's `canBrake` at a link `dist` ahead: the driver at `speed` needs less to stop, or stops within a step.
/// `stop_brake_gap`: its braking distance where the plan computed it (NaN: computed here, where the bound does
/// not decide).
pub(in crate::sim) fn can_brake_before(
    p: &CfModel,
    tc: &TypeConsts,
    speed: f64,
    dist: f64,
    stop_brake_gap: f64,
    dt: f64,
) -> bool {
    dist > tc.brake_gap_above(speed, 0.0)
        || dist
            > if stop_brake_gap.is_nan() {
                p.brake_gap(speed, p.decel, 0.0)
            } else {
                stop_brake_gap
            }
        || speed < p.decel * dt
}

impl Simulation {
    pub(in crate::sim) fn execute_moves(&mut self) {
        let dt = self.spec.step_s;
        // the lights' clock: seconds since the run's begin
        let light_time = self.time_s - self.spec.start_time_s;
        let inv_dt = exact_reciprocal(dt);
        // 1. decide each vehicle's next speed from its plan and the links (plans are in this visiting order)
        let mut pi = 0;
        for li in 0..self.lane_order.len() {
            let lane = self.lane_order[li];
            for qi in 0..self.lane_veh[lane as usize].len() {
                let id = self.lane_veh[lane as usize][qi];
                let plan = &self.plans[pi];
                let v = &self.veh[id as usize];
                let p = &self.types[v.vtype as usize];
                let mut v_safe = plan.v_safe;
                // under SUMO's rules, the least speed past a minor link's point of no return (SUMO's `vSafeMin`),
                // and the distance across
                let mut across_min: Option<(f64, f64)> = None;
                for it in &plan.items[..plan.n_items as usize] {
                    let lk = self.link_at(it.link as usize);
                    let signal = self.signal_of(lk, light_time);
                    if signal == Some(SignalState::Green)
                        || (signal.is_none() && lk.major && !lk.zipper)
                    {
                        continue;
                    }
                    let tc = &self.type_consts[v.vtype as usize];
                    let can_brake =
                        can_brake_before(p, tc, v.speed, it.dist, plan.stop_brake_gap, dt);
                    // the speed that stops `stop_dist` ahead, never above the plan's at the link
                    let wait = |stop_dist: f64| {
                        it.v_link_pass
                            .fmin(p.stop_speed(stop_dist, v.speed, it.desired_speed))
                    };
                    // red: stop; yellow: stop where one still can (SUMO); green yielding: a minor link
                    if matches!(signal, Some(SignalState::Red | SignalState::Yellow)) {
                        if signal == Some(SignalState::Red) || can_brake {
                            v_safe = v_safe.fmin(wait((it.dist - LIGHT_STOP_OFFSET_M).fmax(0.0)));
                            break;
                        }
                        continue;
                    }
                    if lk.zipper {
                        // a zipper link is never waited at: ego takes its turn behind the other stream's
                        // vehicles that reach the merge first, and looks on to the next link
                        if it.will_pass {
                            v_safe = v_safe.fmin(self.zipper_speed(id, it, can_brake));
                        }
                        continue;
                    }
                    // a stop (`s`): a minor link once the driver has stood a step at its stop line (SUMO's stop
                    // sign)
                    let must_stop = signal == Some(SignalState::Stop) && v.waiting_s < dt;
                    let crossing =
                        matches!(signal, Some(SignalState::GreenYield | SignalState::Stop))
                            || (signal.is_none() && !lk.major);
                    let opened =
                        !must_stop && it.will_pass && self.link_opened(id, it, can_brake, crossing);
                    if !opened && (can_brake || !it.will_pass || must_stop) {
                        v_safe = v_safe.fmin(wait(it.stop_dist));
                        break;
                    }
                    if opened
                        && crossing
                        && !lk.yields_inside
                        && self.spec.sumo_junction_lane_changes
                    {
                        // SUMO's approach to an open minor link: a driver who cannot yet see every foe (farther
                        // than the visibility distance) keeps able to stop at the line; nearer, it must get across
                        if it.dist > FOE_VISIBILITY_M {
                            // (the stop speed only where it may be the lower)
                            if !(it.v_link_pass >= v_safe
                                && p.stop_speed_at_least(it.stop_dist, v.speed, v_safe))
                            {
                                v_safe = v_safe.fmin(wait(it.stop_dist));
                            }
                            debug_assert!(v_safe <= wait(it.stop_dist));
                            break;
                        }
                        let across = self.lane_at(v.lane as usize).length - v.pos;
                        across_min =
                            Some((((across + POSITION_EPS) / dt).fmin(it.v_link_pass), across));
                    }
                }
                if let Some((min, dist)) = across_min
                    && v_safe + NUMERICAL_EPS < min
                {
                    // it cannot get across: it stops before the line instead
                    v_safe =
                        v_safe.fmin(p.stop_speed(dist, v.speed, self.desired_speed(v, v.lane)));
                    across_min = None;
                }
                // finalise: acceleration and deceleration bounds (emergency braking allowed when unsafe)
                let v_max = v_safe.fmin(v.speed + p.accel * dt);
                let v_min = (v.speed - p.decel * dt)
                    .fmin(v_safe.fmax(v.speed - p.emergency_decel * dt))
                    .fmax(0.0);
                let mut next = v_max.fmax(v_min);
                if p.dawdles() {
                    let r = self.veh[id as usize].rng.uniform();
                    next = self.types[self.veh[id as usize].vtype as usize].dawdle(v_min, next, r);
                }
                let v = &self.veh[id as usize];
                if self.net.multi_lane {
                    let (speed, vtype, lane) = (v.speed, v.vtype as usize, v.lane);
                    let desired = self.desired_speed(v, lane);
                    next = self.patch_lc_speed(id, speed, vtype, lane, desired, v_min, next, v_max);
                }
                if let Some((min, _)) = across_min {
                    // (SUMO's `finalizeSpeed` then its least speed)
                    next = next.fmax(min);
                }
                let v = &self.veh[id as usize];
                let p = &self.types[v.vtype as usize];
                if v.controlled && v.accel_cmd.is_finite() && self.in_region[v.lane as usize] {
                    let a = v.accel_cmd.clamp(-p.decel, p.accel);
                    next = (v.speed + a * dt).fmax(0.0).fmin(v_safe);
                }
                self.plans[pi].v_safe = next.fmax(0.0);
                pi += 1;
            }
        }
        // 2. move, downstream lanes first and front to back, never past the (already moved) leader
        let mut pi = 0;
        let mut longest_wait: f64 = 0.0;
        for li in 0..self.lane_order.len() {
            let lane = self.lane_order[li];
            let mut qi = 0;
            while qi < self.lane_veh[lane as usize].len() {
                let id = self.lane_veh[lane as usize][qi];
                let mut next = self.plans[pi].v_safe;
                pi += 1;
                let mut cap = f64::INFINITY;
                // a leader's back may reach up to its length behind the start of its lane
                self.for_each_leader_at(
                    id,
                    qi,
                    next * dt + self.max_length + 1.0,
                    Some(next * dt),
                    |l, gap| {
                        // the leader's movement this step, if it already moved
                        let _ = l;
                        cap = cap.fmin(gap);
                    },
                );
                // `for_each_leader` measured gaps from positions partly updated this step: leaders that moved
                // report their new position, the rest their old one; both are safe bounds.
                if cap.is_finite() {
                    let cap_speed = inv_dt.map_or(cap / dt, |r| cap * r);
                    next = next.fmin(cap_speed.fmax(0.0));
                }
                let v = &mut self.veh[id as usize];
                v.accel_cmd = f64::NAN;
                v.speed = next;
                v.pos += next * dt;
                v.distance_m += next * dt;
                self.metrics.distance_m += next * dt;
                v.waiting_s = if next < HALTING_SPEED {
                    v.waiting_s + dt
                } else {
                    0.0
                };
                longest_wait = longest_wait.fmax(v.waiting_s);
                qi += 1;
            }
        }
        self.longest_wait_s = longest_wait;
        // 3. lane changes along routes and arrivals; vehicles moved into a lane are appended behind its others
        for li in 0..self.lane_order.len() {
            let lane = self.lane_order[li];
            while let Some(&id) = self.lane_veh[lane as usize].first() {
                let len = self.lane_at(lane as usize).length;
                let v = &self.veh[id as usize];
                let r = &self.routes[v.route as usize];
                let last = v.route_pos as usize + 1 >= r.lanes.len();
                if last && r.dead_end {
                    // stopped at the end of a lane that does not continue: it waits there for a gap
                    if v.pos > len {
                        self.veh[id as usize].pos = len;
                    }
                    break;
                }
                if last {
                    if v.pos > len - POSITION_EPS {
                        self.lane_veh[lane as usize].remove(0);
                        self.in_network -= 1;
                        self.arrive(id);
                        continue;
                    }
                    break;
                }
                if v.pos <= len {
                    break;
                }
                self.lane_veh[lane as usize].remove(0);
                self.in_network -= 1;
                let mut v_pos = v.pos;
                let mut rp = v.route_pos as usize;
                // a fast vehicle (or a long step) may cross several short lanes in one step
                let mut arrived = false;
                let mut stopped_at_red = None;
                loop {
                    let length = self.lane_at(r.lanes[rp] as usize).length;
                    if v_pos <= length {
                        break;
                    }
                    if rp + 1 >= r.lanes.len() {
                        // past the end of a dead end's lane (an arrival ended the loop on entering a last lane
                        // that continues): it stops there and waits for a gap
                        v_pos = length;
                        break;
                    }
                    if self.red_between(r.lanes[rp], r.lanes[rp + 1], light_time) {
                        // SUMO's emergency stop at the end of the lane: a vehicle whose move would take it past
                        // a red light (it could not brake in time) stands at the stop line instead
                        stopped_at_red = Some(v_pos - length);
                        v_pos = length;
                        break;
                    }
                    v_pos -= length;
                    rp += 1;
                    self.measure.entered(r.lanes[rp], id);
                    if rp + 1 >= r.lanes.len()
                        && !r.dead_end
                        && v_pos > self.lane_at(r.lanes[rp] as usize).length - POSITION_EPS
                    {
                        arrived = true;
                        break;
                    }
                }
                if arrived {
                    self.arrive(id);
                    continue;
                }
                let new_lane = r.lanes[rp];
                let v = &mut self.veh[id as usize];
                if let Some(overshoot) = stopped_at_red {
                    v.speed = 0.0;
                    v.distance_m -= overshoot;
                    self.metrics.distance_m -= overshoot;
                }
                v.pos = v_pos;
                v.route_pos = rp as u32;
                v.lane = new_lane;
                // behind every vehicle already on the new lane
                let q = &mut self.lane_veh[new_lane as usize];
                let at = q
                    .iter()
                    .rposition(|&o| self.veh[o as usize].pos >= v_pos)
                    .map_or(0, |i| i + 1);
                q.insert(at, id);
                self.in_network += 1;
                self.note_entered(new_lane);
            }
        }
    }

    /// Whether the link from lane `from` to lane `to` of a route (its via lane, or the next lane where it has
    /// none) has a red light at `light_time`.
    fn red_between(&self, from: LaneIdx, to: LaneIdx, light_time: f64) -> bool {
        self.lane_at(from as usize).out_links.iter().any(|&k| {
            let lk = self.link_at(k as usize);
            lk.signal.is_some()
                && (lk.via_lane == to || lk.to_lane == to)
                && self.signal_of(lk, light_time) == Some(SignalState::Red)
        })
    }

    pub(in crate::sim) fn arrive(&mut self, id: VehicleId) {
        self.forget_lc(id);
        let v = &mut self.veh[id as usize];
        v.status = VehicleStatus::Arrived;
        v.arrive_s = self.time_s + self.spec.step_s;
        if let Some(&last) = self.routes[v.route as usize].lanes.last() {
            self.measure.arrived(last, id);
        }
        self.metrics.arrived += 1;
        let tt = v.arrive_s - v.depart_s;
        self.metrics.travel_time_sum += tt;
        self.metrics.delay_sum += (tt - v.free_flow_s).fmax(0.0);
        self.arrived_last.push(id);
    }
}
