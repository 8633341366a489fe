//! What a simulation run is made of, in the simulator's own plain terms: the lane graph plus driver types, flows,
//! initial vehicles, step and horizon. [`SimSpec::from_scenario`] fills it from a resolved scenario.

use crate::error::SimError;
use mapc_graph::{LaneGraph, RoadId};
use mapc_scenario::ranges;
use serde::{Deserialize, Serialize};

/// One driver/vehicle type.
#[derive(Clone, Debug, PartialEq)]
pub struct VehicleTypeSpec {
    pub name: String,
    pub accel: f64,
    pub decel: f64,
    /// Hardest braking when the safe speed demands it (SUMO's passenger default: 9).
    pub emergency_decel: f64,
    pub tau: f64,
    pub min_gap: f64,
    pub delta: f64,
    pub max_speed: f64,
    pub length: f64,
    /// Mean of the per-driver speed factor (desired speed = factor x speed limit, capped by `max_speed`).
    pub speed_factor: f64,
    /// Standard deviation of the speed factor; the draw is repeated until it lies in [0.2, 2] (SUMO's bounds).
    pub speed_dev: f64,
    /// Base impatience in [0, 1]; it grows by waiting time / 300 s.
    pub impatience: f64,
    /// Vehicles of this type take accelerations from the caller (AVs).
    pub controlled: bool,
    /// IDM integration sub-step (s); the step is split into round(step / this) sub-steps.
    pub idm_stepping_s: f64,
    /// The car-following model (`delta` and `idm_stepping_s` are the IDM's, `sigma` Krauss').
    pub car_follow_model: CarFollowModelKind,
    /// Krauss' dawdling in [0, 1].
    pub sigma: f64,
    /// LC2013's parameters of the type (absent ones: SUMO 1.8's defaults).
    pub lane_change: mapc_scenario::LaneChangeParams,
}

pub use mapc_scenario::CarFollowModel as CarFollowModelKind;

impl VehicleTypeSpec {
    /// The paper's human driver (SUMO IDM as Flow configured it).
    pub fn paper_human(name: &str) -> Self {
        VehicleTypeSpec {
            name: name.to_string(),
            accel: 2.6,
            decel: 4.5,
            emergency_decel: 9.0,
            tau: 1.0,
            min_gap: 2.5,
            delta: 4.0,
            max_speed: 30.0,
            length: 5.0,
            speed_factor: 1.0,
            speed_dev: 0.1,
            impatience: 0.5,
            controlled: false,
            idm_stepping_s: 0.25,
            car_follow_model: CarFollowModelKind::Idm,
            sigma: 0.0,
            lane_change: mapc_scenario::LaneChangeParams::default(),
        }
    }
}

/// Periodic departures with SUMO's vehsPerHour semantics: departure i at `begin_s + i * 3600 / vehs_per_hour`
/// while before `end_s`.
#[derive(Clone, Debug, PartialEq)]
pub struct FlowSpec {
    /// The flow's name in errors (the scenario's flow id).
    pub id: String,
    pub from: RoadId,
    pub to: Option<RoadId>,
    pub vehs_per_hour: f64,
    /// Index into [`SimSpec::vehicle_types`].
    pub vehicle_type: usize,
    /// m/s, or [`DEPART_SPEED_MAX`] / [`DEPART_SPEED_DESIRED`] (SUMO's `max` and `desired`).
    pub depart_speed: f64,
    pub begin_s: f64,
    pub end_s: f64,
    /// The lane of the entry road its vehicles depart on.
    pub depart_lane: DepartLane,
    /// Roads the route passes between `from` and `to`, in order.
    pub via: Vec<RoadId>,
    /// Departures by chance: per second a vehicle with this probability (at most one a step), instead of the
    /// periodic `vehs_per_hour`.
    pub probability: Option<f64>,
    /// At most this many vehicles.
    pub number: Option<u64>,
    /// Demand above what its entry takes queues there (SUMO's behaviour) instead of being refused.
    pub queue_excess: bool,
    /// Where on the entry lane its vehicles are inserted.
    pub depart_pos: DepartPos,
    /// A mix of types, as (type index, cumulative weight up to 1): each vehicle's type is drawn; empty: always
    /// `vehicle_type`.
    pub type_mix: Vec<(usize, f64)>,
    /// One named vehicle (a SUMO `<vehicle>` or `<trip>`): SUMO's outputs call it `id`, not `id.0`.
    pub single_vehicle: bool,
    /// Departures on SUMO's clock of whole milliseconds (a SUMO user's scenario): begin and period rounded to the
    /// millisecond as SUMO 1.8 stores them (`TIME2STEPS`), departure `n` at their exact sum.
    pub whole_ms: bool,
}

