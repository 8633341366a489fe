//! The stepping simulator: plan every vehicle's safe speed from the state at the start of the step (leaders
//! across lanes and junctions, speed limits ahead, minor-link requests), register junction approaches, decide
//! links (right of way with impatience), then move every vehicle, front to back, never into its leader.

mod accounting;
mod entry;
#[cfg(test)]
mod lanes_tests;
mod queries;
mod step;
#[cfg(test)]
mod sumo_run_tests;
mod table;
#[cfg(test)]
mod tests;
mod vehicle;

use crate::demand::vehicle_table::VehicleTable;
use crate::demand::waiting::EntryQueue;
use crate::error::SimError;
use crate::measure::metrics::RunMetrics;
use crate::measure::points::MeasureAcc;
use crate::models::cf::{CarFollowModel, CfModel, IdmParams, Krauss, kinematics};
use crate::network::{FOE_VISIBILITY_M, LaneIdx, LaneKind, LinkIdx, Network, SimLane, SimLink};
use crate::numeric::{FastMinMax, NUMERICAL_EPS};
use crate::spec::{CarFollowModelKind, DepartLane, SimSpec};
use accounting::MetricsAcc;
use entry::{lane_choice, teleport};
use junction::Approach;
use junction::LinkItem;
use lane_change::BestLanesCache;
use mapc_graph::RoadId;
use planning::Plan;
use rand::rngs::StdRng;
use rand::{RngExt, SeedableRng};
use rand_distr::{Distribution, Normal};
use step::{junction, lane_change, planning, side_lanes};
use table::Table;
use vehicle::{Route, TypeConsts, Veh};

pub use queries::{LaneRef, MergeFoe, Neighbor, VehicleView};
pub use side_lanes::SideNeighbors;
pub use vehicle::VehicleStatus;

pub use crate::demand::vehicle_table::VehicleId;

/// How far the stop point lies before a minor link's stop line (SUMO's POSITION_EPS).
const POSITION_EPS: f64 = 0.1;
/// How far before the stop line a vehicle stops at a red or yellow light (SUMO's `DIST_TO_STOPLINE_EXPECT_PRIORITY`:
/// it will have the right of way, so it need not stop at the line; on a metered ramp the first vehicle then
/// stands about a metre back and often misses the first step of green).
const LIGHT_STOP_OFFSET_M: f64 = 1.0;

/// Where merging connections start to conflict, as a share of the shorter one's length before its end
/// (netconvert's internal lanes come within a lane width of each other about a third of the way from the end).
const CONFLICT_POINT_SHARE: f64 = 0.35;

/// What a route is asked for: (from, via, to, first lane).
type RouteRequest = (RoadId, Vec<RoadId>, Option<RoadId>, Option<u8>);

