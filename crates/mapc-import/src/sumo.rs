//! SUMO net.xml, streamed once: edges with their lanes, junctions with their request tables, connections and the
//! location. Internal edges (inside junctions) are not roads: their lanes' lengths and speeds are folded into the
//! connections that drive through them.

use crate::error::ParseError;
use crate::xml::{Item, XmlStream, attrs, describe};
use mapc_graph::validate::{LANE_SPEED_MPS, LANE_WIDTH_M, MAX_LENGTH_M, outside};
use mapc_graph::{
    Connection, ConnectionLanes, Junction, JunctionId, JunctionKind, Lane, LaneGraph, Projection,
    Provenance, RightOfWay, Road, RoadId, Source, Warnings,
};
use std::collections::{HashMap, HashSet};
use std::io::BufRead;

// Above this (300 km/h) a lane's speed is a mistake in the data; counted as `speed_implausible`.
use crate::osm::MAX_PLAUSIBLE_SPEED_MPS;
/// A lane longer than this (100 km) is counted as `length_implausible`.
const MAX_PLAUSIBLE_LANE_M: f64 = 100_000.0;

/// Width SUMO gives a lane that states none.
const SUMO_DEFAULT_LANE_WIDTH_M: f64 = 3.2;

struct SumoLane {
    id: String,
    index: u8,
    speed: f64,
    length: f64,
    width: f64,
    shape: Vec<[f64; 2]>,
    /// Passenger cars may drive it (its `allow` and `disallow`): not a sidewalk, a cycle, bus or tram lane.
    cars: bool,
}

/// Whether SUMO lets a passenger car (the default vehicle class) on a lane with these `allow` and `disallow`
/// lists: `allow` names the only classes let on (`all` for every one), `disallow` the classes kept off.
fn cars_allowed(allow: Option<&str>, disallow: Option<&str>) -> bool {
    let names = |list: &str| {
        list.split_whitespace()
            .any(|c| c == "passenger" || c == "all")
    };
    match (allow, disallow) {
        (Some(a), _) => names(a),
        (None, Some(d)) => !names(d),
        (None, None) => true,
    }
}

struct SumoEdge {
    id: String,
    at: u64,
    internal: bool,
    from: String,
    to: String,
    type_: Option<String>,
    priority: i32,
    name: Option<String>,
    shape: Option<Vec<[f64; 2]>>,
    lanes: Vec<SumoLane>,
}

struct SumoJunction {
    id: String,
    pos: [f64; 2],
    internal: bool,
    inc_lanes: Vec<String>,
    /// (request index, response bits).
    requests: Vec<(usize, String)>,
}

struct SumoConnection {
    at: u64,
    from: String,
    to: String,
    from_lane: u8,
    to_lane: u8,
    via: Option<String>,
    state: Option<String>,
    /// The traffic light and the index in its states (`tl`, `linkIndex`).
    signal: Option<(String, u32)>,
}

type Attrs<'a> = Vec<(&'a str, std::borrow::Cow<'a, str>)>;

struct Element<'a> {
    kv: Attrs<'a>,
    at: u64,
    described: String,
}

impl Element<'_> {
    fn err(&self, message: impl Into<String>) -> ParseError {
        ParseError::new(self.at, Some(self.described.clone()), message)
    }
    fn get(&self, key: &str) -> Option<&str> {
        self.kv
            .iter()
            .find(|(k, _)| *k == key)
            .map(|(_, v)| v.as_ref())
    }
    fn req(&self, key: &str) -> Result<&str, ParseError> {
        self.get(key)
            .ok_or_else(|| self.err(format!("missing `{key}`")))
    }
    fn num(&self, key: &str) -> Result<Option<f64>, ParseError> {
        crate::sumo_xml::number_attr(key, self.get(key)).map_err(|m| self.err(m))
    }
    fn req_num(&self, key: &str) -> Result<f64, ParseError> {
        self.num(key)?
            .ok_or_else(|| self.err(format!("missing `{key}`")))
    }
    fn int<T: std::str::FromStr>(&self, key: &str) -> Result<Option<T>, ParseError> {
        match self.get(key) {
            None => Ok(None),
            Some(v) => v
                .trim()
                .parse::<T>()
                .map(Some)
                .map_err(|_| self.err(format!("`{key}` is `{v}`, not a valid integer"))),
        }
    }
    fn shape(&self, key: &str) -> Result<Option<Vec<[f64; 2]>>, ParseError> {
        let Some(text) = self.get(key) else {
            return Ok(None);
        };
        let mut out = Vec::new();
        for point in text.split_whitespace() {
            let mut it = point.split(',');
            let mut coord = || {
                it.next()
                    .and_then(|c| c.parse::<f64>().ok())
                    .filter(|c| c.is_finite())
            };
            match (coord(), coord()) {
                (Some(x), Some(y)) => out.push([x, y]),
                _ => {
                    return Err(
                        self.err(format!("`{key}` has the point `{point}`, not x,y numbers"))
                    );
                }
            }
        }
        Ok(Some(out))
    }
}

