//! The lane graph's data: junctions, directed roads with their lanes, and lane-to-lane connections.

use crate::ids::{JunctionId, RoadId};
use crate::projection::Projection;
use serde::{Deserialize, Serialize};
use std::collections::BTreeMap;

/// Name written in every graph file, so that another JSON file is recognised as "not a graph".
pub const FORMAT_NAME: &str = "mapc-graph";
/// Bumped on any change that an older reader would misread.
pub const FORMAT_VERSION: u32 = 1;

/// Where a junction or road came from. Several entries when a transformation joined pieces.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct Provenance {
    /// OSM way ids, in driving order.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub osm_ways: Vec<i64>,
    /// OSM node ids: the node of a junction; for a road, the nodes at its two ends.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub osm_nodes: Vec<i64>,
    /// SUMO edge, junction or connection ids.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub sumo_ids: Vec<String>,
    /// A generator or transformation step that made or changed the element (`simple_merge`, `cut_at`, ...).
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub made_by: Vec<String>,
    /// The mapc ids of the junctions and roads a transformation joined into this road (`J7`, `R12`): the ids the
    /// source map's graph gave them stay findable in every later stage.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub joined: Vec<String>,
    /// A road from a SUMO edge some of whose lanes are closed to cars (sidewalks, cycle and bus lanes, left out):
    /// the SUMO index of each of its lanes, right to left. Empty where the indices are the road's own.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub sumo_lanes: Vec<u8>,
}

impl Provenance {
    pub fn osm_node(node: i64) -> Self {
        Provenance {
            osm_nodes: vec![node],
            ..Default::default()
        }
    }
    pub fn sumo(id: impl Into<String>) -> Self {
        Provenance {
            sumo_ids: vec![id.into()],
            ..Default::default()
        }
    }
    pub fn made_by(step: impl Into<String>) -> Self {
        Provenance {
            made_by: vec![step.into()],
            ..Default::default()
        }
    }
    /// Everything both provenances name, in order, without repeats.
    pub fn merged(&self, other: &Provenance) -> Provenance {
        fn union<T: Clone + PartialEq>(a: &[T], b: &[T]) -> Vec<T> {
            let mut out = a.to_vec();
            for x in b {
                if !out.contains(x) {
                    out.push(x.clone());
                }
            }
            out
        }
        Provenance {
            osm_ways: union(&self.osm_ways, &other.osm_ways),
            osm_nodes: union(&self.osm_nodes, &other.osm_nodes),
            sumo_ids: union(&self.sumo_ids, &other.sumo_ids),
            made_by: union(&self.made_by, &other.made_by),
            joined: union(&self.joined, &other.joined),
            // (the lanes of the first piece: a road joined of several keeps its lane count)
            sumo_lanes: if self.sumo_lanes.is_empty() {
                other.sumo_lanes.clone()
            } else {
                self.sumo_lanes.clone()
            },
        }
    }
}

/// What a junction does to the traffic through it, from its counts of roads in and out.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum JunctionKind {
    /// Two roads in, one out.
    Merge,
    /// One road in, two out.
    Diverge,
    /// One in, one out (a shape point where a road's attributes change, or a cut).
    Through,
    /// No road in: where traffic enters the map.
    Source,
    /// No road out: where traffic leaves the map.
    Sink,
    /// Anything else (intersections, interchanges with more legs).
    Complex,
}

/// Road classes that carry no motor traffic or only access traffic (OSM `highway` values; a SUMO type
/// `highway.X` counts as `X`). They are roads of the graph, but a junction where one of them meets a motorway is
/// not a motorway merge: junction kinds "among the main classes" and the corridor's merging roads leave them out
/// unless asked.
pub const MINOR_CLASSES: [&str; 14] = [
    "footway",
    "path",
    "cycleway",
    "pedestrian",
    "steps",
    "bridleway",
    "track",
    "service",
    "corridor",
    "sidewalk",
    "crossing",
    "platform",
    "elevator",
    "busway",
];

/// Whether a road class is one of [`MINOR_CLASSES`]; SUMO's rail and ship types (`railway.*`, `ship`) count too.
pub fn is_minor_class(class: &str) -> bool {
    if class.starts_with("railway.") || class.starts_with("ship") {
        return true;
    }
    let c = class.strip_prefix("highway.").unwrap_or(class);
    // SUMO joins types of stacked ways with `|` (`highway.footway|highway.steps`): minor when every part is.
    c.split('|')
        .map(|p| p.strip_prefix("highway.").unwrap_or(p))
        .all(|p| MINOR_CLASSES.contains(&p))
}

