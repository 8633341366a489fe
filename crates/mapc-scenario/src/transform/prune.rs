//! `prune`: remove every road that is neither the main road, a merging road nor a kept exit, and the junctions
//! left with no road; make sure each road of the corridor connects to the next (OSM input leaves some joints
//! without a connection).

use super::{Corridor, SimplifyOptions, TransformError, ensure_connection, remove_roads};
use mapc_graph::RoadId;
use std::collections::HashSet;

pub const NAME: &str = "prune";

pub fn apply(c: &mut Corridor, _opts: &SimplifyOptions) -> Result<String, TransformError> {
    let keep: HashSet<RoadId> = c
        .main
        .iter()
        .chain(c.feeders.iter().flatten())
        .chain(c.exits.iter().flatten())
        .copied()
        .collect();
    let gone: HashSet<RoadId> = c
        .graph
        .roads
        .iter()
        .map(|r| r.id)
        .filter(|r| !keep.contains(r))
        .collect();
    let (roads_before, junctions_before, connections_before) = (
        c.graph.roads.len(),
        c.graph.junctions.len(),
        c.graph.connections.len(),
    );
    remove_roads(&mut c.graph, &gone);
    let mut pairs: Vec<(RoadId, RoadId)> = Vec::new();
    for chain in std::iter::once(&c.main).chain(&c.feeders).chain(&c.exits) {
        pairs.extend(chain.windows(2).map(|w| (w[0], w[1])));
    }
    let main_from = |j| {
        c.main
            .iter()
            .copied()
            .find(|r| c.graph.road(*r).unwrap().from == j)
    };
    let main_into = |j| {
        c.main
            .iter()
            .copied()
            .find(|r| c.graph.road(*r).unwrap().to == j)
    };
    for f in &c.feeders {
        let last = *f.last().unwrap();
        if let Some(next) = main_from(c.graph.road(last).unwrap().to) {
            pairs.push((last, next));
        }
    }
    for e in &c.exits {
        if let Some(prev) = main_into(c.graph.road(e[0]).unwrap().from) {
            pairs.push((prev, e[0]));
        }
    }
    let mut added = 0;
    for (a, b) in pairs {
        let n = c.graph.connections.len();
        ensure_connection(&mut c.graph, a, b, NAME);
        added += c.graph.connections.len() - n;
    }
    c.pruned = true;
    Ok(format!(
        "removed {} of {roads_before} roads and {} of {junctions_before} junctions; {} of {connections_before} \
         connections left, {added} added where the corridor had none",
        gone.len(),
        junctions_before - c.graph.junctions.len(),
        c.graph.connections.len() - added,
    ))
}
