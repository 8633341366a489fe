//! Built-in networks. The Simple Merge is laid out as the original code's MergeNetwork: the main road runs east
//! along y = 0 with the merge at x = pre_merge_m; the ramp comes in from below at `angle_deg`.

use crate::model::{LaneDropParams, MajorRoad, SimpleMergeParams};
use crate::ranges::show;
use mapc_graph::{
    Connection, Junction, JunctionId, JunctionKind, Lane, LaneGraph, Projection, Provenance,
    RightOfWay, Road, RoadId, Source, SourceFormat,
};

mod flow_bottleneck;
pub use flow_bottleneck::{FLOW_BOTTLENECK, flow_bottleneck};

pub const SIMPLE_MERGE: &str = "simple_merge";
/// Road names of the Simple Merge, as in the original code (and its SUMO net), so SUMO-style ids find them.
pub const MAIN_ENTRY: &str = "inflow_highway";
pub const MAIN_PRE_MERGE: &str = "left";
pub const RAMP_ENTRY: &str = "inflow_merge";
pub const RAMP_PRE_MERGE: &str = "bottom";
pub const POST_MERGE: &str = "center";
/// With an acceleration lane: where it ends, and the main road after that.
pub const ACCELERATION_LANE_END: &str = "accel_end";
pub const AFTER_LANE_DROP: &str = "after_lane_drop";
/// The Simple Merge with a two-lane main road and the ramp joining through an acceleration lane.
pub const TWO_LANE_MERGE: &str = "two_lane_merge";
const LANE_WIDTH_M: f64 = 3.2;
/// The lane-drop bottleneck and its roads.
pub const LANE_DROP: &str = "lane_drop";
pub const LANE_DROP_UPSTREAM: &str = "upstream";
pub const LANE_DROP_DOWNSTREAM: &str = "downstream";

/// The parameter `key` must be a finite positive number.
fn positive(key: &str, v: f64) -> Result<(), String> {
    if v.is_finite() && v > 0.0 {
        Ok(())
    } else {
        Err(format!("{key} must be a positive number, not {}", show(v)))
    }
}

