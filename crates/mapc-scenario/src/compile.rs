//! The scenario compiler on files, as `mapc simplify`, `mapc window` and the Python package run it: a map file
//! simplified to a corridor, a window cut and written as a scenario beside its graph and checked by reading it
//! back, and the JSON reports both print.

use crate::simplify::{MergeSummary, Simplified, corridor_merges, simplify};
use crate::transform::pick_route::describe_junction;
use crate::transform::{Corridor, CorridorRoles, SimplifyOptions, TransformError};
use crate::window::{DemandOverride, SourceShape, WindowCut, cut_window, window_scenario};
use crate::{ResolvedScenario, ScenarioError};
use mapc_graph::LaneGraph;
use serde_json::{Value, json};
use std::path::{Path, PathBuf};

/// What can go wrong compiling a scenario from files; every message names the file or the argument at fault.
#[derive(Debug, thiserror::Error)]
pub enum CompileError {
    #[error("cannot read map {path}: {source}")]
    Map {
        path: PathBuf,
        source: mapc_import::ImportError,
    },
    #[error("{path}: {source}")]
    Transform {
        path: PathBuf,
        source: TransformError,
    },
    #[error("--match {arg}: {source}")]
    Source { arg: String, source: ScenarioError },
    #[error("--match {arg}: {source}")]
    SourceShape { arg: String, source: TransformError },
    #[error(transparent)]
    Scenario(#[from] ScenarioError),
    #[error("{path}: {source}")]
    Graph {
        path: PathBuf,
        source: mapc_graph::GraphFileError,
    },
    #[error("{0}")]
    Demand(String),
    #[error("the written scenario {path} does not load back: {source}")]
    ReadBack {
        path: PathBuf,
        source: ScenarioError,
    },
}

/// A map or graph file, with the importer's defaults.
pub fn load_map(path: &Path) -> Result<LaneGraph, CompileError> {
    mapc_import::load_any(path).map_err(|source| CompileError::Map {
        path: path.to_path_buf(),
        source,
    })
}

/// A map file simplified to a corridor.
pub fn simplify_map(map: &Path, options: &SimplifyOptions) -> Result<Simplified, CompileError> {
    let raw = load_map(map)?;
    simplify(&raw, options).map_err(|source| CompileError::Transform {
        path: map.to_path_buf(),
        source,
    })
}

/// The JSON report of a corridor: its main road, merges and steps.
pub fn corridor_report(s: &Simplified, map: &Path, output: &Path) -> Value {
    let g = &s.graph;
    let merges: Vec<MergeSummary> = corridor_merges(g, &s.roles);
    let first = g.road(s.roles.main[0]).map(|r| r.from);
    let last = s.roles.main.last().and_then(|r| g.road(*r)).map(|r| r.to);
    json!({
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
    })
}

/// The corridor of `map`: the graph itself when it is one, else the map simplified with `options` (without
/// `via`, along the longest route through `junction`).
pub fn corridor_of(
    map: &Path,
    junction: &str,
    options: &SimplifyOptions,
) -> Result<LaneGraph, CompileError> {
    let g = load_map(map)?;
    if CorridorRoles::of(&g).is_ok() {
        return Ok(g);
    }
    let mut opts = options.clone();
    if opts.via.is_empty() {
        opts.via = vec![junction.to_string()];
    }
    simplify(&g, &opts)
        .map(|s| s.graph)
        .map_err(|source| CompileError::Transform {
            path: map.to_path_buf(),
            source,
        })
}

/// A window cut from a corridor and written: the scenario file and its cut corridor graph beside it.
#[derive(Clone, Debug)]
pub struct WrittenWindow {
    pub cut: WindowCut,
    pub shape: SourceShape,
    pub scenario: PathBuf,
    pub graph: PathBuf,
    /// The warm-up picked for a corridor longer than the source's timing allows (`None`: the source's kept).
    pub timing: Option<crate::timing::PickedTiming>,
}

/// Cut the window of `corridor` (read from `map`) around `junction` matched to the scenario `source` (a built-in
/// name or a file), and write it to `output` (a `.toml`; the graph goes beside it as `<name>.graph.json`). What
/// is written must load back as a sound scenario. Demand overrides must be zero or positive rates
/// (`--main-vph`, `--merge-vph`).
pub fn write_window(
    corridor: &LaneGraph,
    map: &Path,
    junction: &str,
    source: &str,
    output: &Path,
    demand: &DemandOverride,
) -> Result<WrittenWindow, CompileError> {
    for (name, v) in [
        ("--main-vph", demand.main_vph),
        ("--merge-vph", demand.merge_vph),
    ] {
        if let Some(v) = v
            && !(v.is_finite() && v >= 0.0)
        {
            return Err(CompileError::Demand(format!(
                "{name} must be zero or a positive rate, not {v}"
            )));
        }
    }
    let resolved = ResolvedScenario::load(source).map_err(|e| CompileError::Source {
        arg: source.to_string(),
        source: e,
    })?;
    let transform = |source: TransformError| CompileError::Transform {
        path: map.to_path_buf(),
        source,
    };
    let shape = SourceShape::of(&resolved).map_err(|e| CompileError::SourceShape {
        arg: source.to_string(),
        source: e,
    })?;
    let cut = cut_window(corridor, junction, &shape).map_err(transform)?;
    let name = output
        .file_name()
        .and_then(|n| n.to_str())
        .map(|n| n.trim_end_matches(".toml").to_string())
        .filter(|n| !n.is_empty())
        .unwrap_or_else(|| "window".into());
    let graph_file = format!("{name}.graph.json");
    let graph = output.parent().unwrap_or(Path::new("")).join(&graph_file);
    let mut scenario =
        window_scenario(&cut, &resolved, &shape, &name, &graph_file, demand).map_err(transform)?;
    // refused before anything is written: the source's step cannot insert this demand
    let flows: Vec<crate::bounds::FlowDemand> = scenario
        .flows
        .iter()
        .map(|f| crate::bounds::FlowDemand {
            id: &f.id,
            entry: f.from.clone(),
            vehs_per_hour: f.vehs_per_hour,
        })
        .collect();
    crate::bounds::check_demand(&flows, scenario.step_s).map_err(|r| {
        CompileError::Demand(format!(
            "--main-vph / --merge-vph: {} (nothing written)",
            r.message
        ))
    })?;
    let timing = crate::timing::fit_to_corridor(
        &mut scenario,
        &cut.graph,
        &[cut.main_entry, cut.merge_entry],
    );
    cut.graph
        .save(&graph)
        .map_err(|source| CompileError::Graph {
            path: graph.clone(),
            source,
        })?;
    scenario.save(output)?;
    ResolvedScenario::load(&output.display().to_string()).map_err(|source| {
        CompileError::ReadBack {
            path: output.to_path_buf(),
            source,
        }
    })?;
    Ok(WrittenWindow {
        cut,
        shape,
        scenario: output.to_path_buf(),
        graph,
        timing,
    })
}

impl WrittenWindow {
    /// The JSON report `mapc window --json` prints (`render`: the picture drawn, if any).
    pub fn report(&self, matched_to: &str, render: Option<&Path>) -> Value {
        let cut = &self.cut;
        let junction = cut.graph.junction(cut.junction);
        json!({
            "junction": cut.junction.to_string(),
            "osm_node": junction.and_then(|j| j.provenance.osm_nodes.first()),
            "sumo_id": junction.and_then(|j| j.provenance.sumo_ids.first()),
            "matched_to": matched_to,
            "source": {
                "upstream_m": self.shape.upstream_m,
                "merge_m": self.shape.merge_m,
                "downstream_m": self.shape.downstream_m,
            },
            "upstream_m": cut.upstream_m,
            "merge_m": cut.merge_m,
            "downstream_m": cut.downstream_m,
            "region": cut.region().iter().map(|r| r.to_string()).collect::<Vec<_>>(),
            "main_entry": cut.main_entry.to_string(),
            "merge_entry": cut.merge_entry.to_string(),
            "cuts": cut.notes,
            "scenario": self.scenario.display().to_string(),
            "graph": self.graph.display().to_string(),
            "render": render.map(|r| r.display().to_string()),
            "timing": self.timing,
        })
    }
}
