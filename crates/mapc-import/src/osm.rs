//! OSM data, whatever file it came from, into a lane graph: tag interpretation (oneway, lanes, maxspeed), splitting
//! ways at shared nodes, projection, lengths, connections and right of way. The XML and PBF readers only collect
//! [`OsmWay`]s and node coordinates, so both formats give the identical graph.

use crate::ImportOptions;
use geo::{Distance, Geodesic, Point};
use mapc_graph::{
    Connection, Junction, JunctionId, JunctionKind, Lane, LaneGraph, Projection, Provenance,
    RightOfWay, Road, RoadId, Source, Warnings,
};
use std::collections::{BTreeSet, HashMap, HashSet};

/// Lane width given to every OSM lane (US interstate lanes are 12 ft).
pub const OSM_LANE_WIDTH_M: f64 = 3.65;
const MPH: f64 = 0.447_04;
const KMH: f64 = 1.0 / 3.6;
const KNOT: f64 = 0.514_444;
/// A speed limit above this (300 km/h) is a mistake in the data, not a road.
pub const MAX_PLAUSIBLE_SPEED_MPS: f64 = 300.0 / 3.6;
/// Two consecutive nodes of a road further apart than this (10 km) are counted as `long_segment`: real highway
/// geometry has a node every few hundred metres at most, so this is a misplaced node.
pub const LONG_SEGMENT_M: f64 = 10_000.0;

/// The tags of a way that the importer reads; everything else is dropped while streaming.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct WayTags {
    pub highway: String,
    pub oneway: Option<String>,
    pub junction: Option<String>,
    pub lanes: Option<String>,
    pub lanes_forward: Option<String>,
    pub lanes_backward: Option<String>,
    pub maxspeed: Option<String>,
    pub maxspeed_forward: Option<String>,
    pub maxspeed_backward: Option<String>,
    pub name: Option<String>,
    pub ref_: Option<String>,
    pub area: Option<String>,
    /// `turn:lanes` (and per direction): one `|`-separated entry per lane, read for the lane count when `lanes`
    /// is missing.
    pub turn_lanes: Option<String>,
    pub turn_lanes_forward: Option<String>,
    pub turn_lanes_backward: Option<String>,
}

impl WayTags {
    /// Record one `k=v` tag; returns false for tags the importer ignores.
    pub fn set(&mut self, k: &str, v: &str) -> bool {
        let slot = match k {
            "highway" => {
                self.highway = v.to_string();
                return true;
            }
            "oneway" => &mut self.oneway,
            "junction" => &mut self.junction,
            "lanes" => &mut self.lanes,
            "lanes:forward" => &mut self.lanes_forward,
            "lanes:backward" => &mut self.lanes_backward,
            "maxspeed" => &mut self.maxspeed,
            "maxspeed:forward" => &mut self.maxspeed_forward,
            "maxspeed:backward" => &mut self.maxspeed_backward,
            "name" => &mut self.name,
            "ref" => &mut self.ref_,
            "area" => &mut self.area,
            "turn:lanes" => &mut self.turn_lanes,
            "turn:lanes:forward" => &mut self.turn_lanes_forward,
            "turn:lanes:backward" => &mut self.turn_lanes_backward,
            _ => return false,
        };
        *slot = Some(v.to_string());
        true
    }
}

/// A kept highway way: its id, node ids in order and tags.
#[derive(Clone, Debug, PartialEq)]
pub struct OsmWay {
    pub id: i64,
    pub nodes: Vec<i64>,
    pub tags: WayTags,
}

/// What a reader collected: the kept ways (file order, one per id), the positions of the nodes they use, and
/// what the reader noticed on the way (duplicates, ignored turn restrictions), counted.
#[derive(Clone, Debug, Default)]
pub struct OsmData {
    pub ways: Vec<OsmWay>,
    pub nodes: HashMap<i64, NodePos>,
    pub warnings: Warnings,
    /// Kept way ids, to find a second way of the same id.
    way_index: HashMap<i64, usize>,
}

