//! What callers read of a running simulation: clock, vehicles, neighbours, distances to junctions, the
//! controlled vehicles' commands and traces.

use super::*;

/// A vehicle that is ahead of or behind another, with the bumper-to-bumper gap in metres (without min gap).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Neighbor {
    pub id: VehicleId,
    pub gap_m: f64,
    pub speed: f64,
}

/// A vehicle on another road approaching the same merge.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct MergeFoe {
    pub id: VehicleId,
    /// Its front's distance to the merge point (end of its junction connection).
    pub dist_to_merge_m: f64,
    pub speed: f64,
}

/// A lane of the network as front ends name it: a road's lane by its index, or a junction's connection by the lanes
/// it joins.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum LaneRef {
    Road {
        road: RoadId,
        lane: u8,
    },
    Via {
        from: (RoadId, u8),
        to: (RoadId, u8),
    },
}

/// Read-only view of one vehicle.
#[derive(Clone, Debug, PartialEq)]
pub struct VehicleView<'a> {
    pub id: VehicleId,
    pub vehicle_type: &'a str,
    pub controlled: bool,
    pub status: VehicleStatus,
    /// The road the vehicle is on; for a vehicle inside a junction, the road it came from.
    pub road: RoadId,
    /// True while inside a junction (on the connection from `road` to the next road).
    pub in_junction: bool,
    /// The lane's index on `road`, 0 rightmost (inside a junction, the lane it came from).
    pub lane_index: u8,
    /// Its lane as front ends name it (inside a junction, the connection's lanes).
    pub place: LaneRef,
    pub pos_m: f64,
    pub speed: f64,
    pub length: f64,
    pub entry_order: u64,
    pub depart_s: f64,
    /// Metres driven since its insertion.
    pub distance_m: f64,
    /// Its desired speed over the speed limit (SUMO's chosen speed factor).
    pub speed_factor: f64,
    /// The time its route takes at its desired speed on every lane.
    pub free_flow_s: f64,
}

impl Simulation {
    pub fn step_s(&self) -> f64 {
        self.spec.step_s
    }

    /// Simulation time in seconds (SUMO's clock: step 0 starts at `start_time_s`).
    pub fn time_s(&self) -> f64 {
        self.time_s
    }

    /// Steps done so far.
    pub fn step_index(&self) -> u64 {
        self.step
    }

    pub fn horizon_steps(&self) -> u64 {
        self.spec.horizon_steps
    }

    /// True once the warm-up and the horizon have been simulated.
    pub fn is_done(&self) -> bool {
        self.step >= self.spec.warmup_steps + self.spec.horizon_steps
    }

    /// True while in the warm-up (metrics are not collected).
    pub fn in_warmup(&self) -> bool {
        self.step < self.spec.warmup_steps
    }

    pub fn network(&self) -> &Network {
        &self.net
    }

    pub fn spec(&self) -> &SimSpec {
        &self.spec
    }

