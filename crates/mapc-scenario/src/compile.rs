//! The scenario compiler on files, as `mapc simplify`, `mapc window` and the Python package run it: a map file
//! simplified to a corridor, a window cut and written as a scenario beside its graph and checked by reading it
//! back, and the JSON reports both print.

use crate::ResolvedScenario;
pub use crate::compile_error::CompileError;
use crate::compile_files::CheckedFiles;
use crate::simplify::{
    MergeSummary, Simplified, corridor_complex_junctions, corridor_merges, no_merge_warning,
    simplify,
};
use crate::transform::pick_route::describe_junction;
use crate::transform::{Corridor, CorridorRoles, SimplifyOptions, TransformError};
use crate::window::{
    DemandOverride, Fit, FittedLength, Overlap, SourceShape, WindowRequest, WindowsCut,
    cut_windows, junction_name, windows_scenario,
};
use mapc_graph::LaneGraph;
use serde_json::{Value, json};
use std::path::{Path, PathBuf};

/// A map or graph file, with the importer's defaults.
pub fn load_map(path: &Path) -> Result<LaneGraph, CompileError> {
    mapc_import::load_any(path).map_err(|error| CompileError::Map {
        path: path.to_path_buf(),
        error,
    })
}

/// A map file simplified to a corridor.
pub fn simplify_map(map: &Path, options: &SimplifyOptions) -> Result<Simplified, CompileError> {
    let raw = load_map(map)?;
    simplify(&raw, options).map_err(|error| CompileError::Transform {
        path: map.to_path_buf(),
        error,
    })
}

/// The JSON report of a corridor: its main road, merges and steps.
pub fn corridor_report(s: &Simplified, map: &Path, output: &Path) -> Value {
    let g = &s.graph;
    let merges: Vec<MergeSummary> = corridor_merges(g, &s.roles);
    let first = g.road(s.roles.main[0]).map(|r| r.from);
    let last = s.roles.main.last().and_then(|r| g.road(*r)).map(|r| r.to);
    let complex = corridor_complex_junctions(g, &s.roles);
    let mut report = json!({
        "map": map.display().to_string(),
        "output": output.display().to_string(),
        "main_road": {
            "roads": s.roles.main.iter().map(|r| r.to_string()).collect::<Vec<_>>(),
            "length_m": Corridor::chain_length_m(g, &s.roles.main),
            "from": first.map(|j| describe_junction(g, j)),
            "to": last.map(|j| describe_junction(g, j)),
        },
        "merges": merges,
        "exits": s.roles.exits.len(),
        "roads": g.roads.len(),
        "junctions": g.junctions.len(),
        "steps": s.steps,
    });
    if !complex.is_empty() {
        report["junctions_with_several_merging_roads"] = json!(complex);
    }
    if let Some(lanes) = lane_report(g, &g.roads.iter().map(|r| r.id).collect::<Vec<_>>()) {
        report["lanes"] = lanes;
    }
    if let Some(warning) = no_merge_warning(s, map) {
        report["warning"] = json!(warning);
    }
    report
}

/// Lanes per road of `roads`, the lanes that end where their road goes on, and the lane connections, for a graph
/// with several lanes on some road (`--keep-lanes`); `None` for a graph of one lane a road, whose reports stay as
/// they were.
pub fn lane_report(g: &LaneGraph, roads: &[mapc_graph::RoadId]) -> Option<Value> {
    if g.roads.iter().all(|r| r.lanes.len() == 1) {
        return None;
    }
    let mut per_road = serde_json::Map::new();
    let mut ends = Vec::new();
    for r in roads.iter().filter_map(|r| g.road(*r)) {
        per_road.insert(r.id.to_string(), json!(r.lanes.len()));
        for l in r.lanes.iter().filter(|l| l.end.is_some()) {
            ends.push(json!({"road": r.id.to_string(), "lane": l.index, "end": l.end}));
        }
    }
    let count = |kind: mapc_graph::LaneEnd| {
        g.roads
            .iter()
            .flat_map(|r| &r.lanes)
            .filter(|l| l.end == Some(kind))
            .count()
    };
    Some(json!({
        "per_road": per_road,
        "connections": g.connections.len(),
        "acceleration_lanes": count(mapc_graph::LaneEnd::Acceleration),
        "lane_drops": count(mapc_graph::LaneEnd::Drop),
        "ends": ends,
    }))
}

