//! The network as the page draws it: every road's centre line with its class colour and provenance, every
//! junction with its kind, and the controlled windows.

use crate::colors::{class_colors, class_rank};
use mapc_graph::{JunctionKind, LaneGraph, Provenance, RoadId};
use serde::Serialize;
use std::collections::{BTreeMap, BTreeSet};

/// A controlled window to highlight: its roads and the merge it is centred on.
#[derive(Clone, Debug, Default)]
pub struct WindowMark {
    pub roads: Vec<RoadId>,
    /// The merge junction as the scenario names it (`osm:61862553`, `J43`); looked up in the graph.
    pub junction: Option<String>,
    pub label: String,
}

#[derive(Clone, Debug, Serialize)]
pub struct RoadView {
    pub id: String,
    pub label: String,
    pub class: String,
    /// `#rrggbb`, the class colour of the PNG renders.
    pub color: String,
    /// Drawing order: lower classes first, so motorways lie on top.
    pub rank: usize,
    pub lanes: usize,
    pub length_m: f64,
    pub speed_mps: f64,
    pub priority: i32,
    /// Centre line as x0, y0, x1, y1, ... in the graph's local metres (east, north), to the decimetre.
    pub pts: Vec<f64>,
    pub provenance: String,
    /// Index into [`NetworkView::windows`] of the window this road belongs to.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub window: Option<usize>,
}

#[derive(Clone, Debug, Serialize)]
pub struct JunctionView {
    pub id: String,
    pub kind: &'static str,
    pub x: f64,
    pub y: f64,
    pub provenance: String,
    pub roads_in: Vec<String>,
    pub roads_out: Vec<String>,
}

/// A traffic light's program and where its links stop.
#[derive(Clone, Debug, Serialize)]
pub struct LightView {
    pub id: String,
    pub offset_s: f64,
    /// `[duration_s, state]` per phase.
    pub phases: Vec<(f64, String)>,
    /// Per controlled link: the road it leaves (its id in `roads`), that road's lane, and the link's index in
    /// the phase states.
    pub links: Vec<(String, u8, u32)>,
}

#[derive(Clone, Debug, Serialize)]
pub struct WindowView {
    pub label: String,
    /// The window's merge junction in this graph, when found.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub junction: Option<String>,
}

#[derive(Clone, Debug, Serialize)]
pub struct NetworkView {
    pub source: String,
    /// `true` when the frame is UTM (north up, metres); `false` for a generator's local frame.
    pub geographic: bool,
    pub roads: Vec<RoadView>,
    pub junctions: Vec<JunctionView>,
    pub windows: Vec<WindowView>,
    /// Fixed-time traffic lights, drawn at their links' stop lines in the colour of the current phase.
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub lights: Vec<LightView>,
    /// Run time at which the lights' programs start (the simulation's clock at its first step).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub light_clock_start_s: Option<f64>,
    /// Length driven inside each connection, by its trace label `R1>R2` (the page places vehicles on it).
    #[serde(skip)]
    pub via_length_m: BTreeMap<String, f64>,
}

impl NetworkView {
    pub fn of(graph: &LaneGraph, windows: &[WindowMark]) -> NetworkView {
        let classes: Vec<String> = graph.roads.iter().map(|r| r.class.clone()).collect();
        let colors = class_colors(&classes);
        let window_of = |id: RoadId| windows.iter().position(|w| w.roads.contains(&id));
        let roads = graph
            .roads
            .iter()
            .map(|r| {
                let c = colors
                    .iter()
                    .find(|(k, _)| *k == r.class)
                    .map(|(_, c)| *c)
                    .expect("every class has a colour");
                RoadView {
                    id: r.id.to_string(),
                    label: r.label(),
                    class: r.class.clone(),
                    color: format!("#{:02x}{:02x}{:02x}", c.0, c.1, c.2),
                    rank: class_rank(&r.class),
                    lanes: r.lane_count(),
                    length_m: round(r.length_m, 100.0),
                    speed_mps: round(r.speed_mps(), 100.0),
                    priority: r.priority,
                    pts: r
                        .geometry
                        .iter()
                        .flat_map(|p| [round(p[0], 10.0), round(p[1], 10.0)])
                        .collect(),
                    provenance: provenance_text(&r.provenance),
                    window: window_of(r.id),
                }
            })
            .collect();
        let junctions = graph
            .junctions
            .iter()
            .map(|j| JunctionView {
                id: j.id.to_string(),
                kind: kind_name(j.kind),
                x: round(j.pos[0], 10.0),
                y: round(j.pos[1], 10.0),
                provenance: provenance_text(&j.provenance),
                roads_in: j.incoming.iter().map(|r| r.to_string()).collect(),
                roads_out: j.outgoing.iter().map(|r| r.to_string()).collect(),
            })
            .collect();
        let windows = windows
            .iter()
            .map(|w| WindowView {
                label: w.label.clone(),
                junction: w
                    .junction
                    .as_deref()
                    .and_then(|q| graph.find_junction(q).ok())
                    .map(|j| j.to_string()),
            })
            .collect();
        NetworkView {
            source: graph.source.file.clone(),
            geographic: graph.projection.is_geographic(),
            roads,
            junctions,
            windows,
            lights: graph
                .lights
                .iter()
                .map(|l| LightView {
                    id: l.id.clone(),
                    offset_s: l.offset_s,
                    phases: l
                        .phases
                        .iter()
                        .map(|p| (p.duration_s, p.state.clone()))
                        .collect(),
                    links: graph
                        .connections
                        .iter()
                        .filter_map(|c| {
                            let s = c.signal.as_ref().filter(|s| s.light == l.id)?;
                            Some((c.from_road.to_string(), c.from_lane, s.index))
                        })
                        .collect(),
                })
                .collect(),
            light_clock_start_s: None,
            via_length_m: graph
                .connections
                .iter()
                .map(|c| (format!("{}>{}", c.from_road, c.to_road), c.via_length_m))
                .collect(),
        }
    }

    /// The roads of every window (to tell AVs inside a window from the others).
    pub fn window_roads(&self) -> BTreeSet<String> {
        self.roads
            .iter()
            .filter(|r| r.window.is_some())
            .map(|r| r.id.clone())
            .collect()
    }
}

fn round(x: f64, per_unit: f64) -> f64 {
    (x * per_unit).round() / per_unit
}

fn kind_name(k: JunctionKind) -> &'static str {
    match k {
        JunctionKind::Merge => "merge",
        JunctionKind::Diverge => "diverge",
        JunctionKind::Through => "through",
        JunctionKind::Source => "source",
        JunctionKind::Sink => "sink",
        JunctionKind::Complex => "complex",
    }
}

/// Where an element came from, as the lookups accept it: `osm:NODE`, `osm-way:WAY`, SUMO ids, and the steps that
/// made it.
pub fn provenance_text(p: &Provenance) -> String {
    let mut parts: Vec<String> = Vec::new();
    parts.extend(p.osm_ways.iter().map(|w| format!("osm-way:{w}")));
    parts.extend(p.osm_nodes.iter().map(|n| format!("osm:{n}")));
    parts.extend(p.sumo_ids.iter().map(|s| format!("sumo:{s}")));
    if !p.made_by.is_empty() {
        parts.push(format!("made by {}", p.made_by.join(", ")));
    }
    parts.join(" · ")
}
