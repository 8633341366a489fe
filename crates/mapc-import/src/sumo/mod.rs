//! SUMO net.xml, streamed once: edges with their lanes, junctions with their request tables, connections and the
//! location. Internal edges (inside junctions) are not roads: their lanes' lengths and speeds are folded into the
//! connections that drive through them.

mod parse;

use crate::error::ParseError;
use mapc_graph::{
    Connection, ConnectionLanes, Junction, JunctionId, JunctionKind, Lane, LaneGraph, Projection,
    Provenance, RightOfWay, Road, RoadId, Source, Warnings,
};
use parse::{SumoConnection, SumoEdge, SumoJunction, SumoLane, parse};
use std::collections::{HashMap, HashSet};
use std::io::BufRead;

fn row_from_state(state: &str) -> Option<RightOfWay> {
    match state {
        "M" | "O" | "G" => Some(RightOfWay::Major),
        "Z" => Some(RightOfWay::Zipper),
        "m" | "=" | "s" | "w" | "o" | "g" | "y" | "Y" | "r" | "u" => Some(RightOfWay::Minor),
        _ => None,
    }
}

/// An OSM id carried in a SUMO id made by netconvert from OSM (`123`, `-123#4`), for provenance.
fn osm_id_in(sumo_id: &str) -> Option<i64> {
    let base = sumo_id.split('#').next()?;
    let n: i64 = base.parse().ok()?;
    Some(n.abs())
}