pub fn simple_merge(p: &SimpleMergeParams) -> Result<LaneGraph, String> {
    for (name, v) in [
        ("inflow_edge_m", p.inflow_edge_m),
        ("pre_merge_m", p.pre_merge_m),
        ("merge_m", p.merge_m),
        ("post_merge_m", p.post_merge_m),
        ("speed_limit_mps", p.speed_limit_mps),
    ] {
        positive(&format!("network.simple_merge.{name}"), v)?;
    }
    for (name, v) in [
        ("main_internal_m", p.main_internal_m),
        ("ramp_internal_m", p.ramp_internal_m),
        ("through_internal_m", p.through_internal_m),
    ] {
        if !(v.is_finite() && v >= 0.0) {
            return Err(format!(
                "network.simple_merge.{name} must be zero or positive, not {}",
                show(v)
            ));
        }
    }
    if !(p.angle_deg > 0.0 && p.angle_deg < 90.0) {
        return Err(format!(
            "network.simple_merge.angle_deg must be between 0 and 90, not {}",
            show(p.angle_deg)
        ));
    }
    if p.lanes == 0 {
        return Err("network.simple_merge.lanes must be at least 1".to_string());
    }
    let (sin, cos) = p.angle_deg.to_radians().sin_cos();
    let made_by = || Provenance::made_by(crate::generator::SIMPLE_MERGE);
    let with_sumo = |id: &str| Provenance {
        sumo_ids: vec![id.to_string()],
        ..made_by()
    };
    let l = p.inflow_edge_m;
    let x_merge = p.pre_merge_m;
    let ramp_total = p.merge_m + l;
    // Junctions, in the original's names.
    if !(p.acceleration_lane_m.is_finite() && p.acceleration_lane_m >= 0.0) {
        return Err(format!(
            "network.simple_merge.acceleration_lane_m must be zero or positive, not {}",
            show(p.acceleration_lane_m)
        ));
    }
    let accel = p.acceleration_lane_m > 0.0;
    let x_end = x_merge + p.acceleration_lane_m;
    let mut nodes: Vec<(&str, [f64; 2])> = vec![
        ("inflow_highway", [-l, 0.0]),
        ("left", [0.0, 0.0]),
        ("center", [x_merge, 0.0]),
        ("right", [x_end + p.post_merge_m, 0.0]),
        (
            "inflow_merge",
            [x_merge - ramp_total * cos, -ramp_total * sin],
        ),
        ("bottom", [x_merge - p.merge_m * cos, -p.merge_m * sin]),
    ];
    if accel {
        nodes.push((ACCELERATION_LANE_END, [x_end, 0.0]));
    }
    let mut g = generated_graph(SIMPLE_MERGE, &nodes, with_sumo);
    let jid = |name: &str| JunctionId(nodes.iter().position(|(n, _)| *n == name).unwrap() as u32);
    let (main_priority, ramp_priority) = match p.major {
        MajorRoad::Ramp => (-1, 1),
        MajorRoad::Main => (1, -1),
        MajorRoad::Both => (1, 1),
    };
    let (main_lanes, ramp_lanes) = (p.lanes, if accel { 1 } else { p.lanes });
    let mut edges: Vec<(&str, &str, &str, f64, &str, i32, u8)> = vec![
        (
            MAIN_ENTRY,
            "inflow_highway",
            "left",
            l,
            "highway",
            main_priority,
            main_lanes,
        ),
        (
            MAIN_PRE_MERGE,
            "left",
            "center",
            p.pre_merge_m,
            "highway",
            main_priority,
            main_lanes,
        ),
        (
            RAMP_ENTRY,
            "inflow_merge",
            "bottom",
            l,
            "merge",
            ramp_priority,
            ramp_lanes,
        ),
        (
            RAMP_PRE_MERGE,
            "bottom",
            "center",
            p.merge_m,
            "merge",
            ramp_priority,
            ramp_lanes,
        ),
    ];
    if accel {
        edges.push((
            POST_MERGE,
            "center",
            ACCELERATION_LANE_END,
            p.acceleration_lane_m,
            "highway",
            main_priority,
            main_lanes + 1,
        ));
        edges.push((
            AFTER_LANE_DROP,
            ACCELERATION_LANE_END,
            "right",
            p.post_merge_m,
            "highway",
            main_priority,
            main_lanes,
        ));
    } else {
        edges.push((
            POST_MERGE,
            "center",
            "right",
            p.post_merge_m,
            "highway",
            main_priority,
            main_lanes,
        ));
    }
    g.roads = edges
        .iter()
        .enumerate()
        .map(
            |(i, &(name, from, to, length_m, class, priority, lanes))| Road {
                id: RoadId(i as u32),
                from: jid(from),
                to: jid(to),
                class: class.to_string(),
                name: Some(name.to_string()),
                ref_: None,
                priority,
                lanes: uniform_lanes(lanes, p.speed_limit_mps, length_m),
                geometry: vec![nodes[jid(from).0 as usize].1, nodes[jid(to).0 as usize].1],
                length_m,
                provenance: with_sumo(name),
            },
        )
        .collect();
    let rid = |name: &str| RoadId(edges.iter().position(|e| e.0 == name).unwrap() as u32);
    let (main_row, ramp_row) = match p.major {
        MajorRoad::Ramp => (RightOfWay::Minor, RightOfWay::Major),
        MajorRoad::Main => (RightOfWay::Major, RightOfWay::Minor),
        MajorRoad::Both => (RightOfWay::Major, RightOfWay::Major),
    };
    let connection =
        |from: &str, from_lane: u8, to: &str, to_lane: u8, via: f64, speed: f64, row| Connection {
            via_lanes: Vec::new(),
            yields_to: Vec::new(),
            yields_inside: false,
            junction: jid(edges.iter().find(|e| e.0 == from).unwrap().2),
            from_road: rid(from),
            from_lane,
            to_road: rid(to),
            to_lane,
            via_length_m: via,
            via_speed_mps: Some(speed),
            right_of_way: row,
            signal: None,
            right_of_way_overridden: false,
            provenance: made_by(),
        };
    let (v, through) = (p.speed_limit_mps, p.through_internal_m);
    // with an acceleration lane, the main road's lanes shift one to the left at the merge
    let shift = u8::from(accel);
    for lane in 0..main_lanes {
        g.connections.push(connection(
            MAIN_PRE_MERGE,
            lane,
            POST_MERGE,
            lane + shift,
            p.main_internal_m,
            v,
            main_row,
        ));
        g.connections.push(connection(
            MAIN_ENTRY,
            lane,
            MAIN_PRE_MERGE,
            lane,
            through,
            v,
            RightOfWay::Major,
        ));
        if accel {
            g.connections.push(connection(
                POST_MERGE,
                lane + 1,
                AFTER_LANE_DROP,
                lane,
                through,
                v,
                RightOfWay::Major,
            ));
        }
    }
    for lane in 0..ramp_lanes {
        g.connections.push(connection(
            RAMP_PRE_MERGE,
            lane,
            POST_MERGE,
            lane,
            p.ramp_internal_m,
            p.ramp_internal_speed_mps,
            ramp_row,
        ));
        g.connections.push(connection(
            RAMP_ENTRY,
            lane,
            RAMP_PRE_MERGE,
            lane,
            through,
            v,
            RightOfWay::Major,
        ));
    }
    g.connections
        .sort_by_key(|c| (c.junction, c.from_road, c.from_lane, c.to_road, c.to_lane));
    g.rebuild_junction_links();
    Ok(g)
}

