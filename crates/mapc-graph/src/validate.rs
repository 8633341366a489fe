//! Structural invariants every graph must satisfy, checked after import and after every transformation step.

use crate::model::{JunctionKind, LaneGraph};
use std::collections::HashSet;

/// The speed limit a lane of a real road has, in m/s: a vanishing one would make a vehicle take ages to pass, and
/// nothing on wheels does 1000 m/s. The importers refuse a map outside it; a graph file is checked on loading.
pub const LANE_SPEED_MPS: [f64; 2] = [0.1, 1000.0];
/// A lane's width, in metres.
pub const LANE_WIDTH_M: [f64; 2] = [0.1, 100.0];
/// The longest road, lane or way through a junction, in metres (1000 km): beyond it a length is a mistake in the
/// data, and times and step counts derived from it leave any sane range.
pub const MAX_LENGTH_M: f64 = 1e6;

/// `value` (named `what`) within `[lo, hi]` of `unit`, or why not.
pub fn outside(what: &str, value: f64, [lo, hi]: [f64; 2], unit: &str) -> Option<String> {
    (!(value.is_finite() && value >= lo && value <= hi)).then(|| {
        format!(
            "{what} {} is outside [{}, {}] {unit}",
            crate::terminal::number(value),
            crate::terminal::number(lo),
            crate::terminal::number(hi)
        )
    })
}

/// Why a sorted list of ids is not strictly increasing: the first id that repeats or comes out of order.
fn id_order_problem<T: Ord + Copy + std::fmt::Display>(ids: &[T], what: &str) -> Option<String> {
    ids.windows(2).find(|w| w[0] >= w[1]).map(|w| {
        if w[0] == w[1] {
            format!("{what} {} appears twice (ids are unique)", w[1])
        } else {
            format!(
                "{what} {} comes after {} ({what}s are sorted by id)",
                w[1], w[0]
            )
        }
    })
}

impl LaneGraph {
    /// Every broken invariant, as one message each, naming the element first (`road R3 ...`, `junction J2 ...`);
    /// empty when the graph is sound. Ids out of order or repeated come first: with them, lookups by id fail.
    pub fn invariant_violations(&self) -> Vec<String> {
        let mut out = Vec::new();
        let junction_ids: Vec<_> = self.junctions.iter().map(|j| j.id).collect();
        out.extend(id_order_problem(&junction_ids, "junction"));
        let road_ids: Vec<_> = self.roads.iter().map(|r| r.id).collect();
        out.extend(id_order_problem(&road_ids, "road"));
        for j in &self.junctions {
            if !j.pos.iter().all(|x| x.is_finite()) {
                out.push(format!(
                    "junction {} has a position that is not a number",
                    j.id
                ));
            }
        }
        for r in &self.roads {
            for end in [r.from, r.to] {
                match self.junction(end) {
                    None => out.push(format!("road {} names missing junction {end}", r.id)),
                    Some(j) => {
                        let listed = if end == r.from {
                            j.outgoing.contains(&r.id)
                        } else {
                            j.incoming.contains(&r.id)
                        };
                        if !listed {
                            out.push(format!("junction {end} does not list its road {}", r.id));
                        }
                    }
                }
            }
            if r.lanes.is_empty() {
                out.push(format!("road {} has no lanes", r.id));
            }
            if let Some(why) = lane_numbering_problem(&r.lanes) {
                out.push(format!("road {} {why}", r.id));
            }
            if !(r.length_m.is_finite() && r.length_m > 0.0 && r.length_m <= MAX_LENGTH_M) {
                out.push(format!(
                    "road {} has length_m {}, outside (0, {}] m",
                    r.id,
                    crate::terminal::number(r.length_m),
                    crate::terminal::number(MAX_LENGTH_M)
                ));
            }
            for l in &r.lanes {
                let lane = |what: &str| format!("lane {} {what}", l.index);
                let problems = [
                    outside(&lane("speed_mps"), l.speed_mps, LANE_SPEED_MPS, "m/s"),
                    outside(&lane("width_m"), l.width_m, LANE_WIDTH_M, "m"),
                    (l.length_m <= 0.0).then(|| format!("{} is not positive", lane("length_m"))),
                    outside(&lane("length_m"), l.length_m, [0.0, MAX_LENGTH_M], "m"),
                ];
                if let Some(why) = problems.into_iter().flatten().next() {
                    out.push(format!("road {} {why}", r.id));
                }
            }
            if r.geometry.len() < 2 {
                out.push(format!("road {} has fewer than two shape points", r.id));
            }
            if !r.geometry.iter().flatten().all(|x| x.is_finite()) {
                out.push(format!(
                    "road {} has a shape point that is not a number",
                    r.id
                ));
            }
        }
        let road_ids: HashSet<_> = road_ids.into_iter().collect();
        for j in &self.junctions {
            for rid in j.incoming.iter().chain(&j.outgoing) {
                if !road_ids.contains(rid) {
                    out.push(format!("junction {} lists missing road {rid}", j.id));
                }
            }
            let expected = JunctionKind::classify(j.incoming.len(), j.outgoing.len());
            if j.kind != expected {
                out.push(format!(
                    "junction {} is marked {:?} but has the roads of a {expected:?}",
                    j.id, j.kind
                ));
            }
        }
        for c in &self.connections {
            let (Some(from), Some(to)) = (self.road(c.from_road), self.road(c.to_road)) else {
                out.push(format!("connection at {} names a missing road", c.junction));
                continue;
            };
            if from.to != c.junction || to.from != c.junction {
                out.push(format!(
                    "connection {} -> {} is not at junction {}",
                    c.from_road, c.to_road, c.junction
                ));
            }
            if c.from_lane as usize >= from.lanes.len() || c.to_lane as usize >= to.lanes.len() {
                out.push(format!(
                    "connection {} -> {} names a missing lane",
                    c.from_road, c.to_road
                ));
            }
            let via = [
                outside("via_length_m", c.via_length_m, [0.0, MAX_LENGTH_M], "m"),
                c.via_speed_mps
                    .and_then(|v| outside("via_speed_mps", v, LANE_SPEED_MPS, "m/s")),
            ];
            if let Some(why) = via.into_iter().flatten().next() {
                out.push(format!(
                    "connection {} -> {} at {}: {why}",
                    c.from_road, c.to_road, c.junction
                ));
            }
        }
        out
    }