/// The corridor of `map`: the graph itself when it is one, else the map simplified with `options` (with no
/// `junction`, as `mapc simplify` does: the longest route, or the one `via` names). Without `via`, the corridor
/// must keep `junction` a merge (the window is cut there): the route through `junction` alone
/// is tried first, then the routes through each road into it (higher class, then longer, first), since the longest
/// route through a merge may come in on the merging road and leave the other road in as one that leaves and
/// rejoins it, which is no merge. The first corridor where `junction` is a merge is taken; failing that, the first
/// one, whose window cut then says why.
pub fn corridor_of(
    map: &Path,
    junction: Option<&str>,
    options: &SimplifyOptions,
) -> Result<LaneGraph, CompileError> {
    let g = load_map(map)?;
    if CorridorRoles::of(&g).is_ok() {
        return Ok(g);
    }
    let transform = |error| CompileError::Transform {
        path: map.to_path_buf(),
        error,
    };
    let Some(junction) = junction.filter(|_| options.via.is_empty()) else {
        return simplify(&g, options).map(|s| s.graph).map_err(transform);
    };
    // the map's junction, named as `--junction` (not as the `--via` it becomes below)
    let j = g
        .find_junction(junction)
        .map_err(|error| CompileError::Junction {
            path: map.to_path_buf(),
            junction: junction.to_string(),
            error,
        })?;
    let mut attempts = vec![junction.to_string()];
    let mut incoming: Vec<&mapc_graph::Road> = g
        .junction(j)
        .map(|x| x.incoming.iter().filter_map(|r| g.road(*r)).collect())
        .unwrap_or_default();
    incoming.sort_by(|a, b| {
        b.priority
            .cmp(&a.priority)
            .then(b.length_m.total_cmp(&a.length_m))
            .then(a.id.cmp(&b.id))
    });
    attempts.extend(incoming.iter().map(|r| r.id.to_string()));
    let mut first = None;
    for via in attempts {
        let opts = SimplifyOptions {
            via: vec![via],
            ..options.clone()
        };
        match simplify(&g, &opts) {
            Ok(s) => {
                let merge = j.to_string();
                if corridor_merges(&s.graph, &s.roles)
                    .iter()
                    .any(|m| m.junction == merge)
                {
                    return Ok(s.graph);
                }
                first.get_or_insert(Ok(s.graph));
            }
            Err(e) => {
                first.get_or_insert(Err(e));
            }
        }
    }
    first.expect("one attempt at least").map_err(transform)
}

/// Demand overrides must be zero or positive rates.
fn check_demand(demand: &DemandOverride) -> Result<(), CompileError> {
    let per_road = demand
        .ramp_vph
        .iter()
        .map(|(road, v)| (format!("--ramp-vph {road}"), Some(*v)));
    for (name, v) in [
        ("--main-vph".to_string(), demand.main_vph),
        ("--merge-vph".to_string(), demand.merge_vph),
    ]
    .into_iter()
    .chain(per_road)
    {
        if let Some(v) = v
            && !(v.is_finite() && v >= 0.0)
        {
            return Err(CompileError::Demand(format!(
                "{name} must be zero or a positive rate, not {v}"
            )));
        }
    }
    Ok(())
}

/// The source scenario (`--match`) and the shape of its merge.
fn source_shape(source: &str) -> Result<(ResolvedScenario, SourceShape), CompileError> {
    let resolved = ResolvedScenario::load(source).map_err(|e| CompileError::Source {
        arg: source.to_string(),
        error: e,
    })?;
    let shape = SourceShape::of(&resolved).map_err(|e| CompileError::SourceShape {
        arg: source.to_string(),
        error: e,
    })?;
    Ok((resolved, shape))
}

