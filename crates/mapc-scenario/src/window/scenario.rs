//! The scenario of a cut corridor: the source's vehicle types, step, horizon and initial vehicles, its flows
//! moved to the corridor's entries (main-road flows onto the main road's first road, merging-road flows onto
//! the merging roads' first roads), and the window(s) as the controlled region(s).

use super::SourceShape;
use super::cut::WindowsCut;
use super::fit::FittedLength;
use crate::transform::{CorridorRoles, TransformError};
use crate::{
    Control, ControlWindow, Flow, NetworkSpec, ResolvedScenario, SCENARIO_VERSION, Scenario,
    VehicleType, WindowInfo,
};
use mapc_graph::{JunctionId, LaneGraph, RoadId};
use std::collections::{BTreeMap, HashSet};

/// How the window scenario's demand differs from the source's.
#[derive(Clone, Debug, Default)]
pub struct DemandOverride {
    /// Total main-road demand (veh/h), split among vehicle types as in the source.
    pub main_vph: Option<f64>,
    /// Total demand of each merging road (veh/h); default the source's merging-road demand.
    pub merge_vph: Option<f64>,
    /// Controlled AVs at once (default: the source's).
    pub n_av: Option<u32>,
    /// Demand of single merging roads (veh/h), each named by any id of one of its roads (`R80`,
    /// `osm-way:N`); 0 leaves that road without a flow.
    pub ramp_vph: Vec<(String, f64)>,
    /// A flow on every merging road of the corridor, not only the window's (always so with several windows).
    pub every_ramp: bool,
}

/// How a scenario names a junction: its first OSM node, else its first SUMO id, else its graph id.
pub fn junction_name(g: &LaneGraph, j: JunctionId) -> String {
    let junction = g.junction(j).unwrap();
    junction
        .provenance
        .osm_nodes
        .first()
        .map(|n| format!("osm:{n}"))
        .or_else(|| junction.provenance.sumo_ids.first().cloned())
        .unwrap_or_else(|| j.to_string())
}

/// `matched_to` of a window: the source scenario's name or file.
fn matched_to(source: &ResolvedScenario) -> String {
    source
        .origin
        .strip_prefix("builtin:")
        .unwrap_or(&source.origin)
        .to_string()
}

/// The main road's road that ends at merge `j`.
fn main_road_into(g: &LaneGraph, roles: &CorridorRoles, j: JunctionId) -> RoadId {
    *roles
        .main
        .iter()
        .find(|r| g.road(**r).unwrap().to == j)
        .expect("a window's merge is on the main road")
}

/// The first road of every merging road of the corridor, in driving order of their merges.
fn ramp_entries(g: &LaneGraph, roles: &CorridorRoles) -> Vec<RoadId> {
    let at = |f: &Vec<RoadId>| {
        let j = g.road(*f.last().unwrap()).unwrap().to;
        roles
            .main
            .iter()
            .position(|r| g.road(*r).unwrap().from == j)
    };
    let mut feeders: Vec<&Vec<RoadId>> = roles.feeders.iter().collect();
    feeders.sort_by_key(|f| (at(f), f[0]));
    feeders.iter().map(|f| f[0]).collect()
}

/// Lanes of `road` that continue at its end (an acceleration lane or a dropped lane does not count); all its
/// lanes where nothing continues.
fn through_lanes(g: &LaneGraph, road: RoadId) -> usize {
    let lanes = g.road(road).unwrap().lanes.len();
    let continuing: HashSet<u8> = g
        .connections
        .iter()
        .filter(|c| c.from_road == road)
        .map(|c| c.from_lane)
        .collect();
    if continuing.is_empty() {
        lanes
    } else {
        continuing.len()
    }
}

/// How many lanes a flow's demand is for: a single-lane source's demand is per lane (Flow's and SUMO's
/// convention), so a road of several lanes at the window's boundary gets it once per lane.
struct LaneScale {
    /// Through lanes of the source's road into its merge.
    source_lanes: usize,
    /// Through lanes of the corridor's road into the (first) window's merge.
    boundary_lanes: usize,
    /// Lanes of the entry road the flow departs on (its demand is spread over them, one flow per lane).
    entry_lanes: usize,
}

