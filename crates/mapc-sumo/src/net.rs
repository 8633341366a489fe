//! The network as a SUMO `.net.xml`, written directly so that every lane keeps mapc's length to the millimetre
//! (netconvert would recompute lengths from the geometry). Each connection becomes an internal lane of its
//! `via_length_m` (at least mapc-sim's minimum, the length mapc drives), and each junction a request table in
//! which a minor link yields to every major link into the same lane: mapc's model of right of way, where the only
//! conflicts are merges (`junctions.rs`).

pub use crate::junctions::InternalEdges;
use crate::junctions::{Link, junction, links_by_junction};
use crate::names::{SumoNames, road_index};
use crate::xml::{element, num, shape, start};
use mapc_graph::{Connection, LaneGraph, Projection, RightOfWay, Road, TrafficLight};
use mapc_sim::network::MIN_VIA_LENGTH_M;
use std::collections::BTreeMap;

pub use crate::junctions::internal_edges;

/// Decimals of lengths: a millimetre's tenth, so that a round trip keeps them far inside 0.1 m.
const LENGTH_DECIMALS: usize = 4;
/// The net.xml text of `graph`.
pub fn net_xml(graph: &LaneGraph, names: &SumoNames, grouping: InternalEdges) -> String {
    let mut out = String::from("<?xml version=\"1.0\" encoding=\"UTF-8\"?>\n\n");
    out.push_str("<!-- written by `mapc export` for SUMO 1.8: lane lengths are mapc's -->\n\n");
    start(
        &mut out,
        0,
        "net",
        &[
            ("version", "1.6".into()),
            ("junctionCornerDetail", "5".into()),
            ("limitTurnSpeed", "5.50".into()),
        ],
    );
    location(&mut out, graph);
    let links = links_by_junction(graph, names, grouping);
    write_internal_edges(&mut out, graph, &links);
    for (i, road) in graph.roads.iter().enumerate() {
        edge(&mut out, graph, names, i, road);
    }
    for light in &graph.lights {
        traffic_light(&mut out, light);
    }
    for ji in 0..graph.junctions.len() {
        junction(
            &mut out,
            graph,
            names,
            ji,
            links.get(&ji).map_or(&[][..], Vec::as_slice),
        );
    }
    for list in links.values() {
        for l in list {
            let c = l.connection;
            let (from, to) = (road_index(graph, c.from_road), road_index(graph, c.to_road));
            let mut attrs = vec![
                ("from", names.edges[from].clone()),
                ("to", names.edges[to].clone()),
                ("fromLane", c.from_lane.to_string()),
                ("toLane", c.to_lane.to_string()),
                ("via", l.via()),
            ];
            if let Some(s) = &c.signal {
                attrs.push(("tl", s.light.clone()));
                attrs.push(("linkIndex", s.index.to_string()));
            }
            attrs.push((
                "dir",
                direction(&graph.roads[from], &graph.roads[to]).into(),
            ));
            // a link under a light is `O` in netconvert's nets: its state is the light's
            let link_state = if c.signal.is_some() { "O" } else { state(c) };
            attrs.push(("state", link_state.into()));
            element(&mut out, 4, "connection", &attrs);
        }
    }
    for list in links.values() {
        for l in list {
            let c = l.connection;
            let to = road_index(graph, c.to_road);
            element(
                &mut out,
                4,
                "connection",
                &[
                    ("from", l.internal_edge.clone()),
                    ("to", names.edges[to].clone()),
                    ("fromLane", l.internal_lane.to_string()),
                    ("toLane", c.to_lane.to_string()),
                    ("dir", "s".into()),
                    ("state", "M".into()),
                ],
            );
        }
    }
    out.push_str("</net>\n");
    out
}

