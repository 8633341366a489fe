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

    /// Total driving length: every road's length times its lanes, plus every connection's internal length.
    pub fn total_lane_length_m(&self) -> f64 {
        self.roads
            .iter()
            .map(|r| r.length_m * r.lanes.len() as f64)
            .sum::<f64>()
            + self.connections.iter().map(|c| c.via_length_m).sum::<f64>()
    }
}
