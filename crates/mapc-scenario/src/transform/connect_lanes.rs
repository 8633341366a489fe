//! `connect_lanes` (with `--keep-lanes`, in place of `collapse_lanes`): every lane of the corridor is kept, with
//! lane-level connections, and every lane that stops where its road goes on is recorded as ending.
//!
//! A SUMO net's connections are its own (`fromLane`/`toLane`) and are kept. An OSM map has none: the importer maps
//! lane i to lane i, which is wrong wherever lane counts change, so they are derived again on the corridor, as
//! SUMO's netconvert guesses them for motorways:
//! - one road in, one out: lanes line up on the left; where the road loses lanes its rightmost lanes end, where it
//!   gains lanes they are added on the left (on the right where the road loses as many again at its end: an
//!   exit lane), fed by the nearest lane;
//! - a merge whose road out has as many lanes as the two roads in: the road on the right (by the drawn geometry)
//!   takes the rightmost lanes, the other the rest: the merging road's lanes run on as acceleration lanes;
//!   otherwise the main road keeps its lanes lined up on its far side and the merging road takes the lanes left
//!   over on its side, all of them into the nearest one if none is left over (it merges into the rightmost lane);
//! - a diverge whose road in has as many lanes as the two out (or one fewer): the road on the right takes the
//!   rightmost lanes, the other the rest; otherwise the main road goes on as through a joint and the exit takes
//!   the lanes on its side;
//! - any other junction keeps the importer's connections.
//!
//! Road pairs that `prune` connected (the map had no connection there) are derived the same way on any map.
//!
//! A lane that stops is the end of an acceleration lane when, followed upstream along the main road, it began as
//! a merging road's lane; any other lane that stops is a lane drop.

use super::{Corridor, SimplifyOptions, TransformError, mark, prune, sort_connections};
use mapc_graph::{Connection, JunctionId, LaneEnd, LaneGraph, Road, RoadId};
use std::collections::{BTreeSet, HashSet};

pub const NAME: &str = "connect_lanes";

/// One lane-level link: (from road, from lane, to road, to lane).
type Link = (RoadId, u8, RoadId, u8);

pub fn apply(c: &mut Corridor, _opts: &SimplifyOptions) -> Result<String, TransformError> {
    let junctions: Vec<JunctionId> = c.graph.junctions.iter().map(|j| j.id).collect();
    let (mut derived, mut derived_at) = (0, 0);
    for j in junctions {
        let pairs: BTreeSet<(RoadId, RoadId)> = c
            .graph
            .connections
            .iter()
            .filter(|k| k.junction == j)
            .map(|k| (k.from_road, k.to_road))
            .collect();
        let guessed: Vec<(RoadId, RoadId)> = pairs
            .iter()
            .copied()
            .filter(|&(a, b)| c.guessed_connections || made_by_prune(&c.graph, a, b))
            .collect();
        if guessed.is_empty() {
            continue;
        }
        let links = derive_links(c, j, &pairs);
        for (a, b) in guessed {
            let template = c
                .graph
                .connections
                .iter()
                .find(|k| k.from_road == a && k.to_road == b)
                .cloned()
                .expect("the pair has a connection");
            c.graph
                .connections
                .retain(|k| !(k.from_road == a && k.to_road == b));
            for &(from, from_lane, to, to_lane) in links.iter().filter(|l| l.0 == a && l.2 == b) {
                let mut k = Connection {
                    yields_to: Vec::new(),
                    yields_inside: false,
                    from_road: from,
                    from_lane,
                    to_road: to,
                    to_lane,
                    ..template.clone()
                };
                mark(&mut k.provenance, NAME);
                c.graph.connections.push(k);
                derived += 1;
            }
        }
        derived_at += 1;
    }
    sort_connections(&mut c.graph);
    let (acceleration, drops) = record_lane_ends(c);
    c.lanes_connected = true;
    let lanes: usize = c.graph.roads.iter().map(|r| r.lanes.len()).sum();
    let most = c
        .graph
        .roads
        .iter()
        .map(|r| r.lanes.len())
        .max()
        .unwrap_or(0);
    Ok(format!(
        "{} roads keep their {lanes} lanes (up to {most} a road); {} lane connections, {derived} of them derived \
         at {derived_at} junctions where the map gives none; {acceleration} acceleration lanes and {drops} lane \
         drops end where their road goes on",
        c.graph.roads.len(),
        c.graph.connections.len(),
    ))
}

fn made_by_prune(g: &LaneGraph, a: RoadId, b: RoadId) -> bool {
    g.connections
        .iter()
        .filter(|k| k.from_road == a && k.to_road == b)
        .all(|k| k.provenance.made_by.iter().any(|m| m == prune::NAME))
}