impl JunctionKind {
    pub fn classify(incoming: usize, outgoing: usize) -> JunctionKind {
        match (incoming, outgoing) {
            (0, _) => JunctionKind::Source,
            (_, 0) => JunctionKind::Sink,
            (2, 1) => JunctionKind::Merge,
            (1, 2) => JunctionKind::Diverge,
            (1, 1) => JunctionKind::Through,
            _ => JunctionKind::Complex,
        }
    }
}

#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Junction {
    pub id: JunctionId,
    /// Position in the graph's local metric frame (metres east, north).
    pub pos: [f64; 2],
    pub kind: JunctionKind,
    /// Roads ending here, sorted by id.
    pub incoming: Vec<RoadId>,
    /// Roads starting here, sorted by id.
    pub outgoing: Vec<RoadId>,
    pub provenance: Provenance,
}

#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Lane {
    /// 0 is the rightmost lane (as in SUMO); a road's lanes are numbered 0, 1, 2, ... without gaps.
    pub index: u8,
    pub speed_mps: f64,
    pub width_m: f64,
    pub length_m: f64,
    /// Set where the lane has no way on at the road's end although the road continues (`simplify --keep-lanes`
    /// records it): its traffic must change lanes before the end.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub end: Option<LaneEnd>,
    /// The lane's own centre line where the input drew one (a SUMO net's lane `shape`, cut back at the junctions),
    /// from its start to its end; empty elsewhere, and where a transformation changed the lane's length (then the
    /// road's centre line moved sideways stands for it).
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub shape: Vec<[f64; 2]>,
}

/// Why a lane ends where its road goes on.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum LaneEnd {
    /// A lane the road loses (its lane count falls): a lane drop.
    Drop,
    /// The end of an acceleration lane: a lane that a merging road's traffic entered on, beside the main road's.
    Acceleration,
}

/// A directed road between two junctions: one carriageway, one direction of travel.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Road {
    pub id: RoadId,
    pub from: JunctionId,
    pub to: JunctionId,
    /// Road class: the OSM `highway` value (`motorway`, `motorway_link`, ...) or the SUMO edge type.
    pub class: String,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub name: Option<String>,
    #[serde(default, rename = "ref", skip_serializing_if = "Option::is_none")]
    pub ref_: Option<String>,
    /// Higher wins the right of way where roads meet (SUMO's edge priority, or derived from the class).
    pub priority: i32,
    /// Lanes from right to left; never empty.
    pub lanes: Vec<Lane>,
    /// Centre line in the local metric frame, from `from` to `to`.
    pub geometry: Vec<[f64; 2]>,
    /// Driving length in metres (geodesic for OSM input; SUMO's lane length for SUMO input).
    pub length_m: f64,
    pub provenance: Provenance,
}

impl Road {
    pub fn lane_count(&self) -> usize {
        self.lanes.len()
    }
    /// The road's lane of SUMO lane index `sumo_index` (`EDGE_2` is the edge's lane 2): the same index unless
    /// lanes closed to cars were left out ([`Provenance::sumo_lanes`]); `None` for a lane left out or beyond.
    pub fn lane_of_sumo_index(&self, sumo_index: u32) -> Option<u8> {
        if self.provenance.sumo_lanes.is_empty() {
            return (sumo_index < self.lanes.len() as u32).then_some(sumo_index as u8);
        }
        self.provenance
            .sumo_lanes
            .iter()
            .position(|&i| i as u32 == sumo_index)
            .map(|k| k as u8)
    }
    /// The SUMO lane index of the road's lane `lane` (the inverse of [`Self::lane_of_sumo_index`]).
    pub fn sumo_index_of_lane(&self, lane: u8) -> u8 {
        self.provenance
            .sumo_lanes
            .get(lane as usize)
            .copied()
            .unwrap_or(lane)
    }
    /// Speed limit of the rightmost lane.
    pub fn speed_mps(&self) -> f64 {
        self.lanes.first().map_or(0.0, |l| l.speed_mps)
    }
    /// A short human label: `ref name` or the class.
    pub fn label(&self) -> String {
        match (&self.ref_, &self.name) {
            (Some(r), Some(n)) => format!("{r} {n}"),
            (Some(r), None) => r.clone(),
            (None, Some(n)) => n.clone(),
            (None, None) => self.class.clone(),
        }
    }
}

/// Which of the roads meeting at a junction goes first.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum RightOfWay {
    /// Drives through without yielding (SUMO `M`).
    Major,
    /// Yields to major traffic (SUMO `m`).
    Minor,
    /// One of the streams of a zipper merge (SUMO `Z`, netconvert's lane drops and many merges): the streams
    /// take turns, each driver yielding to the one that reaches the merge first.
    Zipper,
}