/// A running simulation of one seed.
pub struct Simulation {
    net: Network,
    spec: SimSpec,
    types: Table<CfModel>,
    routes: Table<Route>,
    /// Routes by (lanes, roads), so vehicles that drive the same share one.
    route_index: rustc_hash::FxHashMap<(Vec<LaneIdx>, Vec<usize>), u32>,
    /// Routes by what they were asked for (from, via, to, first lane): a SUMO user's routes file names the same
    /// few routes for each of its vehicles, and each is found on the network once.
    route_asked: rustc_hash::FxHashMap<RouteRequest, u32>,
    veh: VehicleTable<Veh>,
    /// Vehicles per lane, front first (a plain vector: lanes are short and indexing is on the hot path).
    lane_veh: Table<Table<VehicleId>>,
    lane_order: Vec<LaneIdx>,
    plans: Table<Plan>,
    /// This step's (vehicle, index in its lane) in planning order (kept to reuse its allocation).
    plan_order: Vec<(VehicleId, u32)>,
    approaches: Table<Vec<Approach>>,
    /// Each light's phase at a light time (seconds since the run's begin), found once a step
    /// ([`Self::signal_of`] reads it for that time).
    light_phases: (f64, Vec<Option<usize>>),
    /// Teleported vehicles on their way back ([`teleport`]).
    transfers: Vec<teleport::InTransfer>,
    /// Right of way is decided at the link (a major link with minor foes, a zipper link, a link another one
    /// crosses by the net's request table): approaching vehicles register their requests there.
    link_takes_requests: Table<bool>,
    /// Per entry lane, the vehicles waiting to be inserted, in departure order.
    pending: Vec<EntryQueue>,
    entry_lanes: Vec<LaneIdx>,
    /// Vehicles of flows whose lane is chosen at insertion (`random`, `free`), waiting at their entry road.
    road_entries: Vec<lane_choice::RoadEntry>,
    /// The entry lanes where an insertion failed in this step (kept to reuse its allocation).
    refused_lanes: Vec<LaneIdx>,
    /// [`Simulation::insert_in_due_order`]'s per-queue state, kept between steps.
    due_order_open: Vec<bool>,
    due_order_place: Vec<usize>,
    flow_next: Vec<u64>,
    /// Per flow, (n, departure time of its vehicle n): `FlowSpec::departure_s` of `flow_next`, kept so that each
    /// step compares instead of computing it again.
    flow_due: Vec<(u64, Option<f64>)>,
    /// The earliest departure time of any flow's next vehicle, when no flow draws by probability: no flow has a
    /// departure due in a step that ends before it (the flows are not visited then). NaN: visit them.
    flows_quiet_until: f64,
    /// The flows each step visits for departures.
    flow_schedule: entry::flow_schedule::FlowSchedule,
    /// No vehicle was on the network at the last step's start ([`Simulation::step`]'s short way).
    was_empty: bool,
    /// Per flow, its vehicles built so far; and, once [`Simulation::record_origins`] asked for them, each
    /// vehicle's flow and number in it (SUMO names a flow's vehicles `flow.N`).
    flow_built: Vec<u32>,
    origins: Option<rustc_hash::FxHashMap<VehicleId, (u32, u32)>>,
    /// Per flow, its route (for `random` and `free`: the one from the rightmost lane, until a lane is chosen).
    flow_route: Vec<u32>,
    /// Per flow whose lane is chosen at insertion, where its vehicles wait and its route from each lane.
    flow_lanes: Vec<Option<lane_choice::FlowLanes>>,
    in_region: Table<bool>,
    rng: StdRng,
    /// The run's seed, from which each dawdling driver's own generator is derived ([`vehicle::DriverRng`]).
    seed: u64,
    step: u64,
    time_s: f64,
    next_entry: u64,
    arrived_last: Vec<VehicleId>,
    departed_last: Vec<VehicleId>,
    main_line: Vec<(LaneIdx, f64)>,
    metrics: MetricsAcc,
    measure: MeasureAcc,
    /// The induction loops and their intervals.
    detectors: crate::measure::detectors::Detectors,
    /// What a loop sees of the vehicles on its lane and of those it tracks (kept to reuse its allocation).
    detector_seen: (
        Vec<crate::measure::detectors::Seen>,
        Vec<crate::measure::detectors::Seen>,
    ),
    check_invariants: bool,
    /// Longest vehicle of any type (m).
    max_length: f64,
    /// Per vehicle type, what the hot loop reads (cached from the spec and the IDM parameters).
    type_consts: Table<TypeConsts>,
    /// Lane changing (networks with a road of several lanes only): the model (each vehicle's record is in `Veh`).
    /// Per vehicle type, its LC2013 (its `lc*` parameters).
    lc_models: Table<lane_change::LcModel>,
    /// Road sequences of the routes, numbered (routes that differ only in lanes share one).
    road_seqs: rustc_hash::FxHashMap<Vec<usize>, u32>,
    /// Best lanes computed so far, by (road sequence, index of the current road in it, vehicle type).
    best_cache: BestLanesCache,
    /// Per lane, the summed lengths with min gaps of its vehicles during the lane-change pass.
    lane_brutto: Vec<f64>,
    lc_scratch: lane_change::LcScratch,
    /// SUMO's list of active lanes, under SUMO's junction rules ([`step::active_lanes`]).
    active_lanes: step::active_lanes::ActiveLanes,
    /// The vehicles on the network's lanes (kept where a vehicle joins or leaves a lane's queue).
    in_network: usize,
    /// The longest any vehicle has waited, after the last moves (the teleport check looks at lanes only beyond it).
    longest_wait_s: f64,
}