impl FlowSpec {
    /// When departure `n` of a periodic flow is due: `begin_s`, then one period apart (the first without the
    /// product, so that a period too long to be a number departs once); `None` for a flow by probability, whose
    /// vehicles are drawn step by step, or one without a rate.
    #[inline]
    pub fn departure_s(&self, n: u64) -> Option<f64> {
        if self.probability.is_some() || self.vehs_per_hour <= 0.0 {
            return None;
        }
        if self.whole_ms {
            let ms = |s: f64| crate::numeric::floor_exact(s * 1000.0 + 0.5);
            return Some((ms(self.begin_s) + n as f64 * ms(3600.0 / self.vehs_per_hour)) / 1000.0);
        }
        Some(if n == 0 {
            self.begin_s
        } else {
            self.begin_s + n as f64 * (3600.0 / self.vehs_per_hour)
        })
    }
}

pub use mapc_scenario::DepartLane;

/// Where a flow's vehicles are inserted on their entry lane (SUMO's `departPos`).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum DepartPos {
    /// The front one length and 0.1 m in (SUMO's `base`).
    #[default]
    Base,
    /// A uniform place along the lane, drawn again at each try (never behind `Base`).
    Random,
    /// Up to ten random places in a step, then as `Free`.
    RandomFree,
    /// The first free place on the lane (SUMO's `free`, `MSLane::freeInsertion`): at the lane's start behind
    /// the last vehicle, else in the first gap between vehicles wide enough for both secure gaps.
    Free,
}

/// A flow's depart speed meaning SUMO's `departSpeed="max"`: the highest speed up to the vehicle's desired speed
/// at which the insertion is safe.
pub const DEPART_SPEED_MAX: f64 = f64::INFINITY;
/// SUMO's `departSpeed="desired"`: the desired speed, or no insertion.
pub const DEPART_SPEED_DESIRED: f64 = f64::NEG_INFINITY;

/// A point where flow is measured: vehicles entering any of `roads` pass it.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct MeasurePoint {
    /// For reports: `merge J3 (osm:123)`.
    pub name: String,
    pub roads: Vec<RoadId>,
}
/// A vehicle present at time 0, standing on `road` with its front at `pos_m`.
#[derive(Clone, Debug, PartialEq)]
pub struct InitialVehicleSpec {
    pub road: RoadId,
    pub pos_m: f64,
    pub speed: f64,
    pub vehicle_type: usize,
}

#[derive(Clone, Debug)]
pub struct SimSpec {
    pub graph: LaneGraph,
    pub vehicle_types: Vec<VehicleTypeSpec>,
    pub flows: Vec<FlowSpec>,
    pub initial: Vec<InitialVehicleSpec>,
    pub step_s: f64,
    pub horizon_steps: u64,
    /// Steps simulated before the horizon; metrics ignore them.
    pub warmup_steps: u64,
    /// Simulation time at step 0 (the original runs two set-up steps before the horizon starts).
    pub start_time_s: f64,
    /// SUMO's clock at step 0 (a SUMO user's `begin`): SUMO's outputs are stamped on it. The lights' offsets
    /// already run on it ([`mapc_scenario::Scenario::clock_begin_s`]); the simulation itself does not read it.
    pub clock_begin_s: f64,
    /// Roads where controlled vehicles take commands; `None`: everywhere.
    pub control_region: Option<Vec<RoadId>>,
    /// How many controlled vehicles a policy drives at once (for the environment; the simulator obeys every
    /// acceleration it is given).
    pub n_av: usize,
    /// The corridor's main line, upstream first (for corridor positions in traces); empty: derived.
    pub main_line: Vec<RoadId>,
    /// The windows of a several-window scenario, each its own controlled region (their union is
    /// `control_region`); the simulator does not use them, the environment keeps one FIFO of `n_av` per window.
    /// Empty for a scenario with one region.
    pub control_windows: Vec<ControlWindowSpec>,
    /// Where flow is measured besides the outflow (the controlled region's merges).
    pub measure_points: Vec<MeasurePoint>,
    /// A lane's front vehicle that has stood still longer than this is teleported (SUMO's `--time-to-teleport`;
    /// 0: never).
    pub time_to_teleport_s: f64,
    /// SUMO 1.8's rules at junctions and in the lane-change pass (a SUMO user's scenario; `false` for mapc's own,
    /// whose figures were measured without them): a vehicle may change lanes while its back is still inside the
    /// junction behind; the lane-change memory survives connections side by side, and vehicles change lanes on
    /// them; the pass visits roads in the order of SUMO's active lanes; a merging foe's connection leads ego
    /// through a minor link; a vehicle on a lane that ends drives up to its end; a junction leader lowers a driver
    /// with priority no lower than stopping at the link before needs (docs/sumo_scenarios.md).
    pub sumo_junction_lane_changes: bool,
    /// The vehicles due to enter are tried in SUMO 1.8's order (a SUMO user's scenario): one list by the time each
    /// was due, whatever its entry (`MSInsertionControl::emitVehicles`); otherwise entry by entry.
    pub sumo_insertion_order: bool,
    /// Induction loops: points that count passing vehicles and their occupancy over intervals.
    pub detectors: Vec<DetectorSpec>,
}