/// A lane-to-lane link across a junction.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Connection {
    pub junction: JunctionId,
    pub from_road: RoadId,
    pub from_lane: u8,
    pub to_road: RoadId,
    pub to_lane: u8,
    /// Length driven inside the junction (SUMO's internal lane); 0 where the input has none (OSM).
    pub via_length_m: f64,
    /// Speed limit inside the junction, when the input gives one.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub via_speed_mps: Option<f64>,
    pub right_of_way: RightOfWay,
    /// Set when a user or a rule overrode the right of way the input implied.
    #[serde(default, skip_serializing_if = "std::ops::Not::not")]
    pub right_of_way_overridden: bool,
    pub provenance: Provenance,
    /// The traffic light that controls this connection, if any.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub signal: Option<Signal>,
    /// The connections of the same junction this one yields to, crossing ones included (a SUMO net's `<request>`
    /// table; empty elsewhere): by their lanes, which stay what they are whatever the graph's order.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub yields_to: Vec<ConnectionLanes>,
    /// Its driver yields inside the junction, not at the stop line (a SUMO net's internal junction, `cont` in its
    /// request table): a left turn waits in the junction for the oncoming stream to clear.
    #[serde(default, skip_serializing_if = "std::ops::Not::not")]
    pub yields_inside: bool,
    /// The lanes inside the junction where the input has them (a SUMO net's internal lanes, one after another,
    /// their lengths summing to `via_length_m`); empty elsewhere.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub via_lanes: Vec<InternalLane>,
}

/// One of a connection's lanes inside the junction (a SUMO internal lane).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct InternalLane {
    /// The input's id of it (`:J4_0_0`).
    pub id: String,
    pub length_m: f64,
    /// Its centre line, from its start to its end.
    pub shape: Vec<[f64; 2]>,
}

/// A connection named by its lanes: from road and lane, to road and lane.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Serialize, Deserialize)]
pub struct ConnectionLanes {
    pub from_road: RoadId,
    pub from_lane: u8,
    pub to_road: RoadId,
    pub to_lane: u8,
}

impl Connection {
    /// The lanes it joins, which name it.
    pub fn lanes(&self) -> ConnectionLanes {
        ConnectionLanes {
            from_road: self.from_road,
            from_lane: self.from_lane,
            to_road: self.to_road,
            to_lane: self.to_lane,
        }
    }
}

/// A connection's traffic light: the light's id and the connection's index in its phases' states (SUMO's `tl`
/// and `linkIndex`).
#[derive(Clone, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub struct Signal {
    pub light: String,
    pub index: u32,
}

/// A fixed-time traffic light (SUMO's `tlLogic type="static"`, the program that runs).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct TrafficLight {
    pub id: String,
    /// The program's name (SUMO's `programID`).
    pub program: String,
    /// The cycle starts this many seconds after the run's begin.
    pub offset_s: f64,
    pub phases: Vec<SignalPhase>,
}

/// One phase: every controlled connection's state for `duration_s` (SUMO's letters: `G` green with priority,
/// `g` green yielding, `y` yellow, `r` red, `o`/`O` off).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct SignalPhase {
    pub duration_s: f64,
    pub state: String,
}

/// The input format a graph was read from.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum SourceFormat {
    OsmXml,
    OsmPbf,
    SumoNet,
    /// Built by one of mapc's generators.
    Generator,
    /// Made from another graph by a transformation (simplify, window).
    Derived,
}

#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Source {
    /// The input file as given, or the generator's name.
    pub file: String,
    pub format: SourceFormat,
}

/// Problems the importer worked around, counted by kind, with a few examples each.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct Warnings {
    pub counts: BTreeMap<String, usize>,
    pub examples: BTreeMap<String, Vec<String>>,
}

impl Warnings {
    const EXAMPLES_KEPT: usize = 5;

    pub fn add(&mut self, kind: &str, example: impl Into<String>) {
        *self.counts.entry(kind.to_string()).or_default() += 1;
        let ex = self.examples.entry(kind.to_string()).or_default();
        if ex.len() < Self::EXAMPLES_KEPT {
            ex.push(example.into());
        }
    }
    pub fn total(&self) -> usize {
        self.counts.values().sum()
    }
    pub fn is_empty(&self) -> bool {
        self.counts.is_empty()
    }
}

/// The lane graph: what `mapc import` writes and every later stage reads.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct LaneGraph {
    pub format: String,
    pub version: u32,
    pub source: Source,
    pub projection: Projection,
    /// Sorted by id.
    pub junctions: Vec<Junction>,
    /// Sorted by id.
    pub roads: Vec<Road>,
    pub connections: Vec<Connection>,
    /// Fixed-time traffic lights, by id.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub lights: Vec<TrafficLight>,
    #[serde(default)]
    pub warnings: Warnings,
}
