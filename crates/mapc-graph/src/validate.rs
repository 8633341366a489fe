//! Structural invariants every graph must satisfy, checked after import and after every transformation step.

use crate::model::{JunctionKind, LaneGraph};
use std::collections::HashSet;

impl LaneGraph {
    /// Every broken invariant, as one message each; empty when the graph is sound.
    pub fn invariant_violations(&self) -> Vec<String> {
        let mut out = Vec::new();
        if !self.junctions.windows(2).all(|w| w[0].id < w[1].id) {
            out.push("junctions are not sorted by id, or an id repeats".to_string());
        }
        if !self.roads.windows(2).all(|w| w[0].id < w[1].id) {
            out.push("roads are not sorted by id, or an id repeats".to_string());
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
            if !(r.length_m.is_finite() && r.length_m > 0.0) {
                out.push(format!("road {} has length {}", r.id, r.length_m));
            }
            if r.geometry.len() < 2 {
                out.push(format!("road {} has fewer than two shape points", r.id));
            }
        }
        let road_ids: HashSet<_> = self.roads.iter().map(|r| r.id).collect();
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