/// The scenario's name, its graph file's name and path (beside the scenario).
fn output_names(output: &Path) -> (String, String, PathBuf) {
    let name = output
        .file_name()
        .and_then(|n| n.to_str())
        .map(|n| n.trim_end_matches(".toml").to_string())
        .filter(|n| !n.is_empty())
        .unwrap_or_else(|| "window".into());
    let graph_file = format!("{name}.graph.json");
    let graph = output.parent().unwrap_or(Path::new("")).join(&graph_file);
    (name, graph_file, graph)
}

/// Refuses demand the source's step cannot insert (before anything is written) and picks a warm-up when the
/// corridor is longer than the source's timing allows (refused, before anything is written, beyond the
/// scenario's bounds).
fn bounded(
    scenario: &mut crate::Scenario,
    g: &LaneGraph,
    entries: &[mapc_graph::RoadId],
) -> Result<Option<crate::timing::PickedTiming>, CompileError> {
    let flows: Vec<crate::bounds::FlowDemand> = scenario
        .flows
        .iter()
        .map(|f| {
            let road_lanes = g
                .find_roads(&f.from)
                .ok()
                .and_then(|r| g.road(*r.first()?))
                .map_or(1, |r| r.lanes.len());
            crate::bounds::FlowDemand {
                id: &f.id,
                entry: crate::bounds::entry_key(&f.from, f.depart_lane.as_deref()),
                lanes: crate::bounds::entry_lanes(f.depart_lane.as_deref(), road_lanes),
                road: f.from.clone(),
                road_lanes: road_lanes as u32,
                vehs_per_hour: f.vehs_per_hour,
            }
        })
        .collect();
    crate::bounds::check_demand(&flows, scenario.step_s).map_err(|r| {
        CompileError::Demand(format!(
            "--main-vph / --merge-vph / --ramp-vph: {} (nothing written)",
            r.message
        ))
    })?;
    crate::timing::fit_to_corridor(scenario, g, entries).map_err(|r| {
        CompileError::Timing(format!(
            "the window's {}: {} (nothing written)",
            r.key, r.message
        ))
    })
}

/// Windows cut from a corridor and written: the scenario file and its cut corridor graph beside it.
#[derive(Clone, Debug)]
pub struct WrittenWindows {
    pub cut: WindowsCut,
    pub shape: SourceShape,
    pub scenario: PathBuf,
    pub graph: PathBuf,
    /// The warm-up picked for a corridor longer than the source's timing allows (`None`: the source's kept).
    pub timing: Option<crate::timing::PickedTiming>,
    /// What demand each road of several lanes got (the source's per lane on each lane); empty on one lane.
    pub demand_notes: Vec<String>,
    /// Written and reported in the one-window format ([`WindowsOptions::one_window`]).
    pub one_window: bool,
}

/// Which windows [`write_windows`] cuts besides those asked for, and how they are written.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct WindowsOptions {
    /// A window at every merge of the corridor whose window fits, the first of two overlapping ones kept.
    pub all: bool,
    /// Overlapping windows become one region instead of an error.
    pub join: bool,
    /// Every window without a fit of its own is fitted to what the map has (`--fit`); with `all`, merges that
    /// fit only above the floor are skipped and say why.
    pub fit: Option<Fit>,
    /// One window asked for alone (one request, neither `all` nor `join`) is written and reported as before
    /// several windows existed: `[control] region` and `window`, demand on its own merging road, the flat
    /// report; ignored otherwise.
    pub one_window: bool,
}

/// One window: [`write_windows`] of a list of one, in the one-window format.
pub fn write_window(
    corridor: &LaneGraph,
    map: &Path,
    request: impl Into<WindowRequest>,
    source: &str,
    output: &Path,
    demand: &DemandOverride,
) -> Result<WrittenWindows, CompileError> {
    let options = WindowsOptions {
        one_window: true,
        ..WindowsOptions::default()
    };
    write_windows(
        corridor,
        map,
        &[request.into()],
        options,
        source,
        output,
        demand,
    )
}