/// Read a net.xml into a lane graph.
pub(crate) fn read<R: BufRead>(input: R, source: Source) -> Result<LaneGraph, ParseError> {
    let mut net = parse(input)?;
    let mut net_lights = std::mem::take(&mut net.lights);
    let mut warnings = Warnings::default();
    for (kind, example) in &net.notes {
        warnings.add(kind, example.clone());
    }
    let projection = match &net.location {
        None => {
            warnings.add(
                "no_location",
                "the net has no <location>; coordinates kept as they are",
            );
            Projection::Plane { offset: [0.0, 0.0] }
        }
        Some((offset, proj)) => Projection::from_sumo_location(*offset, proj).unwrap_or_else(|m| {
            warnings.add("projection_unsupported", m);
            Projection::Plane { offset: *offset }
        }),
    };
    let geographic = projection.is_geographic();

    // Lanes of internal edges, by lane id: (length, speed, shape).
    let mut internal_lanes: HashMap<&str, (f64, f64, &[[f64; 2]])> = HashMap::new();
    let mut edge_index: HashMap<&str, &SumoEdge> = HashMap::new();
    for e in &net.edges {
        if edge_index.insert(e.id.as_str(), e).is_some() {
            return Err(ParseError::new(
                e.at,
                Some(format!("<edge id=\"{}\">", e.id)),
                "a second edge with this id",
            ));
        }
        if e.lanes.is_empty() {
            return Err(ParseError::new(
                e.at,
                Some(format!("<edge id=\"{}\">", e.id)),
                "edge without lanes",
            ));
        }
        if e.internal {
            for l in &e.lanes {
                internal_lanes.insert(l.id.as_str(), (l.length, l.speed, &l.shape));
            }
        }
    }

    // Lanes closed to cars (sidewalks, cycle, bus and tram lanes) are not the simulator's: a road keeps the others,
    // numbered from 0, and remembers their SUMO indices; an edge with none (a footway, a railway) is left out.
    // (An edge closed to cars altogether, a footway, stays a road as it was: its lanes are all the simulator
    // could give it, and the maps' road ids stay as they were.)
    let car_lane = |e: &SumoEdge, index: u8| {
        e.lanes.iter().any(|l| l.index == index && l.cars) || e.lanes.iter().all(|l| !l.cars)
    };
    let closed_edges: HashSet<&str> = HashSet::new();
    for e in net.edges.iter().filter(|e| !e.internal) {
        let closed = e.lanes.iter().filter(|l| !l.cars).count();
        if closed > 0 && closed < e.lanes.len() {
            warnings.add(
                "lanes_closed_to_cars",
                format!(
                    "edge {}: {closed} of {} lanes closed to passenger cars, left out",
                    e.id,
                    e.lanes.len()
                ),
            );
        }
    }
    // Per kept edge, each SUMO lane index's lane in the graph (`None`: closed to cars).
    let mut lane_in_graph: HashMap<&str, Vec<Option<u8>>> = HashMap::new();

    // Junctions that normal edges use, in file order.
    let normal: Vec<&SumoEdge> = net
        .edges
        .iter()
        .filter(|e| !e.internal && !closed_edges.contains(e.id.as_str()))
        .collect();
    let mut used: HashMap<&str, bool> = HashMap::new();
    for e in &normal {
        used.insert(e.from.as_str(), true);
        used.insert(e.to.as_str(), true);
    }
    let mut junction_of: HashMap<&str, JunctionId> = HashMap::new();
    let mut junctions = Vec::new();
    for sj in &net.junctions {
        if sj.internal || sj.id.starts_with(':') {
            continue;
        }
        if !used.contains_key(sj.id.as_str()) {
            warnings.add(
                "isolated_junction",
                format!("junction {} has no road", sj.id),
            );
            continue;
        }
        let id = JunctionId(junctions.len() as u32);
        junction_of.insert(sj.id.as_str(), id);
        let mut provenance = Provenance::sumo(sj.id.clone());
        if geographic && let Ok(n) = sj.id.parse::<i64>() {
            provenance.osm_nodes.push(n);
        }
        junctions.push(Junction {
            id,
            pos: sj.pos,
            kind: JunctionKind::Through,
            incoming: vec![],
            outgoing: vec![],
            provenance,
        });
    }

    let mut road_of: HashMap<&str, RoadId> = HashMap::new();
    let mut roads = Vec::new();
    for e in &normal {
        let place = || Some(format!("<edge id=\"{}\">", e.id));
        let junction = |attr: &str, id: &str| {
            junction_of.get(id).copied().ok_or_else(|| {
                ParseError::new(
                    e.at,
                    place(),
                    format!("`{attr}` names junction `{id}`, which the net lacks"),
                )
            })
        };
        let (from, to) = (junction("from", &e.from)?, junction("to", &e.to)?);
        let mut lanes: Vec<&SumoLane> = e.lanes.iter().collect();
        lanes.sort_by_key(|l| l.index);
        if let Some((i, l)) = lanes
            .iter()
            .enumerate()
            .find(|(i, l)| l.index as usize != *i)
        {
            let indices: Vec<String> = lanes.iter().map(|l| l.index.to_string()).collect();
            return Err(ParseError::new(
                e.at,
                place(),
                format!(
                    "lane indices are not 0, 1, 2, ...: its {} lanes have indices {} (lane `{}` where {i} was due)",
                    lanes.len(),
                    indices.join(", "),
                    l.id
                ),
            ));
        }
        let some_car_lane = lanes.iter().any(|l| l.cars);
        let sumo_lanes: Vec<u8> = lanes
            .iter()
            .filter(|l| l.cars || !some_car_lane)
            .map(|l| l.index)
            .collect();
        let mut in_graph = vec![None; lanes.len()];
        for (k, &i) in sumo_lanes.iter().enumerate() {
            in_graph[i as usize] = Some(k as u8);
        }
        lane_in_graph.insert(e.id.as_str(), in_graph);
        let all_lanes = lanes.len();
        lanes.retain(|l| l.cars || !some_car_lane);
        let geometry = match &e.shape {
            Some(s) if s.len() >= 2 => s.clone(),
            _ => centre_line(&lanes),
        };
        if geometry.len() < 2 {
            return Err(ParseError::new(
                e.at,
                place(),
                "shape has fewer than two points",
            ));
        }
        let mut length = lanes.iter().map(|l| l.length).sum::<f64>() / lanes.len() as f64;
        if !(length > 0.0) {
            warnings.add("zero_length_road", format!("edge {}", e.id));
            length = 0.01;
        }
        let id = RoadId(roads.len() as u32);
        road_of.insert(e.id.as_str(), id);
        let mut provenance = Provenance::sumo(e.id.clone());
        if geographic && let Some(w) = osm_id_in(&e.id) {
            provenance.osm_ways.push(w);
        }
        if sumo_lanes.len() < all_lanes {
            provenance.sumo_lanes = sumo_lanes;
        }
        roads.push(Road {
            id,
            from,
            to,
            class: e.type_.clone().unwrap_or_else(|| "unknown".to_string()),
            name: e.name.clone(),
            ref_: None,
            priority: e.priority,
            lanes: lanes
                .iter()
                .enumerate()
                .map(|(k, l)| Lane {
                    index: k as u8,
                    speed_mps: l.speed,
                    width_m: l.width,
                    length_m: l.length.max(0.01),
                    end: None,
                    shape: l.shape.clone(),
                })
                .collect(),
            geometry,
            length_m: length,
            provenance,
        });
    }

    // Request tables by SUMO junction id, for connections without a state.
    let requests: HashMap<&str, &SumoJunction> =
        net.junctions.iter().map(|j| (j.id.as_str(), j)).collect();
    // Connections leaving internal lanes, by (internal edge, lane).
    let internal_next: HashMap<(&str, u8), &SumoConnection> = net
        .connections
        .iter()
        .map(|k| ((k.from.as_str(), k.from_lane), k))
        .collect();
    // SUMO numbers a junction's links in the order of its incoming lanes (`incLanes`), then as listed.
    let mut link_index: HashMap<usize, usize> = HashMap::new();
    {
        let mut keyed: Vec<(&str, usize, usize)> = Vec::new();
        for (ci, c) in net.connections.iter().enumerate() {
            let Some(e) = edge_index.get(c.from.as_str()).filter(|e| !e.internal) else {
                continue;
            };
            // (SUMO's requests number the vehicles' links: not those of sidewalks into walking areas)
            if !car_lane(e, c.from_lane) {
                continue;
            }
            let lane = format!("{}_{}", c.from, c.from_lane);
            let pos = requests
                .get(e.to.as_str())
                .and_then(|j| j.inc_lanes.iter().position(|l| *l == lane))
                .unwrap_or(usize::MAX);
            keyed.push((e.to.as_str(), pos, ci));
        }
        keyed.sort();
        let mut last: Option<&str> = None;
        let mut n = 0;
        for (j, _, ci) in keyed {
            if last != Some(j) {
                last = Some(j);
                n = 0;
            }
            link_index.insert(ci, n);
            n += 1;
        }
    }
    let mut connections = Vec::new();
    // per graph connection, its SUMO junction and index in that junction's request table
    let mut link_of_connection: Vec<(&str, usize)> = Vec::new();
    for (ci, c) in net.connections.iter().enumerate() {
        let el = || Some(format!("<connection from=\"{}\" to=\"{}\">", c.from, c.to));
        let from_edge = edge_index.get(c.from.as_str()).ok_or_else(|| {
            ParseError::new(
                c.at,
                el(),
                format!("`from` names edge `{}`, which the net lacks", c.from),
            )
        })?;
        let to_edge = edge_index.get(c.to.as_str()).ok_or_else(|| {
            ParseError::new(
                c.at,
                el(),
                format!("`to` names edge `{}`, which the net lacks", c.to),
            )
        })?;
        if from_edge.internal || to_edge.internal {
            continue;
        }
        for (attr, lane, edge) in [
            ("fromLane", c.from_lane, from_edge),
            ("toLane", c.to_lane, to_edge),
        ] {
            if lane as usize >= edge.lanes.len() {
                return Err(ParseError::new(
                    c.at,
                    el(),
                    format!(
                        "{attr}=\"{lane}\" names a missing lane: edge `{}` has {} lane{} (indices 0 to {})",
                        edge.id,
                        edge.lanes.len(),
                        if edge.lanes.len() == 1 { "" } else { "s" },
                        edge.lanes.len().saturating_sub(1)
                    ),
                ));
            }
        }
        if closed_edges.contains(c.from.as_str()) || closed_edges.contains(c.to.as_str()) {
            continue;
        }
        let graph_lane = |edge: &str, lane: u8| lane_in_graph[edge][lane as usize];
        let (Some(from_lane), Some(to_lane)) = (
            graph_lane(&c.from, c.from_lane),
            graph_lane(&c.to, c.to_lane),
        ) else {
            // a link of a lane closed to cars (a cycle lane's, a sidewalk's)
            continue;
        };
        if from_edge.to != to_edge.from {
            return Err(ParseError::new(
                c.at,
                el(),
                format!(
                    "edge `{}` ends at `{}` but `{}` starts at `{}`",
                    c.from, from_edge.to, c.to, to_edge.from
                ),
            ));
        }
        let junction = junction_of[from_edge.to.as_str()];
        // Follow the internal lanes from `via` to the next normal edge.
        let (mut via_length, mut via_speed) = (0.0, None::<f64>);
        let mut via_lanes: Vec<mapc_graph::InternalLane> = Vec::new();
        let mut next = c.via.clone();
        let mut steps = 0;
        while let Some(lane) = next.take() {
            let &(len, speed, shape) = internal_lanes.get(lane.as_str()).ok_or_else(|| {
                ParseError::new(
                    c.at,
                    el(),
                    format!("`via` names lane `{lane}`, which the net lacks"),
                )
            })?;
            via_length += len;
            via_lanes.push(mapc_graph::InternalLane {
                id: lane.clone(),
                length_m: len,
                shape: shape.to_vec(),
            });
            via_speed = Some(via_speed.map_or(speed, |s: f64| s.min(speed)));
            steps += 1;
            if steps > 16 {
                return Err(ParseError::new(
                    c.at,
                    el(),
                    "the internal lanes after `via` loop",
                ));
            }
            // An internal lane that leads into another internal lane (an internal junction) continues the path.
            let (edge_id, lane_index) = lane.rsplit_once('_').unwrap_or((lane.as_str(), "0"));
            next = lane_index
                .parse::<u8>()
                .ok()
                .and_then(|li| internal_next.get(&(edge_id, li)))
                .and_then(|k| {
                    k.via.clone().or_else(|| {
                        edge_index
                            .get(k.to.as_str())
                            .filter(|e| e.internal)
                            .map(|e| {
                                e.lanes[(k.to_lane as usize).min(e.lanes.len() - 1)]
                                    .id
                                    .clone()
                            })
                    })
                });
        }
        let link = link_index[&ci];
        let right_of_way = match c.state.as_deref().and_then(row_from_state) {
            Some(r) => r,
            None => {
                // The junction's request table: any `1` in the response means this link yields to another.
                let yields = requests
                    .get(from_edge.to.as_str())
                    .and_then(|j| j.requests.iter().find(|r| r.index == link))
                    .is_some_and(|r| r.response.contains('1'));
                if yields {
                    RightOfWay::Minor
                } else {
                    RightOfWay::Major
                }
            }
        };
        let mut provenance = Provenance::default();
        if let Some(v) = &c.via {
            provenance.sumo_ids.push(v.clone());
        }
        link_of_connection.push((from_edge.to.as_str(), link));
        connections.push(Connection {
            junction,
            from_road: road_of[c.from.as_str()],
            from_lane,
            to_road: road_of[c.to.as_str()],
            to_lane,
            via_length_m: via_length,
            via_speed_mps: via_speed,
            right_of_way,
            signal: c.signal.as_ref().map(|(light, index)| mapc_graph::Signal {
                light: light.clone(),
                index: *index,
            }),
            right_of_way_overridden: false,
            provenance,
            yields_to: Vec::new(),
            yields_inside: false,
            via_lanes,
        });
    }

    fill_yields(&mut connections, &link_of_connection, &requests);

    let mut graph = LaneGraph::new(source, projection);
    graph.junctions = junctions;
    graph.roads = roads;
    graph.connections = connections;
    // a light with no phase, or one whose states do not reach a connection's index, is not simulated
    let mut lights = std::mem::take(&mut net_lights);

    lights.retain(|l| !l.phases.is_empty());
    lights.sort_by(|a, b| a.id.cmp(&b.id));
    for c in &mut graph.connections {
        if let Some(s) = &c.signal
            && !lights.iter().any(|l| {
                l.id == s.light && l.phases.iter().all(|p| (s.index as usize) < p.state.len())
            })
        {
            c.signal = None;
        }
    }
    graph.lights = lights;
    graph.warnings = warnings;
    graph.rebuild_junction_links();
    Ok(graph)
}