impl OsmData {
    /// Keep a way. A second way with the same id is a counted warning when it is the same way again, and an
    /// error otherwise: which one is right cannot be known, and taking either silently changes the roads.
    pub fn add_way(&mut self, way: OsmWay) -> Result<(), String> {
        if let Some(&i) = self.way_index.get(&way.id) {
            if self.ways[i] == way {
                self.warnings
                    .add("duplicate_way", format!("way {} appears twice", way.id));
                return Ok(());
            }
            return Err(format!(
                "way {} appears twice with different nodes or tags (duplicate id)",
                way.id
            ));
        }
        self.way_index.insert(way.id, self.ways.len());
        self.ways.push(way);
        Ok(())
    }

    /// Record a used node's position. The same node twice at the same place is a counted warning; at another
    /// place it is an error (a duplicate id: one of the two would silently move roads, or stretch them by
    /// hundreds of kilometres).
    pub fn add_node(&mut self, id: i64, pos: NodePos) -> Result<(), String> {
        match self.nodes.insert(id, pos) {
            None => Ok(()),
            Some(old) if old == pos => {
                self.warnings
                    .add("duplicate_node", format!("node {id} appears twice"));
                Ok(())
            }
            Some(old) => Err(format!(
                "node {id} appears twice, at {:.7},{:.7} and at {:.7},{:.7} (duplicate id)",
                old.lat(),
                old.lon(),
                pos.lat(),
                pos.lon()
            )),
        }
    }

    /// Count the turn restrictions that name a kept way: mapc's connections do not model them.
    pub fn note_restrictions(&mut self, restrictions: &[(i64, Vec<i64>)]) {
        for (id, members) in restrictions {
            if members.iter().any(|w| self.way_index.contains_key(w)) {
                self.warnings.add(
                    "turn_restriction_ignored",
                    format!("relation {id} (type=restriction) on a kept way"),
                );
            }
        }
    }
}

/// Node position in OSM's own fixed point (1e-7 degree): both file formats store exactly this, so converting from it
/// (rather than from the XML text) makes the XML and PBF graphs bit-identical.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct NodePos {
    pub lat_e7: i32,
    pub lon_e7: i32,
}

impl NodePos {
    pub fn lon(self) -> f64 {
        self.lon_e7 as f64 * 1e-7
    }
    pub fn lat(self) -> f64 {
        self.lat_e7 as f64 * 1e-7
    }
}

/// Parse a decimal degree (`-83.4877071`) to 1e-7 degree fixed point, checking its range.
pub fn parse_degrees(text: &str, limit: f64) -> Result<i32, String> {
    let v: f64 = text
        .trim()
        .parse()
        .map_err(|_| format!("`{text}` is not a number"))?;
    if !v.is_finite() || v.abs() > limit {
        return Err(format!("{text} is outside -{limit}..{limit}"));
    }
    Ok((v * 1e7).round() as i32)
}

/// Class defaults: lanes per direction, speed limit (m/s) and priority rank. US values, as the maps are American.
pub fn class_defaults(class: &str) -> (u8, f64, i32) {
    match class {
        "motorway" => (2, 65.0 * MPH, 13),
        "motorway_link" => (1, 45.0 * MPH, 12),
        "trunk" => (2, 55.0 * MPH, 11),
        "trunk_link" => (1, 40.0 * MPH, 10),
        "primary" => (1, 45.0 * MPH, 9),
        "primary_link" => (1, 35.0 * MPH, 8),
        "secondary" => (1, 40.0 * MPH, 7),
        "secondary_link" => (1, 30.0 * MPH, 6),
        "tertiary" => (1, 35.0 * MPH, 6),
        "tertiary_link" => (1, 25.0 * MPH, 5),
        "unclassified" | "residential" => (1, 25.0 * MPH, 4),
        "living_street" => (1, 10.0 * MPH, 3),
        "service" => (1, 15.0 * MPH, 2),
        _ => (1, 25.0 * MPH, 1),
    }
}