impl Simulation {
    /// A simulation of `spec` with every random draw from `seed`.
    pub fn from_spec(spec: SimSpec, seed: u64) -> Result<Simulation, SimError> {
        spec.validate()?;
        let net = Network::from_graph(&spec.graph)?;
        // links another one crosses (the net's request table): their approaches are what a yielding link checks
        let mut crossed = vec![false; net.links.len()];
        for l in &net.links {
            for &f in &l.crossing_foes {
                crossed[f as usize] = true;
            }
        }
        let dt = spec.step_s;
        let types: Vec<CfModel> = spec
            .vehicle_types
            .iter()
            .map(|t| match t.car_follow_model {
                CarFollowModelKind::Idm => CfModel::idm(IdmParams::with_stepping(
                    t.accel,
                    t.decel,
                    t.emergency_decel,
                    t.tau,
                    t.min_gap,
                    t.delta,
                    dt,
                    t.idm_stepping_s,
                )),
                CarFollowModelKind::Krauss => CfModel::krauss(
                    Krauss {
                        accel: t.accel,
                        decel: t.decel,
                        emergency_decel: t.emergency_decel,
                        tau: t.tau,
                        sigma: t.sigma,
                        max_speed: t.max_speed,
                        dt,
                    },
                    t.min_gap,
                ),
            })
            .collect();
        let mut sim = Simulation {
            lane_veh: Table(vec![Table(Vec::new()); net.lanes.len()]),
            approaches: Table(vec![Vec::new(); net.links.len()]),
            light_phases: (f64::NAN, Vec::new()),
            transfers: Vec::new(),
            link_takes_requests: net
                .links
                .iter()
                .enumerate()
                .map(|(i, l)| {
                    l.zipper || l.foes.iter().any(|&f| !net.links[f as usize].major) || crossed[i]
                })
                .collect(),
            pending: Vec::new(),
            entry_lanes: Vec::new(),
            road_entries: Vec::new(),
            refused_lanes: Vec::new(),
            due_order_open: Vec::new(),
            due_order_place: Vec::new(),
            lane_order: Vec::new(),
            flow_next: vec![0; spec.flows.len()],
            flow_due: spec.flows.iter().map(|f| (0, f.departure_s(0))).collect(),
            flows_quiet_until: f64::NAN,
            flow_schedule: Default::default(),
            was_empty: false,
            flow_built: vec![0; spec.flows.len()],
            origins: None,
            flow_route: Vec::new(),
            flow_lanes: Vec::new(),
            in_region: Table(vec![true; net.lanes.len()]),
            routes: Table(Vec::new()),
            route_index: rustc_hash::FxHashMap::default(),
            route_asked: rustc_hash::FxHashMap::default(),
            veh: VehicleTable::default(),
            plans: Table(Vec::new()),
            plan_order: Vec::new(),
            rng: StdRng::seed_from_u64(seed),
            seed,
            step: 0,
            time_s: spec.start_time_s,
            next_entry: 0,
            arrived_last: Vec::new(),
            departed_last: Vec::new(),
            main_line: Vec::new(),
            metrics: MetricsAcc::default(),
            measure: MeasureAcc::new(&net, &spec.measure_points, None),
            detector_seen: (Vec::new(), Vec::new()),
            detectors: crate::measure::detectors::Detectors::new(
                &spec.detectors,
                &spec
                    .detectors
                    .iter()
                    .map(|d| {
                        let r = net
                            .road_ids
                            .iter()
                            .position(|&id| id == d.road)
                            .unwrap_or(0);
                        (net.road_lanes[r][d.lane as usize], r)
                    })
                    .collect::<Vec<_>>(),
                0.0,
            ),
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
                    max_brake_dist: p.brake_gap(t.max_speed, p.decel, p.tau) + t.min_gap,
                    impatience: t.impatience,
                    inv_two_decel: Some(0.5 / p.decel).filter(|x| *x > 0.0 && x.is_finite()),
                    max_arrival_from_visibility: kinematics::speed_after_distance(
                        FOE_VISIBILITY_M,
                        p.maximum_safe_stop_speed(FOE_VISIBILITY_M, 0.0),
                        p.accel,
                    ),
                })
                .collect(),
            types: Table(types),
            lc_models: spec
                .vehicle_types
                .iter()
                .map(|t| lane_change::model_of(&t.lane_change, dt))
                .collect(),
            road_seqs: rustc_hash::FxHashMap::default(),
            best_cache: BestLanesCache::default(),
            lane_brutto: Vec::new(),
            lc_scratch: Default::default(),
            active_lanes: Default::default(),
            longest_wait_s: 0.0,
            in_network: 0,
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
            if let Some(lane) = flow.depart_lane.start_lane() {
                let lanes = sim.spec.graph.road(flow.from).map_or(0, |r| r.lanes.len());
                if lane as usize >= lanes {
                    return Err(SimError::Spec(format!(
                        "flow {}: depart_lane {lane}, but its entry road {} has {lanes} lane(s)",
                        flow.id, flow.from
                    )));
                }
            }
            let r = sim.add_route(flow.from, &flow.via, flow.to, flow.depart_lane.start_lane())?;
            sim.flow_route.push(r);
            if flow.depart_lane.chosen_at_insertion() {
                let lanes = sim.spec.graph.road(flow.from).map_or(0, |r| r.lanes.len());
                let routes = (0..lanes)
                    .map(|i| sim.add_route(flow.from, &flow.via, flow.to, Some(i as u8)))
                    .collect::<Result<Vec<u32>, SimError>>()?;
                let starts: Vec<LaneIdx> = routes
                    .iter()
                    .map(|&r| sim.routes[r as usize].lanes[0])
                    .collect();
                // `best`: the lanes whose routes go furthest without a lane change (SUMO's best lanes)
                let candidates: Vec<usize> = if flow.depart_lane == DepartLane::Best {
                    let roads = sim.routes[routes[0] as usize].roads.clone();
                    let best = sim.net.best_lanes(&roads, 0.0);
                    let top = best.iter().map(|q| q.length).fold(f64::MIN, f64::max);
                    (0..lanes)
                        .filter(|&k| best.get(k).is_some_and(|q| q.length == top))
                        .collect()
                } else {
                    (0..lanes).collect()
                };
                let entry = match sim.road_entries.iter().position(|e| {
                    e.lanes == starts && e.mode == flow.depart_lane && e.candidates == candidates
                }) {
                    Some(e) => e,
                    None => {
                        sim.road_entries.push(lane_choice::RoadEntry {
                            mode: flow.depart_lane,
                            lanes: starts,
                            candidates,
                            queue: EntryQueue::default(),
                        });
                        sim.road_entries.len() - 1
                    }
                };
                sim.flow_lanes.push(Some(lane_choice::FlowLanes {
                    entry: entry as u32,
                    routes,
                }));
                continue;
            }
            sim.flow_lanes.push(None);
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
        // Initial vehicles: standing where the spec puts them, before the first step, none inside another.
        crate::demand::placement::check_initial_spacing(
            &sim.net,
            &sim.spec.initial,
            &sim.spec.vehicle_types,
        )?;
        for i in 0..sim.spec.initial.len() {
            let iv = sim.spec.initial[i].clone();
            let r = sim.add_route(iv.road, &[], None, None)?;
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

    pub(super) fn derive_main_line(&mut self) -> Result<Vec<(LaneIdx, f64)>, SimError> {
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

    /// Keep each vehicle's flow and number in it from now on ([`Self::vehicle_origin`]; for SUMO's outputs, which
    /// name vehicles `flow.N`). The record grows with the vehicles created.
    pub fn record_origins(&mut self) {
        self.origins.get_or_insert_with(Default::default);
    }

    /// The flow (index into the spec's flows) and the number in it of a vehicle created since
    /// [`Self::record_origins`]; `None` for others and initial vehicles.
    pub fn vehicle_origin(&self, id: VehicleId) -> Option<(usize, u32)> {
        self.origins
            .as_ref()?
            .get(&id)
            .map(|&(f, n)| (f as usize, n))
    }

    /// Keep every passage past a measure point or the corridor's end from now on (for tests that follow each
    /// vehicle; the log grows with the run).
    pub fn record_passages(&mut self) {
        self.measure.record();
    }

    /// The passages kept since [`Self::record_passages`], in the order they happened.
    pub fn passages(&self) -> &[crate::measure::points::Passage] {
        self.measure.passages()
    }

    /// Turn the per-step collision check on or off (on by default in debug builds).
    pub fn set_invariant_checks(&mut self, on: bool) {
        self.check_invariants = on;
    }

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
            self.detectors.reset(self.time_s - self.spec.start_time_s);
        }
        // Metrics see the network as it is before the step (as the original rollouts did).
        // (the lanes walked only when vehicles are on them: a SUMO user's run may go on for hours after its last)
        let mut n = 0u64;
        let mut sum = 0.0;
        if self.in_network > 0 {
            for q in self.lane_veh.iter() {
                for &id in q {
                    n += 1;
                    sum += self.veh[id as usize].speed;
                }
            }
        }
        debug_assert_eq!(n as usize, self.in_network);
        if n > 0 && sum / n as f64 > 0.0 {
            self.metrics.speed_sum += sum / n as f64;
            self.metrics.speed_steps += 1;
        }
        self.metrics.veh_steps += n;
        if n == 0 {
            // An empty network (before the first departure, or the hours a SUMO user's run goes on after its last
            // vehicle: sumo-rl's 3x3 grid ends 68 h after it): nothing plans, moves or changes lanes; the loops'
            // intervals, the departures and the clock go on. What the last step with vehicles left behind (their
            // junction requests, the active lanes' list) is cleared once, as that step's successor would.
            if !self.was_empty {
                self.was_empty = true;
                if self.keeps_active_lanes() {
                    self.activate_lanes_at_step_start();
                }
                for a in &mut self.approaches {
                    a.clear();
                }
            }
            if !self.detectors.is_empty() {
                self.observe_detectors();
            }
            return self.end_step();
        }
        self.was_empty = false;
        if self.keeps_active_lanes() {
            self.activate_lanes_at_step_start();
        }

        for a in &mut self.approaches {
            a.clear();
        }
        if !self.net.lights.is_empty() {
            // the lights' phases at this step's light time (the moves'; the insertions compute theirs from the
            // next step's time, whose difference may differ in the last bit, and mostly find their own)
            let light_time = self.time_s - self.spec.start_time_s;
            let (t, phases) = &mut self.light_phases;
            *t = light_time;
            phases.clear();
            phases.extend(
                self.net
                    .lights
                    .iter()
                    .map(|l| crate::network::signals::phase_at(l, light_time)),
            );
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
        self.teleport_stuck();
        if self.keeps_active_lanes() {
            self.activate_lanes_after_moves();
        }
        // the loops see the moves before the lane changes, as SUMO's see them while vehicles move: a vehicle
        // that passes a loop and changes lanes in the same step has passed it
        if !self.detectors.is_empty() {
            self.observe_detectors();
        }
        if self.net.multi_lane {
            self.change_lanes();
        }
        self.end_step()
    }

    /// A step's end: the clock, then the departures and teleported vehicles that enter at its end.
    fn end_step(&mut self) -> Result<(), SimError> {
        self.time_s += self.spec.step_s;
        self.step += 1;
        self.metrics.steps += 1;
        self.insert_departures();
        self.reinsert_teleported();
        if self.check_invariants {
            self.check_no_overlap()?;
        }
        Ok(())
    }

    /// The network's lane `i` (indices come from the network itself; checked in debug builds).
    #[inline(always)]
    pub(super) fn lane_at(&self, i: usize) -> &SimLane {
        debug_assert!(i < self.net.lanes.len());
        // SAFETY: lane indices are created by `Network::from_graph` and never exceed its lanes
        unsafe { self.net.lanes.get_unchecked(i) }
    }

    /// The network's link `i` (indices come from the network itself; checked in debug builds).
    #[inline(always)]
    pub(super) fn link_at(&self, i: usize) -> &SimLink {
        debug_assert!(i < self.net.links.len());
        // SAFETY: link indices are created by `Network::from_graph` and never exceed its links
        unsafe { self.net.links.get_unchecked(i) }
    }

    /// What the light over `link` says at `light_time` seconds after the run's begin; `None` for a link without
    /// one. The moves read it at the step's start, the insertions at its end, for the same step.
    pub(super) fn signal_of(
        &self,
        link: &SimLink,
        light_time: f64,
    ) -> Option<crate::network::signals::SignalState> {
        use crate::network::signals::{phase_at, state_in_phase};
        link.signal.map(|(light, index)| {
            let l = &self.net.lights[light as usize];
            let phase = if light_time.to_bits() == self.light_phases.0.to_bits() {
                self.light_phases.1[light as usize]
            } else {
                phase_at(l, light_time)
            };
            state_in_phase(l, phase, index)
        })
    }
}
