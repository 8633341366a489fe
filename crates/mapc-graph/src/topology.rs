//! Topology with petgraph: junctions are nodes, roads are directed edges weighted by length.

use crate::ids::{JunctionId, RoadId};
use crate::model::{JunctionKind, LaneGraph};
use petgraph::algo::dijkstra;
use petgraph::graph::{DiGraph, NodeIndex};
use std::collections::HashMap;

/// A petgraph view of a lane graph, built once and queried many times.
pub struct Topology {
    pub graph: DiGraph<JunctionId, RoadId>,
    pub node_of: HashMap<JunctionId, NodeIndex>,
}

impl Topology {
    pub fn new(g: &LaneGraph) -> Topology {
        let mut graph = DiGraph::with_capacity(g.junctions.len(), g.roads.len());
        let node_of: HashMap<JunctionId, NodeIndex> = g
            .junctions
            .iter()
            .map(|j| (j.id, graph.add_node(j.id)))
            .collect();
        for r in &g.roads {
            if let (Some(&a), Some(&b)) = (node_of.get(&r.from), node_of.get(&r.to)) {
                graph.add_edge(a, b, r.id);
            }
        }
        Topology { graph, node_of }
    }

    /// Number of weakly connected pieces.
    pub fn component_count(&self) -> usize {
        petgraph::algo::connected_components(&self.graph)
    }
}

/// Roads as nodes and the connections between them as edges, for routing (built once, queried per trip).
pub struct RoadRoutes {
    graph: DiGraph<RoadId, ()>,
    node_of: HashMap<RoadId, NodeIndex>,
}

impl RoadRoutes {
    pub fn new(g: &LaneGraph) -> RoadRoutes {
        let mut graph = DiGraph::with_capacity(g.roads.len(), g.connections.len());
        let node_of: HashMap<RoadId, NodeIndex> = g
            .roads
            .iter()
            .map(|r| (r.id, graph.add_node(r.id)))
            .collect();
        let mut pairs: Vec<(RoadId, RoadId)> = g
            .connections
            .iter()
            .map(|c| (c.from_road, c.to_road))
            .collect();
        pairs.sort();
        pairs.dedup();
        for (a, b) in pairs {
            if let (Some(&na), Some(&nb)) = (node_of.get(&a), node_of.get(&b)) {
                graph.add_edge(na, nb, ());
            }
        }
        RoadRoutes { graph, node_of }
    }

    /// The fastest route of `g` (the graph these routes were built from) from road `from` to road `to`, as roads
    /// in driving order, both ends included: each road costs its length over its speed limit, capped at
    /// `max_speed` (SUMO's routing of a trip at its departure on an empty network).
    pub fn fastest(
        &self,
        g: &LaneGraph,
        from: RoadId,
        to: RoadId,
        max_speed: f64,
    ) -> Option<Vec<RoadId>> {
        if from == to {
            return Some(vec![from]);
        }
        let cost = |rid: RoadId| {
            g.road(rid).map_or(f64::INFINITY, |r| {
                r.length_m / r.speed_mps().min(max_speed).max(0.1)
            })
        };
        let (&start, &goal) = (self.node_of.get(&from)?, self.node_of.get(&to)?);
        let (_cost, path) = petgraph::algo::astar(
            &self.graph,
            start,
            |n| n == goal,
            |e| cost(self.graph[petgraph::visit::EdgeRef::target(&e)]),
            |_| 0.0,
        )?;
        Some(path.into_iter().map(|n| self.graph[n]).collect())
    }
}

impl LaneGraph {
    /// The shortest route by length from junction `from` to junction `to`, as roads in driving order.
    pub fn shortest_route(&self, from: JunctionId, to: JunctionId) -> Option<Vec<RoadId>> {
        let topo = Topology::new(self);
        let (&start, &goal) = (topo.node_of.get(&from)?, topo.node_of.get(&to)?);
        let length_of = |rid: RoadId| self.road(rid).map_or(f64::INFINITY, |r| r.length_m);
        let (_cost, path) = petgraph::algo::astar(
            &topo.graph,
            start,
            |n| n == goal,
            |e| length_of(*e.weight()),
            |_| 0.0,
        )?;
        // astar gives nodes; pick the shortest road between each consecutive pair (parallel roads exist).
        let mut roads = Vec::with_capacity(path.len().saturating_sub(1));
        for w in path.windows(2) {
            let best = topo
                .graph
                .edges_connecting(w[0], w[1])
                .map(|e| *e.weight())
                .min_by(|a, b| length_of(*a).total_cmp(&length_of(*b)).then(a.cmp(b)))?;
            roads.push(best);
        }
        Some(roads)
    }

    /// Road-length distance from `from` to every junction reachable from it.
    pub fn distances_from(&self, from: JunctionId) -> HashMap<JunctionId, f64> {
        let topo = Topology::new(self);
        let Some(&start) = topo.node_of.get(&from) else {
            return HashMap::new();
        };
        let length_of = |rid: RoadId| self.road(rid).map_or(f64::INFINITY, |r| r.length_m);
        dijkstra(&topo.graph, start, None, |e| length_of(*e.weight()))
            .into_iter()
            .map(|(n, d)| (topo.graph[n], d))
            .collect()
    }

    /// Recompute every junction's road lists and kind from the roads (after roads were added, removed or cut).
    pub fn rebuild_junction_links(&mut self) {
        // a light no connection is controlled by any more (cut away with its roads) is dropped with them
        let used: std::collections::HashSet<&str> = self
            .connections
            .iter()
            .filter_map(|c| c.signal.as_ref().map(|s| s.light.as_str()))
            .collect();
        let lights = std::mem::take(&mut self.lights);
        self.lights = lights
            .into_iter()
            .filter(|l| used.contains(l.id.as_str()))
            .collect();
        let mut incoming: HashMap<JunctionId, Vec<RoadId>> = HashMap::new();
        let mut outgoing: HashMap<JunctionId, Vec<RoadId>> = HashMap::new();
        for r in &self.roads {
            incoming.entry(r.to).or_default().push(r.id);
            outgoing.entry(r.from).or_default().push(r.id);
        }
        for j in &mut self.junctions {
            j.incoming = incoming.remove(&j.id).unwrap_or_default();
            j.outgoing = outgoing.remove(&j.id).unwrap_or_default();
            j.incoming.sort();
            j.outgoing.sort();
            j.kind = JunctionKind::classify(j.incoming.len(), j.outgoing.len());
        }
    }

    pub fn next_junction_id(&self) -> JunctionId {
        JunctionId(self.junctions.last().map_or(0, |j| j.id.0 + 1))
    }
    pub fn next_road_id(&self) -> RoadId {
        RoadId(self.roads.last().map_or(0, |r| r.id.0 + 1))
    }
}
