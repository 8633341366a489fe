//! The stepping simulator: plan every vehicle's safe speed from the state at the start of the step (leaders
//! across lanes and junctions, speed limits ahead, minor-link requests), register junction approaches, decide
//! links (right of way with impatience), then move every vehicle, front to back, never into its leader.

use crate::SimError;
use crate::idm::{FastMinMax, IdmParams, NUMERICAL_EPS};
use crate::measure::MeasureAcc;
use crate::metrics::RunMetrics;
use crate::network::{FOE_VISIBILITY_M, LaneIdx, LaneKind, LinkIdx, Network, SimLane, SimLink};
use crate::spec::SimSpec;
use crate::vehicle_table::VehicleTable;
use crate::waiting::EntryQueue;
use mapc_graph::RoadId;
use rand::rngs::StdRng;
use rand::{RngExt, SeedableRng};
use rand_distr::{Distribution, Normal};

/// Index of a vehicle, stable for the whole run (vehicles are numbered in creation order).
pub type VehicleId = u32;

/// Below this speed a vehicle counts as halting (its waiting time grows).
const HALTING_SPEED: f64 = 0.1;
/// Waiting time after which impatience has grown by 1 (SUMO's default time to impatience).
const TIME_TO_IMPATIENCE_S: f64 = 300.0;
/// How far the stop point lies before a minor link's stop line (SUMO's POSITION_EPS).
const POSITION_EPS: f64 = 0.1;
/// A foe must arrive this much later than ego leaves for ego to go first (SUMO's link lookahead).
const LINK_LOOKAHEAD_S: f64 = 1.0;
/// The arrival time of a foe that could stop is this much later than its normal arrival.
const BRAKING_ARRIVAL_DELAY_S: f64 = 30.0;
/// Where merging connections start to conflict, as a share of the shorter one's length before its end
/// (netconvert's internal lanes come within a lane width of each other about a third of the way from the end).
const CONFLICT_POINT_SHARE: f64 = 0.35;
/// Links planned ahead per vehicle.
const MAX_LINK_ITEMS: usize = 4;

/// Where a vehicle is in its life.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum VehicleStatus {
    /// Scheduled or waiting at its entry: not yet in the network.
    Pending,
    Active,
    Arrived,
}

#[derive(Clone, Debug)]
struct Veh {
    vtype: u16,
    controlled: bool,
    status: VehicleStatus,
    lane: LaneIdx,
    pos: f64,
    speed: f64,
    length: f64,
    speed_factor: f64,
    route: u32,
    route_pos: u32,
    waiting_s: f64,
    depart_s: f64,
    arrive_s: f64,
    /// Order of entering the network (0-based); `u64::MAX` while pending.
    entry_order: u64,
    /// Acceleration for the next step (controlled vehicles), NaN when none was set.
    accel_cmd: f64,
    depart_speed: f64,
    distance_m: f64,
    free_flow_s: f64,
}

#[derive(Clone, Copy, Debug, Default)]
struct LinkItem {
    link: LinkIdx,
    dist: f64,
    v_link_pass: f64,
    /// Where the vehicle would stop for this link (the speed to do so is computed only when it must wait).
    stop_dist: f64,
    desired_speed: f64,
    arrival_time: f64,
    arrival_speed: f64,
    leave_time: f64,
    leave_speed: f64,
    arrival_time_braking: f64,
    arrival_speed_braking: f64,
    will_pass: bool,
}

#[derive(Clone, Copy, Debug, Default)]
struct Plan {
    v_safe: f64,
    /// `brake_gap(speed, decel, 0)` at the step's start speed once planning needed it, NaN before.
    stop_brake_gap: f64,
    n_items: u8,
    items: [LinkItem; MAX_LINK_ITEMS],
}

#[derive(Clone, Copy, Debug)]
struct Approach {
    veh: VehicleId,
    arrival_time: f64,
    leave_time: f64,
    leave_speed: f64,
    arrival_time_braking: f64,
    arrival_speed_braking: f64,
    will_pass: bool,
    decel: f64,
}

#[derive(Clone, Debug)]
struct Route {
    lanes: Table<LaneIdx>,
    /// Distance from the route's start to the start of each lane.
    start_m: Table<f64>,
}

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
    pub pos_m: f64,
    pub speed: f64,
    pub length: f64,
    pub entry_order: u64,
    pub depart_s: f64,
}

/// A running simulation of one seed.
pub struct Simulation {
    net: Network,
    spec: SimSpec,
    types: Table<IdmParams>,
    routes: Table<Route>,
    veh: VehicleTable<Veh>,
    /// Vehicles per lane, front first (a plain vector: lanes are short and indexing is on the hot path).
    lane_veh: Table<Table<VehicleId>>,
    lane_order: Vec<LaneIdx>,
    plans: Table<Plan>,
    /// This step's (vehicle, index in its lane) in planning order (kept to reuse its allocation).
    plan_order: Vec<(VehicleId, u32)>,
    approaches: Table<Vec<Approach>>,
    link_has_minor_foe: Table<bool>,
    /// Per entry lane, the vehicles waiting to be inserted, in departure order.
    pending: Vec<EntryQueue>,
    entry_lanes: Vec<LaneIdx>,
    flow_next: Vec<u64>,
    flow_route: Vec<u32>,
    in_region: Table<bool>,
    rng: StdRng,
    step: u64,
    time_s: f64,
    next_entry: u64,
    arrived_last: Vec<VehicleId>,
    departed_last: Vec<VehicleId>,
    main_line: Vec<(LaneIdx, f64)>,
    metrics: MetricsAcc,
    measure: MeasureAcc,
    check_invariants: bool,
    /// Longest vehicle of any type (m).
    max_length: f64,
    /// Per vehicle type, what the hot loop reads (cached from the spec and the IDM parameters).
    type_consts: Table<TypeConsts>,
}

/// Values of one vehicle type that do not change during a run.
#[derive(Clone, Copy, Debug)]
struct TypeConsts {
    max_speed: f64,
    impatience: f64,
    /// Highest arrival speed at a minor link from the foe visibility point (a function of the type only).
    max_arrival_from_visibility: f64,
    /// 1 / (2 decel), for [`TypeConsts::brake_gap_above`]; `None` where it is not positive and finite (the
    /// bound does not apply).
    inv_two_decel: Option<f64>,
}

impl TypeConsts {
    /// A bound strictly above `IdmParams::brake_gap(speed, decel, headway)` as computed in floating point: the
    /// Euler sum is a right Riemann sum of the continuous stop, so it never exceeds v^2 / 2b + v headway; the
    /// margin lies far above rounding. Infinite (no shortcut) where that does not apply. Comparisons against it
    /// decide the far cases without the exact gap, which is computed only when the bound cannot decide.
    #[inline]
    fn brake_gap_above(&self, speed: f64, headway: f64) -> f64 {
        match self.inv_two_decel {
            Some(inv) if speed >= 0.0 && headway >= 0.0 => {
                (speed * speed * inv + speed * headway) * (1.0 + 1e-9) + 1e-6
            }
            _ => f64::INFINITY,
        }
    }
}

#[derive(Clone, Debug, Default)]
struct MetricsAcc {
    arrived: u64,
    departed: u64,
    speed_sum: f64,
    speed_steps: u64,
    steps: u64,
    veh_steps: u64,
    travel_time_sum: f64,
    delay_sum: f64,
}