    /// Vehicles in the network now, in lane order (downstream lanes first, front first).
    pub fn active_ids(&self) -> impl Iterator<Item = VehicleId> + '_ {
        self.lane_order
            .iter()
            .flat_map(move |&l| self.lane_veh[l as usize].iter().copied())
    }

    /// Each lane's vehicles in [`Self::active_ids`]' order, lane by lane, for observers inside the crate that
    /// read only some lanes (no view built, no lookup per vehicle).
    pub(crate) fn lanes_in_order(&self) -> impl Iterator<Item = (LaneIdx, &[VehicleId])> + '_ {
        self.lane_order
            .iter()
            .map(move |&l| (l, self.lane_veh[l as usize].as_slice()))
    }

    /// A vehicle's (position on its lane, speed, length, type index), for [`Self::lanes_in_order`]'s readers.
    pub(crate) fn vehicle_motion(&self, id: VehicleId) -> (f64, f64, f64, usize) {
        let v = &self.veh[id as usize];
        (v.pos, v.speed, v.length, v.vtype as usize)
    }

    /// Number of vehicles in the network.
    pub fn active_count(&self) -> usize {
        debug_assert_eq!(
            self.in_network,
            self.lane_veh.iter().map(|q| q.len()).sum::<usize>()
        );
        self.in_network
    }

    /// Every vehicle created so far (pending, active, arrived).
    pub fn vehicle_count(&self) -> usize {
        self.veh.len()
    }

    /// Vehicle records held now: those on the road, built and waiting to enter, and those that left recently
    /// (older ones are forgotten in long runs, so memory follows the road, not the horizon).
    pub fn vehicle_records(&self) -> usize {
        self.veh.held()
    }

    /// Ids of vehicles that left the network in the last step.
    pub fn arrived_last_step(&self) -> &[VehicleId] {
        &self.arrived_last
    }

    /// The index of the traffic light `id` (its SUMO id).
    pub fn light_index(&self, id: &str) -> Option<usize> {
        self.net.lights.iter().position(|l| l.id == id)
    }

    /// The program light `index` runs now.
    pub fn light(&self, index: usize) -> Option<&mapc_graph::TrafficLight> {
        self.net.lights.get(index)
    }

    /// Light `index` runs `phases` from now on, its cycle starting at this step (a controller's program, as
    /// SUMO's TraCI `setProgramLogic`). Phases need positive durations and one letter per controlled link.
    pub fn set_light_phases(
        &mut self,
        index: usize,
        phases: Vec<mapc_graph::SignalPhase>,
    ) -> Result<(), SimError> {
        let now = self.time_s - self.spec.start_time_s;
        let light = self
            .net
            .lights
            .get_mut(index)
            .ok_or_else(|| SimError::Spec(format!("no traffic light {index}")))?;
        let links = light.phases.first().map_or(0, |p| p.state.len());
        if phases.is_empty()
            || phases.iter().any(|p| {
                !(p.duration_s > 0.0 && p.duration_s.is_finite()) || p.state.len() != links
            })
        {
            return Err(SimError::Spec(format!(
                "light `{}`: a program needs phases of positive duration with {links} letters each",
                light.id
            )));
        }
        light.phases = phases;
        light.offset_s = now;
        // (the phases found for this step's time are the old program's)
        self.light_phases.0 = f64::NAN;
        Ok(())
    }

    /// The induction loops' completed intervals, in order of completion (the last, partial ones once the run is
    /// done), on the run's clock (0 at its begin).
    pub fn detector_intervals(&self) -> &[crate::measure::detectors::DetectorInterval] {
        self.detectors.intervals()
    }

    /// Ids of vehicles that entered the network in the last step.
    pub fn departed_last_step(&self) -> &[VehicleId] {
        &self.departed_last
    }

    pub fn vehicle(&self, id: VehicleId) -> Option<VehicleView<'_>> {
        let v = self.veh.get(id as usize)?;
        let (road, in_junction) = self.road_of_lane(v.lane);
        Some(VehicleView {
            id,
            vehicle_type: &self.spec.vehicle_types[v.vtype as usize].name,
            controlled: v.controlled,
            status: v.status,
            road,
            in_junction,
            lane_index: self.lane_index_on_road(v.lane),
            place: self.lane_ref(v.lane),
            pos_m: v.pos,
            speed: v.speed,
            length: v.length,
            entry_order: v.entry_order,
            depart_s: v.depart_s,
            distance_m: v.distance_m,
            speed_factor: v.speed_factor,
            free_flow_s: v.free_flow_s,
        })
    }

    /// Where a vehicle's back lies when it reaches behind the start of its lane (SUMO's farthest lane behind):
    /// the lane on its route and the position there; `None` when the back is on its own lane, or behind the lanes
    /// its route knows.
    pub fn back_place(&self, id: VehicleId) -> Option<(LaneRef, f64)> {
        let v = self.veh.get(id as usize)?;
        let mut back = v.pos - v.length;
        if back >= 0.0 {
            return None;
        }
        let lanes = &self.routes[v.route as usize].lanes.0;
        for &l in lanes[..v.route_pos as usize].iter().rev() {
            back += self.lane_at(l as usize).length;
            if back >= 0.0 {
                return Some((self.lane_ref(l), back));
            }
        }
        None
    }

    /// The network's lane `l` as front ends name it.
    pub fn lane_ref(&self, l: LaneIdx) -> LaneRef {
        let place = |l: LaneIdx| {
            let r = self.net.road_of(l).expect("a road lane");
            (self.net.road_ids[r], self.lane_at(l as usize).index)
        };
        match self.lane_at(l as usize).kind {
            LaneKind::Road(_) => {
                let (road, lane) = place(l);
                LaneRef::Road { road, lane }
            }
            LaneKind::Via(k) => {
                let lk = self.link_at(k as usize);
                LaneRef::Via {
                    from: place(lk.from_lane),
                    to: place(lk.to_lane),
                }
            }
        }
    }

    /// Index on its road of a road lane; for a via lane, of the lane it leaves.
    fn lane_index_on_road(&self, lane: LaneIdx) -> u8 {
        match self.lane_at(lane as usize).kind {
            LaneKind::Road(_) => self.lane_at(lane as usize).index,
            LaneKind::Via(k) => {
                self.lane_at(self.link_at(k as usize).from_lane as usize)
                    .index
            }
        }
    }

    pub(super) fn road_of_lane(&self, lane: LaneIdx) -> (RoadId, bool) {
        match self.lane_at(lane as usize).kind {
            LaneKind::Road(r) => (self.net.road_ids[r], false),
            LaneKind::Via(k) => {
                let from = self.link_at(k as usize).from_lane;
                (self.net.road_ids[self.net.road_of(from).unwrap()], true)
            }
        }
    }

    /// Whether the vehicle is in the scenario's control region (everywhere when the scenario has none).
    pub fn in_control_region(&self, id: VehicleId) -> bool {
        self.veh
            .get(id as usize)
            .is_some_and(|v| v.status == VehicleStatus::Active && self.in_region[v.lane as usize])
    }

    /// The routes the run has made so far (departures, lane changes, teleports) and their lanes in all: what the
    /// routes hold in memory.
    pub fn routes_held(&self) -> (usize, usize) {
        let lanes = self.routes.iter().map(|r| r.lanes.len()).sum();
        (self.routes.len(), lanes)
    }

    /// Distance travelled along the route so far and the route's total length.
    pub fn route_progress(&self, id: VehicleId) -> Option<(f64, f64)> {
        let v = self.veh.get(id as usize)?;
        let r = &self.routes[v.route as usize];
        let total = r.start_m.last().copied().unwrap_or(0.0)
            + r.lanes
                .last()
                .map_or(0.0, |&l| self.lane_at(l as usize).length);
        let done = match v.status {
            VehicleStatus::Pending => 0.0,
            VehicleStatus::Arrived => total,
            VehicleStatus::Active | VehicleStatus::Teleporting => {
                r.start_m[v.route_pos as usize] + v.pos
            }
        };
        Some((done, total))
    }

    /// Distance from the vehicle's front to the next junction where roads merge or split (a link with foes or a
    /// road with several exits), and that junction; `None` if no such junction lies ahead on its route.
    pub fn distance_to_next_junction(
        &self,
        id: VehicleId,
    ) -> Option<(f64, mapc_graph::JunctionId)> {
        self.distance_to_next_link(id, |l| {
            !l.foes.is_empty() || self.lane_at(l.from_lane as usize).out_links.len() > 1
        })
    }

    /// Distance from the vehicle's front to the next merge on its route (a connection onto a road that another
    /// road joins in the same junction, whichever lane it joins: on one-lane roads, a connection with foes;
    /// diverges are passed), and that junction; `None` if no merge lies ahead.
    pub fn distance_to_next_merge(&self, id: VehicleId) -> Option<(f64, mapc_graph::JunctionId)> {
        self.distance_to_next_link_at(id, |k| self.joins_another_road(k))
    }

    /// Distance from the vehicle's front to the next connection on its route that `wanted` picks, and its junction.
    pub(super) fn distance_to_next_link(
        &self,
        id: VehicleId,
        wanted: impl Fn(&SimLink) -> bool,
    ) -> Option<(f64, mapc_graph::JunctionId)> {
        self.distance_to_next_link_at(id, |k| wanted(self.link_at(k as usize)))
    }

    /// As [`Self::distance_to_next_link`], `wanted` given the link's index.
    fn distance_to_next_link_at(
        &self,
        id: VehicleId,
        wanted: impl Fn(LinkIdx) -> bool,
    ) -> Option<(f64, mapc_graph::JunctionId)> {
        let v = self
            .veh
            .get(id as usize)
            .filter(|v| v.status == VehicleStatus::Active)?;
        let r = &self.routes[v.route as usize];
        let mut seen = self.lane_at(v.lane as usize).length - v.pos;
        for k in (v.route_pos as usize + 1)..r.lanes.len() {
            let lane = self.lane_at(r.lanes[k] as usize);
            if let LaneKind::Via(link) = lane.kind
                && wanted(link)
            {
                return Some((seen, self.link_at(link as usize).junction));
            }
            seen += lane.length;
        }
        None
    }

    /// The road whose vehicles count as past the corridor's end when they leave the network (the main line's
    /// last road; `None` without a main line).
    pub fn corridor_end_road(&self) -> Option<RoadId> {
        let &(lane, _) = self.main_line.last()?;
        self.net.road_of(lane).map(|r| self.net.road_ids[r])
    }

    /// Distance from the vehicle's front to the network's end along its route position's main line
    /// (`corridor_x_m` of traces): `Some` only on main-line roads and their connections.
    pub fn corridor_x(&self, id: VehicleId) -> Option<f64> {
        let v = self
            .veh
            .get(id as usize)
            .filter(|v| v.status == VehicleStatus::Active)?;
        self.main_line
            .iter()
            .find(|(l, _)| *l == v.lane)
            .map(|(_, start)| start + v.pos)
    }

    /// The nearest vehicle ahead on the route (across lanes and junctions, including vehicles on a merging
    /// connection that are closer to the merge point), within `max_dist` metres.
    pub fn leader(&self, id: VehicleId, max_dist: f64) -> Option<Neighbor> {
        let v = self
            .veh
            .get(id as usize)
            .filter(|v| v.status == VehicleStatus::Active)?;
        let mut best: Option<Neighbor> = None;
        self.for_each_leader(id, max_dist, |l, gap| {
            if best.is_none_or(|b| gap < b.gap_m) {
                best = Some(Neighbor {
                    id: l,
                    gap_m: gap,
                    speed: self.veh[l as usize].speed,
                });
            }
        });
        let _ = v;
        best
    }

    /// The nearest vehicle behind (on this road, the connections into it, and the roads before them, the merging
    /// road included), within `max_dist` metres.
    pub fn follower(&self, id: VehicleId, max_dist: f64) -> Option<Neighbor> {
        let v = self
            .veh
            .get(id as usize)
            .filter(|v| v.status == VehicleStatus::Active)?;
        let q = &self.lane_veh[v.lane as usize];
        let idx = q.iter().position(|&o| o == id)?;
        if idx + 1 < q.len() {
            let f = q[idx + 1];
            let fv = &self.veh[f as usize];
            let gap = v.pos - v.length - fv.pos;
            return (gap <= max_dist).then_some(Neighbor {
                id: f,
                gap_m: gap,
                speed: fv.speed,
            });
        }
        self.first_behind(id, v.lane, v.pos - v.length, max_dist)
    }

    /// The nearest vehicle behind the start of `lane` (on the connections into it and the lanes before them),
    /// `back_from_start` m from `id`'s back, within `max_dist`.
    pub(super) fn first_behind(
        &self,
        id: VehicleId,
        lane: LaneIdx,
        back_from_start: f64,
        max_dist: f64,
    ) -> Option<Neighbor> {
        let mut best: Option<Neighbor> = None;
        let mut stack: Vec<(LaneIdx, f64)> = vec![(lane, back_from_start)];
        // a bound on the search, for safety against a cycle in a malformed network
        for _ in 0..64 {
            let Some((lane, back_from_start)) = stack.pop() else {
                break;
            };
            for (up, len) in self.upstream_lanes(lane) {
                if let Some(&f) = self.lane_veh[up as usize].first() {
                    let fv = &self.veh[f as usize];
                    let gap = back_from_start + (len - fv.pos);
                    if f != id && gap <= max_dist && best.is_none_or(|b| gap < b.gap_m) {
                        best = Some(Neighbor {
                            id: f,
                            gap_m: gap,
                            speed: fv.speed,
                        });
                    }
                } else if back_from_start + len <= max_dist {
                    stack.push((up, back_from_start + len));
                }
            }
        }
        best
    }

    pub(super) fn upstream_lanes(&self, lane: LaneIdx) -> Vec<(LaneIdx, f64)> {
        match self.lane_at(lane as usize).kind {
            LaneKind::Via(k) => {
                let from = self.link_at(k as usize).from_lane;
                vec![(from, self.lane_at(from as usize).length)]
            }
            LaneKind::Road(_) => self
                .net
                .links
                .iter()
                .filter(|l| l.to_lane == lane)
                .map(|l| (l.via_lane, self.lane_at(l.via_lane as usize).length))
                .collect(),
        }
    }

    /// The vehicle on another road nearest to the merge point that this vehicle's route reaches next, among those
    /// approaching it (on the merging road within `max_dist` of the merge, or inside the junction). The merge is
    /// the next junction where another road joins the road the route enters, on the same lane (one-lane roads)
    /// or on one of its own (an acceleration lane); its point is the end of the merging connection.
    pub fn nearest_merge_foe(&self, id: VehicleId, max_dist: f64) -> Option<MergeFoe> {
        let v = self
            .veh
            .get(id as usize)
            .filter(|v| v.status == VehicleStatus::Active)?;
        let r = &self.routes[v.route as usize];
        // find the next via lane on the route with foes
        let mut k = v.route_pos as usize;
        if !matches!(self.lane_at(v.lane as usize).kind, LaneKind::Via(_)) {
            k += 1;
        }
        while k < r.lanes.len() {
            if let LaneKind::Via(link) = self.lane_at(r.lanes[k] as usize).kind {
                let foes = self.joining_links(link);
                if !foes.is_empty() {
                    let mut best: Option<MergeFoe> = None;
                    for f in foes {
                        let fl = self.link_at(f as usize);
                        let via_len = self.lane_at(fl.via_lane as usize).length;
                        let mut consider = |o: VehicleId, d: f64| {
                            if o != id
                                && d <= max_dist
                                && best.is_none_or(|b| d < b.dist_to_merge_m)
                            {
                                best = Some(MergeFoe {
                                    id: o,
                                    dist_to_merge_m: d,
                                    speed: self.veh[o as usize].speed,
                                });
                            }
                        };
                        for &o in &self.lane_veh[fl.via_lane as usize] {
                            consider(o, via_len - self.veh[o as usize].pos);
                        }
                        let from_len = self.lane_at(fl.from_lane as usize).length;
                        for &o in &self.lane_veh[fl.from_lane as usize] {
                            consider(o, via_len + from_len - self.veh[o as usize].pos);
                        }
                    }
                    return best;
                }
            }
            k += 1;
        }
        None
    }

    /// Set the acceleration a controlled vehicle applies in the next step (clamped to [-decel, accel], then
    /// capped by the safe speed). An error for a vehicle that is not controlled or not in the network, and for an
    /// acceleration that is not a finite number (the vehicle keeps its command).
    pub fn set_acceleration(&mut self, id: VehicleId, accel: f64) -> Result<(), SimError> {
        let v = self
            .veh
            .get_mut(id as usize)
            .ok_or(SimError::UnknownVehicle(id))?;
        if !v.controlled {
            return Err(SimError::NotControlled(id));
        }
        if !accel.is_finite() {
            return Err(SimError::BadAcceleration { vehicle: id, accel });
        }
        v.accel_cmd = accel;
        Ok(())
    }

    /// Draw a uniform number from the run's generator (for callers that need run-bound randomness).
    pub fn random_unit(&mut self) -> f64 {
        self.rng.random::<f64>()
    }

    /// Vehicles waiting at their entry roads.
    pub fn waiting_to_enter(&self) -> usize {
        let at_roads: u64 = self.road_entries.iter().map(|e| e.queue.len()).sum();
        self.pending.iter().map(|q| q.len() as usize).sum::<usize>() + at_roads as usize
    }

    /// Per entry road of the flows (in the order of their first flow): the vehicles due to depart there since the
    /// start of the run (warm-up included), and how many of them still wait to enter; the others were inserted.
    pub fn entry_counts(&self) -> Vec<crate::measure::metrics::EntryCounts> {
        use crate::measure::metrics::EntryCounts;
        fn at(out: &mut Vec<EntryCounts>, road: RoadId) -> &mut EntryCounts {
            let i = match out.iter().position(|e| e.road == road) {
                Some(i) => i,
                None => {
                    out.push(EntryCounts {
                        road,
                        demand: 0,
                        inserted: 0,
                        waiting: 0,
                    });
                    out.len() - 1
                }
            };
            &mut out[i]
        }
        let mut out = Vec::new();
        for (flow, &due) in self.spec.flows.iter().zip(&self.flow_next) {
            at(&mut out, flow.from).demand += due;
        }
        let at_lanes = self.entry_lanes.iter().zip(&self.pending);
        let at_roads = self
            .road_entries
            .iter()
            .filter_map(|e| Some((e.lanes.first()?, &e.queue)));
        for (&lane, queue) in at_lanes.chain(at_roads) {
            if let Some(r) = self.net.road_of(lane) {
                at(&mut out, self.net.road_ids[r]).waiting += queue.len();
            }
        }
        for e in &mut out {
            e.inserted = e.demand.saturating_sub(e.waiting);
        }
        out
    }

    /// Append this step's rows to a trace ([`crate::TRACE_HEADER`]).
    pub fn write_trace_rows(&self, out: &mut impl std::io::Write) -> std::io::Result<()> {
        for id in self.active_ids() {
            let v = &self.veh[id as usize];
            let x = self
                .corridor_x(id)
                .map(|x| format!("{x:.3}"))
                .unwrap_or_default();
            writeln!(
                out,
                "{:.2},{},{},{},{:.3},{},{:.3},{},{}",
                self.time_s,
                id,
                self.spec.vehicle_types[v.vtype as usize].name,
                self.net.road_labels[v.lane as usize],
                v.pos,
                x,
                v.speed,
                v.controlled,
                self.lane_index_on_road(v.lane)
            )?;
        }
        Ok(())
    }
}