/// A fixed-time light's program as SUMO's `tlLogic` (its id, program and offset as mapc read them, so that SUMO
/// runs the program mapc runs; a scenario's `light_programs` have replaced the net's).
fn traffic_light(out: &mut String, light: &TrafficLight) {
    start(
        out,
        4,
        "tlLogic",
        &[
            ("id", light.id.clone()),
            ("type", "static".into()),
            // SUMO keeps the program name `off` for a light switched off (no program to load): mapc's
            // always-green program of that name goes as a static one
            (
                "programID",
                if light.program == "off" {
                    "always_green".to_string()
                } else {
                    light.program.clone()
                },
            ),
            ("offset", num(light.offset_s, 2)),
        ],
    );
    for p in &light.phases {
        element(
            out,
            8,
            "phase",
            &[
                ("duration", num(p.duration_s, 2)),
                ("state", p.state.clone()),
            ],
        );
    }
    out.push_str("    </tlLogic>\n");
}

pub(crate) fn state(c: &Connection) -> &'static str {
    match c.right_of_way {
        RightOfWay::Major => "M",
        RightOfWay::Minor => "m",
        RightOfWay::Zipper => "Z",
    }
}

fn location(out: &mut String, graph: &LaneGraph) {
    let points = graph
        .roads
        .iter()
        .flat_map(|r| r.geometry.iter())
        .chain(graph.junctions.iter().map(|j| &j.pos));
    let mut b = [
        f64::INFINITY,
        f64::INFINITY,
        f64::NEG_INFINITY,
        f64::NEG_INFINITY,
    ];
    for p in points {
        b = [
            b[0].min(p[0]),
            b[1].min(p[1]),
            b[2].max(p[0]),
            b[3].max(p[1]),
        ];
    }
    if !b[0].is_finite() {
        b = [0.0; 4];
    }
    let (offset, proj) = match &graph.projection {
        Projection::Plane { offset } => (*offset, "!".to_string()),
        Projection::Utm {
            zone,
            north,
            offset,
        } => (
            *offset,
            format!(
                "+proj=utm +zone={zone}{} +ellps=WGS84 +datum=WGS84 +units=m +no_defs",
                if *north { "" } else { " +south" }
            ),
        ),
    };
    let orig = match (
        graph.projection.to_lonlat([b[0], b[1]]),
        graph.projection.to_lonlat([b[2], b[3]]),
    ) {
        (Some(lo), Some(hi)) => [lo[0], lo[1], hi[0], hi[1]].map(|v| num(v, 6)),
        _ => [
            b[0] - offset[0],
            b[1] - offset[1],
            b[2] - offset[0],
            b[3] - offset[1],
        ]
        .map(|v| num(v, 2)),
    };
    element(
        out,
        4,
        "location",
        &[
            (
                "netOffset",
                format!("{},{}", num(offset[0], 2), num(offset[1], 2)),
            ),
            ("convBoundary", b.map(|v| num(v, 2)).join(",")),
            ("origBoundary", orig.join(",")),
            ("projParameter", proj),
        ],
    );
}

fn write_internal_edges(out: &mut String, graph: &LaneGraph, links: &BTreeMap<usize, Vec<Link>>) {
    for list in links.values() {
        // each internal edge once, where its first lane's link comes, its lanes from the right
        let mut edges: Vec<(&str, Vec<&Link>)> = Vec::new();
        for l in list {
            match edges.iter_mut().find(|(id, _)| *id == l.internal_edge) {
                Some((_, lanes)) => lanes.push(l),
                None => edges.push((&l.internal_edge, vec![l])),
            }
        }
        for (id, mut lanes) in edges {
            lanes.sort_by_key(|l| l.internal_lane);
            start(
                out,
                4,
                "edge",
                &[("id", id.to_string()), ("function", "internal".into())],
            );
            for l in lanes {
                let c = l.connection;
                let from = &graph.roads[road_index(graph, c.from_road)];
                let to = &graph.roads[road_index(graph, c.to_road)];
                let speed = c
                    .via_speed_mps
                    .filter(|s| *s > 0.0)
                    .unwrap_or(from.speed_mps().min(to.speed_mps()));
                let a = *lane_shape(from, c.from_lane as usize)
                    .last()
                    .expect("a shape has points");
                let b = lane_shape(to, c.to_lane as usize)[0];
                element(
                    out,
                    8,
                    "lane",
                    &[
                        ("id", l.via()),
                        ("index", l.internal_lane.to_string()),
                        ("speed", num(speed, 2)),
                        (
                            "length",
                            num(c.via_length_m.max(MIN_VIA_LENGTH_M), LENGTH_DECIMALS),
                        ),
                        ("shape", shape(&[a, b])),
                    ],
                );
            }
            out.push_str("    </edge>\n");
        }
    }
}

