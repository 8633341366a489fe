//! # mapc-sumo: mapc's networks and scenarios as SUMO 1.8 inputs
//!
//! Glossary:
//! - **net** (`NAME.net.xml`): SUMO's compiled network: edges (mapc's roads) with lanes, internal edges (an
//!   internal lane per mapc connection, its length driven inside the junction: one edge per connection, or, in a
//!   SUMO user's scenario, one per pair of roads with its connections side by side, as netconvert builds them),
//!   junctions with request tables (who yields to whom), and connections. Written directly, not through
//!   netconvert, so lane lengths are mapc's.
//! - **routes** (`NAME.rou.xml`): vehicle types (`vType`, IDM), flows (`vehsPerHour`, `departSpeed`) each with its
//!   route, and the initial vehicles.
//! - **sumocfg** (`NAME.sumocfg`): what `sumo -c` runs: the files, the step, the paper's options.
//! - **manifest** (`NAME.mapc.json`): what SUMO's files cannot say and `tools/sumo_check` needs: the horizon, the
//!   set-up steps before it, the controlled region as SUMO edge ids, N_AV, which types are AVs, and which SUMO id
//!   each mapc road got.
//! - **speed mode 9**: SUMO's TraCI setting the paper's runs give every vehicle (safe speed kept, right of way
//!   not braked for); a plain `sumo -c` run uses SUMO's default (31), so tools/sumo_check sets it.
//!
//! The export is a front end on the stages' public APIs: the network is the resolved scenario's lane graph, and
//! the routes and initial positions are mapc-sim's ([`mapc_sim::spec_from_scenario`]).

pub mod demand;
pub mod fcd;
mod junctions;
pub mod names;
pub mod net;
mod output;
pub mod run_outputs;
pub mod xml;

use mapc_graph::LaneGraph;
use mapc_scenario::ResolvedScenario;
use names::SumoNames;
use serde::Serialize;
use std::path::{Path, PathBuf};

/// The SUMO release the files are written for (and were checked with).
pub const SUMO_VERSION: &str = "1.8.0";
/// Name written in every manifest.
pub const MANIFEST_FORMAT: &str = "mapc-sumo-export";
/// Bumped on any change an older reader of the manifest would misread.
pub const MANIFEST_VERSION: u32 = 1;

#[derive(Debug, thiserror::Error)]
pub enum ExportError {
    #[error("{path}: cannot write: {error}")]
    Io {
        path: PathBuf,
        error: std::io::Error,
    },
    #[error("{path}: exists and is not a directory; give a directory to write the SUMO files into")]
    NotADirectory { path: PathBuf },
    #[error("{origin}: {error}")]
    Scenario {
        origin: String,
        error: mapc_sim::SimError,
    },
}

/// What `mapc export --sumo` wrote.
#[derive(Clone, Debug, Serialize)]
pub struct ExportSummary {
    pub dir: PathBuf,
    pub files: Vec<String>,
    pub edges: usize,
    pub lanes: usize,
    pub junctions: usize,
    pub connections: usize,
    pub flows: usize,
    pub initial_vehicles: usize,
    pub sumo_version: &'static str,
}

/// The manifest beside the SUMO files (see the glossary).
#[derive(Clone, Debug, Serialize)]
pub struct Manifest {
    pub format: &'static str,
    pub version: u32,
    pub sumo_version: &'static str,
    pub scenario: Option<String>,
    pub origin: String,
    pub files: ManifestFiles,
    pub step_s: f64,
    pub horizon_steps: u64,
    pub warmup_steps: u64,
    /// Steps SUMO runs before the horizon's first (the original's start and reset steps).
    pub setup_steps: u64,
    pub n_av: usize,
    /// SUMO edge ids of the controlled region; empty: the whole network.
    pub control_edges: Vec<String>,
    /// SUMO internal edges of the controlled region (connections with both roads in it, as mapc-sim counts
    /// them).
    pub control_internal_edges: Vec<String>,
    /// Vehicle types whose vehicles a policy may drive.
    pub av_types: Vec<String>,
    /// mapc road id -> SUMO edge id.
    pub edges: std::collections::BTreeMap<String, String>,
    /// Where mapc measures flow (after the warm-up): vehicles entering any of a point's edges pass it.
    pub measure_points: Vec<ManifestPoint>,
    /// The edge whose vehicles count as past the corridor's end when they leave the network (mapc's
    /// `end_flow`); `None` for a bare network.
    pub end_edge: Option<String>,
}

