//! Flow's bottleneck benchmark network, built from its parameters as netconvert builds Flow's plain files
//! (maps/flow_bottleneck/README.md): nodes on a straight line, roads named as Flow's edges ("1" to "5"), straight
//! joints at nodes 2 and 3, zippers at nodes 4 and 5 where lanes 2i and 2i+1 go on as lane i.

use super::{generated_graph, positive, uniform_lanes};
use crate::model::FlowBottleneckParams;
use crate::ranges::show;
use mapc_graph::{Connection, JunctionId, LaneGraph, Provenance, RightOfWay, Road, RoadId};

/// The generator's name, and the built-in scenario's.
pub const FLOW_BOTTLENECK: &str = "flow_bottleneck";

pub fn flow_bottleneck(p: &FlowBottleneckParams) -> Result<LaneGraph, String> {
    let key = |name: &str| format!("network.{FLOW_BOTTLENECK}.{name}");
    for (i, &l) in p.lengths_m.iter().enumerate() {
        positive(&format!("{}[{i}]", key("lengths_m")), l)?;
    }
    for (i, &l) in p.zipper_internal_m.iter().enumerate() {
        positive(&format!("{}[{i}]", key("zipper_internal_m")), l)?;
    }
    positive(&key("speed_limit_mps"), p.speed_limit_mps)?;
    positive(&key("through_internal_m"), p.through_internal_m)?;
    let r = p.junction_radius_m;
    if !(r.is_finite() && r >= 0.0) {
        return Err(format!(
            "{} must be 0 or more, not {}",
            key("junction_radius_m"),
            show(r)
        ));
    }
    if p.scaling == 0 || p.scaling > 16 {
        return Err(format!(
            "{} must be 1 to 16, not {}",
            key("scaling"),
            p.scaling
        ));
    }
    let s = p.scaling;
    let lanes = [4 * s, 4 * s, 4 * s, 2 * s, s];
    // nodes 4 and 5 (indices 3 and 4) are the zippers: each road touching one loses the radius at that end
    let zipper = |node: usize| node == 3 || node == 4;
    let mut x = 0.0;
    let mut nodes: Vec<(String, [f64; 2])> = vec![("1".to_string(), [0.0, 0.0])];
    for (i, l) in p.lengths_m.iter().enumerate() {
        x += l;
        nodes.push(((i + 2).to_string(), [x, 0.0]));
    }
    let mut roads = Vec::with_capacity(5);
    for (i, &length) in p.lengths_m.iter().enumerate() {
        let start = if zipper(i) { r } else { 0.0 };
        let end = if zipper(i + 1) { r } else { 0.0 };
        let kept = length - start - end;
        if kept <= 0.0 {
            return Err(format!(
                "{}[{i}] = {} leaves no road between zippers of radius {}",
                key("lengths_m"),
                show(length),
                show(r)
            ));
        }
        let x0 = nodes[i].1[0] + start;
        let id = (i + 1).to_string();
        roads.push(Road {
            id: RoadId(i as u32),
            from: JunctionId(i as u32),
            to: JunctionId(i as u32 + 1),
            class: "highway".to_string(),
            name: Some(id.clone()),
            ref_: None,
            priority: 1,
            lanes: uniform_lanes(lanes[i], p.speed_limit_mps, kept),
            geometry: vec![[x0, 0.0], [x0 + kept, 0.0]],
            length_m: kept,
            provenance: provenance(&id),
        });
    }
    let node_names: Vec<(&str, [f64; 2])> =
        nodes.iter().map(|(n, pos)| (n.as_str(), *pos)).collect();
    let mut g = generated_graph(FLOW_BOTTLENECK, &node_names, provenance);
    g.roads = roads;
    let link = |junction: u32, from_lane: u8, to_lane: u8, via: f64, right_of_way| Connection {
        via_lanes: Vec::new(),
        yields_to: Vec::new(),
        yields_inside: false,
        junction: JunctionId(junction),
        from_road: RoadId(junction - 1),
        from_lane,
        to_road: RoadId(junction),
        to_lane,
        via_length_m: via,
        via_speed_mps: Some(p.speed_limit_mps),
        right_of_way,
        signal: None,
        right_of_way_overridden: false,
        provenance: Provenance::made_by(FLOW_BOTTLENECK),
    };
    let mut connections = Vec::new();
    for junction in [1, 2] {
        for lane in 0..4 * s {
            connections.push(link(
                junction,
                lane,
                lane,
                p.through_internal_m,
                RightOfWay::Major,
            ));
        }
    }
    for (junction, lanes_in, via) in [
        (3, 4 * s, p.zipper_internal_m[0]),
        (4, 2 * s, p.zipper_internal_m[1]),
    ] {
        for lane in 0..lanes_in {
            connections.push(link(junction, lane, lane / 2, via, RightOfWay::Zipper));
        }
    }
    g.connections = connections;
    g.rebuild_junction_links();
    Ok(g)
}

/// Roads and nodes keep Flow's names, so that a scenario written for the netconvert build (`from = "1"`) finds
/// them.
fn provenance(id: &str) -> Provenance {
    Provenance {
        sumo_ids: vec![id.to_string()],
        ..Provenance::made_by(FLOW_BOTTLENECK)
    }
}