/// The lane-drop bottleneck: road `upstream` (`lanes_before` lanes) east along y = 0 to the junction `drop`,
/// then road `downstream` (`lanes_after` lanes); the rightmost `lanes_before - lanes_after` lanes of `upstream`
/// have no connection onward, the others continue lane for lane (upstream lane i + dropped to downstream lane i).
pub fn lane_drop(p: &LaneDropParams) -> Result<LaneGraph, String> {
    for (name, v) in [
        ("upstream_m", p.upstream_m),
        ("downstream_m", p.downstream_m),
        ("speed_limit_mps", p.speed_limit_mps),
    ] {
        positive(&format!("network.lane_drop.{name}"), v)?;
    }
    if p.lanes_after == 0 || p.lanes_after > p.lanes_before {
        return Err(format!(
            "network.lane_drop: lanes_after must be between 1 and lanes_before ({}), not {}",
            p.lanes_before, p.lanes_after
        ));
    }
    let provenance = |id: &str| Provenance {
        sumo_ids: vec![id.to_string()],
        ..Provenance::made_by(LANE_DROP)
    };
    let nodes = [
        ("start", [0.0, 0.0]),
        ("drop", [p.upstream_m, 0.0]),
        ("end", [p.upstream_m + p.downstream_m, 0.0]),
    ];
    let mut g = generated_graph(LANE_DROP, &nodes, provenance);
    let roads = [
        (LANE_DROP_UPSTREAM, 0, p.upstream_m, p.lanes_before),
        (LANE_DROP_DOWNSTREAM, 1, p.downstream_m, p.lanes_after),
    ];
    g.roads = roads
        .iter()
        .enumerate()
        .map(|(i, &(name, from, length_m, lanes))| Road {
            id: RoadId(i as u32),
            from: JunctionId(from),
            to: JunctionId(from + 1),
            class: "highway".to_string(),
            name: Some(name.to_string()),
            ref_: None,
            priority: 1,
            lanes: uniform_lanes(lanes, p.speed_limit_mps, length_m),
            geometry: vec![nodes[from as usize].1, nodes[from as usize + 1].1],
            length_m,
            provenance: provenance(name),
        })
        .collect();
    let dropped = p.lanes_before - p.lanes_after;
    g.connections = (0..p.lanes_after)
        .map(|lane| Connection {
            via_lanes: Vec::new(),
            yields_to: Vec::new(),
            yields_inside: false,
            junction: JunctionId(1),
            from_road: RoadId(0),
            from_lane: lane + dropped,
            to_road: RoadId(1),
            to_lane: lane,
            via_length_m: p.through_internal_m,
            via_speed_mps: Some(p.speed_limit_mps),
            right_of_way: RightOfWay::Major,
            signal: None,
            right_of_way_overridden: false,
            provenance: Provenance::made_by(LANE_DROP),
        })
        .collect();
    g.rebuild_junction_links();
    Ok(g)
}

/// `n` lanes of one road, all alike, none ending.
fn uniform_lanes(n: u8, speed_mps: f64, length_m: f64) -> Vec<Lane> {
    (0..n)
        .map(|index| Lane {
            shape: Vec::new(),
            index,
            speed_mps,
            width_m: LANE_WIDTH_M,
            length_m,
            end: None,
        })
        .collect()
}