/// `70 mph`, `100`, `100 km/h`, `20 knots` -> m/s. `None` for anything else (`US:urban`, `none`, `signals`).
pub fn parse_maxspeed(text: &str) -> Option<f64> {
    let t = text.split(';').next()?.trim();
    let digits_end = t
        .find(|c: char| !(c.is_ascii_digit() || c == '.'))
        .unwrap_or(t.len());
    let value: f64 = t[..digits_end].parse().ok()?;
    let unit = t[digits_end..].trim();
    let factor = match unit {
        "" | "km/h" | "kmh" | "kph" => KMH,
        "mph" => MPH,
        "knots" => KNOT,
        _ => return None,
    };
    (value > 0.0 && value.is_finite()).then_some(value * factor)
}

fn parse_lanes(text: &str) -> Option<u8> {
    let n: u32 = text.split(';').next()?.trim().parse().ok()?;
    (1..=16).contains(&n).then_some(n as u8)
}

/// Which directions a way can be driven in.
#[derive(Clone, Copy, Debug, PartialEq)]
struct Directions {
    forward: bool,
    backward: bool,
}

fn directions(way: &OsmWay, warnings: &mut Warnings) -> Directions {
    let implied = matches!(way.tags.highway.as_str(), "motorway" | "motorway_link")
        || way.tags.junction.as_deref() == Some("roundabout");
    match way.tags.oneway.as_deref() {
        Some("yes" | "true" | "1") => Directions {
            forward: true,
            backward: false,
        },
        Some("-1" | "reverse") => Directions {
            forward: false,
            backward: true,
        },
        Some("no" | "false" | "0") => Directions {
            forward: true,
            backward: true,
        },
        None => Directions {
            forward: true,
            backward: !implied,
        },
        Some(other) => {
            warnings.add(
                "oneway_unknown",
                format!(
                    "way {}: oneway={other}, read as {}",
                    way.id,
                    if implied { "yes" } else { "no" }
                ),
            );
            Directions {
                forward: true,
                backward: !implied,
            }
        }
    }
}

/// Why a kept way cannot become roads, as (warning kind, reason): an area (`area=yes`: a square, not a line to
/// drive along) or a way whose direction changes with the time of day (`oneway=reversible|alternating`).
fn unusable(way: &OsmWay) -> Option<(&'static str, String)> {
    if way.tags.area.as_deref() == Some("yes") {
        return Some((
            "area_dropped",
            format!("{} with area=yes", way.tags.highway),
        ));
    }
    match way.tags.oneway.as_deref() {
        Some(v @ ("reversible" | "alternating")) => Some((
            "oneway_reversible_dropped",
            format!("oneway={v}: its direction depends on the time"),
        )),
        _ => None,
    }
}

/// Lanes (forward, backward) of a way.
fn lane_counts(way: &OsmWay, dirs: Directions, warnings: &mut Warnings) -> (u8, u8) {
    let (default, _, _) = class_defaults(&way.tags.highway);
    let t = &way.tags;
    let mut read = |key: &str, v: &Option<String>| -> Option<u8> {
        let text = v.as_deref()?;
        let n = parse_lanes(text);
        match n {
            None => warnings.add("lanes_unparsed", format!("way {}: {key}={text}", way.id)),
            // `2;3`: the tag holds several values (lanes that change along the way); the first is read
            Some(first) if text.contains(';') => warnings.add(
                "lanes_multiple_values",
                format!("way {}: {key}={text}, read as {first}", way.id),
            ),
            Some(_) => {}
        }
        n
    };
    // `turn:lanes` has one `|`-separated entry per lane: the lane count where `lanes` is missing
    let turn_count = |v: &Option<String>| -> Option<u8> {
        let n = v.as_deref()?.split('|').count();
        (1..=16).contains(&n).then_some(n as u8)
    };
    let total = read("lanes", &t.lanes);
    let fwd = read("lanes:forward", &t.lanes_forward).or_else(|| turn_count(&t.turn_lanes_forward));
    let bwd =
        read("lanes:backward", &t.lanes_backward).or_else(|| turn_count(&t.turn_lanes_backward));
    let one_way = dirs.forward != dirs.backward;
    let total = total.or_else(|| turn_count(&t.turn_lanes).filter(|_| one_way));
    let two_way = dirs.forward && dirs.backward;
    let result = if two_way {
        match (fwd, bwd, total) {
            (Some(f), Some(b), _) => Some((f, b)),
            (Some(f), None, Some(n)) => Some((f, n.saturating_sub(f).max(1))),
            (None, Some(b), Some(n)) => Some((n.saturating_sub(b).max(1), b)),
            (None, None, Some(n)) => Some((n.div_ceil(2).max(1), (n / 2).max(1))),
            _ => None,
        }
    } else if dirs.forward {
        fwd.or(total).map(|n| (n, 0))
    } else {
        bwd.or(total).map(|n| (0, n))
    };
    result.unwrap_or_else(|| {
        warnings.add(
            "lanes_defaulted",
            format!(
                "way {} ({}): no lanes tag, {default} per direction",
                way.id, way.tags.highway
            ),
        );
        (default, default)
    })
}

