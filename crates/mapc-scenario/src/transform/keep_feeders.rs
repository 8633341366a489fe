//! `keep_feeders`: find the roads that merge into the main road and keep each back to where it starts in the map:
//! walking upstream while the road only continues another (a junction with one road in and one out), or until it
//! is `--feeder-length` long. A road that starts on the main road itself (a loop ramp or a collector that leaves
//! and rejoins the corridor) is not a merging road and is dropped; so are footways, paths and service roads
//! ([`mapc_graph::MINOR_CLASSES`]) unless `--minor-roads` asks for them.

use super::{Corridor, SimplifyOptions, TransformError, mark};
use mapc_graph::{JunctionId, LaneGraph, RoadId};
use std::collections::HashSet;

pub const NAME: &str = "keep_feeders";

/// Junctions inside the main road (not its two ends), in driving order.
pub fn interior_junctions(g: &LaneGraph, main: &[RoadId]) -> Vec<JunctionId> {
    main.iter()
        .skip(1)
        .map(|r| g.road(*r).unwrap().from)
        .collect()
}

pub fn apply(c: &mut Corridor, opts: &SimplifyOptions) -> Result<String, TransformError> {
    let g = &c.graph;
    let main_set: HashSet<RoadId> = c.main.iter().copied().collect();
    let main_junctions: HashSet<JunctionId> = c
        .main
        .iter()
        .flat_map(|r| [g.road(*r).unwrap().from, g.road(*r).unwrap().to])
        .collect();
    let mut taken: HashSet<RoadId> = main_set.clone();
    let mut feeders = Vec::new();
    let mut loops = Vec::new();
    let mut minor = Vec::new();
    for j in interior_junctions(g, &c.main) {
        for &first in &g.junction(j).unwrap().incoming {
            if taken.contains(&first) {
                continue;
            }
            // a footway or service road that touches the motorway is not a merging road (unless asked)
            if !opts.minor_roads && mapc_graph::is_minor_class(&g.road(first).unwrap().class) {
                minor.push(first);
                continue;
            }
            let mut chain = vec![first];
            let mut length = g.road(first).unwrap().length_m;
            loop {
                if opts.feeder_length_m.is_some_and(|limit| length >= limit) {
                    break;
                }
                let start = g.junction(g.road(chain[0]).unwrap().from).unwrap();
                if start.incoming.len() != 1 || start.outgoing.len() != 1 {
                    break;
                }
                let prev = start.incoming[0];
                if taken.contains(&prev) || chain.contains(&prev) {
                    break;
                }
                length += g.road(prev).unwrap().length_m;
                chain.insert(0, prev);
            }
            let start_junction = g.road(chain[0]).unwrap().from;
            if main_junctions.contains(&start_junction) {
                loops.push(chain[0]);
                continue;
            }
            taken.extend(chain.iter().copied());
            feeders.push(chain);
        }
    }
    for chain in &feeders {
        for r in chain {
            mark(&mut c.graph.road_mut(*r).unwrap().provenance, NAME);
        }
    }
    let pieces: usize = feeders.iter().map(Vec::len).sum();
    c.feeders = feeders;
    let mut summary = format!(
        "{} merging roads kept ({pieces} road pieces)",
        c.feeders.len()
    );
    if !minor.is_empty() {
        summary += &format!(
            "; {} footways, paths or service roads dropped ({}; --minor-roads keeps them)",
            minor.len(),
            minor
                .iter()
                .map(|r| r.to_string())
                .collect::<Vec<_>>()
                .join(", ")
        );
    }
    if !loops.is_empty() {
        summary += &format!(
            "; {} roads that leave and rejoin the main road dropped ({})",
            loops.len(),
            loops
                .iter()
                .map(|r| r.to_string())
                .collect::<Vec<_>>()
                .join(", ")
        );
    }
    Ok(summary)
}