impl Simulation {
    /// A simulation of `spec` with every random draw from `seed`.
    pub fn from_spec(spec: SimSpec, seed: u64) -> Result<Simulation, SimError> {
        spec.validate()?;
        let net = Network::from_graph(&spec.graph)?;
        let dt = spec.step_s;
        let types: Vec<IdmParams> = spec
            .vehicle_types
            .iter()
            .map(|t| {
                IdmParams::with_stepping(
                    t.accel,
                    t.decel,
                    t.emergency_decel,
                    t.tau,
                    t.min_gap,
                    t.delta,
                    dt,
                    t.idm_stepping_s,
                )
            })
            .collect();
        let mut sim = Simulation {
            lane_veh: Table(vec![Table(Vec::new()); net.lanes.len()]),
            approaches: Table(vec![Vec::new(); net.links.len()]),
            link_has_minor_foe: net
                .links
                .iter()
                .map(|l| l.foes.iter().any(|&f| !net.links[f as usize].major))
                .collect(),
            pending: Vec::new(),
            entry_lanes: Vec::new(),
            lane_order: Vec::new(),
            flow_next: vec![0; spec.flows.len()],
            flow_route: Vec::new(),
            in_region: Table(vec![true; net.lanes.len()]),
            routes: Table(Vec::new()),
            veh: VehicleTable::default(),
            plans: Table(Vec::new()),
            plan_order: Vec::new(),
            rng: StdRng::seed_from_u64(seed),
            step: 0,
            time_s: spec.start_time_s,
            next_entry: 0,
            arrived_last: Vec::new(),
            departed_last: Vec::new(),
            main_line: Vec::new(),
            metrics: MetricsAcc::default(),
            measure: MeasureAcc::new(&net, &spec.measure_points, None),
            check_invariants: cfg!(debug_assertions),
            max_length: spec
                .vehicle_types
                .iter()
                .map(|t| t.length)
                .fold(0.0, f64::max),
            type_consts: spec
                .vehicle_types
                .iter()
                .zip(&types)
                .map(|(t, p)| TypeConsts {
                    max_speed: t.max_speed,
                    impatience: t.impatience,
                    inv_two_decel: Some(0.5 / p.decel).filter(|x| *x > 0.0 && x.is_finite()),
                    max_arrival_from_visibility: IdmParams::speed_after_distance(
                        FOE_VISIBILITY_M,
                        p.maximum_safe_stop_speed(FOE_VISIBILITY_M, 0.0),
                        p.accel,
                    ),
                })
                .collect(),
            types: Table(types),
            net,
            spec,
        };
        // Downstream lanes first, so a leader has moved before its follower.
        let mut order: Vec<LaneIdx> = (0..sim.net.lanes.len() as LaneIdx).collect();
        order.sort_by(|&a, &b| {
            sim.net.lanes[a as usize]
                .downstream_m
                .total_cmp(&sim.net.lanes[b as usize].downstream_m)
                .then(a.cmp(&b))
        });
        sim.lane_order = order;
        if let Some(region) = &sim.spec.control_region {
            for (i, lane) in sim.net.lanes.iter().enumerate() {
                sim.in_region[i] = match lane.kind {
                    LaneKind::Road(r) => region.contains(&sim.net.road_ids[r]),
                    LaneKind::Via(k) => {
                        let l = &sim.net.links[k as usize];
                        let from = sim.net.road_ids[sim.net.road_of(l.from_lane).unwrap()];
                        let to = sim.net.road_ids[sim.net.road_of(l.to_lane).unwrap()];
                        region.contains(&from) && region.contains(&to)
                    }
                };
            }
        }
        for f in 0..sim.spec.flows.len() {
            let flow = sim.spec.flows[f].clone();
            let r = sim.add_route(flow.from, flow.to)?;
            sim.flow_route.push(r);
            let entry = sim.routes[r as usize].lanes[0];
            if !sim.entry_lanes.contains(&entry) {
                sim.entry_lanes.push(entry);
                sim.pending.push(EntryQueue::default());
            }
        }
        sim.main_line = sim.derive_main_line()?;
        sim.measure = MeasureAcc::new(
            &sim.net,
            &sim.spec.measure_points,
            sim.main_line.last().map(|&(l, _)| l),
        );
        // Initial vehicles: standing where the spec puts them, before the first step.
        for i in 0..sim.spec.initial.len() {
            let iv = sim.spec.initial[i].clone();
            let r = sim.add_route(iv.road, None)?;
            let lane = sim.routes[r as usize].lanes[0];
            let len = sim.net.lanes[lane as usize].length;
            if !(iv.pos_m >= 0.0 && iv.pos_m <= len) {
                return Err(SimError::Spec(format!(
                    "initial vehicle {i}: position {} m is off road {} (length {len} m)",
                    iv.pos_m, iv.road
                )));
            }
            let id = sim.create_vehicle(iv.vehicle_type, r, iv.speed);
            sim.place(id, lane, iv.pos_m, iv.speed, false)?;
        }
        Ok(sim)
    }

    fn add_route(&mut self, from: RoadId, to: Option<RoadId>) -> Result<u32, SimError> {
        let lanes = self.net.route(&self.spec.graph, from, to)?;
        if let Some(i) = self.routes.iter().position(|r| r.lanes == lanes) {
            return Ok(i as u32);
        }
        let mut start_m = Vec::with_capacity(lanes.len());
        let mut acc = 0.0;
        for &l in &lanes {
            start_m.push(acc);
            acc += self.lane_at(l as usize).length;
        }
        self.routes.push(Route {
            lanes: Table(lanes),
            start_m: Table(start_m),
        });
        Ok(self.routes.len() as u32 - 1)
    }

    fn derive_main_line(&mut self) -> Result<Vec<(LaneIdx, f64)>, SimError> {
        let roads: Vec<RoadId> = if !self.spec.main_line.is_empty() {
            self.spec.main_line.clone()
        } else if let Some(f) = self.spec.flows.iter().max_by(|a, b| {
            a.vehs_per_hour
                .total_cmp(&b.vehs_per_hour)
                .then(b.from.cmp(&a.from))
        }) {
            let lanes = self.net.route(&self.spec.graph, f.from, None)?;
            lanes
                .iter()
                .filter_map(|&l| self.net.road_of(l))
                .map(|r| self.net.road_ids[r])
                .collect()
        } else {
            return Ok(Vec::new());
        };
        let lanes = self
            .net
            .route(&self.spec.graph, roads[0], roads.last().copied())?;
        let mut acc = 0.0;
        let mut out = Vec::with_capacity(lanes.len());
        for l in lanes {
            out.push((l, acc));
            acc += self.lane_at(l as usize).length;
        }
        Ok(out)
    }

