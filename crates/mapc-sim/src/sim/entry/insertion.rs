//! Departures: flows' vehicles created when due and inserted at their entry lane where SUMO's insertion check
//! allows (at most one per entry lane and step); flows whose lane is chosen at insertion wait at their road
//! (`lane_choice.rs`).

use super::*;
use crate::network::signals::SignalState;
use crate::spec::{DEPART_SPEED_MAX, DepartPos};

impl Simulation {
    /// Create the flows' vehicles due by now and insert waiting vehicles where it is safe (SUMO's insertion: at
    /// most one per entry lane and step; a refused vehicle blocks the ones behind it).
    // out of line: inlined into the step, its code changes the planning's register use and inlining (the
    // instructions of every plan moved by several per cent as insertion grew)
    #[inline(never)]
    pub(in crate::sim) fn insert_departures(&mut self) {
        let now = self.time_s - self.spec.step_s; // insertion happens within the step just executed
        // before the next departure by period no flow has one due (`flows_quiet_until`): none is visited
        if !(self.flows_quiet_until > now + 1e-9) {
            self.flows_quiet_until = self.enqueue_due(now);
        }
        // lanes where an insertion failed in this step: no later vehicle is tried there (SUMO's failed-insertion
        // memory; lanes chosen at insertion are tried after the fixed ones)
        let mut refused = std::mem::take(&mut self.refused_lanes);
        refused.clear();
        if self.spec.sumo_insertion_order {
            self.insert_in_due_order(&mut refused);
            self.refused_lanes = refused;
            return;
        }
        for ei in 0..self.entry_lanes.len() {
            loop {
                let id = match self.pending[ei].front_built() {
                    Some(id) => id,
                    None => match self.pending[ei].take_counted() {
                        // a counted vehicle reaches the front: built now, then waits like any other
                        Some(f) => {
                            let id = self.build_flow_vehicle(f);
                            self.pending[ei].push_taken(id);
                            id
                        }
                        None => break,
                    },
                };
                if self.try_insert(id) {
                    self.pending[ei].pop_built();
                } else {
                    refused.push(self.entry_lanes[ei]);
                    break;
                }
            }
        }
        for re in 0..self.road_entries.len() {
            self.insert_at_road(re, &mut refused);
        }
        self.refused_lanes = refused;
    }

    /// Every flow's vehicles due by `now` join their entries' queues, flow by flow in index order; returns the
    /// earliest departure time of any flow's next vehicle by period, NaN when a flow draws by probability (it is
    /// visited every step).
    fn enqueue_due(&mut self, now: f64) -> f64 {
        if !self.flow_schedule.started() {
            let (flows, due) = (&self.spec.flows, &self.flow_due);
            self.flow_schedule
                .start(flows.iter().zip(due).map(|(flow, &(_, first))| {
                    let left =
                        first.filter(|&t| t < flow.end_s && flow.number.is_none_or(|m| m > 0));
                    (flow.probability.is_some(), left)
                }));
        }
        let visit = self.flow_schedule.take_visit(now);
        for &f in &visit {
            let flow = &self.spec.flows[f];
            if let Some(p) = flow.probability {
                if flow.number.is_some_and(|n| self.flow_next[f] >= n) {
                    self.flow_schedule.drop_probability(f);
                    continue;
                }
                // SUMO: one draw a step, a vehicle with probability p per second (at most one a step)
                let due = flow.begin_s <= now + 1e-9 && now < flow.end_s;
                if due && self.rng.random::<f64>() < p * self.spec.step_s {
                    self.enqueue_departure(f);
                }
                continue;
            }
            // the scalars only: the flow's lists (via, type mix) stay where they are
            let (end_s, number) = (flow.end_s, flow.number);
            // Departure n is due at `FlowSpec::departure_s(n)`. `validate` keeps begin within the longest run and
            // the period at least one step, so each departure time is a distinct sane number and this loop makes
            // at most a few departures per step (a begin of -1e308 once made `depart` stand still: a run without
            // end).
            loop {
                let n = self.flow_next[f];
                if self.flow_due[f].0 != n {
                    self.flow_due[f] = (n, self.spec.flows[f].departure_s(n));
                }
                let Some(depart) = self.flow_due[f].1 else {
                    break;
                };
                if depart >= end_s || number.is_some_and(|m| n >= m) {
                    break;
                }
                if !(depart <= now + 1e-9) {
                    self.flow_schedule.wait(f, depart);
                    break;
                }
                self.enqueue_departure(f);
            }
        }
        self.flow_schedule.give_back(visit);
        self.flow_schedule.quiet_until()
    }