/// Cut the windows of `requests` (and more, as `options` says) of `corridor` (read from `map`) matched to the
/// scenario `source` (a built-in name or a file), and write them as one scenario with one controlled region per
/// window to `output` (a `.toml`; the graph goes beside it as `<name>.graph.json`). Both are checked to load back
/// as a sound scenario before either is written ([`CheckedFiles`]); on any error nothing is written. Demand
/// overrides must be zero or positive rates (`--main-vph`, `--merge-vph`).
pub fn write_windows(
    corridor: &LaneGraph,
    map: &Path,
    requests: &[WindowRequest],
    options: WindowsOptions,
    source: &str,
    output: &Path,
    demand: &DemandOverride,
) -> Result<WrittenWindows, CompileError> {
    let (windows, files) =
        prepare_windows(corridor, map, requests, options, source, output, demand)?;
    files.write()?;
    Ok(windows)
}

/// [`write_windows`] up to the writing: the windows and their files, checked, for a caller that has more to
/// check (the merges' regime) before anything is written.
pub fn prepare_windows(
    corridor: &LaneGraph,
    map: &Path,
    requests: &[WindowRequest],
    options: WindowsOptions,
    source: &str,
    output: &Path,
    demand: &DemandOverride,
) -> Result<(WrittenWindows, CheckedFiles), CompileError> {
    check_demand(demand)?;
    let (resolved, shape) = source_shape(source)?;
    let transform = |error: TransformError| CompileError::Transform {
        path: map.to_path_buf(),
        error,
    };
    let WindowsOptions {
        all,
        join,
        fit,
        one_window,
    } = options;
    let one_window = one_window && requests.len() == 1 && !all && !join;
    let mut requests: Vec<WindowRequest> = requests
        .iter()
        .map(|r| WindowRequest {
            fit: r.fit.or(fit),
            ..r.clone()
        })
        .collect();
    if all {
        let roles = CorridorRoles::of(corridor).map_err(transform)?;
        for m in corridor_merges(corridor, &roles) {
            // A merge asked for by name keeps its own upstream length.
            let j = corridor
                .find_junction(&m.junction)
                .expect("a corridor's own junction");
            if !requests
                .iter()
                .any(|r| corridor.find_junction(&r.junction) == Ok(j))
            {
                requests.push(WindowRequest::at(&m.junction).fitted(fit));
            }
        }
    }
    let overlap = if join {
        Overlap::Join
    } else if all {
        Overlap::SkipLater
    } else {
        Overlap::Refuse
    };
    let cut = cut_windows(corridor, &requests, &shape, overlap).map_err(transform)?;
    let (name, graph_file, graph) = output_names(output);
    let (mut scenario, demand_notes) = windows_scenario(
        &cut,
        &resolved,
        &shape,
        &name,
        &graph_file,
        demand,
        one_window,
    )
    .map_err(transform)?;
    // The warm-up fits the routes from the main road's entry; a one-window scenario's, as it always has, also
    // the route from its merging road's.
    let mut entries = vec![cut.main_entry];
    if one_window {
        entries.extend(&cut.regions[0].merge_entries);
    }
    let timing = bounded(&mut scenario, &cut.graph, &entries)?;
    let files = CheckedFiles::check(&cut.graph, &graph, &scenario, output)?;
    let windows = WrittenWindows {
        cut,
        shape,
        scenario: output.to_path_buf(),
        graph,
        timing,
        demand_notes,
        one_window,
    };
    Ok((windows, files))
}