/// Each connection's `yields_to`: the connections its junction's request table says it yields to (the response's
/// last character is link 0), crossing ones too, where the table is the only word on them. `link_of_connection`:
/// per connection, its SUMO junction and index in that junction's table.
fn fill_yields(
    connections: &mut [Connection],
    link_of_connection: &[(&str, usize)],
    requests: &HashMap<&str, &SumoJunction>,
) {
    let lanes_of: HashMap<(&str, usize), ConnectionLanes> = link_of_connection
        .iter()
        .zip(connections.iter())
        .map(|(&key, c)| (key, c.lanes()))
        .collect();
    for (c, &(junction, link)) in connections.iter_mut().zip(link_of_connection) {
        let Some(request) = requests
            .get(junction)
            .and_then(|j| j.requests.iter().find(|r| r.index == link))
        else {
            continue;
        };
        c.yields_inside = request.cont;
        c.yields_to = request
            .response
            .bytes()
            .rev()
            .enumerate()
            .filter(|&(_, b)| b == b'1')
            .filter_map(|(foe, _)| lanes_of.get(&(junction, foe)).copied())
            .collect();
    }
}

/// The middle of an edge's lanes, point by point when they have the same number of points, else the middle lane.
fn centre_line(lanes: &[&SumoLane]) -> Vec<[f64; 2]> {
    let n = lanes[0].shape.len();
    if lanes.iter().all(|l| l.shape.len() == n) {
        (0..n)
            .map(|i| {
                let k = lanes.len() as f64;
                [
                    lanes.iter().map(|l| l.shape[i][0]).sum::<f64>() / k,
                    lanes.iter().map(|l| l.shape[i][1]).sum::<f64>() / k,
                ]
            })
            .collect()
    } else {
        lanes[lanes.len() / 2].shape.clone()
    }
}