    /// The next vehicle of flow `f` joins the queue at its entry (built now while the queue is short, else
    /// counted and built when it reaches the front).
    fn enqueue_departure(&mut self, f: usize) {
        if let Some(fl) = &self.flow_lanes[f] {
            let re = fl.entry as usize;
            if self.road_entries[re].queue.builds_next() {
                let id = self.build_flow_vehicle(f);
                self.road_entries[re].queue.push_built(id);
            } else {
                self.road_entries[re].queue.push_counted(f);
            }
        } else {
            let entry = self.routes[self.flow_route[f] as usize].lanes[0];
            let ei = self.entry_lanes.iter().position(|&l| l == entry).unwrap();
            if self.pending[ei].builds_next() {
                let id = self.build_flow_vehicle(f);
                self.pending[ei].push_built(id);
            } else {
                self.pending[ei].push_counted(f);
            }
        }
        self.flow_next[f] += 1;
    }

    /// A new vehicle of flow `f` (pending until inserted); a flow with a mix of types draws its type.
    pub(in crate::sim) fn build_flow_vehicle(&mut self, f: usize) -> VehicleId {
        let flow = &self.spec.flows[f];
        let speed = flow.depart_speed;
        let vt = if flow.type_mix.is_empty() {
            flow.vehicle_type
        } else {
            let u: f64 = self.rng.random();
            let mix = &self.spec.flows[f].type_mix;
            mix.iter()
                .find(|&&(_, c)| u < c)
                .unwrap_or(&mix[mix.len() - 1])
                .0
        };
        let id = self.create_vehicle(vt, self.flow_route[f], speed);
        self.veh[id as usize].depart_pos = self.spec.flows[f].depart_pos;
        // a flow by probability departs in the step it is drawn in
        self.veh[id as usize].due_s = self.spec.flows[f]
            .departure_s(u64::from(self.flow_built[f]))
            .unwrap_or(self.time_s - self.spec.step_s);
        if let Some(origins) = &mut self.origins {
            origins.insert(id, (f as u32, self.flow_built[f]));
        }
        self.flow_built[f] += 1;
        id
    }

    /// SUMO's insertion check at the start of the entry road: front at length + POSITION_EPS, the depart speed
    /// safe behind the leader and able to stop before a minor link within reach.
    pub(in crate::sim) fn try_insert(&mut self, id: VehicleId) -> bool {
        let tries = match self.veh[id as usize].depart_pos {
            DepartPos::Base => return self.try_insert_at(id, None),
            DepartPos::Free => return self.try_insert_free(id),
            DepartPos::Random => 1,
            DepartPos::RandomFree => 10,
        };
        let v = &self.veh[id as usize];
        let lane = self.routes[v.route as usize].lanes[0];
        let len = self.lane_at(lane as usize).length;
        let base = (v.length + POSITION_EPS).fmin(len);
        for _ in 0..tries {
            let pos = (self.rng.random::<f64>() * len).fmax(base);
            if self.try_insert_at(id, Some(pos)) {
                return true;
            }
        }
        self.veh[id as usize].depart_pos == DepartPos::RandomFree && self.try_insert_free(id)
    }

