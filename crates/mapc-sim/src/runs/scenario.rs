//! From a resolved scenario to a [`SimSpec`], and the scenario-level entry points.

use super::kept::KeptRuns;
use crate::demand::placement::{check_initial_spacing, initial_placement};
use crate::error::SimError;
use crate::measure::metrics::RunMetrics;
use crate::measure::points::MeasurePoint;
use crate::network::Network;
use crate::sim::Simulation;
use crate::spec::{
    DEPART_SPEED_DESIRED, DEPART_SPEED_MAX, DepartLane, DepartPos, DetectorSpec, FlowSpec, SimSpec,
    VehicleTypeSpec,
};
use mapc_graph::RoadId;
use mapc_scenario::ResolvedScenario;
use rayon::prelude::*;

/// SUMO's default emergency deceleration of a passenger car (m/s^2).
const EMERGENCY_DECEL: f64 = 9.0;
/// Krauss' dawdling when a type does not give it (SUMO 1.8's default).
const KRAUSS_SIGMA: f64 = 0.5;
/// The original rollouts ran two steps (start, and the reset that inserts the initial vehicles) before the
/// horizon; the clock at step 0 is two steps in, except in a SUMO user's scenario (`sumo_clock`), where it is 0
/// as SUMO's at its begin: its first step inserts the departures due at 0, as SUMO's does.
const SETUP_STEPS: f64 = 2.0;

/// The scenario's induction loops on its roads.
fn detector_specs(rs: &ResolvedScenario, types: &[&String]) -> Result<Vec<DetectorSpec>, SimError> {
    rs.detectors
        .iter()
        .map(|d| {
            let vehicle_types = d
                .vehicle_types
                .iter()
                .map(|t| {
                    types.iter().position(|n| *n == t).ok_or_else(|| {
                        SimError::Spec(format!(
                            "{}: detector `{}`: no vehicle type `{t}`",
                            rs.origin, d.id
                        ))
                    })
                })
                .collect::<Result<_, _>>()?;
            Ok(DetectorSpec {
                id: d.id.clone(),
                road: d.road,
                lane: d.lane,
                pos_m: d.pos_m,
                period_s: d.period_s,
                vehicle_types,
            })
        })
        .collect()
}