impl LaneScale {
    /// The default demand's factor on a source flow's rate: the source's per-lane demand on each lane the flow
    /// can use, the window's lanes or, where the entry road is narrower, the entry's (a four-lane window fed by
    /// a one-lane stub gets one lane's demand, not four lanes' queued outside).
    fn factor(&self) -> f64 {
        let lanes = self.sized_lanes();
        if lanes == self.source_lanes {
            1.0
        } else {
            lanes as f64 / self.source_lanes as f64
        }
    }

    /// The lanes the default demand is sized on.
    fn sized_lanes(&self) -> usize {
        self.boundary_lanes.min(self.entry_lanes.max(1))
    }
}

/// About how many vehicles an hour one lane takes in at free flow at `speed_mps`: one a time headway plus the
/// time the vehicle and its gap take to pass, for the slowest to pass of `types` (SUMO inserts no closer).
fn lane_intake_vph<'a>(speed_mps: f64, types: impl Iterator<Item = &'a VehicleType>) -> f64 {
    types
        .map(|t| {
            let v = (speed_mps * t.speed_factor).min(t.max_speed).max(1e-3);
            3600.0 / (t.tau + (t.length + t.min_gap) / v)
        })
        .fold(f64::INFINITY, f64::min)
}

/// One line for each entry road whose demand is more than its lanes take in at free flow: that demand cannot
/// all enter, and the rest waits outside (reported per entry by `mapc sim`).
fn entry_intake_notes(
    g: &LaneGraph,
    flows: &[Flow],
    types: &BTreeMap<String, VehicleType>,
) -> Vec<String> {
    let mut entries: Vec<&str> = Vec::new();
    for f in flows {
        if !entries.contains(&f.from.as_str()) {
            entries.push(&f.from);
        }
    }
    let mut notes = Vec::new();
    for entry in entries {
        let Some(road) = g.find_roads(entry).ok().and_then(|r| g.road(*r.first()?)) else {
            continue;
        };
        let here: Vec<&Flow> = flows.iter().filter(|f| f.from == entry).collect();
        let demand: f64 = here.iter().map(|f| f.vehs_per_hour).sum();
        let lanes = road.lanes.len();
        let intake = lanes as f64
            * lane_intake_vph(
                road.speed_mps(),
                here.iter().filter_map(|f| types.get(&f.vehicle_type)),
            );
        if demand > intake {
            notes.push(format!(
                "warning: entry {entry} ({lanes} lane(s), {:.0} m) takes in about {intake:.0} veh/h at free flow, \
                 less than its demand of {demand:.0} veh/h: the rest waits to enter (`mapc sim` reports it per \
                 entry); lower the demand or cut the window where the road is wider",
                road.length_m
            ));
        }
    }
    notes
}

/// The flows of one source flow at an entry: one flow as it is on a one-lane entry road, else one flow per entry
/// lane (`depart_lane` its index, id suffixed `_lane<i>`) sharing `vph` equally.
fn per_lane(flow: Flow, vph: f64, entry_lanes: usize) -> Vec<Flow> {
    if entry_lanes <= 1 {
        return vec![Flow {
            vehs_per_hour: vph,
            ..flow
        }];
    }
    (0..entry_lanes)
        .map(|lane| Flow {
            id: format!("{}_lane{lane}", flow.id),
            vehs_per_hour: vph / entry_lanes as f64,
            depart_lane: Some(lane.to_string()),
            ..flow.clone()
        })
        .collect()
}

