//! The scenario of a cut corridor: the source's vehicle types, step, horizon and initial vehicles, its flows
//! moved to the corridor's entries (main-road flows onto the main road's first road, merging-road flows onto
//! the merging roads' first roads), and the window(s) as the controlled region(s).

use super::SourceShape;
use super::cut::{WindowCut, WindowsCut};
use super::fit::FittedLength;
use crate::transform::{CorridorRoles, TransformError};
use crate::{
    Control, ControlWindow, Flow, NetworkSpec, ResolvedScenario, SCENARIO_VERSION, Scenario,
    WindowInfo,
};
use mapc_graph::{JunctionId, LaneGraph, RoadId};
use std::collections::HashSet;

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

/// The flows of a corridor scenario: each source flow on the main road moved to `main_entry`, each source
/// flow on the merging road repeated on every entry of `ramps` (its id suffixed with the road's when there are
/// several), scaled as `demand` says.
fn corridor_flows(
    g: &LaneGraph,
    roles: &CorridorRoles,
    main_entry: RoadId,
    ramps: &[RoadId],
    source: &ResolvedScenario,
    shape: &SourceShape,
    demand: &DemandOverride,
) -> Result<Vec<Flow>, TransformError> {
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
    let mut flows = Vec::new();
    for (f, role) in s.flows.iter().zip(kinds) {
        let scaled = |wanted: Option<f64>| match wanted {
            Some(total) if totals[role] > 0.0 => f.vehs_per_hour * total / totals[role],
            _ => f.vehs_per_hour,
        };
        if role == 0 {
            flows.push(Flow {
                from: main_entry.to_string(),
                to: None,
                vehs_per_hour: scaled(demand.main_vph),
                ..f.clone()
            });
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
            flows.push(Flow {
                id: if ramps.len() > 1 {
                    format!("{}_{entry}", f.id)
                } else {
                    f.id.clone()
                },
                from: entry.to_string(),
                to: None,
                vehs_per_hour: scaled(wanted),
                ..f.clone()
            });
        }
    }
    Ok(flows)
}

/// The window scenario: the whole cut corridor (saved as `graph_file`, relative to the scenario), the source's
/// vehicle types, step, horizon and initial vehicles, its flows moved to the corridor's entries, and the window
/// as the controlled region.
pub fn window_scenario(
    cut: &WindowCut,
    source: &ResolvedScenario,
    shape: &SourceShape,
    name: &str,
    graph_file: &str,
    demand: &DemandOverride,
) -> Result<Scenario, TransformError> {
    let s = &source.scenario;
    let ramps = if demand.every_ramp {
        ramp_entries(&cut.graph, &cut.roles)
    } else {
        vec![cut.merge_entry]
    };
    let flows = corridor_flows(
        &cut.graph,
        &cut.roles,
        cut.main_entry,
        &ramps,
        source,
        shape,
        demand,
    )?;
    let n_av = controlled_avs(source, demand);
    let junction_name = junction_name(&cut.graph, cut.junction);
    let matched_to = matched_to(source);
    let description = format!(
        "The corridor of {} with a window around merge {} ({junction_name}) matched to {matched_to}: \
         {:.1} m of main road before the merge, {:.1} m of merging road, {:.1} m after.{}",
        cut.graph.source.file,
        cut.junction,
        cut.upstream_m,
        cut.merge_m,
        cut.downstream_m,
        fitted_list(&cut.fitted).map_or(String::new(), |l| format!(" Fitted to the map: {l}."))
    );
    let control = Control {
        n_av,
        region: cut.region().iter().map(|r| r.to_string()).collect(),
        window: Some(WindowInfo {
            junction: junction_name,
            matched_to,
            upstream_m: cut.upstream_m,
            merge_m: cut.merge_m,
            downstream_m: cut.downstream_m,
        }),
        windows: vec![],
    };
    Ok(corridor_scenario(
        s,
        name,
        description,
        graph_file,
        flows,
        control,
    ))
}

/// The scenario of a corridor cut for several windows: as [`window_scenario`], with a flow on every merging road
/// of the corridor and one `[[control.windows]]` entry per region.
pub fn windows_scenario(
    cut: &WindowsCut,
    source: &ResolvedScenario,
    shape: &SourceShape,
    name: &str,
    graph_file: &str,
    demand: &DemandOverride,
) -> Result<Scenario, TransformError> {
    let s = &source.scenario;
    let g = &cut.graph;
    let ramps = ramp_entries(g, &cut.roles);
    let flows = corridor_flows(g, &cut.roles, cut.main_entry, &ramps, source, shape, demand)?;
    let n_av = controlled_avs(source, demand);
    let matched_to = matched_to(source);
    let windows: Vec<ControlWindow> = cut
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
    Ok(corridor_scenario(
        s,
        name,
        description,
        graph_file,
        flows,
        control,
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
        network: NetworkSpec::Graph(graph_file.into()),
        vehicle_types: s.vehicle_types.clone(),
        flows,
        initial_vehicles: s.initial_vehicles.clone(),
        control: Some(control),
        measure: None,
    }
}