/// The simulator's description of a resolved scenario.
pub fn spec_from_scenario(rs: &ResolvedScenario) -> Result<SimSpec, SimError> {
    let sc = &rs.scenario;
    let names: Vec<&String> = sc.vehicle_types.keys().collect();
    let vehicle_types: Vec<VehicleTypeSpec> = sc
        .vehicle_types
        .iter()
        .map(|(name, t)| VehicleTypeSpec {
            name: name.clone(),
            accel: t.accel,
            decel: t.decel,
            emergency_decel: t.emergency_decel.unwrap_or(EMERGENCY_DECEL.max(t.decel)),
            tau: t.tau,
            min_gap: t.min_gap,
            delta: t.delta,
            max_speed: t.max_speed,
            length: t.length,
            speed_factor: t.speed_factor,
            speed_dev: t.speed_dev,
            impatience: t.impatience,
            controlled: t.controlled,
            idm_stepping_s: t.idm_stepping_s,
            car_follow_model: t.car_follow_model,
            sigma: t.sigma.unwrap_or(KRAUSS_SIGMA),
            lane_change: t.lane_change,
        })
        .collect();
    let type_index = |name: &str, what: &str| -> Result<usize, SimError> {
        names
            .iter()
            .position(|n| n.as_str() == name)
            .ok_or_else(|| {
                SimError::Spec(format!("{}: {what}: no vehicle type `{name}`", rs.origin))
            })
    };
    let mut flows = Vec::with_capacity(sc.flows.len());
    for (i, f) in sc.flows.iter().enumerate() {
        let (from, to) = *rs.flow_roads.get(i).ok_or_else(|| {
            SimError::Spec(format!("{}: flows[{i}] has no resolved roads", rs.origin))
        })?;
        // a mix: the first type stands for the flow where one is needed, each vehicle draws its own
        let (vehicle_type, type_mix) = match sc.vehicle_type_mixes.get(&f.vehicle_type) {
            Some(mix) => {
                let total: f64 = mix.values().sum();
                let mut acc = 0.0;
                let mut cumulative = Vec::with_capacity(mix.len());
                for (name, w) in mix {
                    acc += w / total;
                    cumulative.push((
                        type_index(name, &format!("vehicle_type_mixes.{}", f.vehicle_type))?,
                        acc,
                    ));
                }
                if let Some(last) = cumulative.last_mut() {
                    last.1 = 1.0;
                }
                (cumulative[0].0, cumulative)
            }
            None => (
                type_index(&f.vehicle_type, &format!("flows[{i}].vehicle_type"))?,
                Vec::new(),
            ),
        };
        flows.push(FlowSpec {
            id: f.id.clone(),
            from,
            to,
            vehs_per_hour: f.vehs_per_hour,
            vehicle_type,
            type_mix,
            via: rs.flow_via.get(i).cloned().unwrap_or_default(),
            probability: f.probability,
            number: f.number,
            queue_excess: rs.queue_excess_demand,
            depart_pos: match f.depart_pos.as_deref() {
                Some("random") => DepartPos::Random,
                Some("random_free") => DepartPos::RandomFree,
                Some("free") => DepartPos::Free,
                _ => DepartPos::Base,
            },
            depart_speed: match f.depart_speed.as_deref() {
                Some("max") => DEPART_SPEED_MAX,
                Some("desired") => DEPART_SPEED_DESIRED,
                _ => f.depart_speed_mps,
            },
            begin_s: f.begin_s,
            end_s: f.end_s.unwrap_or(f64::INFINITY),
            single_vehicle: f.vehicle && f.number == Some(1),
            whole_ms: sc.sumo_clock,
            depart_lane: match &f.depart_lane {
                None => DepartLane::First,
                Some(text) => DepartLane::parse(text)
                    .map_err(|e| SimError::Spec(format!("{}: flow {}: {e}", rs.origin, f.id)))?,
            },
        });
    }
    // Main line: the route of the busiest flow.
    let net = Network::from_graph(&rs.graph)?;
    let main_line: Vec<RoadId> = match flows
        .iter()
        .max_by(|a, b| a.vehs_per_hour.total_cmp(&b.vehs_per_hour))
    {
        Some(f) => net
            .route(&rs.graph, f.from, f.to)?
            .into_iter()
            .filter_map(|l| net.road_of(l))
            .map(|r| net.road_ids[r])
            .collect(),
        None => Vec::new(),
    };
    let mut initial = Vec::new();
    if let Some(iv) = &sc.initial_vehicles {
        let vt = type_index(&iv.vehicle_type, "initial_vehicles.vehicle_type")?;
        let t = &vehicle_types[vt];
        let total: f64 = rs.graph.roads.iter().map(|r| r.length_m).sum();
        let room = t.length + t.min_gap;
        if iv.count > 0 && total / (iv.count as f64) < room {
            return Err(SimError::Spec(format!(
                "{}: initial_vehicles.count = {}: spaced evenly over the roads' {total:.1} m they would stand \
                 {:.2} m apart, less than a `{}` vehicle's length plus minimum gap ({room} m); at most {} fit",
                rs.origin,
                iv.count,
                total / iv.count as f64,
                t.name,
                (total / room).floor()
            )));
        }
        initial = initial_placement(
            &rs.graph,
            &net,
            &main_line,
            iv.count as usize,
            iv.speed_mps,
            vt,
        )
        .and_then(|initial| {
            check_initial_spacing(&net, &initial, &vehicle_types)?;
            Ok(initial)
        })
        .map_err(|e| SimError::Spec(format!("{}: initial_vehicles: {e}", rs.origin)))?;
    }
    let step_s = sc.step_s;
    Ok(SimSpec {
        detectors: detector_specs(rs, &names)?,
        time_to_teleport_s: sc.time_to_teleport_s.unwrap_or(0.0),
        sumo_junction_lane_changes: sc.sumo_junction_lane_changes,
        sumo_insertion_order: sc.sumo_clock,
        graph: rs.graph.clone(),
        vehicle_types,
        flows,
        initial,
        step_s,
        horizon_steps: sc.horizon_steps as u64,
        warmup_steps: sc.warmup_steps as u64,
        clock_begin_s: sc.clock_begin_s,
        start_time_s: if sc.sumo_clock {
            0.0
        } else {
            SETUP_STEPS * step_s
        },
        control_region: if rs.region_roads.is_empty() {
            None
        } else {
            Some(rs.region_roads.clone())
        },
        n_av: sc.control.as_ref().map_or(0, |c| c.n_av as usize),
        main_line,
        control_windows: rs
            .windows
            .iter()
            .map(|w| crate::spec::ControlWindowSpec {
                name: w.name.clone(),
                merges: w.merges.clone(),
                roads: w.roads.clone(),
            })
            .collect(),
        measure_points: rs
            .measure_junctions
            .iter()
            .map(|&j| {
                let junction = rs.graph.junction(j);
                let known_as = junction
                    .and_then(|j| {
                        j.provenance
                            .osm_nodes
                            .first()
                            .map(|n| format!(" (osm:{n})"))
                            .or_else(|| j.provenance.sumo_ids.first().map(|s| format!(" ({s})")))
                    })
                    .unwrap_or_default();
                MeasurePoint {
                    name: format!("merge {j}{known_as}"),
                    roads: junction.map(|j| j.outgoing.clone()).unwrap_or_default(),
                }
            })
            .collect(),
    })
}

impl Simulation {
    /// A simulation of a resolved scenario with every random draw from `seed`.
    pub fn new(rs: &ResolvedScenario, seed: u64) -> Result<Simulation, SimError> {
        Simulation::from_spec(spec_from_scenario(rs)?, seed)
    }
}

/// All-human baseline over `seeds` (controlled vehicles drive as humans; parallel, results in seed order).
pub fn run_baseline(rs: &ResolvedScenario, seeds: &[u64]) -> Result<Vec<RunMetrics>, SimError> {
    run_baseline_spec(&spec_from_scenario(rs)?, seeds)
}

/// Run every seed to the horizon in parallel (rayon's current pool); results in seed order. Runs kept
/// ([`super::kept`]) are not run again.
pub fn run_baseline_spec(spec: &SimSpec, seeds: &[u64]) -> Result<Vec<RunMetrics>, SimError> {
    let runs = KeptRuns::of(spec);
    seeds.par_iter().map(|&seed| runs.run(seed)).collect()
}
