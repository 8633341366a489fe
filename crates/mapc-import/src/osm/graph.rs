//! The lane graph from the kept ways: splitting ways at shared nodes, projection, lengths, connections and right
//! of way.

use super::tags::{Directions, class_defaults, directions, lane_counts, speeds, unusable};
use super::{LONG_SEGMENT_M, OSM_LANE_WIDTH_M, OsmData};
use crate::ImportOptions;
use geo::{Distance, Geodesic, Point};
use mapc_graph::{
    Connection, Junction, JunctionId, JunctionKind, Lane, LaneGraph, Projection, Provenance,
    RightOfWay, Road, RoadId, Source,
};
use std::collections::{BTreeSet, HashMap};

/// One piece of a way between two junction nodes.
struct Piece {
    way: usize,
    index: u32,
    nodes: Vec<i64>,
}

fn heading(a: [f64; 2], b: [f64; 2]) -> f64 {
    (b[1] - a[1]).atan2(b[0] - a[0])
}

fn turn_angle(h1: f64, h2: f64) -> f64 {
    let mut d = (h2 - h1).abs() % std::f64::consts::TAU;
    if d > std::f64::consts::PI {
        d = std::f64::consts::TAU - d;
    }
    d
}

/// Build the lane graph from the kept ways and the positions of the nodes they reference. Nodes a way names but
/// `nodes` lacks (cut off by the extract's bounding box) clip the way there.
pub fn build_graph(
    data: OsmData,
    source: Source,
    options: &ImportOptions,
) -> Result<LaneGraph, String> {
    let _ = options;
    let OsmData {
        mut ways,
        nodes,
        mut warnings,
        ..
    } = data;
    let nodes = &nodes;
    // Readers keep one way per id (a second one is a warning or an error there).
    ways.sort_by_key(|w| w.id);
    ways.retain(|w| match unusable(w) {
        Some((kind, why)) => {
            warnings.add(kind, format!("way {}: {why}", w.id));
            false
        }
        None => true,
    });

    // Runs of consecutive present nodes per way.
    let mut runs: Vec<(usize, Vec<i64>)> = Vec::new();
    for (wi, way) in ways.iter().enumerate() {
        let mut current: Vec<i64> = Vec::new();
        let mut missing = Vec::new();
        for &n in &way.nodes {
            if nodes.contains_key(&n) {
                if current.last() != Some(&n) {
                    current.push(n);
                }
            } else {
                missing.push(n);
                if current.len() >= 2 {
                    runs.push((wi, std::mem::take(&mut current)));
                }
                current.clear();
            }
        }
        if current.len() >= 2 {
            runs.push((wi, current));
        }
        if !missing.is_empty() {
            warnings.add(
                "way_clipped_at_missing_node",
                format!(
                    "way {}: {} of its {} nodes are not in the file (first {})",
                    way.id,
                    missing.len(),
                    way.nodes.len(),
                    missing[0]
                ),
            );
        }
    }

    // A node where a run ends, or that two ways (or one way twice) pass through, splits roads.
    let mut uses: HashMap<i64, u32> = HashMap::new();
    for (_, run) in &runs {
        for &n in run {
            *uses.entry(n).or_default() += 1;
        }
    }
    let mut pieces: Vec<Piece> = Vec::new();
    let mut piece_counter: HashMap<usize, u32> = HashMap::new();
    for (wi, run) in &runs {
        let mut start = 0;
        for i in 1..run.len() {
            if i == run.len() - 1 || uses[&run[i]] >= 2 {
                let counter = piece_counter.entry(*wi).or_default();
                pieces.push(Piece {
                    way: *wi,
                    index: *counter,
                    nodes: run[start..=i].to_vec(),
                });
                *counter += 1;
                start = i;
            }
        }
    }
    if pieces.is_empty() {
        return Err("no road of the chosen highway classes in this map".to_string());
    }

    // The local frame: UTM around the centre of the kept nodes' bounding box.
    let mut bbox = [
        f64::INFINITY,
        f64::INFINITY,
        f64::NEG_INFINITY,
        f64::NEG_INFINITY,
    ];
    for p in &pieces {
        for n in &p.nodes {
            let pos = nodes[n];
            bbox = [
                bbox[0].min(pos.lon()),
                bbox[1].min(pos.lat()),
                bbox[2].max(pos.lon()),
                bbox[3].max(pos.lat()),
            ];
        }
    }
    let projection = Projection::utm_around((bbox[0] + bbox[2]) / 2.0, (bbox[1] + bbox[3]) / 2.0);
    let local = |n: i64| -> [f64; 2] {
        let p = nodes[&n];
        projection
            .to_local(p.lon(), p.lat())
            .expect("UTM frame is geographic")
    };

    // Junctions sorted by OSM node id.
    let junction_nodes: BTreeSet<i64> = pieces
        .iter()
        .flat_map(|p| [p.nodes[0], *p.nodes.last().unwrap()])
        .collect();
    let junction_of: HashMap<i64, JunctionId> = junction_nodes
        .iter()
        .enumerate()
        .map(|(i, &n)| (n, JunctionId(i as u32)))
        .collect();
    let mut graph = LaneGraph::new(source, projection.clone());
    graph.junctions = junction_nodes
        .iter()
        .map(|&n| Junction {
            id: junction_of[&n],
            pos: local(n),
            kind: JunctionKind::Through,
            incoming: vec![],
            outgoing: vec![],
            provenance: Provenance::osm_node(n),
        })
        .collect();

    // Per-way attributes, computed once (and warned about once).
    struct WayInfo {
        dirs: Directions,
        lanes: (u8, u8),
        speeds: (f64, f64),
        priority: i32,
    }
    let used_ways: BTreeSet<usize> = pieces.iter().map(|p| p.way).collect();
    let info: HashMap<usize, WayInfo> = used_ways
        .iter()
        .map(|&wi| {
            let way = &ways[wi];
            let dirs = directions(way, &mut warnings);
            let lanes = lane_counts(way, dirs, &mut warnings);
            let speeds = speeds(way, &mut warnings);
            (
                wi,
                WayInfo {
                    dirs,
                    lanes,
                    speeds,
                    priority: class_defaults(&way.tags.highway).2,
                },
            )
        })
        .collect();

    // Roads, ordered by (way, piece, forward before backward).
    pieces.sort_by_key(|p| (ways[p.way].id, p.index));
    // Which (way, piece) each road came from, for U-turn detection.
    let mut road_piece: Vec<(i64, u32)> = Vec::new();
    for p in &pieces {
        let way = &ways[p.way];
        let wi = &info[&p.way];
        for w in p.nodes.windows(2) {
            let (a, b) = (nodes[&w[0]], nodes[&w[1]]);
            let step =
                Geodesic.distance(Point::new(a.lon(), a.lat()), Point::new(b.lon(), b.lat()));
            if step > LONG_SEGMENT_M {
                warnings.add(
                    "long_segment",
                    format!(
                        "way {}: nodes {} and {} are {:.1} km apart",
                        way.id,
                        w[0],
                        w[1],
                        step / 1000.0
                    ),
                );
            }
        }
        for forward in [true, false] {
            let (allowed, lanes, speed) = if forward {
                (wi.dirs.forward, wi.lanes.0, wi.speeds.0)
            } else {
                (wi.dirs.backward, wi.lanes.1, wi.speeds.1)
            };
            if !allowed {
                continue;
            }
            let mut seq = p.nodes.clone();
            if !forward {
                seq.reverse();
            }
            let mut length = 0.0;
            for w in seq.windows(2) {
                let (a, b) = (nodes[&w[0]], nodes[&w[1]]);
                length +=
                    Geodesic.distance(Point::new(a.lon(), a.lat()), Point::new(b.lon(), b.lat()));
            }
            if !(length > 0.01) {
                warnings.add(
                    "zero_length_road",
                    format!(
                        "way {} between nodes {} and {}",
                        way.id,
                        seq[0],
                        seq[seq.len() - 1]
                    ),
                );
                length = length.max(0.01);
            }
            let id = RoadId(graph.roads.len() as u32);
            graph.roads.push(Road {
                id,
                from: junction_of[&seq[0]],
                to: junction_of[seq.last().unwrap()],
                class: way.tags.highway.clone(),
                name: way.tags.name.clone(),
                ref_: way.tags.ref_.clone(),
                priority: wi.priority,
                lanes: (0..lanes.max(1))
                    .map(|i| Lane {
                        index: i,
                        speed_mps: speed,
                        width_m: OSM_LANE_WIDTH_M,
                        length_m: length,
                        end: None,
                        shape: Vec::new(),
                    })
                    .collect(),
                geometry: seq.iter().map(|&n| local(n)).collect(),
                length_m: length,
                provenance: Provenance {
                    osm_ways: vec![way.id],
                    osm_nodes: vec![seq[0], seq[seq.len() - 1]],
                    ..Default::default()
                },
            });
            road_piece.push((way.id, p.index));
        }
    }
    graph.rebuild_junction_links();
    graph.connections = osm_connections(&graph, &road_piece);
    graph.warnings = warnings;
    Ok(graph)
}

