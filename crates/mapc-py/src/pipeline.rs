//! The scenario pipeline from Python: import, simplify, window, each returning the report the command prints
//! with `--json`, from the same library code (`mapc_import`, `mapc_scenario::compile`).

use crate::mapc_error;
use mapc_import::{ImportOptions, Summary};
use mapc_scenario::compile::{corridor_of, corridor_report, simplify_map, write_window};
use mapc_scenario::transform::SimplifyOptions;
use mapc_scenario::window::DemandOverride;
use pyo3::prelude::*;
use std::path::PathBuf;

fn options(
    via: Vec<String>,
    classes: Option<Vec<String>>,
    feeder_length: Option<f64>,
    keep_exits: bool,
) -> SimplifyOptions {
    let defaults = SimplifyOptions::default();
    SimplifyOptions {
        via,
        classes: classes.unwrap_or(defaults.classes),
        feeder_length_m: feeder_length,
        keep_exits,
        minor_roads: defaults.minor_roads,
        keep_lanes: defaults.keep_lanes,
    }
}

/// Read a map (OSM XML, OSM PBF, SUMO net.xml) into a lane graph, write it to `output` when given, and return
/// `mapc import --json`'s summary.
#[pyfunction]
#[pyo3(signature = (path, output = None, highways = None))]
pub fn import_map(
    path: PathBuf,
    output: Option<PathBuf>,
    highways: Option<Vec<String>>,
) -> PyResult<String> {
    let mut opts = ImportOptions::default();
    if let Some(h) = highways {
        if h.is_empty() {
            return Err(mapc_error("highways: name at least one class"));
        }
        opts.highways = h;
    }
    let graph = mapc_import::import_path(&path, &opts).map_err(mapc_error)?;
    if let Some(out) = &output {
        graph.save(out).map_err(mapc_error)?;
    }
    let mut report = serde_json::to_value(Summary::of(&graph)).map_err(mapc_error)?;
    report["output"] = output.map_or(serde_json::Value::Null, |o| o.display().to_string().into());
    Ok(report.to_string())
}

/// Reduce a map to a single-lane corridor with its merging roads, write it to `output`, and return `mapc
/// simplify --json`'s report.
#[pyfunction]
#[pyo3(signature = (map, output, via = vec![], classes = None, feeder_length = None, keep_exits = false))]
pub fn simplify(
    map: PathBuf,
    output: PathBuf,
    via: Vec<String>,
    classes: Option<Vec<String>>,
    feeder_length: Option<f64>,
    keep_exits: bool,
) -> PyResult<String> {
    let s = simplify_map(&map, &options(via, classes, feeder_length, keep_exits))
        .map_err(mapc_error)?;
    s.graph.save(&output).map_err(mapc_error)?;
    Ok(corridor_report(&s, &map, &output).to_string())
}

/// Cut a window around `junction` of a corridor (or of a map, simplified first along `via`, else the longest
/// route through the junction) matched to `match_` (a built-in scenario or a file), write the scenario to
/// `output` with its graph beside it, and return `mapc window --json`'s report.
#[pyfunction]
#[pyo3(signature = (map, junction, output, match_ = "simple_merge", main_vph = None, merge_vph = None,
                    n_av = None, via = vec![]))]
#[allow(clippy::too_many_arguments)]
pub fn window(
    map: PathBuf,
    junction: &str,
    output: PathBuf,
    match_: &str,
    main_vph: Option<f64>,
    merge_vph: Option<f64>,
    n_av: Option<u32>,
    via: Vec<String>,
) -> PyResult<String> {
    let corridor =
        corridor_of(&map, Some(junction), &options(via, None, None, false)).map_err(mapc_error)?;
    let demand = DemandOverride {
        main_vph,
        merge_vph,
        n_av,
        ..DemandOverride::default()
    };
    let written =
        write_window(&corridor, &map, junction, match_, &output, &demand).map_err(mapc_error)?;
    Ok(written.report(match_, None).to_string())
}
