//! `window`: cut the piece of a corridor around a merge whose lengths equal a source scenario's (upstream main
//! road, merging road, downstream), and make a scenario of the whole corridor with that piece as the controlled
//! region and the source's demand; or several such pieces along one corridor, each its own controlled region
//! (one window is cut and written as a list of one).
//!
//! A window boundary falls exactly at the asked distance from the merge: the road there is cut in two
//! ([`crate::transform::cut_road`]) unless an existing junction lies within [`SNAP_M`] of the point.
//!
//! - [`cut`]: where the boundaries fall, the overlap rules, the roads of each region;
//! - [`fit`]: how much of each length a window needs, and cutting shorter where the map has less (`--fit`);
//! - [`scenario`]: the scenario written around the cut corridor (flows on its entries, the control regions).

pub mod cut;
pub mod fit;
pub mod scenario;
#[cfg(test)]
mod tests;

pub use cut::{CutRegion, Overlap, WindowRequest, WindowsCut, cut_windows};
pub use fit::{Fit, FittedLength, Lengths, Part};
pub use scenario::{DemandOverride, junction_name, windows_scenario};

use crate::ResolvedScenario;
use crate::transform::{CorridorRoles, TransformError};
use mapc_graph::{JunctionId, JunctionKind, LaneGraph, RoadId};
use serde::Serialize;

/// A window boundary this close to an existing junction uses that junction instead of a cut.
pub const SNAP_M: f64 = 0.5;

/// The lengths and entry roads of a source scenario's merge.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct SourceShape {
    pub junction: JunctionId,
    pub upstream_m: f64,
    pub merge_m: f64,
    pub downstream_m: f64,
    /// The main road before the merge, in driving order (its first road is where main-road flows enter).
    pub main_roads: Vec<RoadId>,
    /// The merging road, in driving order.
    pub merge_roads: Vec<RoadId>,
}

/// Roads upstream of `road` (included) while each start junction only joins two roads.
fn chain_back(g: &LaneGraph, road: RoadId) -> Vec<RoadId> {
    let mut chain = vec![road];
    loop {
        let j = g.junction(g.road(chain[0]).unwrap().from).unwrap();
        if j.incoming.len() != 1 || j.outgoing.len() != 1 || chain.contains(&j.incoming[0]) {
            return chain;
        }
        chain.insert(0, j.incoming[0]);
    }
}

fn chain_forward(g: &LaneGraph, road: RoadId) -> Vec<RoadId> {
    let mut chain = vec![road];
    loop {
        let j = g
            .junction(g.road(*chain.last().unwrap()).unwrap().to)
            .unwrap();
        if j.incoming.len() != 1 || j.outgoing.len() != 1 || chain.contains(&j.outgoing[0]) {
            return chain;
        }
        chain.push(j.outgoing[0]);
    }
}

fn sum(g: &LaneGraph, roads: &[RoadId]) -> f64 {
    roads.iter().map(|r| g.road(*r).unwrap().length_m).sum()
}

impl SourceShape {
    /// The merge of a source scenario: its only merge junction; the main road is the longer of the two roads in
    /// (the one that is not the ramp), the merging road the other.
    pub fn of(source: &ResolvedScenario) -> Result<SourceShape, TransformError> {
        let g = &source.graph;
        let merges: Vec<_> = g
            .junctions
            .iter()
            .filter(|j| j.kind == JunctionKind::Merge)
            .collect();
        if merges.len() != 1 {
            return Err(TransformError::NotACorridor(format!(
                "{}: a window matches a scenario with one merge, this one has {}",
                source.origin,
                merges.len()
            )));
        }
        let j = merges[0];
        let mut ins: Vec<Vec<RoadId>> = j.incoming.iter().map(|r| chain_back(g, *r)).collect();
        ins.sort_by(|a, b| sum(g, b).total_cmp(&sum(g, a)).then(a.cmp(b)));
        let down = chain_forward(g, j.outgoing[0]);
        Ok(SourceShape {
            junction: j.id,
            upstream_m: sum(g, &ins[0]),
            merge_m: sum(g, &ins[1]),
            downstream_m: sum(g, &down),
            main_roads: ins[0].clone(),
            merge_roads: ins[1].clone(),
        })
    }
}

/// Where along a chain of roads (driving order) a distance measured from one end falls.
enum Boundary {
    /// At the start of road `chain[k]` (an existing junction).
    AtStartOf(usize),
    /// At the end of road `chain[k]`.
    AtEndOf(usize),
    /// Inside road `chain[k]`, this far from its start.
    Inside(usize, f64),
}

/// The point `distance` upstream of the chain's end.
fn boundary_upstream(g: &LaneGraph, chain: &[RoadId], distance: f64) -> Option<Boundary> {
    let mut acc = 0.0;
    for k in (0..chain.len()).rev() {
        let len = g.road(chain[k]).unwrap().length_m;
        if (acc - distance).abs() <= SNAP_M {
            return Some(Boundary::AtEndOf(k));
        }
        if acc + len + SNAP_M >= distance {
            let offset = acc + len - distance;
            return Some(if offset <= SNAP_M {
                Boundary::AtStartOf(k)
            } else {
                Boundary::Inside(k, offset)
            });
        }
        acc += len;
    }
    None
}

/// The point `distance` downstream of the chain's start.
fn boundary_downstream(g: &LaneGraph, chain: &[RoadId], distance: f64) -> Option<Boundary> {
    let mut acc = 0.0;
    for (k, rid) in chain.iter().enumerate() {
        let len = g.road(*rid).unwrap().length_m;
        if (acc - distance).abs() <= SNAP_M {
            return Some(Boundary::AtStartOf(k));
        }
        if acc + len + SNAP_M >= distance {
            let offset = distance - acc;
            return Some(if len - offset <= SNAP_M {
                Boundary::AtEndOf(k)
            } else {
                Boundary::Inside(k, offset)
            });
        }
        acc += len;
    }
    None
}

/// The merges of a corridor, for error messages.
fn merge_list(g: &LaneGraph, roles: &CorridorRoles) -> String {
    let list: Vec<String> = crate::simplify::corridor_merges(g, roles)
        .iter()
        .map(|m| match m.osm_node {
            Some(n) => format!("{} (osm:{n})", m.junction),
            None => m
                .sumo_id
                .as_ref()
                .map_or(m.junction.clone(), |s| format!("{} ({s})", m.junction)),
        })
        .collect();
    if list.is_empty() {
        "none".into()
    } else {
        list.join(", ")
    }
}