/// The flows of a corridor scenario: each source flow on the main road moved to `main_entry`, each source
/// flow on the merging road repeated on every entry of `ramps` (its id suffixed with the road's when there are
/// several), scaled as `demand` says. By default a road of several lanes gets the source's per-lane demand on
/// each of its lanes at the window (`main_boundary`: the main road's road into the first window's merge; a
/// merging road's: its last road); `--main-vph` and the other overrides stay totals. On an entry road of several
/// lanes a flow is split into one flow per lane. Also returns one line per road of several lanes saying so.
#[allow(clippy::too_many_arguments)]
fn corridor_flows(
    g: &LaneGraph,
    roles: &CorridorRoles,
    main_entry: RoadId,
    main_boundary: RoadId,
    ramps: &[RoadId],
    source: &ResolvedScenario,
    shape: &SourceShape,
    demand: &DemandOverride,
) -> Result<(Vec<Flow>, Vec<String>), TransformError> {
    let s = &source.scenario;
    let main_set: HashSet<RoadId> = shape.main_roads.iter().copied().collect();
    let merge_set: HashSet<RoadId> = shape.merge_roads.iter().copied().collect();
    let mut totals = [0.0f64; 2];
    let mut kinds = Vec::new();
    for (f, (from, _)) in s.flows.iter().zip(&source.flow_roads) {
        let role = if main_set.contains(from) {
            0
        } else if merge_set.contains(from) {
            1
        } else {
            return Err(TransformError::NotACorridor(format!(
                "{}: flow `{}` enters at `{}`, which is neither the main road nor the merging road",
                source.origin, f.id, f.from
            )));
        };
        totals[role] += f.vehs_per_hour;
        kinds.push(role);
    }
    // Per-road demand: each named road's merging road, found by its first road.
    let mut ramps: Vec<RoadId> = ramps.to_vec();
    let mut per_road: Vec<(RoadId, f64)> = Vec::new();
    let all_ramps = ramp_entries(g, roles);
    for (query, vph) in &demand.ramp_vph {
        let found = g
            .find_roads(query)
            .map_err(|e| TransformError::NotACorridor(format!("--ramp-vph {query}: {e}")))?;
        let Some(feeder) = roles.feeders.iter().find(|f| f.contains(&found[0])) else {
            let names: Vec<String> = all_ramps.iter().map(|r| r.to_string()).collect();
            return Err(TransformError::NotACorridor(format!(
                "--ramp-vph {query}: road {} is not on a merging road of the corridor; merging roads start at {}",
                found[0],
                names.join(", ")
            )));
        };
        per_road.retain(|(r, _)| *r != feeder[0]);
        per_road.push((feeder[0], *vph));
        if !ramps.contains(&feeder[0]) {
            ramps.push(feeder[0]);
        }
    }
    ramps.sort_by_key(|r| all_ramps.iter().position(|a| a == r));
    let source_main = through_lanes(&source.graph, *shape.main_roads.last().unwrap());
    let source_merge = through_lanes(&source.graph, *shape.merge_roads.last().unwrap());
    let main_scale = LaneScale {
        source_lanes: source_main,
        boundary_lanes: through_lanes(g, main_boundary),
        entry_lanes: g.road(main_entry).unwrap().lanes.len(),
    };
    let ramp_scale = |entry: RoadId| {
        let feeder = roles.feeders.iter().find(|f| f[0] == entry).unwrap();
        LaneScale {
            source_lanes: source_merge,
            boundary_lanes: through_lanes(g, *feeder.last().unwrap()),
            entry_lanes: g.road(entry).unwrap().lanes.len(),
        }
    };
    let mut notes = Vec::new();
    let mut note = |what: &str, road: RoadId, scale: &LaneScale, total: f64, overridden: bool| {
        if scale.boundary_lanes <= 1 && scale.entry_lanes <= 1 && scale.source_lanes <= 1 {
            return;
        }
        let how = if overridden {
            "as asked".to_string()
        } else {
            let lanes = scale.sized_lanes();
            let narrower = if lanes < scale.boundary_lanes {
                format!(
                    " (its entry road is narrower than the window's {} lanes)",
                    scale.boundary_lanes
                )
            } else {
                String::new()
            };
            format!(
                "the source's {:.0} veh/h per lane x {lanes} lane(s) at the window{narrower}",
                total / lanes as f64
            )
        };
        let spread = if scale.entry_lanes > 1 {
            format!(
                ", one flow per lane of its {} entry lanes",
                scale.entry_lanes
            )
        } else {
            String::new()
        };
        notes.push(format!(
            "demand {what} (enters at {road}): {total:.0} veh/h, {how}{spread}"
        ));
    };
    let mut flows = Vec::new();
    let mut main_total = 0.0;
    for (f, role) in s.flows.iter().zip(kinds.iter().copied()) {
        let scaled = |wanted: Option<f64>, scale: &LaneScale| match wanted {
            Some(total) if totals[role] > 0.0 => f.vehs_per_hour * total / totals[role],
            Some(_) => f.vehs_per_hour,
            None if scale.factor() == 1.0 => f.vehs_per_hour,
            None => f.vehs_per_hour * scale.factor(),
        };
        if role == 0 {
            let vph = scaled(demand.main_vph, &main_scale);
            main_total += vph;
            let moved = Flow {
                from: main_entry.to_string(),
                to: None,
                ..f.clone()
            };
            flows.extend(per_lane(moved, vph, main_scale.entry_lanes));
            continue;
        }
        for &entry in &ramps {
            let wanted = per_road
                .iter()
                .find(|(r, _)| *r == entry)
                .map(|(_, v)| *v)
                .or(demand.merge_vph);
            if wanted == Some(0.0) && per_road.iter().any(|(r, _)| *r == entry) {
                continue;
            }
            let scale = ramp_scale(entry);
            let moved = Flow {
                id: if ramps.len() > 1 {
                    format!("{}_{entry}", f.id)
                } else {
                    f.id.clone()
                },
                from: entry.to_string(),
                to: None,
                ..f.clone()
            };
            flows.extend(per_lane(moved, scaled(wanted, &scale), scale.entry_lanes));
        }
    }
    note(
        "on the main road",
        main_entry,
        &main_scale,
        main_total,
        demand.main_vph.is_some(),
    );
    for &entry in &ramps {
        let total: f64 = flows
            .iter()
            .filter(|f| f.from == entry.to_string())
            .map(|f| f.vehs_per_hour)
            .sum();
        let overridden = demand.merge_vph.is_some() || per_road.iter().any(|(r, _)| *r == entry);
        if total > 0.0 {
            note(
                "on the merging road",
                entry,
                &ramp_scale(entry),
                total,
                overridden,
            );
        }
    }
    notes.extend(entry_intake_notes(g, &flows, &s.vehicle_types));
    Ok((flows, notes))
}

