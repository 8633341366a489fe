//! SUMO ids for mapc's roads and junctions: the SUMO id the element came from when it has exactly one and no other
//! element claims it (so a SUMO net keeps its ids through a round trip), else mapc's own id (`R12`, `J3`).

use mapc_graph::{LaneGraph, Provenance};
use std::collections::{HashMap, HashSet};

/// Edge id per road and junction id per junction, in the graph's order.
pub struct SumoNames {
    pub edges: Vec<String>,
    pub junctions: Vec<String>,
}

impl SumoNames {
    pub fn of(graph: &LaneGraph) -> SumoNames {
        let edges = pick(
            graph
                .roads
                .iter()
                .map(|r| (r.id.to_string(), &r.provenance)),
        );
        let junctions = pick(
            graph
                .junctions
                .iter()
                .map(|j| (j.id.to_string(), &j.provenance)),
        );
        SumoNames { edges, junctions }
    }
}

/// A SUMO id usable as an edge or junction id: not an internal one (`:`), nothing an attribute list would split.
fn usable(id: &str) -> bool {
    !id.is_empty() && !id.starts_with(':') && !id.chars().any(|c| c.is_whitespace() || c == '"')
}

fn pick<'a>(items: impl Iterator<Item = (String, &'a Provenance)>) -> Vec<String> {
    let items: Vec<(String, &Provenance)> = items.collect();
    let wanted: Vec<Option<&str>> = items
        .iter()
        .map(|(_, p)| match p.sumo_ids.as_slice() {
            [one] if usable(one) => Some(one.as_str()),
            _ => None,
        })
        .collect();
    let mut claims: HashMap<&str, usize> = HashMap::new();
    for w in wanted.iter().flatten() {
        *claims.entry(w).or_default() += 1;
    }
    let own: HashSet<&str> = items.iter().map(|(id, _)| id.as_str()).collect();
    items
        .iter()
        .zip(&wanted)
        .map(|((own_id, _), w)| match w {
            // A SUMO id that is also another element's mapc id (a SUMO edge called `R3`) could collide.
            Some(w) if claims[w] == 1 && (!own.contains(w) || *w == own_id) => w.to_string(),
            _ => own_id.clone(),
        })
        .collect()
}

/// The index in `graph.roads` of road `id` (roads are sorted by id; the ids come from the graph itself).
pub(crate) fn road_index(graph: &LaneGraph, id: mapc_graph::RoadId) -> usize {
    graph
        .roads
        .binary_search_by_key(&id, |r| r.id)
        .expect("a connection names a road of its graph")
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sumo_ids_are_kept_unless_shared() {
        let p = |ids: &[&str]| Provenance {
            sumo_ids: ids.iter().map(|s| s.to_string()).collect(),
            ..Default::default()
        };
        let (a, b, c, d, e) = (p(&["left"]), p(&["x"]), p(&["x"]), p(&[]), p(&["m", "n"]));
        let names = pick(
            [("R0", &a), ("R1", &b), ("R2", &c), ("R3", &d), ("R4", &e)]
                .into_iter()
                .map(|(id, p)| (id.to_string(), p)),
        );
        assert_eq!(names, ["left", "R1", "R2", "R3", "R4"]);
    }
}