/// An induction loop (SUMO's E1 detector).
#[derive(Clone, Debug, PartialEq)]
pub struct DetectorSpec {
    pub id: String,
    pub road: RoadId,
    /// Lane index on the road (0: rightmost).
    pub lane: u8,
    /// Distance of the point from the lane's start (m).
    pub pos_m: f64,
    /// Length of the intervals it reports (s).
    pub period_s: f64,
    /// The vehicle types it sees (indices in `vehicle_types`); empty: all.
    pub vehicle_types: Vec<usize>,
}

/// One window of a several-window scenario.
#[derive(Clone, Debug, PartialEq)]
pub struct ControlWindowSpec {
    /// How the scenario names its first merge.
    pub name: String,
    /// Its merge junctions, in driving order.
    pub merges: Vec<mapc_graph::JunctionId>,
    /// Its roads, sorted.
    pub roads: Vec<RoadId>,
}

impl SimSpec {
    /// The all-human version: every AV type drives like the humans (its `controlled` flag off; an AV with no
    /// policy otherwise drives as a human too, but is never teleported).
    pub fn all_human(&self) -> SimSpec {
        let mut s = self.clone();
        for t in &mut s.vehicle_types {
            t.controlled = false;
        }
        s
    }

    /// The measured merges' names, in the order of [`crate::RunMetrics::merge_flows_veh_h`].
    pub fn measure_names(&self) -> Vec<String> {
        self.measure_points.iter().map(|p| p.name.clone()).collect()
    }

    /// The junction of each measure point (the one its roads start at), in the order of
    /// [`crate::RunMetrics::merge_flows_veh_h`]; `None` for a point without a road.
    pub fn measure_junctions(&self) -> Vec<Option<mapc_graph::JunctionId>> {
        self.measure_points
            .iter()
            .map(|p| Some(self.graph.road(*p.roads.first()?)?.from))
            .collect()
    }

