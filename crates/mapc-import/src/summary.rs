//! The figures `mapc import` prints and the golden tests compare.

use mapc_graph::{JunctionKind, LaneGraph, SourceFormat};
use serde::{Deserialize, Serialize};
use std::collections::BTreeMap;

/// Counts and lengths of a graph. Lengths are rounded to the centimetre so that summaries compare exactly.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Summary {
    /// The input's file name (no directories, so summaries do not depend on where the map lies).
    pub source: String,
    pub format: SourceFormat,
    pub junctions: usize,
    pub roads: usize,
    /// Lanes over all roads.
    pub lanes: usize,
    pub connections: usize,
    /// Sum of road lengths.
    pub total_length_m: f64,
    /// Sum of road length times lanes, plus the lengths driven inside junctions.
    pub total_lane_length_m: f64,
    pub merges: usize,
    pub diverges: usize,
    /// Junctions by kind (`merge`, `diverge`, `through`, `source`, `sink`, `complex`).
    pub junction_kinds: BTreeMap<String, usize>,
    /// Warnings by kind.
    pub warnings: BTreeMap<String, usize>,
}

fn centimetres(x: f64) -> f64 {
    (x * 100.0).round() / 100.0
}

impl Summary {
    pub fn of(graph: &LaneGraph) -> Summary {
        let mut junction_kinds = BTreeMap::new();
        for j in &graph.junctions {
            let name = serde_json::to_value(j.kind)
                .ok()
                .and_then(|v| v.as_str().map(str::to_string))
                .unwrap_or_default();
            *junction_kinds.entry(name).or_insert(0) += 1;
        }
        let source = std::path::Path::new(&graph.source.file)
            .file_name()
            .map_or_else(
                || graph.source.file.clone(),
                |n| n.to_string_lossy().into_owned(),
            );
        Summary {
            source,
            format: graph.source.format,
            junctions: graph.junctions.len(),
            roads: graph.roads.len(),
            lanes: graph.roads.iter().map(|r| r.lanes.len()).sum(),
            connections: graph.connections.len(),
            total_length_m: centimetres(graph.roads.iter().map(|r| r.length_m).sum()),
            total_lane_length_m: centimetres(graph.total_lane_length_m()),
            merges: graph.count_kind(JunctionKind::Merge),
            diverges: graph.count_kind(JunctionKind::Diverge),
            junction_kinds,
            warnings: graph.warnings.counts.clone(),
        }
    }
}