#[derive(Default)]
struct Net {
    /// What the parser noticed, as (warning kind, example), counted into the graph's warnings.
    notes: Vec<(&'static str, String)>,
    /// Junction ids seen, to refuse a second junction of the same id.
    junction_ids: std::collections::HashSet<String>,
    location: Option<([f64; 2], String)>,
    edges: Vec<SumoEdge>,
    junctions: Vec<SumoJunction>,
    connections: Vec<SumoConnection>,
    /// Fixed-time lights; a later program of the same light replaces an earlier one (SUMO runs the last loaded).
    lights: Vec<mapc_graph::TrafficLight>,
    /// The light whose phases are being read.
    in_light: bool,
}

fn parse<R: BufRead>(input: R) -> Result<Net, ParseError> {
    let mut xml = XmlStream::with_root(input, "net", "a SUMO network");
    let mut net = Net::default();
    // Index into net.edges / net.junctions of the element whose children are being read.
    let mut in_edge = false;
    let mut in_junction = false;
    loop {
        match xml.next()? {
            Item::Eof => break,
            Item::Skip => {}
            Item::End => {
                if xml.depth() < 2 {
                    in_edge = false;
                    in_junction = false;
                }
            }
            Item::Start {
                element,
                empty,
                at,
                depth,
            } => {
                let name = element.name().as_ref().to_string();
                let kv = attrs(&element)
                    .map_err(|m| ParseError::new(at, Some(describe(&element)), m))?;
                let el = Element {
                    kv,
                    at,
                    described: describe(&element),
                };
                match (depth, name.as_str()) {
                    (2, "location") => {
                        let offset = el.get("netOffset").unwrap_or("0,0");
                        let mut parts = offset
                            .split(',')
                            .map(|p| p.trim().parse::<f64>().ok().filter(|v| v.is_finite()));
                        let (Some(Some(x)), Some(Some(y))) = (parts.next(), parts.next()) else {
                            return Err(el.err(format!("netOffset `{offset}` is not two numbers")));
                        };
                        net.location =
                            Some(([x, y], el.get("projParameter").unwrap_or("!").to_string()));
                    }
                    (2, "edge") => {
                        let function = el.get("function").unwrap_or("normal");
                        let internal = function != "normal";
                        let edge = SumoEdge {
                            id: el.req("id")?.to_string(),
                            at,
                            internal,
                            from: if internal {
                                String::new()
                            } else {
                                el.req("from")?.to_string()
                            },
                            to: if internal {
                                String::new()
                            } else {
                                el.req("to")?.to_string()
                            },
                            type_: el.get("type").filter(|t| !t.is_empty()).map(str::to_string),
                            priority: el.int("priority")?.unwrap_or(-1),
                            name: el.get("name").filter(|t| !t.is_empty()).map(str::to_string),
                            shape: el.shape("shape")?,
                            lanes: Vec::new(),
                        };
                        net.edges.push(edge);
                        in_edge = !empty;
                    }
                    (3, "lane") if in_edge => {
                        let index: u8 =
                            el.int("index")?.ok_or_else(|| el.err("missing `index`"))?;
                        let lane = SumoLane {
                            id: el.req("id")?.to_string(),
                            index,
                            speed: el.req_num("speed")?,
                            length: el.req_num("length")?,
                            width: el.num("width")?.unwrap_or(SUMO_DEFAULT_LANE_WIDTH_M),
                            shape: el
                                .shape("shape")?
                                .ok_or_else(|| el.err("missing `shape`"))?,
                            cars: cars_allowed(el.get("allow"), el.get("disallow")),
                        };
                        if lane.length < 0.0 || lane.speed < 0.0 {
                            return Err(el.err("negative length or speed"));
                        }
                        // A lane nobody may drive on cannot be given a speed by guessing.
                        if lane.speed == 0.0 {
                            return Err(el.err(format!(
                                "lane `{}` has speed 0 (a normal or internal lane needs a positive speed limit)",
                                lane.id
                            )));
                        }
                        // what no road has would be fed on to every later stage (a speed of 1e-300 m/s makes
                        // a warm-up of days); the graph loader refuses the same
                        let problems = [
                            outside("speed", lane.speed, LANE_SPEED_MPS, "m/s"),
                            outside("width", lane.width, LANE_WIDTH_M, "m"),
                            outside("length", lane.length, [0.0, MAX_LENGTH_M], "m"),
                        ];
                        if let Some(why) = problems.into_iter().flatten().next() {
                            return Err(el.err(format!("lane `{}`: {why}", lane.id)));
                        }
                        if lane.speed > MAX_PLAUSIBLE_SPEED_MPS {
                            net.notes.push((
                                "speed_implausible",
                                format!(
                                    "lane {}: speed {} m/s (above {:.0} km/h), kept",
                                    lane.id,
                                    lane.speed,
                                    MAX_PLAUSIBLE_SPEED_MPS * 3.6
                                ),
                            ));
                        }
                        if lane.length > MAX_PLAUSIBLE_LANE_M {
                            net.notes.push((
                                "length_implausible",
                                format!(
                                    "lane {}: length {} m (over {:.0} km), kept",
                                    lane.id,
                                    lane.length,
                                    MAX_PLAUSIBLE_LANE_M / 1000.0
                                ),
                            ));
                        }
                        net.edges.last_mut().expect("in an edge").lanes.push(lane);
                    }
                    (2, "junction") => {
                        let id = el.req("id")?;
                        // a second junction of the same id would silently move the first one's roads
                        if !net.junction_ids.insert(id.to_string()) {
                            return Err(el.err(format!(
                                "a second junction with the id `{id}` (duplicate id)"
                            )));
                        }
                        let j = SumoJunction {
                            id: el.req("id")?.to_string(),
                            pos: [el.req_num("x")?, el.req_num("y")?],
                            internal: el.get("type") == Some("internal"),
                            inc_lanes: el
                                .get("incLanes")
                                .unwrap_or("")
                                .split_whitespace()
                                .map(str::to_string)
                                .collect(),
                            requests: Vec::new(),
                        };
                        net.junctions.push(j);
                        in_junction = !empty;
                    }
                    (3, "request") if in_junction => {
                        let index: usize =
                            el.int("index")?.ok_or_else(|| el.err("missing `index`"))?;
                        let response = el.req("response")?.to_string();
                        net.junctions
                            .last_mut()
                            .expect("in a junction")
                            .requests
                            .push((index, response));
                    }
                    (2, "tlLogic") => {
                        let id = el.req("id")?.to_string();
                        net.in_light = false;
                        if el.get("type").unwrap_or("static") != "static" {
                            // actuated and other programs are not simulated: the connections' states give the
                            // right of way
                            net.notes.push((
                                "traffic_light_ignored",
                                format!(
                                    "tlLogic {id}: a `{}` program is not simulated; right of way from the connections",
                                    el.get("type").unwrap_or("?")
                                ),
                            ));
                        } else {
                            net.lights.retain(|l| l.id != id);
                            net.lights.push(mapc_graph::TrafficLight {
                                id,
                                program: el.get("programID").unwrap_or("0").to_string(),
                                offset_s: el.num("offset")?.unwrap_or(0.0),
                                phases: Vec::new(),
                            });
                            net.in_light = !empty;
                        }
                    }
                    (3, "phase") if net.in_light => {
                        let duration_s = el.req_num("duration")?;
                        if !(duration_s > 0.0) {
                            return Err(
                                el.err(format!("phase duration {duration_s}: must be positive"))
                            );
                        }
                        let state = el.req("state")?.to_string();
                        net.lights
                            .last_mut()
                            .expect("in a light")
                            .phases
                            .push(mapc_graph::SignalPhase { duration_s, state });
                    }
                    (2, "connection") => {
                        net.connections.push(SumoConnection {
                            at,
                            from: el.req("from")?.to_string(),
                            to: el.req("to")?.to_string(),
                            from_lane: el
                                .int("fromLane")?
                                .ok_or_else(|| el.err("missing `fromLane`"))?,
                            to_lane: el
                                .int("toLane")?
                                .ok_or_else(|| el.err("missing `toLane`"))?,
                            via: el.get("via").map(str::to_string),
                            state: el.get("state").map(str::to_string),
                            signal: match (el.get("tl"), el.int::<u32>("linkIndex")?) {
                                (Some(tl), Some(i)) => Some((tl.to_string(), i)),
                                _ => None,
                            },
                        });
                    }
                    _ => {}
                }
            }
        }
    }
    Ok(net)
}

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