/// One measurement point in SUMO's names.
#[derive(Clone, Debug, Serialize)]
pub struct ManifestPoint {
    /// `merge J3 (osm:123)`, as mapc's reports name it.
    pub name: String,
    pub edges: Vec<String>,
}

#[derive(Clone, Debug, Serialize)]
pub struct ManifestFiles {
    pub net: String,
    pub routes: Option<String>,
    pub config: Option<String>,
}

/// A file-name stem from a scenario or map name: letters, digits, `-` and `_` kept, the rest `_`.
fn stem(name: &str) -> String {
    let s: String = name
        .chars()
        .map(|c| {
            if c.is_ascii_alphanumeric() || c == '-' || c == '_' {
                c
            } else {
                '_'
            }
        })
        .collect();
    if s.is_empty() { "mapc".into() } else { s }
}

fn edge_map(g: &LaneGraph, names: &SumoNames) -> std::collections::BTreeMap<String, String> {
    g.roads
        .iter()
        .zip(&names.edges)
        .map(|(r, e)| (r.id.to_string(), e.clone()))
        .collect()
}

/// Write a bare network (no demand) into `dir`: `NAME.net.xml` and the manifest.
pub fn export_network(
    graph: &LaneGraph,
    name: &str,
    dir: &Path,
) -> Result<ExportSummary, ExportError> {
    let names = SumoNames::of(graph);
    let stem = stem(name);
    let net_file = format!("{stem}.net.xml");
    let manifest = Manifest {
        format: MANIFEST_FORMAT,
        version: MANIFEST_VERSION,
        sumo_version: SUMO_VERSION,
        scenario: None,
        origin: name.to_string(),
        files: ManifestFiles {
            net: net_file.clone(),
            routes: None,
            config: None,
        },
        step_s: 0.0,
        horizon_steps: 0,
        warmup_steps: 0,
        setup_steps: 0,
        n_av: 0,
        control_edges: vec![],
        control_internal_edges: vec![],
        av_types: vec![],
        edges: edge_map(graph, &names),
        measure_points: vec![],
        end_edge: None,
    };
    let files = vec![
        (
            net_file,
            net::net_xml(graph, &names, net::InternalEdges::PerConnection),
        ),
        (format!("{stem}.mapc.json"), to_json(&manifest)),
    ];
    write(dir, files, graph, 0, 0)
}

