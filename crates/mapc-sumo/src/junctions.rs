//! Junctions as SUMO sees them: links numbered in SUMO's order, internal edges named after them, and the request
//! table in which a minor link yields to every major link into the same lane (mapc's only conflict: merges).

use crate::names::{SumoNames, road_index};
use crate::xml::{element, num, shape, start};
use mapc_graph::{Connection, LaneGraph, RightOfWay};
use std::collections::BTreeMap;

/// Half the side of the square drawn as a junction's shape (SUMO only draws it).
const JUNCTION_HALF_SIDE_M: f64 = 1.5;

/// Which junction link each connection is, and its internal lane's id.
pub(crate) struct Link<'a> {
    pub connection: &'a Connection,
    pub index: usize,
    pub internal_edge: String,
}

/// Every internal edge: its id and the roads it joins.
pub fn internal_edges(
    graph: &LaneGraph,
    names: &SumoNames,
) -> Vec<(String, mapc_graph::RoadId, mapc_graph::RoadId)> {
    links_by_junction(graph, names)
        .into_values()
        .flatten()
        .map(|l| {
            (
                l.internal_edge,
                l.connection.from_road,
                l.connection.to_road,
            )
        })
        .collect()
}

/// SUMO numbers a junction's links by incoming lane (`incLanes` order), then as the connections are listed.
pub(crate) fn links_by_junction<'a>(
    graph: &'a LaneGraph,
    names: &SumoNames,
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
            let links = list
                .into_iter()
                .enumerate()
                .map(|(index, connection)| Link {
                    connection,
                    index,
                    internal_edge: format!(":{}_{index}", names.junctions[ji]),
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
    let int_lanes: Vec<String> = links
        .iter()
        .map(|l| format!("{}_0", l.internal_edge))
        .collect();
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
