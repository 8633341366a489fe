//! The roads a departure drives, as SUMO 1.8 reads them: a route's edges (each leading into the next), or a trip's
//! from, via and to, routed by travel time at its departure.

use super::*;

/// What a vehicle, flow or trip drives: a route's edges, or from, via and to.
pub(super) struct Path {
    pub(super) from: String,
    pub(super) via: Vec<String>,
    pub(super) to: Option<String>,
}

impl Demand<'_> {
    /// A trip's roads between its first and last, routed as SUMO 1.8 routes a trip at its departure: the fastest
    /// way at the speed limits (capped by the type's maximum speed) from each of its stops (from, each via, to) to
    /// the next.
    fn fastest_via(
        &self,
        e: &SumoElement,
        stops: &[Vec<mapc_graph::RoadId>],
        graph: &LaneGraph,
    ) -> Result<Vec<String>, SumoError> {
        let max_speed = e
            .get("type")
            .and_then(|t| self.types.get(t))
            .map_or(f64::INFINITY, |t| t.max_speed);
        let mut roads: Vec<mapc_graph::RoadId> = vec![*stops[0].last().expect("found roads")];
        for (prev, next) in stops.iter().zip(&stops[1..]) {
            if prev == next {
                // SUMO routes a stop on the edge it is already on as that edge alone (a trip from an edge to
                // itself drives it, as RESCO's Cologne trips do)
                continue;
            }
            let here = *roads.last().expect("a first road");
            let leg = self
                .routes_by_road
                .get_or_init(|| mapc_graph::topology::RoadRoutes::new(graph))
                .fastest(graph, here, next[0], max_speed)
                .ok_or_else(|| {
                    SumoError::at(
                        &e.place,
                        format!(
                            "no way from `{}` to `{}` in the network",
                            road_name(graph, here),
                            road_name(graph, next[0])
                        ),
                    )
                })?;
            roads.extend(leg.into_iter().skip(1));
            roads.extend(next.iter().skip(1));
        }
        // (a trip from an edge to itself has no roads between)
        let end = roads
            .len()
            .saturating_sub(stops.last().map_or(1, Vec::len))
            .max(1);
        let inner = &roads[1..end];
        let mut names: Vec<String> = Vec::new();
        for &r in inner {
            let name = road_name(graph, r);
            // a SUMO edge of several roads is named once
            if names.last() != Some(&name) {
                names.push(name);
            }
        }
        Ok(names)
    }

    /// The roads a departure drives: its route (by id or inside it), or a trip's from, via and to.
    pub(super) fn path(&self, e: &SumoElement, graph: &LaneGraph) -> Result<Path, SumoError> {
        let inner = e.children.iter().find(|c| c.name == "route");
        let edges: Option<(Vec<String>, &SumoElement)> = match (e.get("route"), inner) {
            (Some(r), _) => {
                let route = self.routes.get(r).ok_or_else(|| {
                    SumoError::at(&e.place, format!("route `{r}` is not defined"))
                })?;
                Some((split(route.get("edges").unwrap_or("")), route))
            }
            (None, Some(route)) => Some((
                split(
                    route
                        .get("edges")
                        .ok_or_else(|| SumoError::at(&route.place, "a route without `edges`"))?,
                ),
                route,
            )),
            (None, None) => None,
        };
        let path = match edges {
            Some((edges, route)) => {
                if edges.is_empty() {
                    return Err(SumoError::at(&route.place, "a route without edges"));
                }
                check_connected(&edges, graph, &route.place)?;
                Path {
                    from: edges[0].clone(),
                    via: edges
                        .get(1..edges.len().saturating_sub(1))
                        .unwrap_or_default()
                        .to_vec(),
                    // (a one-edge route ends on its edge: `to` is never left to mapc's "down the corridor")
                    to: Some(edges[edges.len() - 1].clone()),
                }
            }
            None => {
                let from = e.get("from").ok_or_else(|| {
                    SumoError::at(&e.place, "neither a route nor `from` and `to`")
                })?;
                let to = e
                    .get("to")
                    .ok_or_else(|| SumoError::at(&e.place, "`from` without `to`"))?;
                let via = split(e.get("via").unwrap_or(""));
                let stops: Vec<Vec<mapc_graph::RoadId>> = std::iter::once(from)
                    .chain(via.iter().map(String::as_str))
                    .chain([to])
                    .map(|edge| find(edge, graph, &e.place))
                    .collect::<Result<_, _>>()?;
                Path {
                    from: from.to_string(),
                    via: self.fastest_via(e, &stops, graph)?,
                    to: Some(to.to_string()),
                }
            }
        };
        Ok(path)
    }
}

fn split(s: &str) -> Vec<String> {
    s.split_whitespace().map(str::to_string).collect()
}

fn find(edge: &str, graph: &LaneGraph, place: &str) -> Result<Vec<mapc_graph::RoadId>, SumoError> {
    graph
        .find_roads(edge)
        .map_err(|_| SumoError::at(place, format!("edge `{edge}` is not in the network")))
}

/// How a scenario names road `r` of `graph`: its SUMO edge id where that names it alone, else its mapc id.
fn road_name(graph: &LaneGraph, r: mapc_graph::RoadId) -> String {
    graph
        .road(r)
        .and_then(|road| road.provenance.sumo_ids.first())
        .filter(|id| graph.find_roads(id).is_ok_and(|found| found == [r]))
        .cloned()
        .unwrap_or_else(|| r.to_string())
}

/// Each edge of a route leads into the next (SUMO refuses a route whose edges do not connect).
fn check_connected(edges: &[String], graph: &LaneGraph, place: &str) -> Result<(), SumoError> {
    let roads: Vec<Vec<mapc_graph::RoadId>> = edges
        .iter()
        .map(|e| find(e, graph, place))
        .collect::<Result<_, _>>()?;
    for (k, pair) in roads.windows(2).enumerate() {
        let last = *pair[0].last().expect("found roads are never empty");
        let next = pair[1][0];
        if !graph.connections_from(last).any(|c| c.to_road == next) {
            return Err(SumoError::at(
                place,
                format!(
                    "edge `{}` does not lead into `{}`: the route's edges do not connect",
                    edges[k],
                    edges[k + 1]
                ),
            ));
        }
    }
    Ok(())
}
