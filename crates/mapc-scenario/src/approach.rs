//! The approach to a network's bottlenecks: the default controlled region of a scenario given AVs
//! (`--av-share`). AVs act where the jam forms, not on every road of a user's network.
//!
//! Glossary:
//! - **bottleneck**: a junction where roads merge (two or more in) or lanes end (fewer lanes out than in).
//! - **approach**: the roads within [`APPROACH_UPSTREAM_M`] upstream of a bottleneck, on every road that leads
//!   to it, and within [`APPROACH_DOWNSTREAM_M`] past it: the Simple Merge window's upstream and downstream
//!   lengths.

use mapc_graph::{JunctionId, LaneGraph, RoadId};
use std::collections::{BTreeSet, HashMap};

/// Road before a bottleneck in its approach (m): the Simple Merge window's main road before the merge.
pub const APPROACH_UPSTREAM_M: f64 = 600.0;
/// Road past a bottleneck in its approach (m): the Simple Merge window's road after the merge.
pub const APPROACH_DOWNSTREAM_M: f64 = 100.0;

/// The network's bottlenecks: junctions with two or more roads in, or fewer lanes out than in (a road that ends
/// at the network's edge is no bottleneck).
pub fn bottlenecks(g: &LaneGraph) -> Vec<JunctionId> {
    let lanes = |roads: &[RoadId]| -> usize {
        roads
            .iter()
            .filter_map(|&r| g.road(r))
            .map(|r| r.lanes.len())
            .sum()
    };
    g.junctions
        .iter()
        .filter(|j| !j.outgoing.is_empty())
        .filter(|j| j.incoming.len() >= 2 || lanes(&j.incoming) > lanes(&j.outgoing))
        .map(|j| j.id)
        .collect()
}

/// The roads of every bottleneck's approach, sorted; empty when the network has no bottleneck.
pub fn approach_roads(g: &LaneGraph) -> Vec<RoadId> {
    let mut region = BTreeSet::new();
    for j in bottlenecks(g) {
        walk(g, j, APPROACH_UPSTREAM_M, true, &mut region);
        walk(g, j, APPROACH_DOWNSTREAM_M, false, &mut region);
    }
    region.into_iter().collect()
}

/// Adds the roads that start (upstream: end) less than `within_m` from `from`, walking against or with the
/// traffic; a road reached again by a shorter way is walked again from there.
fn walk(
    g: &LaneGraph,
    from: JunctionId,
    within_m: f64,
    upstream: bool,
    region: &mut BTreeSet<RoadId>,
) {
    let mut best: HashMap<RoadId, f64> = HashMap::new();
    let mut stack: Vec<(JunctionId, f64)> = vec![(from, 0.0)];
    while let Some((j, dist)) = stack.pop() {
        let Some(junction) = g.junction(j) else {
            continue;
        };
        let roads = if upstream {
            &junction.incoming
        } else {
            &junction.outgoing
        };
        for &r in roads {
            if dist >= within_m || best.get(&r).is_some_and(|&d| d <= dist) {
                continue;
            }
            best.insert(r, dist);
            region.insert(r);
            let Some(road) = g.road(r) else { continue };
            let next = if upstream { road.from } else { road.to };
            stack.push((next, dist + road.length_m));
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::ResolvedScenario;

    #[test]
    fn the_approach_is_the_road_before_the_on_ramp_not_the_whole_network() {
        // a SUMO user's freeway with an on-ramp: 3 km of main road, the ramp's merge in its middle
        let cfg = "scenarios/sumo/highway_ramp/highway-ramp.sumocfg";
        let g = ResolvedScenario::load(cfg)
            .or_else(|_| ResolvedScenario::load(&format!("../../{cfg}")))
            .unwrap_or_else(|e| panic!("{e}"))
            .graph;
        let b = bottlenecks(&g);
        assert!(!b.is_empty());
        let region = approach_roads(&g);
        // not the whole network: roads far before the merge and beyond 100 m past it are left out
        assert!(
            !region.is_empty() && region.len() < g.roads.len(),
            "{region:?} of {}",
            g.roads.len()
        );
        for &r in &region {
            let road = g.road(r).unwrap();
            // each road leads into a bottleneck within the approach, or leaves one
            assert!(
                b.iter().any(|&j| road.to == j || road.from == j)
                    || g.roads
                        .iter()
                        .any(|n| n.from == road.to && region.contains(&n.id)),
                "{r} is cut off from every bottleneck"
            );
        }
    }
}