fn edge(out: &mut String, graph: &LaneGraph, names: &SumoNames, i: usize, road: &Road) {
    let junction = |id| {
        let k = graph
            .junctions
            .binary_search_by_key(&id, |j: &mapc_graph::Junction| j.id)
            .expect("a road's junctions exist");
        names.junctions[k].clone()
    };
    let mut attrs = vec![
        ("id", names.edges[i].clone()),
        ("from", junction(road.from)),
        ("to", junction(road.to)),
        ("priority", road.priority.to_string()),
        ("type", road.class.clone()),
    ];
    if let Some(n) = &road.name {
        attrs.push(("name", n.clone()));
    }
    start(out, 4, "edge", &attrs);
    for (k, lane) in road.lanes.iter().enumerate() {
        element(
            out,
            8,
            "lane",
            &[
                ("id", format!("{}_{k}", names.edges[i])),
                ("index", k.to_string()),
                ("speed", num(lane.speed_mps, 2)),
                ("length", num(lane.length_m, LENGTH_DECIMALS)),
                ("width", num(lane.width_m, 2)),
                ("shape", shape(&lane_shape(road, k))),
            ],
        );
    }
    out.push_str("    </edge>\n");
}

/// A lane's centre line: the road's centre line moved sideways (lane 0 is the rightmost) by whole lane widths.
pub(crate) fn lane_shape(road: &Road, lane: usize) -> Vec<[f64; 2]> {
    let widths: Vec<f64> = road.lanes.iter().map(|l| l.width_m).collect();
    let total: f64 = widths.iter().sum();
    // Distance of the lane's centre to the left of the road's centre line.
    let left = widths[..lane].iter().sum::<f64>() + widths[lane] / 2.0 - total / 2.0;
    let g = &road.geometry;
    if left.abs() < 1e-9 || g.len() < 2 {
        return g.clone();
    }
    (0..g.len())
        .map(|i| {
            let (a, b) = (g[i.saturating_sub(1)], g[(i + 1).min(g.len() - 1)]);
            let (dx, dy) = (b[0] - a[0], b[1] - a[1]);
            let n = dx.hypot(dy).max(1e-9);
            [g[i][0] - dy / n * left, g[i][1] + dx / n * left]
        })
        .collect()
}

/// SUMO's `dir`: straight, partly or fully left or right, from the change of heading across the junction.
fn direction(from: &Road, to: &Road) -> &'static str {
    let heading = |a: [f64; 2], b: [f64; 2]| (b[1] - a[1]).atan2(b[0] - a[0]);
    let g = &from.geometry;
    let h = &to.geometry;
    if g.len() < 2 || h.len() < 2 {
        return "s";
    }
    let mut turn = (heading(h[0], h[1]) - heading(g[g.len() - 2], g[g.len() - 1])).to_degrees();
    while turn > 180.0 {
        turn -= 360.0;
    }
    while turn < -180.0 {
        turn += 360.0;
    }
    match turn {
        t if t.abs() < 30.0 => "s",
        t if t.abs() > 160.0 => "t",
        t if (30.0..60.0).contains(&t) => "L",
        t if t >= 60.0 => "l",
        t if t > -60.0 => "R",
        _ => "r",
    }
}
