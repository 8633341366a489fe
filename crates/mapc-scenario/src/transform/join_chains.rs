//! `join_chains`: a junction with one road in and one out is only a joint; the two roads become one (the first
//! keeps its id; the joint's and the second road's ids go to its provenance's `joined`, where lookups find them).
//! The joined road's length is the driving length, the connection's internal length included, so no length is
//! lost; its speed is the one that keeps the free-flow travel time; class, name and ref are the longer piece's,
//! the priority the downstream piece's (it meets the next junction). With every lane kept (`--keep-lanes`) a joint
//! is only joined where each lane goes straight on into the lane of the same index and none ends: a joint where
//! the lanes change (a drop, a gain, lanes that shift) stays, as the place where they do; each lane's length and
//! speed are then joined like the road's.

use super::{Corridor, SimplifyOptions, TransformError, mark};
use mapc_graph::{JunctionId, JunctionKind, Lane, LaneGraph, Road, RoadId};

pub const NAME: &str = "join_chains";

/// Join the two roads at through junction `j`; returns the surviving and the removed road.
pub fn join_at(c: &mut Corridor, j: JunctionId) -> Option<(RoadId, RoadId)> {
    let g = &c.graph;
    let junction = g.junction(j)?;
    if junction.kind != JunctionKind::Through {
        return None;
    }
    let (a_id, b_id) = (junction.incoming[0], junction.outgoing[0]);
    let (a, b) = (g.road(a_id)?, g.road(b_id)?);
    if a_id == b_id || a.from == b.to {
        return None;
    }
    if c.lanes_connected && !lanes_go_straight_on(g, a, b) {
        return None;
    }
    let via = g
        .connections
        .iter()
        .find(|k| k.from_road == a_id && k.to_road == b_id);
    let via_m = via.map_or(0.0, |k| k.via_length_m);
    let via_speed = via.and_then(|k| k.via_speed_mps).unwrap_or(b.speed_mps());
    let length = a.length_m + via_m + b.length_m;
    let travel_s = a.length_m / a.speed_mps() + via_m / via_speed + b.length_m / b.speed_mps();
    let speed = if travel_s.is_finite() && travel_s > 0.0 {
        length / travel_s
    } else {
        a.speed_mps()
    };
    let longer = if b.length_m > a.length_m { b } else { a };
    let (class, name, ref_) = (
        longer.class.clone(),
        longer.name.clone(),
        longer.ref_.clone(),
    );
    let priority = b.priority;
    let mut geometry = a.geometry.clone();
    let skip = usize::from(b.geometry.first() == a.geometry.last());
    geometry.extend_from_slice(&b.geometry[skip..]);
    let mut provenance = a
        .provenance
        .merged(&junction.provenance)
        .merged(&b.provenance);
    mark(&mut provenance, NAME);
    // The joint and the second road keep their ids as names of this road, so that a junction or road id that
    // `mapc junctions` listed on the map is still found on the corridor.
    for id in [j.to_string(), b_id.to_string()] {
        if !provenance.joined.contains(&id) {
            provenance.joined.push(id);
        }
    }
    let to = b.to;

    let lanes = if c.lanes_connected {
        joined_lanes(g, a, b)
    } else {
        let mut lane = a.lanes[0].clone();
        lane.length_m = length;
        // (the input drew the first road's lane only)
        lane.shape.clear();
        lane.speed_mps = speed;
        vec![lane]
    };
    let a = c.graph.road_mut(a_id).unwrap();
    a.length_m = length;
    a.lanes = lanes;
    a.geometry = geometry;
    a.class = class;
    a.name = name;
    a.ref_ = ref_;
    a.priority = priority;
    a.provenance = provenance;
    a.to = to;
    c.graph.roads.retain(|r| r.id != b_id);
    c.graph.junctions.retain(|x| x.id != j);
    c.graph.connections.retain(|k| k.junction != j);
    for k in &mut c.graph.connections {
        if k.from_road == b_id {
            k.from_road = a_id;
        }
    }
    for chain in std::iter::once(&mut c.main)
        .chain(&mut c.feeders)
        .chain(&mut c.exits)
    {
        chain.retain(|r| *r != b_id);
    }
    Some((a_id, b_id))
}

/// Whether every lane of `a` goes on into the lane of `b` with its index, and only there.
fn lanes_go_straight_on(g: &LaneGraph, a: &Road, b: &Road) -> bool {
    if a.lanes.len() != b.lanes.len() || a.lanes.iter().any(|l| l.end.is_some()) {
        return false;
    }
    let links: Vec<(u8, u8)> = g
        .connections_from(a.id)
        .map(|k| (k.from_lane, k.to_lane))
        .collect();
    links.len() == a.lanes.len() && links.iter().all(|(f, t)| f == t)
}

/// The lanes of `a` and `b` joined lane by lane: each lane's driving length, and the speed that keeps its
/// free-flow travel time.
fn joined_lanes(g: &LaneGraph, a: &Road, b: &Road) -> Vec<Lane> {
    a.lanes
        .iter()
        .zip(&b.lanes)
        .map(|(la, lb)| {
            let via = g
                .connections_from(a.id)
                .find(|k| k.from_lane == la.index && k.to_road == b.id);
            let via_m = via.map_or(0.0, |k| k.via_length_m);
            let via_speed = via.and_then(|k| k.via_speed_mps).unwrap_or(lb.speed_mps);
            let length = la.length_m + via_m + lb.length_m;
            let travel_s =
                la.length_m / la.speed_mps + via_m / via_speed + lb.length_m / lb.speed_mps;
            let mut lane = la.clone();
            lane.length_m = length;
            lane.shape.clear();
            if travel_s.is_finite() && travel_s > 0.0 {
                lane.speed_mps = length / travel_s;
            }
            lane.end = lb.end;
            lane
        })
        .collect()
}

pub fn apply(c: &mut Corridor, _opts: &SimplifyOptions) -> Result<String, TransformError> {
    let roads_before = c.graph.roads.len();
    let mut joints = 0;
    let candidates: Vec<JunctionId> = c
        .graph
        .junctions
        .iter()
        .filter(|j| j.kind == JunctionKind::Through)
        .map(|j| j.id)
        .collect();
    for j in candidates {
        if join_at(c, j).is_some() {
            joints += 1;
            c.graph.rebuild_junction_links();
        }
    }
    c.graph.rebuild_junction_links();
    Ok(format!(
        "{joints} joints removed: {roads_before} roads joined into {} (main road {} roads, merging roads {})",
        c.graph.roads.len(),
        c.main.len(),
        c.feeders
            .iter()
            .map(|f| f.len().to_string())
            .collect::<Vec<_>>()
            .join("/")
    ))
}