    // Lanes of internal edges, by lane id: (length, speed).
    let mut internal_lanes: HashMap<&str, (f64, f64)> = HashMap::new();
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
                internal_lanes.insert(l.id.as_str(), (l.length, l.speed));
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
        let from = *junction_of.get(e.from.as_str()).ok_or_else(|| {
            ParseError::new(
                e.at,
                place(),
                format!("`from` names junction `{}`, which the net lacks", e.from),
            )
        })?;
        let to = *junction_of.get(e.to.as_str()).ok_or_else(|| {
            ParseError::new(
                e.at,
                place(),
                format!("`to` names junction `{}`, which the net lacks", e.to),
            )
        })?;
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
        let mut next = c.via.clone();
        let mut steps = 0;
        while let Some(lane) = next.take() {
            let &(len, speed) = internal_lanes.get(lane.as_str()).ok_or_else(|| {
                ParseError::new(
                    c.at,
                    el(),
                    format!("`via` names lane `{lane}`, which the net lacks"),
                )
            })?;
            via_length += len;
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
                    .and_then(|j| j.requests.iter().find(|(i, _)| *i == link))
                    .is_some_and(|(_, response)| response.contains('1'));
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
        });
    }

    // The links each connection yields to, by its junction's request table (the response's last character is
    // link 0): crossing links too, where the table is the only word on them.
    let lanes_of: HashMap<(&str, usize), ConnectionLanes> = link_of_connection
        .iter()
        .zip(&connections)
        .map(|(&key, c)| {
            (
                key,
                ConnectionLanes {
                    from_road: c.from_road,
                    from_lane: c.from_lane,
                    to_road: c.to_road,
                    to_lane: c.to_lane,
                },
            )
        })
        .collect();
    for (c, &(junction, link)) in connections.iter_mut().zip(&link_of_connection) {
        let Some((_, response)) = requests
            .get(junction)
            .and_then(|j| j.requests.iter().find(|(i, _)| *i == link))
        else {
            continue;
        };
        c.yields_to = response
            .bytes()
            .rev()
            .enumerate()
            .filter(|&(_, b)| b == b'1')
            .filter_map(|(foe, _)| lanes_of.get(&(junction, foe)).copied())
            .collect();
    }

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

#[cfg(test)]
mod tests {
    use super::cars_allowed;

    #[test]
    fn a_lane_is_a_cars_lane_as_its_allow_and_disallow_say() {
        assert!(cars_allowed(None, None));
        // RESCO's Ingolstadt sidewalks, an I-210 cycle path, a bus lane, a tram track
        assert!(!cars_allowed(Some("pedestrian"), None));
        assert!(!cars_allowed(Some("delivery bicycle pedestrian"), None));
        assert!(!cars_allowed(Some("bus"), None));
        assert!(!cars_allowed(None, Some("all")));
        assert!(!cars_allowed(None, Some("pedestrian passenger")));
        // netconvert's lists for motorways and streets
        assert!(cars_allowed(
            Some(
                "private emergency authority army vip passenger hov taxi bus coach delivery truck trailer"
            ),
            None
        ));
        assert!(cars_allowed(
            None,
            Some("pedestrian tram rail_urban rail rail_electric rail_fast ship")
        ));
        assert!(cars_allowed(Some("all"), None));
    }
}
