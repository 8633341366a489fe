//! Junctions as SUMO sees them: links numbered in SUMO's order, internal edges named after them, and the request
//! table in which a minor link yields to every major link into the same lane (mapc's only conflict: merges).

use crate::names::{SumoNames, road_index};
use crate::xml::{element, num, shape, start};
use mapc_graph::{Connection, LaneGraph, RightOfWay};
use std::collections::BTreeMap;

/// Half the side of the square drawn as a junction's shape (SUMO only draws it).
const JUNCTION_HALF_SIDE_M: f64 = 1.5;

/// Which junction link each connection is, and its internal lane: lane `internal_lane` of edge `internal_edge`.
pub(crate) struct Link<'a> {
    pub connection: &'a Connection,
    pub index: usize,
    pub internal_edge: String,
    pub internal_lane: usize,
}

impl Link<'_> {
    /// The id of its internal lane (the connection's `via`).
    pub fn via(&self) -> String {
        format!("{}_{}", self.internal_edge, self.internal_lane)
    }
}

/// How connections become internal edges.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum InternalEdges {
    /// One internal edge of one lane per connection: SUMO's LC2013 then clears its memory in every junction, as
    /// mapc's own scenarios drive.
    PerConnection,
    /// The connections from one road to the next side by side, as one internal edge of as many lanes (netconvert's
    /// networks, a SUMO user's scenario): SUMO keeps the memory there.
    SideBySide,
}

/// Every internal edge: its id and the roads it joins.
pub fn internal_edges(
    graph: &LaneGraph,
    names: &SumoNames,
    grouping: InternalEdges,
) -> Vec<(String, mapc_graph::RoadId, mapc_graph::RoadId)> {
    let mut out: Vec<(String, mapc_graph::RoadId, mapc_graph::RoadId)> = Vec::new();
    for l in links_by_junction(graph, names, grouping)
        .into_values()
        .flatten()
    {
        if out.last().is_none_or(|(id, _, _)| *id != l.internal_edge) {
            out.push((
                l.internal_edge,
                l.connection.from_road,
                l.connection.to_road,
            ));
        }
    }
    out
}

/// SUMO numbers a junction's links by incoming lane (`incLanes` order), then as the connections are listed.
/// Internal edges are named after the link of their first lane (`:J_k`), their lanes numbered from the right.
pub(crate) fn links_by_junction<'a>(
    graph: &'a LaneGraph,
    names: &SumoNames,
    grouping: InternalEdges,
) -> BTreeMap<usize, Vec<Link<'a>>> {
    let mut by: BTreeMap<usize, Vec<&Connection>> = BTreeMap::new();
    for c in &graph.connections {
        let ji = graph
            .junctions
            .binary_search_by_key(&c.junction, |j| j.id)
            .expect("a connection sits at a junction of its graph");
        by.entry(ji).or_default().push(c);
    }
    by.into_iter()
        .map(|(ji, mut list)| {
            list.sort_by_key(|c| (c.from_road, c.from_lane, c.to_road, c.to_lane));
            // per (from road, to road): the first link's index and the lanes given so far
            let mut edges: BTreeMap<(mapc_graph::RoadId, mapc_graph::RoadId), (usize, usize)> =
                BTreeMap::new();
            let links = list
                .into_iter()
                .enumerate()
                .map(|(index, connection)| {
                    let (first, lane) = match grouping {
                        InternalEdges::PerConnection => (index, 0),
                        InternalEdges::SideBySide => {
                            let e = edges
                                .entry((connection.from_road, connection.to_road))
                                .or_insert((index, 0));
                            e.1 += 1;
                            (e.0, e.1 - 1)
                        }
                    };
                    Link {
                        connection,
                        index,
                        internal_edge: format!(":{}_{first}", names.junctions[ji]),
                        internal_lane: lane,
                    }
                })
                .collect();
            (ji, links)
        })
        .collect()
}

pub(crate) fn junction(
    out: &mut String,
    graph: &LaneGraph,
    names: &SumoNames,
    ji: usize,
    links: &[Link],
) {
    let j = &graph.junctions[ji];
    let inc_lanes: Vec<String> = j
        .incoming
        .iter()
        .flat_map(|&r| {
            let i = road_index(graph, r);
            (0..graph.roads[i].lanes.len()).map(move |k| format!("{}_{k}", names.edges[i]))
        })
        .collect();
    let int_lanes: Vec<String> = links.iter().map(Link::via).collect();
    let [x, y] = j.pos;
    let h = JUNCTION_HALF_SIDE_M;
    let square = [
        [x - h, y - h],
        [x + h, y - h],
        [x + h, y + h],
        [x - h, y + h],
        [x - h, y - h],
    ];
    let attrs = [
        ("id", names.junctions[ji].clone()),
        (
            "type",
            if links.is_empty() {
                "dead_end"
            } else if links.iter().any(|l| l.connection.signal.is_some()) {
                "traffic_light"
            } else if links
                .iter()
                .any(|l| l.connection.right_of_way == RightOfWay::Zipper)
            {
                "zipper"
            } else {
                "priority"
            }
            .into(),
        ),
        ("x", num(x, 2)),
        ("y", num(y, 2)),
        ("incLanes", inc_lanes.join(" ")),
        ("intLanes", int_lanes.join(" ")),
        ("shape", shape(&square)),
    ];
    if links.is_empty() {
        element(out, 4, "junction", &attrs);
        return;
    }
    start(out, 4, "junction", &attrs);
    let n = links.len();
    // Bit k of a row, counted from the right, is link k: the link's foes, and the foes it must yield to.
    // two lanes of one road that end in one lane conflict too (a lane drop, the pairs of Flow's bottleneck)
    let conflicts = |a: &Connection, b: &Connection| {
        a.to_road == b.to_road
            && a.to_lane == b.to_lane
            && (a.from_road, a.from_lane) != (b.from_road, b.from_lane)
    };
    for l in links {
        let mut foes = vec!['0'; n];
        let mut response = vec!['0'; n];
        for other in links {
            if conflicts(l.connection, other.connection) {
                foes[n - 1 - other.index] = '1';
                // a minor link yields to the major ones; zipper links to each other (netconvert's response
                // equals the foes there)
                let (own, foe) = (l.connection.right_of_way, other.connection.right_of_way);
                if (own == RightOfWay::Minor && foe != RightOfWay::Minor)
                    || (own == RightOfWay::Zipper && foe == RightOfWay::Zipper)
                {
                    response[n - 1 - other.index] = '1';
                }
            }
        }
        element(
            out,
            8,
            "request",
            &[
                ("index", l.index.to_string()),
                ("response", response.into_iter().collect()),
                ("foes", foes.into_iter().collect()),
                ("cont", "0".into()),
            ],
        );
    }
    out.push_str("    </junction>\n");
}