    fn create_vehicle(&mut self, vtype: usize, route: u32, depart_speed: f64) -> VehicleId {
        let t = &self.spec.vehicle_types[vtype];
        let factor = if t.speed_dev > 0.0 {
            // SUMO redraws until the factor lies in [0.2, 2] (at most 10 tries, then the mean).
            let normal = Normal::new(t.speed_factor, t.speed_dev).expect("validated deviation");
            let mut f = t.speed_factor;
            for _ in 0..10 {
                let x: f64 = normal.sample(&mut self.rng);
                if (0.2..=2.0).contains(&x) {
                    f = x;
                    break;
                }
            }
            f
        } else {
            t.speed_factor
        };
        let route_lanes = &self.routes[route as usize].lanes;
        let free_flow_s: f64 = route_lanes
            .iter()
            .map(|&l| {
                let lane = self.lane_at(l as usize);
                lane.length / (lane.speed_limit * factor).fmin(t.max_speed)
            })
            .sum();
        let id = self.veh.len() as VehicleId;
        self.veh.push(Veh {
            vtype: vtype as u16,
            controlled: t.controlled,
            status: VehicleStatus::Pending,
            lane: route_lanes[0],
            pos: 0.0,
            speed: 0.0,
            length: t.length,
            speed_factor: factor,
            route,
            route_pos: 0,
            waiting_s: 0.0,
            depart_s: f64::NAN,
            arrive_s: f64::NAN,
            entry_order: u64::MAX,
            accel_cmd: f64::NAN,
            depart_speed,
            distance_m: 0.0,
            free_flow_s,
        });
        id
    }

    /// Put a vehicle into the network at the back of `lane`.
    fn place(
        &mut self,
        id: VehicleId,
        lane: LaneIdx,
        pos: f64,
        speed: f64,
        counted: bool,
    ) -> Result<(), SimError> {
        let q = &mut self.lane_veh[lane as usize];
        // keep the lane sorted front-first
        let at = q
            .iter()
            .position(|&o| self.veh[o as usize].pos < pos)
            .unwrap_or(q.len());
        q.insert(at, id);
        let v = &mut self.veh[id as usize];
        v.status = VehicleStatus::Active;
        v.lane = lane;
        v.pos = pos;
        v.speed = speed;
        v.depart_s = self.time_s;
        v.entry_order = self.next_entry;
        self.next_entry += 1;
        if counted {
            self.metrics.departed += 1;
            self.departed_last.push(id);
        }
        Ok(())
    }

    /// Puts a vehicle into the network as another simulator saw it: on the route that starts at road `from`,
    /// `lane_in_route` lanes along it (roads and connections alternate), front at `pos` m on that lane, with its
    /// speed, speed factor and time spent halting. For vehicle-by-vehicle comparisons (docs/calibration.md):
    /// replay a SUMO state, take one step, compare every vehicle's next speed.
    #[allow(clippy::too_many_arguments)]
    pub fn place_replica(
        &mut self,
        vtype: usize,
        from: RoadId,
        lane_in_route: usize,
        pos: f64,
        speed: f64,
        speed_factor: f64,
        waiting_s: f64,
    ) -> Result<VehicleId, SimError> {
        if vtype >= self.spec.vehicle_types.len() {
            return Err(SimError::Spec(format!("no vehicle type {vtype}")));
        }
        let r = self.add_route(from, None)?;
        let Some(&lane) = self.routes[r as usize].lanes.get(lane_in_route) else {
            return Err(SimError::Spec(format!(
                "the route from {from} has no lane {lane_in_route}"
            )));
        };
        let len = self.lane_at(lane as usize).length;
        if !(0.0..=len).contains(&pos) || !(speed >= 0.0) || !(speed_factor > 0.0) {
            return Err(SimError::Spec(format!(
                "replica on lane {lane_in_route} of the route from {from}: position {pos} m (lane {len} m), \
                 speed {speed}, speed factor {speed_factor}"
            )));
        }
        let id = self.create_vehicle(vtype, r, speed);
        let v = &mut self.veh[id as usize];
        v.speed_factor = speed_factor;
        v.route_pos = lane_in_route as u32;
        v.waiting_s = waiting_s;
        self.place(id, lane, pos, speed, false)?;
        Ok(id)
    }