/// Write a scenario into `dir`: net, routes, sumocfg, the manifest, and its induction loops as an additional file
/// if it has any.
pub fn export_scenario(rs: &ResolvedScenario, dir: &Path) -> Result<ExportSummary, ExportError> {
    let scenario_err = |error| ExportError::Scenario {
        origin: rs.origin.clone(),
        error,
    };
    let spec = mapc_sim::spec_from_scenario(rs).map_err(scenario_err)?;
    spec.validate().map_err(scenario_err)?;
    let graph = &spec.graph;
    let names = SumoNames::of(graph);
    let sc = &rs.scenario;
    // the internal edges on which SUMO drives as mapc does: a SUMO user's scenario keeps LC2013's memory across
    // side-by-side connections, mapc's own scenarios clear it in every junction
    let grouping = if spec.sumo_junction_lane_changes {
        net::InternalEdges::SideBySide
    } else {
        net::InternalEdges::PerConnection
    };
    let stem = stem(&sc.name);
    let (net_file, routes_file, config_file) = (
        format!("{stem}.net.xml"),
        format!("{stem}.rou.xml"),
        format!("{stem}.sumocfg"),
    );
    let flow_ids: Vec<String> = sc.flows.iter().map(|f| f.id.clone()).collect();
    let routes = demand::routes_xml(&spec, &names, &flow_ids).map_err(scenario_err)?;
    let setup_steps = 2;
    let end_s = (setup_steps + spec.warmup_steps + spec.horizon_steps) as f64 * spec.step_s;
    let edges = edge_map(graph, &names);
    let end_road = mapc_sim::Simulation::from_spec(spec.clone(), 0)
        .map_err(scenario_err)?
        .corridor_end_road();
    let measure_points = spec
        .measure_points
        .iter()
        .map(|p| ManifestPoint {
            name: p.name.clone(),
            edges: p
                .roads
                .iter()
                .map(|r| edges[&r.to_string()].clone())
                .collect(),
        })
        .collect();
    let manifest = Manifest {
        format: MANIFEST_FORMAT,
        version: MANIFEST_VERSION,
        sumo_version: SUMO_VERSION,
        scenario: Some(sc.name.clone()),
        origin: rs.origin.clone(),
        files: ManifestFiles {
            net: net_file.clone(),
            routes: Some(routes_file.clone()),
            config: Some(config_file.clone()),
        },
        step_s: spec.step_s,
        horizon_steps: spec.horizon_steps,
        warmup_steps: spec.warmup_steps,
        setup_steps,
        n_av: spec.n_av,
        control_edges: rs
            .region_roads
            .iter()
            .map(|r| edges[&r.to_string()].clone())
            .collect(),
        control_internal_edges: net::internal_edges(graph, &names, grouping)
            .into_iter()
            .filter(|(_, from, to)| rs.region_roads.contains(from) && rs.region_roads.contains(to))
            .map(|(id, _, _)| id)
            .collect(),
        av_types: spec
            .vehicle_types
            .iter()
            .filter(|t| t.controlled)
            .map(|t| t.name.clone())
            .collect(),
        end_edge: end_road.map(|r| edges[&r.to_string()].clone()),
        measure_points,
        edges,
    };
    let detectors = demand::detectors_xml(&spec, &names, &format!("{stem}.e1.xml"));
    let additional_file = detectors.as_ref().map(|_| format!("{stem}.add.xml"));
    let mut files = vec![
        (net_file.clone(), net::net_xml(graph, &names, grouping)),
        (routes_file.clone(), routes),
        (
            config_file,
            demand::sumocfg(
                &net_file,
                &routes_file,
                additional_file.as_deref(),
                spec.step_s,
                end_s,
                spec.graph.roads.iter().any(|r| r.lanes.len() > 1),
                spec.time_to_teleport_s,
            ),
        ),
        (format!("{stem}.mapc.json"), to_json(&manifest)),
    ];
    if let (Some(name), Some(xml)) = (additional_file, detectors) {
        files.push((name, xml));
    }
    write(dir, files, graph, spec.flows.len(), spec.initial.len())
}

/// Write the files as the whole of `dir` and say what they hold.
fn write(
    dir: &Path,
    files: Vec<(String, String)>,
    graph: &LaneGraph,
    flows: usize,
    initial_vehicles: usize,
) -> Result<ExportSummary, ExportError> {
    output::write_dir(dir, &files)?;
    Ok(ExportSummary {
        dir: dir.to_path_buf(),
        files: files.into_iter().map(|(n, _)| n).collect(),
        edges: graph.roads.len(),
        lanes: graph.roads.iter().map(|r| r.lanes.len()).sum(),
        junctions: graph.junctions.len(),
        connections: graph.connections.len(),
        flows,
        initial_vehicles,
        sumo_version: SUMO_VERSION,
    })
}

fn to_json(m: &Manifest) -> String {
    serde_json::to_string_pretty(m).expect("a manifest always serialises") + "\n"
}