fn lanes(g: &LaneGraph, r: RoadId) -> u8 {
    g.road(r).map_or(1, |r| r.lanes.len() as u8)
}

/// How far `p` lies to the right of a line through `at` heading `dir` (negative: to the left).
fn right_of(dir: [f64; 2], at: [f64; 2], p: [f64; 2]) -> f64 {
    -(dir[0] * (p[1] - at[1]) - dir[1] * (p[0] - at[0]))
}

fn start_dir(r: &Road) -> [f64; 2] {
    let g = &r.geometry;
    [g[1][0] - g[0][0], g[1][1] - g[0][1]]
}

fn end_dir(r: &Road) -> [f64; 2] {
    let g = &r.geometry;
    let n = g.len();
    [g[n - 1][0] - g[n - 2][0], g[n - 1][1] - g[n - 2][1]]
}

/// The lane links at junction `j` for the connected road `pairs`, by the rules of the module's doc.
fn derive_links(c: &Corridor, j: JunctionId, pairs: &BTreeSet<(RoadId, RoadId)>) -> Vec<Link> {
    let g = &c.graph;
    let ins: BTreeSet<RoadId> = pairs.iter().map(|p| p.0).collect();
    let outs: BTreeSet<RoadId> = pairs.iter().map(|p| p.1).collect();
    let ins: Vec<RoadId> = ins.into_iter().collect();
    let outs: Vec<RoadId> = outs.into_iter().collect();
    let pos = g.junction(j).map_or([0.0, 0.0], |j| j.pos);
    let on_main = |r: RoadId| c.main.contains(&r);
    match (ins.as_slice(), outs.as_slice()) {
        ([a], [b]) => one_to_one(g, *a, *b),
        ([x, y], [out]) => {
            let out_road = g.road(*out).unwrap();
            let side = |r: RoadId| {
                let geom = &g.road(r).unwrap().geometry;
                right_of(start_dir(out_road), pos, geom[geom.len() - 2])
            };
            // The right one first; on a tie the merging road is taken to come from the right.
            let (right, left) = match side(*x).total_cmp(&side(*y)) {
                std::cmp::Ordering::Greater => (*x, *y),
                std::cmp::Ordering::Less => (*y, *x),
                std::cmp::Ordering::Equal if on_main(*x) => (*y, *x),
                std::cmp::Ordering::Equal => (*x, *y),
            };
            let main = if on_main(left) || !on_main(right) {
                left
            } else {
                right
            };
            merge(g, right, left, main, *out)
        }
        ([inn], [x, y]) => {
            let in_road = g.road(*inn).unwrap();
            let side = |r: RoadId| {
                let geom = &g.road(r).unwrap().geometry;
                right_of(end_dir(in_road), pos, geom[1])
            };
            let (right, left) = match side(*x).total_cmp(&side(*y)) {
                std::cmp::Ordering::Less => (*y, *x),
                _ => (*x, *y),
            };
            let main = if on_main(left) || !on_main(right) {
                left
            } else {
                right
            };
            diverge(g, *inn, right, left, main)
        }
        _ => pairs
            .iter()
            .flat_map(|&(a, b)| {
                let o = lanes(g, b);
                (0..lanes(g, a)).map(move |i| (a, i, b, i.min(o - 1)))
            })
            .collect(),
    }
}

/// One road in, one out: lined up on the left; lost lanes end on the right; gained lanes are added on the left,
/// or on the right as many as the road out loses again at its end (an exit lane).
fn one_to_one(g: &LaneGraph, a: RoadId, b: RoadId) -> Vec<Link> {
    let (i, o) = (lanes(g, a), lanes(g, b));
    if i >= o {
        let d = i - o;
        return (0..o).map(|k| (a, k + d, b, k)).collect();
    }
    let added = o - i;
    let lost_after = g
        .road(b)
        .and_then(|r| g.junction(r.to))
        .filter(|j| j.incoming.len() == 1 && j.outgoing.len() == 1)
        .map_or(0, |j| o.saturating_sub(lanes(g, j.outgoing[0])));
    let added_right = added.min(lost_after);
    let mut links: Vec<Link> = (0..i).map(|k| (a, k, b, k + added_right)).collect();
    links.extend((0..added_right).map(|k| (a, 0, b, k)));
    links.extend((i + added_right..o).map(|k| (a, i - 1, b, k)));
    links
}

