//! Finding junctions and roads by what a user types: mapc ids (`J12`, `R34`), OSM ids (`osm:NODE`,
//! `osm-way:WAY`) or SUMO ids (`gneJ18`, `inflow_highway`).

use crate::ids::{JunctionId, RoadId};
use crate::model::{Junction, LaneGraph, Road};

#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum LookupError {
    #[error("no junction `{0}` in this graph (try `mapc junctions`)")]
    NoJunction(String),
    #[error("no road `{0}` in this graph")]
    NoRoad(String),
    /// The junction was one in an earlier stage, and a transformation joined it into a road here.
    #[error(
        "`{query}` is no longer a junction here: `join_chains` made it part of road {road} (it only joined one road to the next)"
    )]
    JoinedInto { query: String, road: String },
    #[error("`{query}` names {count} junctions ({examples}); use a mapc id")]
    AmbiguousJunction {
        query: String,
        count: usize,
        examples: String,
    },
}

impl LaneGraph {
    pub fn junction(&self, id: JunctionId) -> Option<&Junction> {
        self.junctions
            .binary_search_by_key(&id, |j| j.id)
            .ok()
            .map(|i| &self.junctions[i])
    }
    pub fn junction_mut(&mut self, id: JunctionId) -> Option<&mut Junction> {
        self.junctions
            .binary_search_by_key(&id, |j| j.id)
            .ok()
            .map(|i| &mut self.junctions[i])
    }
    pub fn road(&self, id: RoadId) -> Option<&Road> {
        self.roads
            .binary_search_by_key(&id, |r| r.id)
            .ok()
            .map(|i| &self.roads[i])
    }
    pub fn road_mut(&mut self, id: RoadId) -> Option<&mut Road> {
        self.roads
            .binary_search_by_key(&id, |r| r.id)
            .ok()
            .map(|i| &mut self.roads[i])
    }

    /// `J12`, `osm:61862553` or a SUMO junction id.
    pub fn find_junction(&self, query: &str) -> Result<JunctionId, LookupError> {
        if let Ok(id) = query.parse::<JunctionId>()
            && self.junction(id).is_some()
        {
            return Ok(id);
        }
        let matches: Vec<JunctionId> = if let Some(node) = query.strip_prefix("osm:") {
            let node: i64 = node
                .parse()
                .map_err(|_| LookupError::NoJunction(query.to_string()))?;
            self.junctions
                .iter()
                .filter(|j| j.provenance.osm_nodes.contains(&node))
                .map(|j| j.id)
                .collect()
        } else {
            self.junctions
                .iter()
                .filter(|j| j.provenance.sumo_ids.iter().any(|s| s == query))
                .map(|j| j.id)
                .collect()
        };
        match matches.as_slice() {
            [] => Err(self.joined_junction(query)),
            [one] => Ok(*one),
            many => Err(LookupError::AmbiguousJunction {
                query: query.to_string(),
                count: many.len(),
                examples: many
                    .iter()
                    .take(4)
                    .map(|j| j.to_string())
                    .collect::<Vec<_>>()
                    .join(", "),
            }),
        }
    }

    /// All roads a user's text names: `R34`, `osm-way:124433709` (every piece of the way, in driving order) or a
    /// SUMO edge id.
    pub fn find_roads(&self, query: &str) -> Result<Vec<RoadId>, LookupError> {
        if let Ok(id) = query.parse::<RoadId>()
            && self.road(id).is_some()
        {
            return Ok(vec![id]);
        }
        let found: Vec<&Road> = if let Some(way) = query.strip_prefix("osm-way:") {
            let way: i64 = way
                .parse()
                .map_err(|_| LookupError::NoRoad(query.to_string()))?;
            self.roads
                .iter()
                .filter(|r| r.provenance.osm_ways.contains(&way))
                .collect()
        } else {
            self.roads
                .iter()
                .filter(|r| r.provenance.sumo_ids.iter().any(|s| s == query))
                .collect()
        };
        if found.is_empty() {
            // A road an earlier stage knew under this mapc id, joined onto another since.
            let joined: Vec<&Road> = self
                .roads
                .iter()
                .filter(|r| r.provenance.joined.iter().any(|id| id == query))
                .collect();
            if joined.is_empty() {
                return Err(LookupError::NoRoad(query.to_string()));
            }
            return Ok(order_along_travel(&joined));
        }
        Ok(order_along_travel(&found))
    }

    /// Why `query` names no junction: a road that absorbed it (its mapc id, OSM node or SUMO id), or plainly none.
    fn joined_junction(&self, query: &str) -> LookupError {
        let node = query
            .strip_prefix("osm:")
            .and_then(|n| n.parse::<i64>().ok());
        let absorbed = |r: &&Road| {
            let p = &r.provenance;
            if p.joined.iter().any(|id| id == query) {
                return true;
            }
            // a joined road keeps the joint's provenance; only then is an interior OSM node or SUMO id a joint
            !p.joined.is_empty()
                && (node.is_some_and(|n| {
                    p.osm_nodes.contains(&n)
                        && !self
                            .junctions
                            .iter()
                            .any(|j| j.provenance.osm_nodes.contains(&n))
                }) || p.sumo_ids.iter().any(|s| s == query))
        };
        match self.roads.iter().find(absorbed) {
            Some(r) => LookupError::JoinedInto {
                query: query.to_string(),
                road: r.id.to_string(),
            },
            None => LookupError::NoJunction(query.to_string()),
        }
    }
}

/// Order pieces so that each one's end is the next one's start where possible (the pieces of a split way).
fn order_along_travel(roads: &[&Road]) -> Vec<RoadId> {
    let mut remaining: Vec<&Road> = roads.to_vec();
    remaining.sort_by_key(|r| r.id);
    let mut out = Vec::with_capacity(remaining.len());
    while !remaining.is_empty() {
        // Start a chain at a piece no other remaining piece leads into.
        let start = remaining
            .iter()
            .position(|r| !remaining.iter().any(|o| o.to == r.from))
            .unwrap_or(0);
        let mut cur = remaining.remove(start);
        out.push(cur.id);
        while let Some(next) = remaining.iter().position(|o| o.from == cur.to) {
            cur = remaining.remove(next);
            out.push(cur.id);
        }
    }
    out
}
