//! `simplify`: a highway map becomes a single-lane corridor with the roads that merge into it, by the ordered
//! steps of [`crate::transform`]. Lengths reported here are sums of road lengths (geodesic for OSM input); the
//! internal length of a junction that remains (a merge) is not counted, that of a removed joint is part of the
//! joined road.

use crate::transform::{self, Corridor, CorridorRoles, SimplifyOptions, StepReport, TransformError};
use mapc_graph::{JunctionId, LaneGraph, RoadId, Source, SourceFormat};
use serde::Serialize;

pub use crate::transform::SimplifyOptions as Options;

/// A simplified corridor and what each step did.
#[derive(Clone, Debug)]
pub struct Simplified {
    pub graph: LaneGraph,
    pub roles: CorridorRoles,
    pub steps: Vec<StepReport>,
}

/// One merge on the corridor, with the lengths around it.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct MergeSummary {
    pub junction: String,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub osm_node: Option<i64>,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub sumo_id: Option<String>,
    /// Main road from the corridor's start to the merge.
    pub main_before_m: f64,
    /// The merging road, from where it starts to the merge.
    pub merge_m: f64,
    /// Main road from the merge to the corridor's end.
    pub main_after_m: f64,
    /// The merging road's first and last roads (one road once chains are joined).
    pub merging_roads: Vec<String>,
    pub merging_label: String,
    /// Whether the merging road has the right of way over the main road there.
    pub merging_is_major: bool,
}

/// Run every step of `simplify` on a map's graph.
pub fn simplify(raw: &LaneGraph, opts: &SimplifyOptions) -> Result<Simplified, TransformError> {
    if let Some(l) = opts.feeder_length_m {
        if !(l.is_finite() && l > 0.0) {
            return Err(TransformError::NoRoute(format!("--feeder-length must be a positive length, not {l}")));
        }
    }
    let mut corridor = Corridor::new(raw.clone());
    corridor.graph.source = Source { file: raw.source.file.clone(), format: SourceFormat::Derived };
    let steps = transform::simplify_steps(opts);
    let reports = transform::run_steps(&mut corridor, &steps, opts)?;
    let roles = CorridorRoles { main: corridor.main, feeders: corridor.feeders, exits: corridor.exits };
    Ok(Simplified { graph: corridor.graph, roles, steps: reports })
}

fn road_sum(g: &LaneGraph, roads: &[RoadId]) -> f64 {
    roads.iter().filter_map(|r| g.road(*r)).map(|r| r.length_m).sum()
}

/// Every merge on the corridor's main road, in driving order.
pub fn corridor_merges(g: &LaneGraph, roles: &CorridorRoles) -> Vec<MergeSummary> {
    let mut out = Vec::new();
    for (i, rid) in roles.main.iter().enumerate().skip(1) {
        let j: JunctionId = g.road(*rid).unwrap().from;
        for feeder in roles.feeders.iter().filter(|f| g.road(*f.last().unwrap()).unwrap().to == j) {
            let junction = g.junction(j).unwrap();
            let last = *feeder.last().unwrap();
            let row = |from: RoadId| {
                g.connections.iter().find(|k| k.from_road == from && k.to_road == *rid).map(|k| k.right_of_way)
            };
            out.push(MergeSummary {
                junction: j.to_string(),
                osm_node: junction.provenance.osm_nodes.first().copied(),
                sumo_id: junction.provenance.sumo_ids.first().cloned(),
                main_before_m: road_sum(g, &roles.main[..i]),
                merge_m: road_sum(g, feeder),
                main_after_m: road_sum(g, &roles.main[i..]),
                merging_roads: if feeder.len() == 1 {
                    vec![feeder[0].to_string()]
                } else {
                    vec![feeder[0].to_string(), last.to_string()]
                },
                merging_label: g.road(last).unwrap().label(),
                merging_is_major: row(last) == Some(mapc_graph::RightOfWay::Major)
                    && row(roles.main[i - 1]) != Some(mapc_graph::RightOfWay::Major),
            });
        }
    }
    out
}
