//! What happens to roads that leave the main road: `drop_diverges` (the default) lets `prune` remove them;
//! `keep_exits` keeps each up to the next junction where it meets other roads, as a place where traffic leaves.

use super::keep_feeders::interior_junctions;
use super::{Corridor, SimplifyOptions, TransformError, mark};
use mapc_graph::{JunctionId, RoadId};
use std::collections::HashSet;

pub const DROP_DIVERGES: &str = "drop_diverges";
pub const KEEP_EXITS: &str = "keep_exits";

fn diverging_roads(c: &Corridor) -> Vec<RoadId> {
    let taken: HashSet<RoadId> = c
        .main
        .iter()
        .chain(c.feeders.iter().flatten())
        .copied()
        .collect();
    interior_junctions(&c.graph, &c.main)
        .into_iter()
        .flat_map(|j| c.graph.junction(j).unwrap().outgoing.clone())
        .filter(|r| !taken.contains(r))
        .collect()
}

pub fn drop_diverges(c: &mut Corridor, _opts: &SimplifyOptions) -> Result<String, TransformError> {
    let dropped = diverging_roads(c);
    Ok(format!("{} diverging roads will be dropped", dropped.len()))
}

pub fn keep_exits(c: &mut Corridor, _opts: &SimplifyOptions) -> Result<String, TransformError> {
    let g = &c.graph;
    let mut taken: HashSet<RoadId> = c
        .main
        .iter()
        .chain(c.feeders.iter().flatten())
        .copied()
        .collect();
    let corridor_junctions: HashSet<JunctionId> = taken
        .iter()
        .flat_map(|r| [g.road(*r).unwrap().from, g.road(*r).unwrap().to])
        .collect();
    let mut exits = Vec::new();
    let mut loops = 0;
    for first in diverging_roads(c) {
        if taken.contains(&first) {
            continue;
        }
        let mut chain = vec![first];
        loop {
            let end = g
                .junction(g.road(*chain.last().unwrap()).unwrap().to)
                .unwrap();
            if end.incoming.len() != 1 || end.outgoing.len() != 1 {
                break;
            }
            let next = end.outgoing[0];
            if taken.contains(&next) || chain.contains(&next) {
                break;
            }
            chain.push(next);
        }
        if corridor_junctions.contains(&g.road(*chain.last().unwrap()).unwrap().to) {
            loops += 1;
            continue;
        }
        taken.extend(chain.iter().copied());
        exits.push(chain);
    }
    for chain in &exits {
        for r in chain {
            mark(&mut c.graph.road_mut(*r).unwrap().provenance, KEEP_EXITS);
        }
    }
    c.exits = exits;
    let mut summary = format!("{} diverging roads kept as exits", c.exits.len());
    if loops > 0 {
        summary += &format!("; {loops} that rejoin the corridor dropped");
    }
    Ok(summary)
}