/// At each junction every road in connects to every road out except the U-turn onto the same piece of the same way;
/// lanes map straight across (lane i to lane i, the extra lanes to the leftmost). Where several roads come in, the
/// one with the higher class, then more lanes, then the straighter continuation is major; the others yield.
fn osm_connections(graph: &LaneGraph, road_piece: &[(i64, u32)]) -> Vec<Connection> {
    let road = |id: RoadId| &graph.roads[id.0 as usize];
    let end_heading = |r: &Road| {
        let g = &r.geometry;
        heading(g[g.len() - 2], g[g.len() - 1])
    };
    let start_heading = |r: &Road| heading(r.geometry[0], r.geometry[1]);
    let mut out = Vec::new();
    for j in &graph.junctions {
        let links = |from: RoadId| -> Vec<RoadId> {
            j.outgoing
                .iter()
                .copied()
                .filter(|&to| road_piece[from.0 as usize] != road_piece[to.0 as usize])
                .collect()
        };
        // Rank the roads in: best first.
        let mut ranked: Vec<(RoadId, i32, usize, f64)> = j
            .incoming
            .iter()
            .map(|&from| {
                let r = road(from);
                let straightest = links(from)
                    .iter()
                    .map(|&to| turn_angle(end_heading(r), start_heading(road(to))))
                    .fold(f64::INFINITY, f64::min);
                (from, r.priority, r.lanes.len(), straightest)
            })
            .collect();
        ranked.sort_by(|a, b| {
            b.1.cmp(&a.1)
                .then(b.2.cmp(&a.2))
                .then(a.3.total_cmp(&b.3))
                .then(a.0.cmp(&b.0))
        });
        for (rank, &(from, ..)) in ranked.iter().enumerate() {
            let right_of_way = if rank == 0 {
                RightOfWay::Major
            } else {
                RightOfWay::Minor
            };
            let fr = road(from);
            for to in links(from) {
                let tr = road(to);
                let out_lanes = tr.lanes.len() as u8;
                for lane in 0..fr.lanes.len() as u8 {
                    out.push(Connection {
                        yields_to: Vec::new(),
                        yields_inside: false,
                        junction: j.id,
                        from_road: from,
                        from_lane: lane,
                        to_road: to,
                        to_lane: lane.min(out_lanes - 1),
                        via_length_m: 0.0,
                        via_speed_mps: None,
                        right_of_way,
                        signal: None,
                        right_of_way_overridden: false,
                        provenance: Provenance::default(),
                        via_lanes: Vec::new(),
                    });
                }
            }
        }
    }
    out
}