    // ----------------------------------------------------------------------------------------------------------
    // Queries
    // ----------------------------------------------------------------------------------------------------------

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
    /// Number of vehicles in the network.
    pub fn active_count(&self) -> usize {
        self.lane_veh.iter().map(|q| q.len()).sum()
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
            pos_m: v.pos,
            speed: v.speed,
            length: v.length,
            entry_order: v.entry_order,
            depart_s: v.depart_s,
        })
    }

    fn road_of_lane(&self, lane: LaneIdx) -> (RoadId, bool) {
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
            VehicleStatus::Active => r.start_m[v.route_pos as usize] + v.pos,
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

    /// Distance from the vehicle's front to the next merge on its route (a connection with foes; diverges are
    /// passed), and that junction; `None` if no merge lies ahead.
    pub fn distance_to_next_merge(&self, id: VehicleId) -> Option<(f64, mapc_graph::JunctionId)> {
        self.distance_to_next_link(id, |l| !l.foes.is_empty())
    }

    /// Distance from the vehicle's front to the next connection on its route that `wanted` picks, and its junction.
    fn distance_to_next_link(
        &self,
        id: VehicleId,
        wanted: impl Fn(&SimLink) -> bool,
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
                && wanted(self.link_at(link as usize))
            {
                return Some((seen, self.link_at(link as usize).junction));
            }
            seen += lane.length;
        }
        None
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
        // Search upstream: distance from the start of a lane to ego's back.
        let mut best: Option<Neighbor> = None;
        let mut stack: Vec<(LaneIdx, f64)> = vec![(v.lane, v.pos - v.length)];
        let mut visited = 0;
        while let Some((lane, back_from_start)) = stack.pop() {
            visited += 1;
            if visited > 64 {
                break;
            }
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

    fn upstream_lanes(&self, lane: LaneIdx) -> Vec<(LaneIdx, f64)> {
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
    /// approaching it (on the merging road within `max_dist` of the merge, or inside the junction).
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
                let foes = &self.link_at(link as usize).foes;
                if !foes.is_empty() {
                    let mut best: Option<MergeFoe> = None;
                    for &f in foes {
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
    /// capped by the safe speed). Ignored for vehicles that are not controlled or not in the network.
    pub fn set_acceleration(&mut self, id: VehicleId, accel: f64) -> Result<(), SimError> {
        let v = self
            .veh
            .get_mut(id as usize)
            .ok_or(SimError::UnknownVehicle(id))?;
        if !v.controlled {
            return Err(SimError::NotControlled(id));
        }
        if accel.is_finite() {
            v.accel_cmd = accel;
        }
        Ok(())
    }

    pub fn metrics(&self) -> RunMetrics {
        let m = &self.metrics;
        let secs = (m.steps as f64 * self.spec.step_s).fmax(f64::MIN_POSITIVE);
        RunMetrics {
            outflow_veh_h: 3600.0 * m.arrived as f64 / secs,
            inflow_veh_h: 3600.0 * m.departed as f64 / secs,
            avg_speed_mps: if m.speed_steps > 0 {
                m.speed_sum / m.speed_steps as f64
            } else {
                0.0
            },
            mean_travel_time_s: if m.arrived > 0 {
                m.travel_time_sum / m.arrived as f64
            } else {
                f64::NAN
            },
            mean_delay_s: if m.arrived > 0 {
                m.delay_sum / m.arrived as f64
            } else {
                f64::NAN
            },
            arrived: m.arrived,
            departed: m.departed,
            steps: m.steps,
            vehicle_steps: m.veh_steps,
            end_flow_veh_h: 3600.0 * self.measure.end_count as f64 / secs,
            merge_flows_veh_h: self
                .measure
                .counts
                .iter()
                .map(|&c| 3600.0 * c as f64 / secs)
                .collect(),
        }
    }

    /// Turn the per-step collision check on or off (on by default in debug builds).
    pub fn set_invariant_checks(&mut self, on: bool) {
        self.check_invariants = on;
    }

    // ----------------------------------------------------------------------------------------------------------
    // Stepping
    // ----------------------------------------------------------------------------------------------------------

    /// Run to the horizon.
    pub fn run(&mut self) -> Result<RunMetrics, SimError> {
        while !self.is_done() {
            self.step()?;
        }
        Ok(self.metrics())
    }

    /// Advance one step.
    pub fn step(&mut self) -> Result<(), SimError> {
        // records of vehicles that left before the last step may go (their ids were reported then)
        let now = self.time_s;
        self.veh
            .forget_finished(|v| v.status == VehicleStatus::Arrived && v.arrive_s < now);
        self.arrived_last.clear();
        self.departed_last.clear();
        if self.step == self.spec.warmup_steps {
            self.metrics = MetricsAcc::default();
            self.measure.reset();
        }
        // Metrics see the network as it is before the step (as the original rollouts did).
        let mut n = 0u64;
        let mut sum = 0.0;
        for q in self.lane_veh.iter() {
            for &id in q {
                n += 1;
                sum += self.veh[id as usize].speed;
            }
        }
        if n > 0 && sum / n as f64 > 0.0 {
            self.metrics.speed_sum += sum / n as f64;
            self.metrics.speed_steps += 1;
        }
        self.metrics.veh_steps += n;

        for a in &mut self.approaches {
            a.clear();
        }
        // plans are stored in visiting order (lane order, front to back), which the moves visit again unchanged
        let mut plans = std::mem::take(&mut self.plans);
        if plans.len() < n as usize {
            plans.resize(n as usize, Plan::default());
        }
        // visiting order: lane order, front to back
        let mut order = std::mem::take(&mut self.plan_order);
        order.clear();
        for &lane in &self.lane_order {
            for (qi, &id) in self.lane_veh[lane as usize].iter().enumerate() {
                order.push((id, qi as u32));
            }
        }
        // each vehicle's IDM batch is started one plan ahead, so that its division chains run while the vehicle
        // before it is planned (planning changes no position or speed, so the batch's arguments stay valid)
        let mut pre_next = order
            .first()
            .map_or([0.0; 4], |&(id, qi)| self.plan_idm_batch(id, qi as usize));
        for pi in 0..order.len() {
            let pre = pre_next;
            if let Some(&(id, qi)) = order.get(pi + 1) {
                pre_next = self.plan_idm_batch(id, qi as usize);
            }
            let (id, qi) = order[pi];
            self.plan(id, qi as usize, pre, &mut plans[pi]);
        }
        self.plan_order = order;
        self.plans = plans;
        self.execute_moves();
        self.time_s += self.spec.step_s;
        self.step += 1;
        self.metrics.steps += 1;
        self.insert_departures();
        if self.check_invariants {
            self.check_no_overlap()?;
        }
        Ok(())
    }

    /// The network's lane `i` (indices come from the network itself; checked in debug builds).
    #[inline(always)]
    fn lane_at(&self, i: usize) -> &SimLane {
        debug_assert!(i < self.net.lanes.len());
        // SAFETY: lane indices are created by `Network::from_graph` and never exceed its lanes
        unsafe { self.net.lanes.get_unchecked(i) }
    }

    /// The network's link `i` (indices come from the network itself; checked in debug builds).
    #[inline(always)]
    fn link_at(&self, i: usize) -> &SimLink {
        debug_assert!(i < self.net.links.len());
        // SAFETY: link indices are created by `Network::from_graph` and never exceed its links
        unsafe { self.net.links.get_unchecked(i) }
    }

    fn desired_speed(&self, v: &Veh, lane: LaneIdx) -> f64 {
        (self.lane_at(lane as usize).speed_limit * v.speed_factor)
            .fmin(self.type_consts[v.vtype as usize].max_speed)
    }

    /// Calls `f(leader, gap)` for every vehicle the ego must follow within `max_dist` (gap: bumper to bumper).
    fn for_each_leader(&self, id: VehicleId, max_dist: f64, f: impl FnMut(VehicleId, f64)) {
        let v = &self.veh[id as usize];
        let idx = self.lane_veh[v.lane as usize]
            .iter()
            .position(|&o| o == id)
            .unwrap_or(0);
        self.for_each_leader_at(id, idx, max_dist, None, f)
    }

    /// As [`Self::for_each_leader`] for the vehicle at index `idx` of its lane. `moving`: the distance the ego
    /// travels in this step when the call guards a move (`None` for a query of the state).
    fn for_each_leader_at(
        &self,
        id: VehicleId,
        idx: usize,
        max_dist: f64,
        moving: Option<f64>,
        mut f: impl FnMut(VehicleId, f64),
    ) {
        let v = &self.veh[id as usize];
        let q = &self.lane_veh[v.lane as usize];
        if idx > 0 {
            let l = q[idx - 1];
            let lv = &self.veh[l as usize];
            f(l, lv.pos - lv.length - v.pos);
            return;
        }
        self.leaders_beyond(id, max_dist, moving, &mut f);
    }

    /// Leaders beyond the ego's own lane: on the lanes ahead on its route, tails of vehicles that just entered a
    /// connection, and vehicles on merging connections that are closer to the merge point.
    fn leaders_beyond(
        &self,
        id: VehicleId,
        max_dist: f64,
        moving: Option<f64>,
        f: &mut impl FnMut(VehicleId, f64),
    ) {
        let guard = moving.is_some();
        let v = &self.veh[id as usize];
        let r = &self.routes[v.route as usize];
        let cur = self.lane_at(v.lane as usize);
        let mut seen = cur.length - v.pos;
        let on_via = matches!(cur.kind, LaneKind::Via(_));
        if on_via {
            self.junction_foe_leaders(id, v.lane, seen, guard, f);
        } else {
            // tails of vehicles on any connection out of this road still reach back onto it
            for &k in &cur.out_links {
                let via = self.link_at(k as usize).via_lane;
                if let Some(&o) = self.lane_veh[via as usize].last() {
                    let ov = &self.veh[o as usize];
                    if ov.pos < ov.length && r.lanes.get(v.route_pos as usize + 1) != Some(&via) {
                        f(o, seen + ov.pos - ov.length);
                    }
                }
            }
        }
        let mut k = v.route_pos as usize + 1;
        while k < r.lanes.len() && seen <= max_dist {
            let lane = r.lanes[k];
            let l = self.lane_at(lane as usize);
            // a moving vehicle that stays before its stop line this step cannot meet vehicles on merging
            // connections (they meet only inside the junction)
            let may_enter = moving.is_none_or(|travel| seen < travel);
            if let LaneKind::Via(link) = l.kind
                && may_enter
                && !self.link_at(link as usize).foes.is_empty()
            {
                self.junction_foe_leaders(id, lane, seen + l.length, guard, f);
            }
            if let Some(&o) = self.lane_veh[lane as usize].last() {
                let ov = &self.veh[o as usize];
                f(o, seen + ov.pos - ov.length);
                return;
            }
            seen += l.length;
            k += 1;
        }
    }

    /// Vehicles on connections merging with `via` (or about to enter them) whose front is closer to the merge
    /// point than ego's front at `dist_to_merge`.
    fn junction_foe_leaders(
        &self,
        id: VehicleId,
        via: LaneIdx,
        dist_to_merge: f64,
        guard: bool,
        f: &mut impl FnMut(VehicleId, f64),
    ) {
        let LaneKind::Via(link) = self.lane_at(via as usize).kind else {
            return;
        };
        let ego_in_junction = self.veh[id as usize].lane == via;
        // only a moving check or an ego inside the junction looks at foes still before their stop line
        let check_from = guard || ego_in_junction;
        let own = self.link_at(link as usize);
        let ego_has_priority_inside = ego_in_junction && own.major;
        for &foe in &own.foes {
            let fl = self.link_at(foe as usize);
            let flen = self.lane_at(fl.via_lane as usize).length;
            // a minor-road vehicle beside ego and short of the conflict point yields to ego
            // (`yield_inside_junction`): it does not lead, or both would wait for each other
            let beside_yields = ego_has_priority_inside && !fl.major;
            for &o in self.lane_veh[fl.via_lane as usize].iter() {
                let ov = &self.veh[o as usize];
                let d = flen - ov.pos;
                if d >= dist_to_merge {
                    continue;
                }
                let gap = dist_to_merge - d - ov.length;
                if beside_yields
                    && gap < 0.0
                    && d > CONFLICT_POINT_SHARE * self.lane_at(via as usize).length.fmin(flen)
                {
                    continue;
                }
                f(o, gap);
            }
            // a minor-road vehicle at its stop line enters only when its link opens: an ego with right of way
            // does not brake for it
            if !check_from || beside_yields {
                continue;
            }
            if let Some(&o) = self.lane_veh[fl.from_lane as usize].first() {
                let ov = &self.veh[o as usize];
                let from_len = self.lane_at(fl.from_lane as usize).length;
                let d = flen + from_len - ov.pos;
                // planning: a foe at its stop line may enter this very step ahead of ego (already inside);
                // moving: a foe that entered in this step (moved past its road's end) leads ego
                let relevant = if guard {
                    ov.pos > from_len
                } else {
                    ego_in_junction && d - flen < ov.speed * self.spec.step_s + 1.0
                };
                if d < dist_to_merge && relevant {
                    f(o, dist_to_merge - d - ov.length);
                }
            }
        }
    }

    /// A minor-road vehicle inside the junction that has not reached the conflict point yet keeps yielding to every
    /// major-road vehicle inside the junction, even one behind it (SUMO's right of way among junction leaders):
    /// with a negative gap it brakes as hard as it can.
    fn yield_inside_junction(&self, id: VehicleId, link: LinkIdx, p: &IdmParams, des: f64) -> f64 {
        let lk = self.link_at(link as usize);
        let mut vmax = f64::INFINITY;
        if lk.major || lk.foes.is_empty() {
            return vmax;
        }
        let v = &self.veh[id as usize];
        let own_len = self.lane_at(lk.via_lane as usize).length;
        let d = own_len - v.pos;
        for &foe in &lk.foes {
            let fl = self.link_at(foe as usize);
            if !fl.major {
                continue;
            }
            let flen = self.lane_at(fl.via_lane as usize).length;
            if d <= CONFLICT_POINT_SHARE * own_len.fmin(flen) {
                continue;
            }
            for &o in &self.lane_veh[fl.via_lane as usize] {
                let ov = &self.veh[o as usize];
                let df = flen - ov.pos;
                if df >= d {
                    vmax = vmax.fmin(p.follow_speed(
                        d - df - ov.length - p.min_gap,
                        v.speed,
                        ov.speed,
                        des,
                    ));
                }
            }
        }
        vmax
    }

    /// The four IDM steps most plans need, whose arguments are known before planning: behind the own leader, the
    /// free speed towards the current lane's speed, and behind the last vehicles on the next two lanes of the
    /// route (gaps summed as the look-ahead in [`Self::plan`] sums them). One `next_speed_x4` call, the same bits
    /// as four calls; entries without a vehicle hold a result nobody reads.
    #[inline(always)]
    fn plan_idm_batch(&self, id: VehicleId, qi: usize) -> [f64; 4] {
        let v = &self.veh[id as usize];
        let p = &self.types[v.vtype as usize];
        let des_cur = self.desired_speed(v, v.lane);
        let mut gap = [1e6; 4];
        let mut leader = [0.0; 4];
        if qi > 0 {
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
        p.next_speed_x4(gap, v.speed, leader, des_cur, [true, false, true, true])
    }

    /// One vehicle's plan for this step, as SUMO's `MSVehicle::planMoveInternal` builds it: walk the lanes of the
    /// route ahead, adapting the safe speed to the last vehicle on every lane, to vehicles on merging connections,
    /// and to each next lane's speed (IDM's free speed); at every link where right of way is decided, record the
    /// request (arrival and leave times and speeds) that foes check.
    fn plan(&mut self, id: VehicleId, qi: usize, pre: [f64; 4], plan: &mut Plan) {
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

        // `pre`: most of the plan's IDM steps, computed together ([`Self::plan_idm_batch`])
        let pre_has_free = speed <= des_cur;

        // Leader on the own lane.
        if qi > 0 {
            let vs = pre[0];
            debug_assert_eq!(vs.to_bits(), {
                let lv = &self.veh[self.lane_veh[v.lane as usize][qi - 1] as usize];
                p.follow_speed(
                    lv.pos - lv.length - v.pos - p.min_gap,
                    speed,
                    lv.speed,
                    des_cur,
                )
                .to_bits()
            });
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
                p.free_speed_near_limit(free_cache.1, seen, max_speed)
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
                    let vs = if ahead <= 2 {
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
            if k + 1 >= r.lanes.len() {
                // final lane: drive out at the lane's speed (SUMO's arrival handling)
                let lane_max = self.desired_speed(v, lane);
                let va = free_speed(seen - lane_max * dt, lane_max).fmax(NUMERICAL_EPS);
                vv = vv.fmin(va);
                if let Some(i) = last_item {
                    let it = &mut plan.items[i];
                    it.leave_speed = it.leave_speed.fmin(va);
                }
                break;
            }
            let next = r.lanes[k + 1];
            let next_ref = self.lane_at(next as usize);
            if let LaneKind::Via(cur_link) = lane_ref.kind {
                // the exit link of a junction: vehicles on merging connections closer to the merge point lead
                let cur_major = self.link_at(cur_link as usize).major;
                if k > v.route_pos as usize && !self.link_at(cur_link as usize).foes.is_empty() {
                    let mut m = f64::INFINITY;
                    self.junction_foe_leaders(id, lane, seen, false, &mut |o, gap| {
                        m = m.fmin(p.follow_speed(
                            gap - p.min_gap,
                            speed,
                            self.veh[o as usize].speed,
                            des_cur,
                        ));
                    });
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
                    }
                }
                had_non_internal = true;
                last_item = None;
            } else if let LaneKind::Via(link) = next_ref.kind {
                let lk = self.link_at(link as usize);
                // only links where right of way is decided need a request: minor links, and major links with
                // minor foes
                if (plan.n_items as usize) < MAX_LINK_ITEMS
                    && (!lk.major || self.link_has_minor_foe[link as usize])
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
            let va = free_speed(seen, next_max).fmax(min_comfortable);
            vv = vv.fmin(va);
            if !matches!(next_ref.kind, LaneKind::Via(_)) {
                seen_non_internal += next_ref.length;
            }
            seen += next_ref.length;
            v_link_pass = LazyPassSpeed::new(next_ref.length, vv, p.accel, next_max);
            lane = next;
            k += 1;
        }
        plan.v_safe = vv;
        // leave times from the final leave speeds; register approaches on links that minor foes check
        for it in &mut plan.items[..plan.n_items as usize] {
            let via_len = self
                .lane_at(self.link_at(it.link as usize).via_lane as usize)
                .length;
            it.leave_time = it.arrival_time
                + (via_len + v.length)
                    / (0.5 * (it.arrival_speed + it.leave_speed)).fmax(NUMERICAL_EPS);
            if self.link_has_minor_foe[it.link as usize] {
                self.approaches[it.link as usize].push(Approach {
                    veh: id,
                    arrival_time: it.arrival_time,
                    leave_time: it.leave_time,
                    leave_speed: it.leave_speed,
                    arrival_time_braking: it.arrival_time_braking,
                    arrival_speed_braking: it.arrival_speed_braking,
                    will_pass: it.will_pass,
                    decel: p.decel,
                });
            }
        }
    }

    /// The request for entering the connection `link` at distance `seen` (SUMO's `DriveProcessItem`): arrival time
    /// and speed (a driver approaching a minor link slows so it could still stop once it sees the foes), the
    /// arrival when braking now, and the leave speed (lowered later by constraints beyond the link).
    #[allow(clippy::too_many_arguments)]
    fn link_request(
        &self,
        v: &Veh,
        p: &IdmParams,
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
            .fmin(IdmParams::speed_after_distance(
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

    /// SUMO's `MSLink::opened` for a minor link at a merge: blocked by any foe approach that conflicts in time.
    fn link_opened(&self, id: VehicleId, it: &LinkItem, can_brake: bool) -> bool {
        let lk = self.link_at(it.link as usize);
        if lk.major {
            return true;
        }
        let v = &self.veh[id as usize];
        let tc = &self.type_consts[v.vtype as usize];
        // a driver who can no longer stop takes any gap
        let impatience = if can_brake {
            (tc.impatience + v.waiting_s / TIME_TO_IMPATIENCE_S).clamp(0.0, 1.0)
        } else {
            1.0
        };
        // the spec's deceleration, which the IDM parameters carry unchanged
        let decel = self.types[v.vtype as usize].decel;
        for &foe in &lk.foes {
            for a in &self.approaches[foe as usize] {
                if a.veh == id || !a.will_pass {
                    continue;
                }
                if a.leave_time < it.arrival_time {
                    // ego would follow the foe
                    if it.arrival_time - a.leave_time < LINK_LOOKAHEAD_S
                        || unsafe_merge_speeds(a.leave_speed, it.arrival_speed, a.decel, decel)
                    {
                        return false;
                    }
                } else if (1.0 - impatience) * a.arrival_time + impatience * a.arrival_time_braking
                    > it.leave_time + LINK_LOOKAHEAD_S
                {
                    // (the left side is the foe's arrival as an impatient driver expects it)
                    // ego would lead the foe
                    if unsafe_merge_speeds(it.leave_speed, a.arrival_speed_braking, decel, a.decel)
                    {
                        return false;
                    }
                } else {
                    return false;
                }
            }
        }
        true
    }

    fn execute_moves(&mut self) {
        let dt = self.spec.step_s;
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
                for it in &plan.items[..plan.n_items as usize] {
                    let lk = self.link_at(it.link as usize);
                    if lk.major {
                        continue;
                    }
                    let tc = &self.type_consts[v.vtype as usize];
                    let can_brake = it.dist > tc.brake_gap_above(v.speed, 0.0)
                        || it.dist
                            > if plan.stop_brake_gap.is_nan() {
                                p.brake_gap(v.speed, p.decel, 0.0)
                            } else {
                                plan.stop_brake_gap
                            }
                        || v.speed < p.decel * dt;
                    let opened = it.will_pass && self.link_opened(id, it, can_brake);
                    if !opened && (can_brake || !it.will_pass) {
                        let v_link_wait = it.v_link_pass.fmin(p.stop_speed(
                            it.stop_dist,
                            v.speed,
                            it.desired_speed,
                        ));
                        v_safe = v_safe.fmin(v_link_wait);
                        break;
                    }
                }
                // finalise: acceleration and deceleration bounds (emergency braking allowed when unsafe)
                let v_max = v_safe.fmin(v.speed + p.accel * dt);
                let v_min = (v.speed - p.decel * dt)
                    .fmin(v_safe.fmax(v.speed - p.emergency_decel * dt))
                    .fmax(0.0);
                let mut next = v_max.fmax(v_min);
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
                v.waiting_s = if next < HALTING_SPEED {
                    v.waiting_s + dt
                } else {
                    0.0
                };
                qi += 1;
            }
        }
        // 3. lane changes along routes and arrivals; vehicles moved into a lane are appended behind its others
        for li in 0..self.lane_order.len() {
            let lane = self.lane_order[li];
            while let Some(&id) = self.lane_veh[lane as usize].first() {
                let len = self.lane_at(lane as usize).length;
                let v = &self.veh[id as usize];
                let r = &self.routes[v.route as usize];
                let last = v.route_pos as usize + 1 >= r.lanes.len();
                if last {
                    if v.pos > len - POSITION_EPS {
                        self.lane_veh[lane as usize].remove(0);
                        self.arrive(id);
                        continue;
                    }
                    break;
                }
                if v.pos <= len {
                    break;
                }
                self.lane_veh[lane as usize].remove(0);
                let mut v_pos = v.pos;
                let mut rp = v.route_pos as usize;
                // a fast vehicle may cross a short connection in one step
                let mut arrived = false;
                while v_pos > self.lane_at(r.lanes[rp] as usize).length {
                    v_pos -= self.lane_at(r.lanes[rp] as usize).length;
                    rp += 1;
                    self.measure.entered(r.lanes[rp]);
                    if rp + 1 >= r.lanes.len()
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
            }
        }
    }

    fn arrive(&mut self, id: VehicleId) {
        let v = &mut self.veh[id as usize];
        v.status = VehicleStatus::Arrived;
        v.arrive_s = self.time_s + self.spec.step_s;
        if let Some(&last) = self.routes[v.route as usize].lanes.last() {
            self.measure.arrived(last);
        }
        self.metrics.arrived += 1;
        let tt = v.arrive_s - v.depart_s;
        self.metrics.travel_time_sum += tt;
        self.metrics.delay_sum += (tt - v.free_flow_s).fmax(0.0);
        self.arrived_last.push(id);
    }

    /// Create the flows' vehicles due by now and insert waiting vehicles where it is safe (SUMO's insertion: at
    /// most one per entry lane and step; a refused vehicle blocks the ones behind it).
    fn insert_departures(&mut self) {
        let now = self.time_s - self.spec.step_s; // insertion happens within the step just executed
        for f in 0..self.spec.flows.len() {
            let flow = self.spec.flows[f].clone();
            if flow.vehs_per_hour <= 0.0 {
                continue;
            }
            let period = 3600.0 / flow.vehs_per_hour;
            loop {
                let depart = flow.begin_s + self.flow_next[f] as f64 * period;
                if depart > now + 1e-9 || depart >= flow.end_s {
                    break;
                }
                let entry = self.routes[self.flow_route[f] as usize].lanes[0];
                let ei = self.entry_lanes.iter().position(|&l| l == entry).unwrap();
                if self.pending[ei].builds_next() {
                    let id = self.build_flow_vehicle(f);
                    self.pending[ei].push_built(id);
                } else {
                    self.pending[ei].push_counted(f);
                }
                self.flow_next[f] += 1;
            }
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
                    break;
                }
            }
        }
    }

    /// A new vehicle of flow `f` (pending until inserted).
    fn build_flow_vehicle(&mut self, f: usize) -> VehicleId {
        let flow = &self.spec.flows[f];
        let (vt, speed) = (flow.vehicle_type, flow.depart_speed);
        self.create_vehicle(vt, self.flow_route[f], speed)
    }

    /// SUMO's insertion check at the start of the entry road: front at length + POSITION_EPS, the depart speed
    /// safe behind the leader and able to stop before a minor link within reach.
    fn try_insert(&mut self, id: VehicleId) -> bool {
        let v = &self.veh[id as usize];
        let p = &self.types[v.vtype as usize];
        let route = &self.routes[v.route as usize];
        let lane = route.lanes[0];
        let lane_len = self.lane_at(lane as usize).length;
        let pos = (v.length + POSITION_EPS).fmin(lane_len);
        let speed = v.depart_speed;
        let des = self.desired_speed(v, lane);
        // leader: last vehicle on the lane, or further along the route
        let mut seen = 0.0 - pos;
        let mut k = 0;
        let reach = speed * self.spec.step_s + p.brake_gap(speed, p.decel, p.tau) + 200.0;
        while k < route.lanes.len() && seen < reach {
            let l = route.lanes[k];
            if let Some(&o) = self.lane_veh[l as usize].last() {
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
        let _ = self.place(id, lane, pos, speed, true);
        true
    }

    /// Every pair of consecutive vehicles keeps a non-negative gap, on lanes, from connections into roads, and
    /// between vehicles on merging connections ordered by their distance to the merge point once the follower has
    /// reached the conflict point (before it the connections run side by side).
    pub fn check_no_overlap(&self) -> Result<(), SimError> {
        const EPS: f64 = 1e-6;
        let err = |a: VehicleId, b: VehicleId, gap: f64| SimError::Collision {
            time_s: self.time_s,
            leader: a,
            follower: b,
            gap_m: gap,
            place: format!(
                "leader on {} at {:.2} m, {:.2} m/s; follower on {} at {:.2} m, {:.2} m/s",
                self.net.lane_names[self.veh[a as usize].lane as usize],
                self.veh[a as usize].pos,
                self.veh[a as usize].speed,
                self.net.lane_names[self.veh[b as usize].lane as usize],
                self.veh[b as usize].pos,
                self.veh[b as usize].speed
            ),
        };
        for (li, q) in self.lane_veh.iter().enumerate() {
            for w in q.iter().collect::<Vec<_>>().windows(2) {
                let (a, b) = (&self.veh[*w[0] as usize], &self.veh[*w[1] as usize]);
                let gap = a.pos - a.length - b.pos;
                if gap < -EPS {
                    return Err(err(*w[0], *w[1], gap));
                }
            }
            // a road's last vehicle versus the front vehicle of each connection into it
            if let LaneKind::Road(_) = self.lane_at(li).kind
                && let Some(&last) = q.last()
            {
                let lv = &self.veh[last as usize];
                for l in self.net.links.iter().filter(|l| l.to_lane as usize == li) {
                    if let Some(&f) = self.lane_veh[l.via_lane as usize].first() {
                        let fv = &self.veh[f as usize];
                        let gap = lv.pos - lv.length
                            + (self.lane_at(l.via_lane as usize).length - fv.pos);
                        if gap < -EPS {
                            return Err(err(last, f, gap));
                        }
                    }
                }
            }
        }
        // merging connections: order by distance to the merge point
        for (i, lk) in self.net.links.iter().enumerate() {
            for &foe in &lk.foes {
                if (foe as usize) < i {
                    continue;
                }
                let a_len = self.lane_at(lk.via_lane as usize).length;
                let b_len = self
                    .lane_at(self.link_at(foe as usize).via_lane as usize)
                    .length;
                for &a in &self.lane_veh[lk.via_lane as usize] {
                    for &b in &self.lane_veh[self.link_at(foe as usize).via_lane as usize] {
                        let (av, bv) = (&self.veh[a as usize], &self.veh[b as usize]);
                        let (da, db) = (a_len - av.pos, b_len - bv.pos);
                        let (lead, fol, gap) = if da <= db {
                            (a, b, db - da - av.length)
                        } else {
                            (b, a, da - db - bv.length)
                        };
                        // the connections run side by side up to the conflict point
                        let beside = da.fmax(db) > CONFLICT_POINT_SHARE * a_len.fmin(b_len);
                        if gap < -EPS && !beside {
                            return Err(err(lead, fol, gap));
                        }
                    }
                }
            }
        }
        Ok(())
    }

    /// Append this step's rows to a trace (`time_s,vehicle_id,vehicle_type,road,pos_on_road_m,corridor_x_m,
    /// speed_mps,controlled`).
    pub fn write_trace_rows(&self, out: &mut impl std::io::Write) -> std::io::Result<()> {
        for id in self.active_ids() {
            let v = &self.veh[id as usize];
            let x = self
                .corridor_x(id)
                .map(|x| format!("{x:.3}"))
                .unwrap_or_default();
            writeln!(
                out,
                "{:.2},{},{},{},{:.3},{},{:.3},{}",
                self.time_s,
                id,
                self.spec.vehicle_types[v.vtype as usize].name,
                self.net.lane_names[v.lane as usize],
                v.pos,
                x,
                v.speed,
                v.controlled
            )?;
        }
        Ok(())
    }

    /// Draw a uniform number from the run's generator (for callers that need run-bound randomness).
    pub fn random_unit(&mut self) -> f64 {
        self.rng.random::<f64>()
    }

    /// Vehicles waiting at their entry roads.
    pub fn waiting_to_enter(&self) -> usize {
        self.pending.iter().map(|q| q.len() as usize).sum()
    }
}

/// The speed at the next link, `speed_after_distance(dist, speed, accel).fmin(cap)` lowered by every leader
/// found on the way, with the square root taken only when a link request reads it (most lanes' pass speeds are
/// never read). `fmin` (`b < a ? b : a`) keeps the first operand that attains the minimum, so folding the leaders
/// into their own minimum and taking it with the root's last gives the same bits as the eager chain, signed zeros
/// included.
#[derive(Clone, Copy)]
struct LazyPassSpeed {
    dist: f64,
    speed: f64,
    accel: f64,
    cap: f64,
    leaders_min: f64,
}

impl LazyPassSpeed {
    #[inline]
    fn new(dist: f64, speed: f64, accel: f64, cap: f64) -> LazyPassSpeed {
        LazyPassSpeed {
            dist,
            speed,
            accel,
            cap,
            leaders_min: f64::INFINITY,
        }
    }

    #[inline]
    fn lower(&mut self, v: f64) {
        self.leaders_min = self.leaders_min.fmin(v);
    }

    #[inline]
    fn get(&self) -> f64 {
        IdmParams::speed_after_distance(self.dist, self.speed, self.accel)
            .fmin(self.cap)
            .fmin(self.leaders_min)
    }
}

/// `1 / d` where multiplying by it gives the bits of dividing by `d`: when `d` is a power of two (0.5 s, 0.25 s,
/// 1 s), `1 / d` is exact and both operations round the same real number; `None` otherwise. The move's cap is on the
/// chain from each moved leader to its follower, and a division is several times a multiplication's latency.
fn exact_reciprocal(d: f64) -> Option<f64> {
    const MANTISSA: u64 = (1 << 52) - 1;
    (d.is_normal() && d.to_bits() & MANTISSA == 0).then(|| 1.0 / d)
}

/// Whether a follower behind a leader at the merge could not brake in time: it can only when the leader's
/// braking distance (v^2 / b) is the longer one (SUMO's `MSLink::unsafeMergeSpeeds`).
fn unsafe_merge_speeds(
    leader_speed: f64,
    follower_speed: f64,
    leader_decel: f64,
    follower_decel: f64,
) -> bool {
    leader_speed * leader_speed / leader_decel <= follower_speed * follower_speed / follower_decel
}

#[cfg(test)]
mod bound_tests {
    use super::*;

    #[test]
    fn division_by_the_step_is_division_bit_for_bit() {
        let mut state = 0x9e37_79b9_7f4a_7c15u64;
        let mut next = || {
            state ^= state << 13;
            state ^= state >> 7;
            state ^= state << 17;
            state
        };
        let steps = [
            0.5,
            0.25,
            1.0,
            2.0,
            0.125,
            0.1,
            0.3,
            0.75,
            1.5,
            f64::MIN_POSITIVE,
            5e-324,
        ];
        // the shortcut applies to the steps people use, not to the others
        assert!(
            [0.5, 0.25, 1.0, 2.0]
                .iter()
                .all(|&d| exact_reciprocal(d).is_some())
        );
        assert!(
            [0.1, 0.3, 0.75, 5e-324]
                .iter()
                .all(|&d| exact_reciprocal(d).is_none())
        );
        for &dt in &steps {
            for _ in 0..20_000 {
                // any finite f64, subnormals and huge values included, and ordinary gaps
                let raw = f64::from_bits(next());
                let x = if raw.is_finite() { raw } else { 1.0 };
                let gap = (next() >> 11) as f64 / (1u64 << 53) as f64 * 400.0 - 5.0;
                for v in [x, gap, 0.0, -0.0] {
                    assert_eq!(
                        exact_reciprocal(dt).map_or(v / dt, |r| v * r).to_bits(),
                        (v / dt).to_bits(),
                        "{v} / {dt}"
                    );
                }
            }
        }
    }

    #[test]
    fn lazy_pass_speed_is_the_eager_chain_bit_for_bit() {
        // the eager chain: root, then cap, then every leader, each with fmin; ties and signed zeros included
        let mut rng = StdRng::seed_from_u64(7);
        let pick = |rng: &mut StdRng| -> f64 {
            match rng.random_range(0..6) {
                0 => 0.0,
                1 => -0.0,
                2 => 5.0,
                3 => f64::INFINITY,
                _ => rng.random_range(-1.0..30.0),
            }
        };
        for _ in 0..20_000 {
            let (dist, speed) = (rng.random_range(0.0..200.0), pick(&mut rng).abs());
            let (accel, cap) = (2.6, pick(&mut rng));
            let leaders: Vec<f64> = (0..rng.random_range(0..5))
                .map(|_| pick(&mut rng))
                .collect();
            let mut eager = IdmParams::speed_after_distance(dist, speed, accel).fmin(cap);
            let mut lazy = LazyPassSpeed::new(dist, speed, accel, cap);
            for &v in &leaders {
                eager = eager.fmin(v);
                lazy.lower(v);
            }
            assert_eq!(
                lazy.get().to_bits(),
                eager.to_bits(),
                "{dist} {speed} {cap} {leaders:?}"
            );
        }
    }

    #[test]
    fn brake_gap_bound_lies_above_the_exact_gap() {
        for (decel, dt) in [(4.5, 0.5), (4.5, 0.1), (1.0, 1.0), (7.5, 0.2), (3.0, 2.0)] {
            let p = IdmParams::new(2.6, decel, 9.0, 1.0, 2.5, 4.0, dt);
            let tc = TypeConsts {
                max_speed: 30.0,
                impatience: 0.5,
                max_arrival_from_visibility: 0.0,
                inv_two_decel: Some(0.5 / p.decel),
            };
            for i in 0..200_000 {
                let v = i as f64 * 0.000_37;
                for h in [0.0, 1.0, 1.6] {
                    let exact = p.brake_gap(v, p.decel, h);
                    assert!(tc.brake_gap_above(v, h) > exact, "v {v} h {h}: {exact}");
                }
            }
        }
    }
}

/// A vector of the simulation's own records (vehicles, lanes' vehicle lists, routes, plans, per-type and per-link
/// values) whose indexing skips the bounds check in release builds: the checks, with the code around them, were
/// 17 % of the hot loop's instructions. Only indices the simulation made itself reach it (vehicle ids from
/// `create_vehicle`, lane, link and route indices from the network and `add_route`, positions within the lists
/// they index); ids that come from callers (`vehicle`, `leader`, `set_acceleration`, ...) go through `get` first.
/// Debug builds, and so every test, check each index.
#[derive(Clone, Debug, Default)]
struct Table<T>(Vec<T>);

impl<T> std::ops::Deref for Table<T> {
    type Target = Vec<T>;
    fn deref(&self) -> &Vec<T> {
        &self.0
    }
}
impl<T> std::ops::DerefMut for Table<T> {
    fn deref_mut(&mut self) -> &mut Vec<T> {
        &mut self.0
    }
}
impl<T> std::ops::Index<usize> for Table<T> {
    type Output = T;
    #[inline(always)]
    fn index(&self, i: usize) -> &T {
        debug_assert!(i < self.0.len(), "index {i} of {}", self.0.len());
        // SAFETY: indices are the simulation's own (see the type's documentation), checked in debug builds
        unsafe { self.0.get_unchecked(i) }
    }
}
impl<T> std::ops::IndexMut<usize> for Table<T> {
    #[inline(always)]
    fn index_mut(&mut self, i: usize) -> &mut T {
        debug_assert!(i < self.0.len(), "index {i} of {}", self.0.len());
        // SAFETY: as for `index`
        unsafe { self.0.get_unchecked_mut(i) }
    }
}
impl<T> FromIterator<T> for Table<T> {
    fn from_iter<I: IntoIterator<Item = T>>(it: I) -> Self {
        Table(it.into_iter().collect())
    }
}
impl<'a, T> IntoIterator for &'a Table<T> {
    type Item = &'a T;
    type IntoIter = std::slice::Iter<'a, T>;
    fn into_iter(self) -> Self::IntoIter {
        self.0.iter()
    }
}
impl<'a, T> IntoIterator for &'a mut Table<T> {
    type Item = &'a mut T;
    type IntoIter = std::slice::IterMut<'a, T>;
    fn into_iter(self) -> Self::IntoIter {
        self.0.iter_mut()
    }
}
impl<T: PartialEq> PartialEq<Vec<T>> for Table<T> {
    fn eq(&self, other: &Vec<T>) -> bool {
        self.0 == *other
    }
}