    /// SUMO 1.8's `freeInsertion` with the speed adapted (the front at the lane's start behind the last vehicle,
    /// at about the speed of the lane's first vehicle; else the first gap, upstream first, that leaves both the
    /// leader's and the follower's secure gaps).
    fn try_insert_free(&mut self, id: VehicleId) -> bool {
        let v = &self.veh[id as usize];
        let p = &self.types[v.vtype as usize];
        let lane = self.routes[v.route as usize].lanes[0];
        let lane_len = self.lane_at(lane as usize).length;
        let top = match v.depart_speed {
            s if s.is_infinite() => self.desired_speed(v, lane),
            s => s,
        };
        let (length, min_gap) = (v.length, p.min_gap);
        // upstream first: mapc keeps each lane front first
        let on_lane: Vec<(f64, f64, f64, usize)> = self.lane_veh[lane as usize]
            .iter()
            .rev()
            .map(|&o| {
                let ov = &self.veh[o as usize];
                (ov.pos, ov.length, ov.speed, ov.vtype as usize)
            })
            .collect();
        let mut candidates: Vec<(f64, f64)> = Vec::new();
        // "behind the last one" is judged, as in SUMO 1.8, by the lane's first vehicle, the farthest downstream
        // (`getFirstFullVehicle`, kept there on purpose): its back must leave the secure gap at its speed, and the
        // speed tried is the follow speed at that gap, about its speed
        match on_lane.last() {
            None => candidates.push((0.0, top)),
            Some(&(pos, len, speed, _)) => {
                let needed = p.secure_gap(speed, speed) + min_gap;
                if pos - len >= needed {
                    candidates.push((
                        0.0,
                        p.insertion_follow_speed(top, needed, speed, top).fmin(top),
                    ));
                }
            }
        }
        for (i, &(f_pos, _, f_speed, f_type)) in on_lane.iter().enumerate() {
            let (front_max, speed) = match on_lane.get(i + 1) {
                Some(&(l_pos, l_len, l_speed, _)) => {
                    let speed = l_speed.fmin(top);
                    (
                        l_pos - l_len - (p.secure_gap(speed, l_speed) + min_gap),
                        speed,
                    )
                }
                None => (lane_len, top),
            };
            let fp = &self.types[f_type];
            let back_min = f_pos + fp.min_gap + fp.secure_gap(f_speed, 0.0) + length;
            if front_max > 0.0 && back_min + POSITION_EPS < front_max {
                candidates.push((back_min + POSITION_EPS, speed));
            }
        }
        let rule = self.veh[id as usize].depart_speed;
        for (at, speed) in candidates {
            if self.try_insert_adapted(id, at, speed) {
                return true;
            }
            self.veh[id as usize].depart_speed = rule;
        }
        false
    }

    /// The insertion with the front at `at` and the speed adapted from `upper` (SUMO's adaptable speed).
    fn try_insert_adapted(&mut self, id: VehicleId, at: f64, upper: f64) -> bool {
        match self.adapted_insertion_speed(id, Some(at), upper) {
            Some(speed) => {
                self.veh[id as usize].depart_speed = speed;
                self.place_on_entry(id, Some(at), true);
                true
            }
            None => false,
        }
    }

    /// SUMO 1.8's insertion check with an adaptable speed (`MSLane::isInsertionSuccess` with `patchSpeed`: a depart
    /// speed `max`, and free insertion): from `upper`, the speed is lowered to what each constraint within its
    /// braking distance allows (the next lanes' leaders and limits, a stop before a minor link), then to the
    /// insertion follow speed behind the leader on the lane; the vehicle behind must then have its secure gap at
    /// that speed. `None` where a leader overlaps the place or the follower is too close. The follower is checked
    /// at the adapted speed only: a check at a standstill, the most demanding for it, refused insertions SUMO
    /// makes (on a three-lane entry with random positions, 1.29 vehicles a second entered against SUMO's 1.47).
    fn adapted_insertion_speed(&self, id: VehicleId, at: Option<f64>, upper: f64) -> Option<f64> {
        let v = &self.veh[id as usize];
        let p = &self.types[v.vtype as usize];
        let route = &self.routes[v.route as usize];
        let (lane, lane_len, pos) = self.entry_place(id, at);
        let des = self.desired_speed(v, lane);
        let mut speed = upper;
        let reach = |speed: f64| p.brake_gap(speed, p.decel, p.tau) + p.min_gap;
        let mut dist = reach(speed);
        // SUMO's `checkFailure` with `patchSpeed`: a lower speed is taken, with its braking distance
        let lowered = |speed: f64, dist: f64, nspeed: f64| {
            if nspeed < speed {
                (nspeed, reach(nspeed))
            } else {
                (speed, dist)
            }
        };
        // the lanes ahead within the braking distance; a link the vehicle may not pass now (a minor one, or a
        // light other than green with priority: SUMO's `!opened() || !havePriority()`) is stopped at
        let light_time = self.time_s - self.spec.step_s - self.spec.start_time_s;
        let mut seen = lane_len - pos;
        let mut k = 0;
        while seen < dist && k + 1 < route.lanes.len() {
            let next = route.lanes[k + 1];
            if let LaneKind::Via(link) = self.lane_at(next as usize).kind {
                let lk = self.link_at(link as usize);
                let stopped_by_light = self
                    .signal_of(lk, light_time)
                    .is_some_and(|s| s != SignalState::Green);
                if !lk.major || stopped_by_light {
                    (speed, dist) = lowered(speed, dist, p.stop_speed(seen, speed, des));
                    break;
                }
            }
            if let Some(&o) = self.lane_veh[next as usize].last() {
                let ov = &self.veh[o as usize];
                let gap = seen + ov.pos - ov.length - p.min_gap;
                if gap < 0.0 {
                    return None;
                }
                (speed, dist) = lowered(
                    speed,
                    dist,
                    p.insertion_follow_speed(speed, gap, ov.speed, des),
                );
            }
            let limit = self.desired_speed(v, next);
            (speed, dist) = lowered(speed, dist, p.free_speed(speed, seen, limit, des));
            seen += self.lane_at(next as usize).length;
            k += 1;
        }
        // the leader on the lane: the nearest vehicle ahead of the place, else the tail of one that has just left
        // the lane onto a connection
        let q = &self.lane_veh[lane as usize];
        let ahead = match at {
            Some(_) => q.iter().rev().find(|&&o| self.veh[o as usize].pos >= pos),
            None => q.last(),
        };
        let on_lane = ahead.map(|&o| {
            let ov = &self.veh[o as usize];
            (ov.pos - ov.length - pos - p.min_gap, ov.speed)
        });
        let tails = self
            .lane_at(lane as usize)
            .out_links
            .iter()
            .filter(|_| on_lane.is_none())
            .filter_map(|&lk| {
                let via = self.link_at(lk as usize).via_lane;
                let ov = &self.veh[*self.lane_veh[via as usize].last()? as usize];
                Some((lane_len - pos + ov.pos - ov.length - p.min_gap, ov.speed))
            });
        for (gap, leader_speed) in on_lane.into_iter().chain(tails) {
            if gap < 0.0 {
                return None;
            }
            (speed, dist) = lowered(
                speed,
                dist,
                p.insertion_follow_speed(speed, gap, leader_speed, des),
            );
        }
        // the vehicle behind needs its secure gap at the adapted speed
        (self.follower_allows(lane, pos, v.length, speed) && speed >= 0.0).then_some(speed)
    }

