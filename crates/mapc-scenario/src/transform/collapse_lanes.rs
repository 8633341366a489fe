//! `collapse_lanes`: every road keeps one lane (its rightmost, with that lane's speed and width), and the
//! connections between two roads become one, from lane 0 to lane 0 (the first of them, so its internal length and
//! right of way are the input's).

use super::{Corridor, SimplifyOptions, TransformError, mark, sort_connections};
use std::collections::HashSet;

pub const NAME: &str = "collapse_lanes";

pub fn apply(c: &mut Corridor, _opts: &SimplifyOptions) -> Result<String, TransformError> {
    let mut collapsed = 0;
    let mut most = 1;
    for r in &mut c.graph.roads {
        most = most.max(r.lanes.len());
        if r.lanes.len() > 1 {
            collapsed += 1;
            r.lanes.truncate(1);
            mark(&mut r.provenance, NAME);
        }
        r.lanes[0].index = 0;
        // A road's driving length is its rightmost lane's.
        r.lanes[0].length_m = r.length_m;
        // (the lane drawn by the input is no longer the road's)
        r.lanes[0].shape.clear();
    }
    sort_connections(&mut c.graph);
    let before = c.graph.connections.len();
    let mut seen = HashSet::new();
    c.graph
        .connections
        .retain(|k| seen.insert((k.junction, k.from_road, k.to_road)));
    for k in &mut c.graph.connections {
        k.from_lane = 0;
        k.to_lane = 0;
    }
    c.single_lane = true;
    Ok(format!(
        "{collapsed} roads of up to {most} lanes reduced to one lane; {before} lane connections became {}",
        c.graph.connections.len()
    ))
}