/// Speed limits (forward, backward) in m/s.
fn speeds(way: &OsmWay, warnings: &mut Warnings) -> (f64, f64) {
    let (_, default, _) = class_defaults(&way.tags.highway);
    let t = &way.tags;
    let mut read = |key: &str, v: &Option<String>| -> Option<f64> {
        let text = v.as_deref()?;
        match parse_maxspeed(text) {
            None => {
                warnings.add(
                    "maxspeed_unparsed",
                    format!("way {}: {key}={text}, class default used", way.id),
                );
                None
            }
            // a typo (`650`) or a unit mix-up: the class default is closer to the truth than 650 km/h
            Some(s) if s > MAX_PLAUSIBLE_SPEED_MPS => {
                warnings.add(
                    "maxspeed_implausible",
                    format!(
                        "way {}: {key}={text}, above {:.0} km/h: class default used",
                        way.id,
                        MAX_PLAUSIBLE_SPEED_MPS * 3.6
                    ),
                );
                None
            }
            s => s,
        }
    };
    let both = read("maxspeed", &t.maxspeed);
    let fwd = read("maxspeed:forward", &t.maxspeed_forward).or(both);
    let bwd = read("maxspeed:backward", &t.maxspeed_backward).or(both);
    if fwd.is_none() && bwd.is_none() && t.maxspeed.is_none() {
        warnings.add(
            "maxspeed_defaulted",
            format!("way {} ({}): no maxspeed tag", way.id, way.tags.highway),
        );
    }
    (fwd.unwrap_or(default), bwd.unwrap_or(default))
}

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
                        junction: j.id,
                        from_road: from,
                        from_lane: lane,
                        to_road: to,
                        to_lane: lane.min(out_lanes - 1),
                        via_length_m: 0.0,
                        via_speed_mps: None,
                        right_of_way,
                        right_of_way_overridden: false,
                        provenance: Provenance::default(),
                    });
                }
            }
        }
    }
    out
}

/// The OSM node ids a set of kept ways needs.
pub fn needed_nodes(ways: &[OsmWay]) -> HashSet<i64> {
    ways.iter().flat_map(|w| w.nodes.iter().copied()).collect()
}