    /// Check the numbers a run relies on; errors name the item.
    pub fn validate(&self) -> Result<(), SimError> {
        let range = |what: String, v: f64, range: ranges::Range| {
            ranges::check(what, v, range)
                .map_err(|r| SimError::Spec(format!("{}: {}", r.key, r.message)))
        };
        range("step_s".into(), self.step_s, ranges::STEP_S)?;
        range(
            "time_to_teleport_s".into(),
            self.time_to_teleport_s,
            ranges::TIME_TO_TELEPORT_S,
        )?;
        for (i, t) in self.vehicle_types.iter().enumerate() {
            let bad = |what: &str, v: f64| {
                SimError::Spec(format!("vehicle type {i} `{}`: {what} = {v}", t.name))
            };
            for (what, v) in [
                ("accel", t.accel),
                ("decel", t.decel),
                ("max_speed", t.max_speed),
                ("length", t.length),
                ("speed_factor", t.speed_factor),
                ("delta", t.delta),
            ] {
                if !(v > 0.0 && v.is_finite()) {
                    return Err(bad(what, v));
                }
            }
            range(
                format!("vehicle type {i} `{}`: idm_stepping_s", t.name),
                t.idm_stepping_s,
                ranges::IDM_STEPPING_S,
            )?;
            for (what, v) in [
                ("tau", t.tau),
                ("min_gap", t.min_gap),
                ("speed_dev", t.speed_dev),
            ] {
                if !(v >= 0.0 && v.is_finite()) {
                    return Err(bad(what, v));
                }
            }
            if !(0.0..=1.0).contains(&t.impatience) {
                return Err(bad("impatience", t.impatience));
            }
            if !(0.0..=1.0).contains(&t.sigma) {
                return Err(bad("sigma", t.sigma));
            }
            if !(t.emergency_decel >= t.decel) {
                return Err(bad("emergency_decel (must be >= decel)", t.emergency_decel));
            }
        }
        for (i, f) in self.flows.iter().enumerate() {
            if f.vehicle_type >= self.vehicle_types.len() {
                return Err(SimError::Spec(format!(
                    "flow {i}: unknown vehicle type index {}",
                    f.vehicle_type
                )));
            }
            if !(f.vehs_per_hour >= 0.0 && f.vehs_per_hour.is_finite()) {
                return Err(SimError::Spec(format!(
                    "flow {i}: vehs_per_hour = {}",
                    f.vehs_per_hour
                )));
            }
            if !(f.depart_speed >= 0.0 && f.depart_speed.is_finite()
                || f.depart_speed == DEPART_SPEED_MAX
                || f.depart_speed == DEPART_SPEED_DESIRED)
            {
                return Err(SimError::Spec(format!(
                    "flow {i}: depart_speed = {}",
                    f.depart_speed
                )));
            }
            // departure times are begin + n * period: a begin out of range makes them stand still or pile up
            range(format!("flow {i}: begin_s"), f.begin_s, ranges::FLOW_TIME_S)?;
            if !(f.end_s > f.begin_s) {
                return Err(SimError::Spec(format!(
                    "flow {i}: end_s = {} is not after begin_s = {}",
                    f.end_s, f.begin_s
                )));
            }
        }
        let road_lanes = |road: RoadId| self.graph.road(road).map_or(1, |r| r.lanes.len());
        let demand: Vec<mapc_scenario::bounds::FlowDemand> = self
            .flows
            .iter()
            .filter(|f| !f.queue_excess)
            .map(|f| mapc_scenario::bounds::FlowDemand {
                id: &f.id,
                entry: mapc_scenario::bounds::entry_key(
                    &f.from.to_string(),
                    Some(&f.depart_lane.sumo_value()),
                ),
                lanes: mapc_scenario::bounds::entry_lanes(
                    Some(&f.depart_lane.sumo_value()),
                    road_lanes(f.from),
                ),
                road: f.from.to_string(),
                road_lanes: road_lanes(f.from) as u32,
                vehs_per_hour: f.vehs_per_hour,
            })
            .collect();
        // queued demand is counted departure by departure: bounded all the same
        let most = mapc_scenario::bounds::MOST_QUEUED_VEHICLES_A_STEP * 3600.0 / self.step_s;
        if let Some(f) = self
            .flows
            .iter()
            .find(|f| f.queue_excess && !(f.vehs_per_hour <= most))
        {
            return Err(SimError::Spec(format!(
                "flow {}: {} veh/h, more than {} vehicles a step",
                f.id,
                f.vehs_per_hour,
                mapc_scenario::bounds::MOST_QUEUED_VEHICLES_A_STEP
            )));
        }
        mapc_scenario::bounds::check_demand(&demand, self.step_s)
            .and_then(|()| {
                mapc_scenario::bounds::check_horizon(
                    self.warmup_steps,
                    self.horizon_steps,
                    self.step_s,
                )
            })
            .map_err(|r| SimError::Spec(format!("{}: {}", r.key, r.message)))?;
        for (i, v) in self.initial.iter().enumerate() {
            if v.vehicle_type >= self.vehicle_types.len() {
                return Err(SimError::Spec(format!(
                    "initial vehicle {i}: unknown vehicle type index {}",
                    v.vehicle_type
                )));
            }
        }
        for d in &self.detectors {
            let bad = |what: String| SimError::Spec(format!("detector `{}`: {what}", d.id));
            let road = self
                .graph
                .road(d.road)
                .ok_or_else(|| bad(format!("no road {}", d.road)))?;
            if d.lane as usize >= road.lanes.len() {
                return Err(bad(format!(
                    "road {} has no lane {} ({} lanes)",
                    d.road,
                    d.lane,
                    road.lanes.len()
                )));
            }
            if !(0.0..=road.length_m).contains(&d.pos_m) {
                return Err(bad(format!(
                    "position {} m is off the lane ({} m)",
                    d.pos_m, road.length_m
                )));
            }
            if !(d.period_s > 0.0 && d.period_s.is_finite()) {
                return Err(bad(format!("period {} s", d.period_s)));
            }
            if let Some(t) = d
                .vehicle_types
                .iter()
                .find(|&&t| t >= self.vehicle_types.len())
            {
                return Err(bad(format!("unknown vehicle type index {t}")));
            }
        }
        Ok(())
    }
}
