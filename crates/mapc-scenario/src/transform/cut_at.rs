//! `cut_at`: split a road at an exact distance from its start into two roads joined by a new through junction.
//! The first piece keeps the road's id, the second gets a new one above the largest; the centre line is split at
//! the same fraction of its drawn length, and lengths are split so that they add up to the road's.

use super::{TransformError, mark, sort_connections};
use mapc_graph::{
    Connection, Junction, JunctionId, JunctionKind, LaneGraph, Provenance, RightOfWay, RoadId,
};

pub const CUT_AT: &str = "cut_at";

/// The point at `fraction` (0..1) of a polyline's drawn length, and the index of the segment it falls in.
fn point_along(line: &[[f64; 2]], fraction: f64) -> ([f64; 2], usize) {
    let seg_len = |w: &[[f64; 2]]| (w[1][0] - w[0][0]).hypot(w[1][1] - w[0][1]);
    let total: f64 = line.windows(2).map(seg_len).sum();
    let target = fraction.clamp(0.0, 1.0) * total;
    let mut walked = 0.0;
    for (i, w) in line.windows(2).enumerate() {
        let l = seg_len(w);
        if walked + l >= target && l > 0.0 {
            let t = ((target - walked) / l).clamp(0.0, 1.0);
            return (
                [
                    w[0][0] + t * (w[1][0] - w[0][0]),
                    w[0][1] + t * (w[1][1] - w[0][1]),
                ],
                i,
            );
        }
        walked += l;
    }
    (*line.last().unwrap(), line.len().saturating_sub(2))
}

/// Cut `road` at `at_m` metres from its start (strictly inside it). Returns (first piece, second piece, new
/// junction).
pub fn cut_road(
    g: &mut LaneGraph,
    road: RoadId,
    at_m: f64,
) -> Result<(RoadId, RoadId, JunctionId), TransformError> {
    let r = g
        .road(road)
        .ok_or_else(|| TransformError::Cut(format!("no road {road} to cut")))?
        .clone();
    if !(at_m > 0.0 && at_m < r.length_m) {
        return Err(TransformError::Cut(format!(
            "cannot cut road {road} ({:.2} m long) at {at_m:.2} m from its start",
            r.length_m
        )));
    }
    let fraction = at_m / r.length_m;
    let (point, seg) = point_along(&r.geometry, fraction);
    let new_road = g.next_road_id();
    let new_junction = g.next_junction_id();
    let mut first_geom: Vec<[f64; 2]> = r.geometry[..=seg].to_vec();
    if first_geom.last() != Some(&point) {
        first_geom.push(point);
    }
    let mut second_geom = vec![point];
    second_geom.extend(
        r.geometry[seg + 1..]
            .iter()
            .copied()
            .filter(|p| *p != point),
    );
    if second_geom.len() < 2 {
        second_geom.push(*r.geometry.last().unwrap());
    }
    if first_geom.len() < 2 {
        first_geom.insert(0, r.geometry[0]);
    }
    let mut provenance = r.provenance.clone();
    mark(&mut provenance, CUT_AT);
    let mut second = r.clone();
    second.id = new_road;
    second.from = new_junction;
    second.geometry = second_geom;
    second.length_m = r.length_m - at_m;
    second.provenance = provenance.clone();
    for lane in &mut second.lanes {
        lane.length_m -= lane.length_m * fraction;
        // (the input's drawing was of the whole lane)
        lane.shape.clear();
    }
    {
        let first = g.road_mut(road).unwrap();
        first.to = new_junction;
        first.geometry = first_geom;
        first.length_m = at_m;
        first.provenance = provenance;
        for lane in &mut first.lanes {
            lane.length_m *= fraction;
            lane.shape.clear();
            // a lane that ends does so at the road's end, now the second piece's
            lane.end = None;
        }
    }
    g.roads.push(second);
    g.junctions.push(Junction {
        id: new_junction,
        pos: point,
        kind: JunctionKind::Through,
        incoming: vec![],
        outgoing: vec![],
        provenance: Provenance::made_by(CUT_AT),
    });
    for k in &mut g.connections {
        if k.from_road == road {
            k.from_road = new_road;
        }
    }
    for lane in 0..r.lanes.len() as u8 {
        g.connections.push(Connection {
            via_lanes: Vec::new(),
            yields_to: Vec::new(),
            yields_inside: false,
            junction: new_junction,
            from_road: road,
            from_lane: lane,
            to_road: new_road,
            to_lane: lane,
            via_length_m: 0.0,
            via_speed_mps: None,
            right_of_way: RightOfWay::Major,
            signal: None,
            right_of_way_overridden: false,
            provenance: Provenance::made_by(CUT_AT),
        });
    }
    sort_connections(g);
    g.rebuild_junction_links();
    Ok((road, new_road, new_junction))
}
