//! OSM data, whatever file it came from, into a lane graph: tag interpretation (oneway, lanes, maxspeed), splitting
//! ways at shared nodes, projection, lengths, connections and right of way. The XML and PBF readers only collect
//! [`OsmWay`]s and node coordinates, so both formats give the identical graph.

mod data;
mod graph;
mod tags;
#[cfg(test)]
mod tests;

pub use data::{NodePos, OsmData, OsmWay, keeps, needed_nodes, parse_degrees};
pub use graph::build_graph;
pub use tags::{
    LONG_SEGMENT_M, MAX_PLAUSIBLE_SPEED_MPS, OSM_LANE_WIDTH_M, WayTags, class_defaults,
    parse_maxspeed,
};