    /// The entry lane of `id`'s route, its length, and where the front is put: at `at`, or one length in.
    fn entry_place(&self, id: VehicleId, at: Option<f64>) -> (LaneIdx, f64, f64) {
        let v = &self.veh[id as usize];
        let lane = self.routes[v.route as usize].lanes[0];
        let lane_len = self.lane_at(lane as usize).length;
        (
            lane,
            lane_len,
            at.unwrap_or((v.length + POSITION_EPS).fmin(lane_len)),
        )
    }

    /// Whether the vehicle behind the place `pos` on `lane`, if any, keeps its secure gap behind a vehicle of
    /// `length` put there driving at `speed`.
    fn follower_allows(&self, lane: LaneIdx, pos: f64, length: f64, speed: f64) -> bool {
        let q = &self.lane_veh[lane as usize];
        let Some(&f) = q.iter().find(|&&o| self.veh[o as usize].pos < pos) else {
            return true;
        };
        let fv = &self.veh[f as usize];
        let fp = &self.types[fv.vtype as usize];
        let gap = pos - length - fv.pos - fp.min_gap;
        gap >= 0.0 && gap >= fp.secure_gap(fv.speed, speed)
    }

    /// The insertion check and, where it passes, the insertion: the front at `at` on the entry lane, or at its
    /// start.
    fn try_insert_at(&mut self, id: VehicleId, at: Option<f64>) -> bool {
        let rule = self.veh[id as usize].depart_speed;
        if rule.is_infinite() {
            return self.try_insert_at_desired(id, at, rule == DEPART_SPEED_MAX);
        }
        if !self.insertion_allowed_at(id, at) {
            return false;
        }
        self.place_on_entry(id, at, true);
        true
    }

    /// SUMO's `departSpeed="desired"`: at the vehicle's desired speed on its first lane, or not now; with
    /// `adapt` (`"max"`), that speed lowered as SUMO adapts it ([`Self::adapted_insertion_speed`]). The vehicle
    /// keeps its rule for a later try.
    fn try_insert_at_desired(&mut self, id: VehicleId, at: Option<f64>, adapt: bool) -> bool {
        let v = &self.veh[id as usize];
        let rule = v.depart_speed;
        let lane = self.routes[v.route as usize].lanes[0];
        let desired = self.desired_speed(v, lane);
        let speed = if adapt {
            self.adapted_insertion_speed(id, at, desired)
        } else {
            self.veh[id as usize].depart_speed = desired;
            self.insertion_allowed_at(id, at).then_some(desired)
        };
        match speed {
            Some(s) => {
                self.veh[id as usize].depart_speed = s;
                self.place_on_entry(id, at, true);
                true
            }
            None => {
                self.veh[id as usize].depart_speed = rule;
                false
            }
        }
    }