/// The scenario of a cut corridor: the whole corridor (saved as `graph_file`, relative to the scenario), the
/// source's vehicle types, step, horizon and initial vehicles, its flows moved to the corridor's entries (every
/// merging road's), and one `[[control.windows]]` entry per region; with it, a line per road of several lanes
/// saying what demand it got. `one_window` (a cut of one window asked for alone) writes it as one-window
/// scenarios always were: the window as `[control] region` and `window`, demand on its own merging road only
/// unless `every_ramp`.
pub fn windows_scenario(
    cut: &WindowsCut,
    source: &ResolvedScenario,
    shape: &SourceShape,
    name: &str,
    graph_file: &str,
    demand: &DemandOverride,
    one_window: bool,
) -> Result<(Scenario, Vec<String>), TransformError> {
    let s = &source.scenario;
    let g = &cut.graph;
    let ramps = if one_window && !demand.every_ramp {
        cut.regions[0].merge_entries.clone()
    } else {
        ramp_entries(g, &cut.roles)
    };
    let first_merge = cut.regions[0].merges[0];
    let (flows, demand_notes) = corridor_flows(
        g,
        &cut.roles,
        cut.main_entry,
        main_road_into(g, &cut.roles, first_merge),
        &ramps,
        source,
        shape,
        demand,
    )?;
    let n_av = controlled_avs(source, demand);
    let matched_to = matched_to(source);
    let mut windows: Vec<ControlWindow> = cut
        .regions
        .iter()
        .map(|r| ControlWindow {
            junction: junction_name(g, r.merges[0]),
            joined: r.merges[1..].iter().map(|j| junction_name(g, *j)).collect(),
            matched_to: matched_to.clone(),
            upstream_m: r.upstream_m,
            merge_m: r.merge_m[0],
            downstream_m: r.downstream_m,
            region: r.roads().iter().map(|x| x.to_string()).collect(),
        })
        .collect();
    if one_window {
        let (r, w) = (&cut.regions[0], windows.remove(0));
        let description = format!(
            "The corridor of {} with a window around merge {} ({}) matched to {matched_to}: {:.1} m of main \
             road before the merge, {:.1} m of merging road, {:.1} m after.{}",
            g.source.file,
            r.merges[0],
            w.junction,
            w.upstream_m,
            w.merge_m,
            w.downstream_m,
            fitted_list(&r.fitted).map_or(String::new(), |l| format!(" Fitted to the map: {l}."))
        );
        let control = Control {
            n_av,
            region: w.region,
            window: Some(WindowInfo {
                junction: w.junction,
                matched_to: w.matched_to,
                upstream_m: w.upstream_m,
                merge_m: w.merge_m,
                downstream_m: w.downstream_m,
            }),
            windows: vec![],
        };
        let scenario = corridor_scenario(s, name, description, graph_file, flows, control);
        return Ok((scenario, demand_notes));
    }
    let listed: Vec<String> = windows
        .iter()
        .zip(&cut.regions)
        .map(|(w, r)| {
            let merges: Vec<String> = w.merges().cloned().collect();
            format!(
                "{} ({:.1} / {:.1} / {:.1} m, {:.1} m of main road{})",
                merges.join(" + "),
                w.upstream_m,
                w.merge_m,
                w.downstream_m,
                r.end_m() - r.start_m(),
                fitted_list(&r.fitted)
                    .map_or(String::new(), |l| format!("; fitted to the map: {l}"))
            )
        })
        .collect();
    let description = format!(
        "The corridor of {} with {} controlled windows matched to {matched_to} (upstream / merging road / \
         downstream): {}; the source's demand on the main road and on every merging road.",
        g.source.file,
        windows.len(),
        listed.join(", ")
    );
    let control = Control {
        n_av,
        region: vec![],
        window: None,
        windows,
    };
    Ok((
        corridor_scenario(s, name, description, graph_file, flows, control),
        demand_notes,
    ))
}

