//! A SUMO net.xml streamed into plain records (edges with their lanes and who may drive them, junctions with their
//! request tables, connections, lights, the location), checked value by value; `super::read` makes the lane graph.

use crate::error::ParseError;
use crate::xml::{Item, XmlStream, attrs, describe};
use mapc_graph::validate::{LANE_SPEED_MPS, LANE_WIDTH_M, MAX_LENGTH_M, outside};
use std::io::BufRead;

// Above this (300 km/h) a lane's speed is a mistake in the data; counted as `speed_implausible`.
use crate::osm::MAX_PLAUSIBLE_SPEED_MPS;
/// A lane longer than this (100 km) is counted as `length_implausible`.
const MAX_PLAUSIBLE_LANE_M: f64 = 100_000.0;

/// Width SUMO gives a lane that states none.
const SUMO_DEFAULT_LANE_WIDTH_M: f64 = 3.2;

pub(super) struct SumoLane {
    pub(super) id: String,
    pub(super) index: u8,
    pub(super) speed: f64,
    pub(super) length: f64,
    pub(super) width: f64,
    pub(super) shape: Vec<[f64; 2]>,
    /// Passenger cars may drive it (its `allow` and `disallow`): not a sidewalk, a cycle, bus or tram lane.
    pub(super) cars: bool,
}

/// Whether SUMO lets a passenger car (the default vehicle class) on a lane with these `allow` and `disallow`
/// lists: `allow` names the only classes let on (`all` for every one), `disallow` the classes kept off.
pub(super) fn cars_allowed(allow: Option<&str>, disallow: Option<&str>) -> bool {
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

pub(super) struct SumoEdge {
    pub(super) id: String,
    pub(super) at: u64,
    pub(super) internal: bool,
    pub(super) from: String,
    pub(super) to: String,
    pub(super) type_: Option<String>,
    pub(super) priority: i32,
    pub(super) name: Option<String>,
    pub(super) shape: Option<Vec<[f64; 2]>>,
    pub(super) lanes: Vec<SumoLane>,
}

pub(super) struct SumoJunction {
    pub(super) id: String,
    pub(super) pos: [f64; 2],
    pub(super) internal: bool,
    pub(super) inc_lanes: Vec<String>,
    pub(super) requests: Vec<SumoRequest>,
}

/// A junction's `<request>`: its link index, the response bits (the last character is link 0) and `cont` (the
/// link leads into an internal junction).
pub(super) struct SumoRequest {
    pub(super) index: usize,
    pub(super) response: String,
    pub(super) cont: bool,
}

pub(super) struct SumoConnection {
    pub(super) at: u64,
    pub(super) from: String,
    pub(super) to: String,
    pub(super) from_lane: u8,
    pub(super) to_lane: u8,
    pub(super) via: Option<String>,
    pub(super) state: Option<String>,
    /// The traffic light and the index in its states (`tl`, `linkIndex`).
    pub(super) signal: Option<(String, u32)>,
}

type Attrs<'a> = Vec<(&'a str, std::borrow::Cow<'a, str>)>;

pub(super) struct Element<'a> {
    pub(super) kv: Attrs<'a>,
    pub(super) at: u64,
    pub(super) described: String,
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
    fn flag(&self, key: &str) -> Result<Option<bool>, ParseError> {
        match self.get(key) {
            None => Ok(None),
            Some(v) => crate::sumo_xml::sumo_bool(v)
                .map(Some)
                .ok_or_else(|| self.err(format!("`{key}` is `{v}`, not true or false"))),
        }
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
pub(super) struct Net {
    /// What the parser noticed, as (warning kind, example), counted into the graph's warnings.
    pub(super) notes: Vec<(&'static str, String)>,
    /// Junction ids seen, to refuse a second junction of the same id.
    pub(super) junction_ids: std::collections::HashSet<String>,
    pub(super) location: Option<([f64; 2], String)>,
    pub(super) edges: Vec<SumoEdge>,
    pub(super) junctions: Vec<SumoJunction>,
    pub(super) connections: Vec<SumoConnection>,
    /// Fixed-time lights; a later program of the same light replaces an earlier one (SUMO runs the last loaded).
    pub(super) lights: Vec<mapc_graph::TrafficLight>,
    /// The light whose phases are being read.
    pub(super) in_light: bool,
}

pub(super) fn parse<R: BufRead>(input: R) -> Result<Net, ParseError> {
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
                        let cont = el.flag("cont")?.unwrap_or(false);
                        net.junctions
                            .last_mut()
                            .expect("in a junction")
                            .requests
                            .push(SumoRequest {
                                index,
                                response,
                                cont,
                            });
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