    /// Where a vehicle is inserted: at the start of its route's first lane, its front one length in.
    pub(in crate::sim) fn place_at_route_start(&mut self, id: VehicleId, counted: bool) {
        self.place_on_entry(id, None, counted);
    }

    /// Inserts a vehicle with its front at `at` on its route's first lane, or at its start.
    fn place_on_entry(&mut self, id: VehicleId, at: Option<f64>, counted: bool) {
        let (lane, _, pos) = self.entry_place(id, at);
        let speed = self.veh[id as usize].depart_speed;
        let _ = self.place(id, lane, pos, speed, counted);
    }

    /// SUMO's insertion check at [`Self::place_at_route_start`] with the vehicle's depart speed.
    pub(in crate::sim) fn insertion_allowed(&self, id: VehicleId) -> bool {
        self.insertion_allowed_at(id, None)
    }

    /// SUMO's insertion check with the front at `at` on the entry lane (`None`: its start), with the vehicle's
    /// depart speed: room behind the leader, a stop possible before a minor link within reach, and away from
    /// the lane's start, room before the follower (its secure gap).
    fn insertion_allowed_at(&self, id: VehicleId, at: Option<f64>) -> bool {
        let v = &self.veh[id as usize];
        let p = &self.types[v.vtype as usize];
        let route = &self.routes[v.route as usize];
        let (lane, lane_len, pos) = self.entry_place(id, at);
        // away from the lane's start, the vehicle behind needs its secure gap to the inserted one
        if at.is_some() && !self.follower_allows(lane, pos, v.length, v.depart_speed.fmax(0.0)) {
            return false;
        }
        let speed = v.depart_speed;
        let des = self.desired_speed(v, lane);
        // leader: last vehicle on the lane, or further along the route
        let mut seen = 0.0 - pos;
        let mut k = 0;
        let reach = speed * self.spec.step_s + p.brake_gap(speed, p.decel, p.tau) + 200.0;
        while k < route.lanes.len() && seen < reach {
            let l = route.lanes[k];
            // the leader: the last vehicle on the lane, or on the entry lane the last one ahead of the place
            let leader = match at {
                Some(_) if k == 0 => self.lane_veh[l as usize]
                    .iter()
                    .rev()
                    .find(|&&o| self.veh[o as usize].pos >= pos),
                _ => self.lane_veh[l as usize].last(),
            };
            if let Some(&o) = leader {
                let ov = &self.veh[o as usize];
                let gap = seen + ov.pos - ov.length - p.min_gap;
                if gap < 0.0 {
                    return false;
                }
                // with a given depart speed, SUMO refuses whenever the insertion follow speed falls below it,
                // which for IDM is exactly when the gap is below the desired dynamic gap
                if gap < p.secure_gap(speed, ov.speed) {
                    return false;
                }
                break;
            }
            // tails of vehicles that just left this road onto a connection
            if k == 0 {
                for &lk in &self.lane_at(l as usize).out_links {
                    let via = self.link_at(lk as usize).via_lane;
                    if let Some(&o) = self.lane_veh[via as usize].last() {
                        let ov = &self.veh[o as usize];
                        let gap = seen + lane_len + ov.pos - ov.length - p.min_gap;
                        if gap < 0.0 || gap < p.secure_gap(speed, ov.speed) {
                            return false;
                        }
                    }
                }
            }
            seen += self.lane_at(l as usize).length;
            // a minor link ahead must be reachable with a stop
            if k + 1 < route.lanes.len()
                && let LaneKind::Via(link) = self.lane_at(route.lanes[k + 1] as usize).kind
                && !self.link_at(link as usize).major
                && seen < p.brake_gap(speed, p.decel, 0.0) + speed * self.spec.step_s
            {
                let vs = p.stop_speed((seen - POSITION_EPS).fmax(0.0), speed, des);
                if vs < speed {
                    return false;
                }
            }
            k += 1;
        }
        true
    }
}

#[cfg(test)]
#[path = "insertion_tests.rs"]
mod tests;