impl WrittenWindows {
    /// The JSON report `mapc window --json` prints (`render`: the picture drawn, if any): every window's merges,
    /// lengths and offsets along the corridor's main road; in the one-window format, the window's fields at the
    /// top (its merging road's length and entry as one, its merge's OSM node and SUMO id) instead of `windows`.
    pub fn report(&self, matched_to: &str, render: Option<&Path>) -> Value {
        let g = &self.cut.graph;
        let mut windows: Vec<Value> = self
            .cut
            .regions
            .iter()
            .map(|r| {
                json!({
                    "junction": r.merges[0].to_string(),
                    "name": junction_name(g, r.merges[0]),
                    "joined": r.merges[1..].iter().map(|j| junction_name(g, *j)).collect::<Vec<_>>(),
                    "merge_at_m": r.merge_at_m,
                    "start_m": r.start_m(),
                    "end_m": r.end_m(),
                    "upstream_m": r.upstream_m,
                    "merge_m": r.merge_m,
                    "downstream_m": r.downstream_m,
                    "region": r.roads().iter().map(|x| x.to_string()).collect::<Vec<_>>(),
                    "merge_entries": r.merge_entries.iter().map(|x| x.to_string()).collect::<Vec<_>>(),
                    "lengths": lengths_against_source(
                        &self.shape,
                        r.upstream_m,
                        r.merge_m[0],
                        r.downstream_m,
                        &r.fitted,
                    ),
                    "fitted": fitted_report(g, &r.fitted),
                })
            })
            .collect();
        let mut report = json!({
            "matched_to": matched_to,
            "source": {
                "upstream_m": self.shape.upstream_m,
                "merge_m": self.shape.merge_m,
                "downstream_m": self.shape.downstream_m,
            },
            "main_entry": self.cut.main_entry.to_string(),
            "cuts": self.cut.notes,
            "scenario": self.scenario.display().to_string(),
            "graph": self.graph.display().to_string(),
            "render": render.map(|r| r.display().to_string()),
            "timing": self.timing,
        });
        if self.one_window {
            let (r, w) = (&self.cut.regions[0], &mut windows[0]);
            for key in [
                "junction",
                "upstream_m",
                "downstream_m",
                "lengths",
                "fitted",
                "region",
            ] {
                report[key] = w[key].take();
            }
            let junction = g.junction(r.merges[0]);
            report["osm_node"] = json!(junction.and_then(|j| j.provenance.osm_nodes.first()));
            report["sumo_id"] = json!(junction.and_then(|j| j.provenance.sumo_ids.first()));
            report["merge_m"] = json!(r.merge_m[0]);
            report["merge_entry"] = json!(r.merge_entries[0].to_string());
        } else {
            report["windows"] = json!(windows);
            report["skipped"] = json!(self.cut.skipped);
        }
        let roads: Vec<_> = self.cut.regions.iter().flat_map(|r| r.roads()).collect();
        if let Some(lanes) = lane_report(g, &roads) {
            report["lanes"] = lanes;
            report["demand"] = json!(self.demand_notes);
        }
        report
    }
}

/// Each of a window's lengths against the source's: `part`, `source_m`, `window_m`, `ratio` (window / source)
/// and `fitted` (cut shorter by `--fit`).
pub fn lengths_against_source(
    shape: &SourceShape,
    upstream_m: f64,
    merge_m: f64,
    downstream_m: f64,
    fitted: &[FittedLength],
) -> Value {
    use crate::window::Part;
    let row = |part: Part, source: f64, window: f64| {
        json!({
            "part": part,
            "source_m": source,
            "window_m": window,
            "ratio": window / source,
            "fitted": fitted.iter().any(|f| f.part == part),
        })
    };
    json!([
        row(Part::Upstream, shape.upstream_m, upstream_m),
        row(Part::MergingRoad, shape.merge_m, merge_m),
        row(Part::Downstream, shape.downstream_m, downstream_m),
    ])
}

/// The lengths `--fit` cut shorter: the merge (as a scenario names it), which length, asked, fitted, why.
fn fitted_report(g: &LaneGraph, fitted: &[FittedLength]) -> Value {
    fitted
        .iter()
        .map(|f| {
            json!({
                "junction": junction_name(g, f.junction),
                "part": f.part,
                "asked_m": f.asked_m,
                "fitted_m": f.fitted_m,
                "short_by_m": f.short_by_m(),
                "reason": f.reason,
            })
        })
        .collect()
}