    /// Lanes that stop where their road goes on: every lane of a road whose end junction has a road out has a
    /// connection onward or is recorded as a lane that ends ([`crate::LaneEnd`]), and a lane recorded as ending
    /// has no connection onward. Checked on corridors kept with all their lanes (`simplify --keep-lanes`); a
    /// map as imported may have lanes its source left unconnected.
    pub fn lane_continuity_violations(&self) -> Vec<String> {
        let mut onward: HashSet<(crate::RoadId, u8)> = HashSet::new();
        for c in &self.connections {
            onward.insert((c.from_road, c.from_lane));
        }
        let mut out = Vec::new();
        for r in &self.roads {
            let continues = self.junction(r.to).is_some_and(|j| !j.outgoing.is_empty());
            for l in &r.lanes {
                let connected = onward.contains(&(r.id, l.index));
                match (continues, connected, l.end) {
                    (true, false, None) => out.push(format!(
                        "lane {} of road {} stops at {} with no connection onward and is not recorded as ending",
                        l.index, r.id, r.to
                    )),
                    (_, true, Some(end)) => out.push(format!(
                        "lane {} of road {} is recorded as ending ({end:?}) but has a connection onward",
                        l.index, r.id
                    )),
                    _ => {}
                }
            }
        }
        out
    }

    /// Total driving length: every road's length times its lanes, plus every connection's internal length.
    pub fn total_lane_length_m(&self) -> f64 {
        self.roads
            .iter()
            .map(|r| r.length_m * r.lanes.len() as f64)
            .sum::<f64>()
            + self.connections.iter().map(|c| c.via_length_m).sum::<f64>()
    }
}

/// Why a road's lanes are not numbered 0, 1, 2, ... in order (`None` when they are).
pub(crate) fn lane_numbering_problem(lanes: &[crate::Lane]) -> Option<String> {
    lanes
        .iter()
        .enumerate()
        .find(|(i, l)| l.index as usize != *i)
        .map(|(i, l)| {
            format!(
                "lists lane index {} in place {i} of its {} lanes (lanes are numbered 0, 1, 2, ... from the right \
                 without gaps)",
                l.index,
                lanes.len()
            )
        })
}