/// Keep a way if its `highway` class is one of `classes`.
pub fn keeps(classes: &[String], tags: &WayTags) -> bool {
    !tags.highway.is_empty() && classes.iter().any(|c| c == &tags.highway)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn maxspeed_units() {
        assert!((parse_maxspeed("70 mph").unwrap() - 31.2928).abs() < 1e-9);
        assert!((parse_maxspeed("100").unwrap() - 27.777_777_777_777_78).abs() < 1e-9);
        assert!((parse_maxspeed("50 km/h").unwrap() - 13.888_888_888_888_89).abs() < 1e-9);
        assert_eq!(parse_maxspeed("US:urban"), None);
        assert_eq!(parse_maxspeed("none"), None);
    }

    #[test]
    fn degrees_are_checked() {
        assert_eq!(parse_degrees("-83.4877071", 180.0).unwrap(), -834_877_071);
        assert!(
            parse_degrees("abc", 90.0)
                .unwrap_err()
                .contains("not a number")
        );
        assert!(parse_degrees("91", 90.0).is_err());
        assert!(parse_degrees("NaN", 90.0).is_err());
    }

    fn way(id: i64, nodes: &[i64], tags: &[(&str, &str)]) -> OsmWay {
        let mut t = WayTags::default();
        for (k, v) in tags {
            t.set(k, v);
        }
        OsmWay {
            id,
            nodes: nodes.to_vec(),
            tags: t,
        }
    }

    #[test]
    fn lanes_per_direction() {
        let mut w = Warnings::default();
        let two = Directions {
            forward: true,
            backward: true,
        };
        let one = Directions {
            forward: true,
            backward: false,
        };
        assert_eq!(
            lane_counts(
                &way(1, &[], &[("highway", "primary"), ("lanes", "5")]),
                two,
                &mut w
            ),
            (3, 2)
        );
        assert_eq!(
            lane_counts(
                &way(
                    1,
                    &[],
                    &[
                        ("highway", "primary"),
                        ("lanes", "5"),
                        ("lanes:forward", "2")
                    ]
                ),
                two,
                &mut w
            ),
            (2, 3)
        );
        assert_eq!(
            lane_counts(
                &way(1, &[], &[("highway", "motorway"), ("lanes", "4")]),
                one,
                &mut w
            ),
            (4, 0)
        );
        assert!(w.is_empty());
        assert_eq!(
            lane_counts(&way(1, &[], &[("highway", "motorway")]), one, &mut w),
            (2, 2)
        );
        assert_eq!(w.counts["lanes_defaulted"], 1);
    }

    #[test]
    fn oneway_rules() {
        let mut w = Warnings::default();
        let d = |tags: &[(&str, &str)], w: &mut Warnings| {
            let d = directions(&way(1, &[], tags), w);
            (d.forward, d.backward)
        };
        assert_eq!(d(&[("highway", "motorway")], &mut w), (true, false));
        assert_eq!(d(&[("highway", "primary")], &mut w), (true, true));
        assert_eq!(
            d(&[("highway", "primary"), ("oneway", "-1")], &mut w),
            (false, true)
        );
        assert_eq!(
            d(&[("highway", "motorway"), ("oneway", "no")], &mut w),
            (true, true)
        );
        assert!(w.is_empty());
    }

    /// A Y of three ways: 2 and 3 join way 1 at node 20, which is also where way 1 is split.
    #[test]
    fn split_merge_and_right_of_way() {
        let nodes: HashMap<i64, NodePos> = [
            (10, (42.0, -83.0)),
            (20, (42.0, -82.99)),
            (30, (42.0, -82.98)),
            (40, (41.995, -83.0)),
            (41, (41.998, -82.995)),
        ]
        .into_iter()
        .map(|(id, (lat, lon))| {
            (
                id,
                NodePos {
                    lat_e7: (lat * 1e7_f64).round() as i32,
                    lon_e7: (lon * 1e7_f64).round() as i32,
                },
            )
        })
        .collect();
        let ways = vec![
            way(1, &[10, 20, 30], &[("highway", "motorway"), ("lanes", "2")]),
            way(2, &[40, 41, 20, 99], &[("highway", "motorway_link")]),
        ];
        let mut data = OsmData::default();
        for w in ways {
            data.add_way(w).unwrap();
        }
        data.nodes = nodes;
        let g = build_graph(
            data,
            Source {
                file: "t".into(),
                format: mapc_graph::SourceFormat::OsmXml,
            },
            &ImportOptions::default(),
        )
        .unwrap();
        assert!(
            g.invariant_violations().is_empty(),
            "{:?}",
            g.invariant_violations()
        );
        assert_eq!(g.junctions.len(), 4);
        assert_eq!(g.roads.len(), 3);
        let merge = g.find_junction("osm:20").unwrap();
        assert_eq!(g.junction(merge).unwrap().kind, JunctionKind::Merge);
        assert_eq!(g.warnings.counts["way_clipped_at_missing_node"], 1);
        let major: Vec<_> = g
            .connections
            .iter()
            .filter(|c| c.right_of_way == RightOfWay::Major && c.junction == merge)
            .collect();
        assert!(
            major
                .iter()
                .all(|c| g.road(c.from_road).unwrap().class == "motorway")
        );
        let r0 = g.road(RoadId(0)).unwrap();
        assert!((r0.length_m - 828.5).abs() < 1.0, "{}", r0.length_m);
        assert_eq!(r0.provenance.osm_nodes, vec![10, 20]);
    }
}