/// Two roads in (`right` and `left` of each other), one out; `main` is the one of the two on the main road.
fn merge(g: &LaneGraph, right: RoadId, left: RoadId, main: RoadId, out: RoadId) -> Vec<Link> {
    let (r, l, o) = (lanes(g, right), lanes(g, left), lanes(g, out));
    if r as usize + l as usize == o as usize {
        let mut links: Vec<Link> = (0..r).map(|k| (right, k, out, k)).collect();
        links.extend((0..l).map(|k| (left, k, out, r + k)));
        return links;
    }
    let merging = if main == left { right } else { left };
    let (t, m) = (lanes(g, main) as i32, lanes(g, merging) as i32);
    let o = o as i32;
    let free = (o - t).max(0);
    let mut links = Vec::new();
    if main == left {
        // the main road's lanes line up on the left; its rightmost end if the road out is narrower
        for k in 0..t {
            let to = k + o - t;
            if to >= 0 {
                links.push((main, k as u8, out, to as u8));
            }
        }
        for k in 0..m {
            let to = if free == 0 { 0 } else { k.min(free - 1) };
            links.push((merging, k as u8, out, to as u8));
        }
    } else {
        // a merging road from the left: the mirror image
        for k in 0..t.min(o) {
            links.push((main, k as u8, out, k as u8));
        }
        for k in 0..m {
            let from_left = m - 1 - k;
            let to = if free == 0 {
                o - 1
            } else {
                o - 1 - from_left.min(free - 1)
            };
            links.push((merging, k as u8, out, to as u8));
        }
    }
    links
}

/// One road in, two out (`right` and `left` of each other); `main` is the one on the main road.
fn diverge(g: &LaneGraph, inn: RoadId, right: RoadId, left: RoadId, main: RoadId) -> Vec<Link> {
    let (i, r, l) = (
        lanes(g, inn) as i32,
        lanes(g, right) as i32,
        lanes(g, left) as i32,
    );
    let surplus = r + l - i;
    let mut links: Vec<Link> = Vec::new();
    if surplus == 0 || surplus == 1 {
        links.extend((0..r).map(|k| (inn, k as u8, right, k as u8)));
        links.extend((0..l).map(|k| (inn, (r - surplus + k) as u8, left, k as u8)));
        return links;
    }
    let exit = if main == left { right } else { left };
    links.extend(one_to_one(g, inn, main));
    let e = lanes(g, exit) as i32;
    for k in 0..e {
        let from = if exit == right {
            k.min(i - 1)
        } else {
            (i - e + k).max(0)
        };
        links.push((inn, from as u8, exit, k as u8));
    }
    links
}

/// Mark every lane that stops where its road goes on; returns (acceleration lane ends, lane drops).
fn record_lane_ends(c: &mut Corridor) -> (usize, usize) {
    let onward: HashSet<(RoadId, u8)> = c
        .graph
        .connections
        .iter()
        .map(|k| (k.from_road, k.from_lane))
        .collect();
    let mut ends: Vec<(RoadId, u8, LaneEnd)> = Vec::new();
    for r in &c.graph.roads {
        let continues = c
            .graph
            .junction(r.to)
            .is_some_and(|j| !j.outgoing.is_empty());
        for l in &r.lanes {
            if continues && !onward.contains(&(r.id, l.index)) {
                ends.push((r.id, l.index, end_kind(c, r.id, l.index)));
            }
        }
    }
    for r in &mut c.graph.roads {
        for l in &mut r.lanes {
            l.end = None;
        }
    }
    let mut counts = (0, 0);
    for (road, lane, kind) in ends {
        let r = c.graph.road_mut(road).unwrap();
        r.lanes[lane as usize].end = Some(kind);
        mark(&mut r.provenance, NAME);
        match kind {
            LaneEnd::Acceleration => counts.0 += 1,
            LaneEnd::Drop => counts.1 += 1,
        }
    }
    counts
}

/// An acceleration lane's end when the lane, followed upstream along the main road, began as a merging road's
/// lane (fed by it alone); any other lane that stops is a drop.
fn end_kind(c: &Corridor, road: RoadId, lane: u8) -> LaneEnd {
    let feeders: HashSet<RoadId> = c.feeders.iter().flatten().copied().collect();
    if !c.main.contains(&road) {
        return LaneEnd::Drop;
    }
    let mut at = (road, lane);
    for _ in 0..=c.main.len() {
        let feeding: Vec<&Connection> = c
            .graph
            .connections
            .iter()
            .filter(|k| k.to_road == at.0 && k.to_lane == at.1)
            .collect();
        if feeding.is_empty() {
            return LaneEnd::Drop;
        }
        if feeding.iter().all(|k| feeders.contains(&k.from_road)) {
            return LaneEnd::Acceleration;
        }
        // fed by the main road: a main-road lane unless it is the plain continuation of one lane
        match feeding.as_slice() {
            [k] if c.main.contains(&k.from_road) => at = (k.from_road, k.from_lane),
            _ => return LaneEnd::Drop,
        }
    }
    LaneEnd::Drop
}