/// `merging road 194.4 m of 200.0 m` for each fitted length (`None` when nothing was fitted).
fn fitted_list(fitted: &[FittedLength]) -> Option<String> {
    if fitted.is_empty() {
        return None;
    }
    let parts: Vec<String> = fitted
        .iter()
        .map(|f| {
            format!(
                "{} {:.1} m of {:.1} m",
                f.part.name(),
                f.fitted_m,
                f.asked_m
            )
        })
        .collect();
    Some(parts.join(", "))
}

/// N_AV: the flag's, else the source's.
fn controlled_avs(source: &ResolvedScenario, demand: &DemandOverride) -> u32 {
    demand
        .n_av
        .or(source.scenario.control.as_ref().map(|c| c.n_av))
        .unwrap_or(0)
}

/// A corridor scenario on `graph_file` with the source's step, horizon, vehicle types and initial vehicles.
fn corridor_scenario(
    s: &Scenario,
    name: &str,
    description: String,
    graph_file: &str,
    flows: Vec<Flow>,
    control: Control,
) -> Scenario {
    Scenario {
        version: SCENARIO_VERSION,
        name: name.to_string(),
        description,
        step_s: s.step_s,
        horizon_steps: s.horizon_steps,
        warmup_steps: s.warmup_steps,
        time_to_teleport_s: s.time_to_teleport_s,
        network: NetworkSpec::Graph(graph_file.into()),
        vehicle_types: s.vehicle_types.clone(),
        vehicle_type_mixes: s.vehicle_type_mixes.clone(),
        flows,
        initial_vehicles: s.initial_vehicles.clone(),
        control: Some(control),
        measure: None,
        queue_excess_demand: s.queue_excess_demand,
        sumo_clock: s.sumo_clock,
        clock_begin_s: s.clock_begin_s,
        sumo_junction_lane_changes: s.sumo_junction_lane_changes,
        light_programs: s.light_programs.clone(),
        // a window keeps its own roads only: detectors named on the source network are not carried
        detectors: Vec::new(),
    }
}
