//! What a reader collects from an OSM file: the kept ways, the positions of the nodes they use, and the warnings
//! noticed on the way.

use super::WayTags;
use mapc_graph::Warnings;
use std::collections::{HashMap, HashSet};

/// A kept highway way: its id, node ids in order and tags.
#[derive(Clone, Debug, PartialEq)]
pub struct OsmWay {
    pub id: i64,
    pub nodes: Vec<i64>,
    pub tags: WayTags,
}

/// What a reader collected: the kept ways (file order, one per id), the positions of the nodes they use, and
/// what the reader noticed on the way (duplicates, ignored turn restrictions), counted.
#[derive(Clone, Debug, Default)]
pub struct OsmData {
    pub ways: Vec<OsmWay>,
    pub nodes: HashMap<i64, NodePos>,
    pub warnings: Warnings,
    /// Kept way ids, to find a second way of the same id.
    way_index: HashMap<i64, usize>,
}

impl OsmData {
    /// Keep a way. A second way with the same id is a counted warning when it is the same way again, and an
    /// error otherwise: which one is right cannot be known, and taking either silently changes the roads.
    pub fn add_way(&mut self, way: OsmWay) -> Result<(), String> {
        if let Some(&i) = self.way_index.get(&way.id) {
            if self.ways[i] == way {
                self.warnings
                    .add("duplicate_way", format!("way {} appears twice", way.id));
                return Ok(());
            }
            return Err(format!(
                "way {} appears twice with different nodes or tags (duplicate id)",
                way.id
            ));
        }
        self.way_index.insert(way.id, self.ways.len());
        self.ways.push(way);
        Ok(())
    }

    /// Record a used node's position. The same node twice at the same place is a counted warning; at another
    /// place it is an error (a duplicate id: one of the two would silently move roads, or stretch them by
    /// hundreds of kilometres).
    pub fn add_node(&mut self, id: i64, pos: NodePos) -> Result<(), String> {
        match self.nodes.insert(id, pos) {
            None => Ok(()),
            Some(old) if old == pos => {
                self.warnings
                    .add("duplicate_node", format!("node {id} appears twice"));
                Ok(())
            }
            Some(old) => Err(format!(
                "node {id} appears twice, at {:.7},{:.7} and at {:.7},{:.7} (duplicate id)",
                old.lat(),
                old.lon(),
                pos.lat(),
                pos.lon()
            )),
        }
    }

    /// Count the turn restrictions that name a kept way: mapc's connections do not model them.
    pub fn note_restrictions(&mut self, restrictions: &[(i64, Vec<i64>)]) {
        for (id, members) in restrictions {
            if members.iter().any(|w| self.way_index.contains_key(w)) {
                self.warnings.add(
                    "turn_restriction_ignored",
                    format!("relation {id} (type=restriction) on a kept way"),
                );
            }
        }
    }
}

/// Node position in OSM's own fixed point (1e-7 degree): both file formats store exactly this, so converting from it
/// (rather than from the XML text) makes the XML and PBF graphs bit-identical.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct NodePos {
    pub lat_e7: i32,
    pub lon_e7: i32,
}

impl NodePos {
    pub fn lon(self) -> f64 {
        self.lon_e7 as f64 * 1e-7
    }
    pub fn lat(self) -> f64 {
        self.lat_e7 as f64 * 1e-7
    }
}

/// Parse a decimal degree (`-83.4877071`) to 1e-7 degree fixed point, checking its range.
pub fn parse_degrees(text: &str, limit: f64) -> Result<i32, String> {
    let v: f64 = text
        .trim()
        .parse()
        .map_err(|_| format!("`{text}` is not a number"))?;
    if !v.is_finite() || v.abs() > limit {
        return Err(format!("{text} is outside -{limit}..{limit}"));
    }
    Ok((v * 1e7).round() as i32)
}

/// The OSM node ids a set of kept ways needs.
pub fn needed_nodes(ways: &[OsmWay]) -> HashSet<i64> {
    ways.iter().flat_map(|w| w.nodes.iter().copied()).collect()
}

/// Keep a way if its `highway` class is one of `classes`.
pub fn keeps(classes: &[String], tags: &WayTags) -> bool {
    !tags.highway.is_empty() && classes.iter().any(|c| c == &tags.highway)
}
