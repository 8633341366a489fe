//! What a raw map offers the default corridor: which roads may carry its main road, and where roads join. One
//! count for `mapc junctions` and `simplify`: a junction's kind is that among its counted roads (footways,
//! service roads and the like, [`mapc_graph::MINOR_CLASSES`], are not counted unless asked for).

use mapc_graph::{Junction, JunctionId, JunctionKind, LaneGraph, Road, RoadId};
use std::collections::HashSet;

/// A road of no class (a SUMO edge without `type`) may carry the main road when its speed limit is at least
/// this (60 km/h, SUMO's 16.67 m/s rounded down): ramps and motorways are that fast, town streets are not.
pub const UNTYPED_MIN_SPEED_MPS: f64 = 16.6;

/// Whether a road has no class to go by: SUMO edges without `type` are imported as `unknown`.
pub fn is_untyped(road: &Road) -> bool {
    road.class.is_empty() || road.class == "unknown"
}

/// Whether `road` may carry the main road: its class is allowed, or it has none and is as fast as a ramp.
pub fn main_road_allowed(road: &Road, class_allowed: &dyn Fn(&str) -> bool) -> bool {
    if is_untyped(road) {
        road.speed_mps() >= UNTYPED_MIN_SPEED_MPS
    } else {
        class_allowed(&road.class)
    }
}

/// The roads of `ids` that count (all of them with `minor_roads`).
pub fn counted_roads(g: &LaneGraph, ids: &[RoadId], minor_roads: bool) -> Vec<RoadId> {
    ids.iter()
        .copied()
        .filter(|r| {
            minor_roads
                || g.road(*r)
                    .is_some_and(|r| !mapc_graph::is_minor_class(&r.class))
        })
        .collect()
}

/// A junction's kind among its counted roads: `None` where no counted road touches it (a junction of footways).
pub fn junction_kind(g: &LaneGraph, j: &Junction, minor_roads: bool) -> Option<JunctionKind> {
    let incoming = counted_roads(g, &j.incoming, minor_roads).len();
    let outgoing = counted_roads(g, &j.outgoing, minor_roads).len();
    (incoming + outgoing > 0).then(|| JunctionKind::classify(incoming, outgoing))
}

/// The map's merges, as `mapc junctions --kind merge` lists them, in id order.
pub fn merges(g: &LaneGraph, minor_roads: bool) -> Vec<JunctionId> {
    g.junctions
        .iter()
        .filter(|j| junction_kind(g, j, minor_roads) == Some(JunctionKind::Merge))
        .map(|j| j.id)
        .collect()
}

/// Junctions where a route through them is joined by another counted road (two or more in, one or more out):
/// the merges, and the junctions of several legs where a merge may remain once the corridor drops its exits.
pub fn joins(g: &LaneGraph, minor_roads: bool) -> HashSet<JunctionId> {
    g.junctions
        .iter()
        .filter(|j| {
            counted_roads(g, &j.incoming, minor_roads).len() >= 2
                && !counted_roads(g, &j.outgoing, minor_roads).is_empty()
        })
        .map(|j| j.id)
        .collect()
}