/// A generated network's graph with its junctions (named points, in order; roads are added by the caller).
fn generated_graph(
    generator: &str,
    nodes: &[(&str, [f64; 2])],
    provenance: impl Fn(&str) -> Provenance,
) -> LaneGraph {
    let mut g = LaneGraph::new(
        Source {
            file: generator.to_string(),
            format: SourceFormat::Generator,
        },
        Projection::Plane { offset: [0.0, 0.0] },
    );
    g.junctions = nodes
        .iter()
        .enumerate()
        .map(|(i, (name, pos))| Junction {
            id: JunctionId(i as u32),
            pos: *pos,
            kind: JunctionKind::Through,
            incoming: vec![],
            outgoing: vec![],
            provenance: provenance(name),
        })
        .collect();
    g
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn lane_drop_ends_the_rightmost_lane_and_continues_the_others_lane_for_lane() {
        let g = lane_drop(&LaneDropParams::default()).unwrap();
        assert!(
            g.invariant_violations().is_empty(),
            "{:?}",
            g.invariant_violations()
        );
        let up = g.find_roads(LANE_DROP_UPSTREAM).unwrap()[0];
        let down = g.find_roads(LANE_DROP_DOWNSTREAM).unwrap()[0];
        assert_eq!(g.road(up).unwrap().lanes.len(), 3);
        assert_eq!(g.road(down).unwrap().lanes.len(), 2);
        let links: Vec<(u8, u8)> = g
            .connections_from(up)
            .map(|c| (c.from_lane, c.to_lane))
            .collect();
        assert_eq!(links, vec![(1, 0), (2, 1)]);
        assert!((g.total_lane_length_m() - (3.0 * 600.0 + 2.0 * 300.0 + 2.0 * 0.1)).abs() < 1e-6);
        let more_after = LaneDropParams {
            lanes_after: 4,
            ..LaneDropParams::default()
        };
        assert!(lane_drop(&more_after).unwrap_err().contains("lanes_after"));
    }

    #[test]
    fn simple_merge_has_the_papers_lengths_and_right_of_way() {
        let g = simple_merge(&SimpleMergeParams::default()).unwrap();
        assert!(
            g.invariant_violations().is_empty(),
            "{:?}",
            g.invariant_violations()
        );
        let center = g.find_junction("center").unwrap();
        assert_eq!(g.junction(center).unwrap().kind, JunctionKind::Merge);
        let main_before: f64 = [MAIN_ENTRY, MAIN_PRE_MERGE]
            .iter()
            .map(|n| g.road(g.find_roads(n).unwrap()[0]).unwrap().length_m)
            .sum();
        let ramp: f64 = [RAMP_ENTRY, RAMP_PRE_MERGE]
            .iter()
            .map(|n| g.road(g.find_roads(n).unwrap()[0]).unwrap().length_m)
            .sum();
        assert_eq!((main_before, ramp), (600.0, 200.0));
        // docs/reference.md sec. 1: the total lane length the original code normalises by.
        assert!(
            (g.total_lane_length_m() - 947.68).abs() < 1e-9,
            "{}",
            g.total_lane_length_m()
        );
        let ramp_conn = g
            .connections_from(g.find_roads(RAMP_PRE_MERGE).unwrap()[0])
            .next()
            .unwrap();
        assert_eq!(ramp_conn.right_of_way, RightOfWay::Major);
        let main_conn = g
            .connections_from(g.find_roads(MAIN_PRE_MERGE).unwrap()[0])
            .next()
            .unwrap();
        assert_eq!(main_conn.right_of_way, RightOfWay::Minor);
        // The ramp's start lies (merge_m + inflow) away from the merge at 45 degrees.
        let start = g
            .junction(g.find_junction("inflow_merge").unwrap())
            .unwrap()
            .pos;
        assert!(((start[0] - 500.0).hypot(start[1]) - 200.0).abs() < 1e-9);
    }

    #[test]
    fn bad_parameters_are_named() {
        let p = SimpleMergeParams {
            pre_merge_m: -3.0,
            ..Default::default()
        };
        assert!(simple_merge(&p).unwrap_err().contains("pre_merge_m"));
        let p = SimpleMergeParams {
            angle_deg: 95.0,
            ..Default::default()
        };
        assert!(simple_merge(&p).unwrap_err().contains("angle_deg"));
    }
}
