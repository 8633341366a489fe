//! `pick_route`: choose the corridor's main road. Through the `--via` points in order (shortest connections
//! between them over any road), then extended at both ends by the longest route over the allowed roads; with no
//! `--via`, the longest through route of the map over those roads that passes a junction where another road joins
//! (so the corridor has a merge), else the longest of all. That default follows the motorway as a driver would:
//! link roads count a twentieth of their length and may only lead onto the through road or leave it at the
//! corridor's ends, so the route never leaves the motorway at an interchange for its ramps. Allowed roads are those of the allowed classes and,
//! where a map gives a road no class (a SUMO edge without `type`), those as fast as a ramp
//! ([`map_merges::main_road_allowed`]): the route must not depend on types being present. Where the road graph has cycles (loop ramps),
//! the search ignores the edge that closes a cycle, so the result is a simple route and the same on every run.

use super::{Corridor, SimplifyOptions, TransformError, chains_of, map_merges, mark};
use mapc_graph::{JunctionId, LaneGraph, LookupError, Road, RoadId};
use std::collections::{HashMap, HashSet};

pub const NAME: &str = "pick_route";

/// A point the route must pass.
#[derive(Clone, Debug, PartialEq)]
pub enum Waypoint {
    /// A road or the pieces of one OSM way, in driving order.
    Roads(Vec<RoadId>),
    Junction(JunctionId),
}

/// Read a `--via` value: roads first (`R3`, `osm-way:N`, SUMO edge ids), then junctions (`J3`, `osm:N`, SUMO ids).
pub fn resolve_via(g: &LaneGraph, query: &str) -> Result<Waypoint, TransformError> {
    let is_junction_syntax = query.starts_with("osm:") || query.parse::<JunctionId>().is_ok();
    if !is_junction_syntax && let Ok(roads) = g.find_roads(query) {
        let chains = chains_of(g, &roads);
        if chains.len() != 1 {
            return Err(TransformError::NoRoute(format!(
                "--via `{query}` names {} separate stretches of road ({}); name one with a mapc id",
                chains.len(),
                chains
                    .iter()
                    .map(|c| c[0].to_string())
                    .collect::<Vec<_>>()
                    .join(", ")
            )));
        }
        return Ok(Waypoint::Roads(chains.into_iter().next().unwrap()));
    }
    match g.find_junction(query) {
        Ok(j) => Ok(Waypoint::Junction(j)),
        // a junction an earlier stage joined into a road: the route passes it by taking that road
        Err(LookupError::JoinedInto { road, .. }) => match road.parse::<RoadId>() {
            Ok(r) if g.road(r).is_some() => Ok(Waypoint::Roads(vec![r])),
            _ => Err(TransformError::NoRoute(format!(
                "--via `{query}`: joined into road {road}, which this graph lacks"
            ))),
        },
        Err(source) => {
            if is_junction_syntax {
                Err(TransformError::Via {
                    query: query.to_string(),
                    source,
                })
            } else {
                Err(TransformError::NoRoute(format!(
                    "--via `{query}`: no road or junction of that id in this graph"
                )))
            }
        }
    }
}

#[derive(Clone, Copy, PartialEq)]
enum Direction {
    Downstream,
    Upstream,
}

/// The longest route from (downstream) or to (upstream) `start` over roads that `allowed` accepts, never
/// touching a junction in `avoid`. Roads come in driving order.
fn longest_route(
    g: &LaneGraph,
    start: JunctionId,
    dir: Direction,
    allowed: &dyn Fn(&Road) -> bool,
    avoid: &HashSet<JunctionId>,
    memo: &mut HashMap<JunctionId, (f64, Option<RoadId>)>,
) -> (f64, Vec<RoadId>) {
    let mut in_progress = HashSet::new();
    longest_from(g, start, dir, allowed, avoid, memo, &mut in_progress);
    let mut roads = Vec::new();
    let mut cur = start;
    let mut seen = HashSet::from([start]);
    while let Some(&(_, Some(r))) = memo.get(&cur) {
        let road = g.road(r).unwrap();
        cur = if dir == Direction::Downstream {
            road.to
        } else {
            road.from
        };
        if !seen.insert(cur) {
            break;
        }
        roads.push(r);
    }
    let total = roads.iter().map(|r| g.road(*r).unwrap().length_m).sum();
    if dir == Direction::Upstream {
        roads.reverse();
    }
    (total, roads)
}

fn longest_from(
    g: &LaneGraph,
    j: JunctionId,
    dir: Direction,
    allowed: &dyn Fn(&Road) -> bool,
    avoid: &HashSet<JunctionId>,
    memo: &mut HashMap<JunctionId, (f64, Option<RoadId>)>,
    in_progress: &mut HashSet<JunctionId>,
) -> f64 {
    if let Some(&(d, _)) = memo.get(&j) {
        return d;
    }
    in_progress.insert(j);
    let Some(junction) = g.junction(j) else {
        return 0.0;
    };
    let candidates = if dir == Direction::Downstream {
        &junction.outgoing
    } else {
        &junction.incoming
    };
    let mut best: (f64, Option<RoadId>) = (0.0, None);
    for &rid in candidates {
        let road = g.road(rid).unwrap();
        let next = if dir == Direction::Downstream {
            road.to
        } else {
            road.from
        };
        if !allowed(road) || avoid.contains(&next) || in_progress.contains(&next) || next == j {
            continue;
        }
        let d = road.length_m + longest_from(g, next, dir, allowed, avoid, memo, in_progress);
        if d > best.0 {
            best = (d, Some(rid));
        }
    }
    in_progress.remove(&j);
    memo.insert(j, best);
    best.0
}

/// The route through `waypoints`, extended at both ends by the longest allowed routes.
pub fn route_through(
    g: &LaneGraph,
    waypoints: &[Waypoint],
    allowed: &dyn Fn(&Road) -> bool,
) -> Result<Vec<RoadId>, TransformError> {
    let mut route: Vec<RoadId> = Vec::new();
    let mut end: Option<JunctionId> = None;
    let mut start: Option<JunctionId> = None;
    let name = |j: JunctionId| describe_junction(g, j);
    for wp in waypoints {
        let target = match wp {
            Waypoint::Roads(chain) => g.road(chain[0]).unwrap().from,
            Waypoint::Junction(j) => *j,
        };
        if let Some(e) = end {
            if e != target {
                let path = g.shortest_route(e, target).ok_or_else(|| {
                    TransformError::NoRoute(format!(
                        "no route from {} to {} (in the --via order)",
                        name(e),
                        name(target)
                    ))
                })?;
                route.extend(path);
            }
        } else {
            start = Some(target);
        }
        end = Some(match wp {
            Waypoint::Roads(chain) => {
                route.extend(chain);
                g.road(*chain.last().unwrap()).unwrap().to
            }
            Waypoint::Junction(j) => *j,
        });
    }
    let (start, end) = match (start, end) {
        (Some(s), Some(e)) => (s, e),
        _ => return Err(TransformError::NoRoute("no --via points".into())),
    };
    let mut on_route: HashSet<JunctionId> = HashSet::from([start]);
    for r in &route {
        if !on_route.insert(g.road(*r).unwrap().to) {
            return Err(TransformError::NoRoute(format!(
                "the route through the --via points passes {} twice",
                name(g.road(*r).unwrap().to)
            )));
        }
    }
    let (_, upstream) = longest_route(
        g,
        start,
        Direction::Upstream,
        allowed,
        &on_route,
        &mut HashMap::new(),
    );
    on_route.extend(upstream.iter().map(|r| g.road(*r).unwrap().from));
    let (_, downstream) = longest_route(
        g,
        end,
        Direction::Downstream,
        allowed,
        &on_route,
        &mut HashMap::new(),
    );
    let mut full = upstream;
    full.extend(route);
    full.extend(downstream);
    if full.is_empty() {
        return Err(TransformError::NoRoute(format!(
            "no road of the allowed classes passes {}",
            name(start)
        )));
    }
    Ok(full)
}

/// How much a metre of link road (`motorway_link`, `trunk_link`, ...) counts in the default route's length: a
/// driver follows the motorway through an interchange rather than its ramps, so a route takes a link only where
/// it gains twenty times the link's length of through road.
const LINK_METRE_WORTH: f64 = 0.05;

fn is_link(road: &Road) -> bool {
    road.class.ends_with("_link")
}

/// Where a route is in its order of roads: link roads may lead onto the through road (an on-ramp) and follow it
/// (an off-ramp), never lie between two stretches of it (a driver leaving the motorway at an interchange is on
/// another road).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
enum Leg {
    /// No through road yet.
    Before,
    /// On the through road.
    Through,
    /// Left the through road onto a link: links only from here.
    After,
}

impl Leg {
    /// The leg after taking `road`, `None` where the route may not take it.
    fn then(self, road: &Road) -> Option<Leg> {
        match (self, is_link(road)) {
            (Leg::Before, true) => Some(Leg::Before),
            (Leg::Before | Leg::Through, false) => Some(Leg::Through),
            (Leg::Through | Leg::After, true) => Some(Leg::After),
            (Leg::After, false) => None,
        }
    }
}

/// What a road adds to a route's worth: its length, a link's at [`LINK_METRE_WORTH`].
fn worth(road: &Road) -> f64 {
    if is_link(road) {
        road.length_m * LINK_METRE_WORTH
    } else {
        road.length_m
    }
}

/// The best routes downstream of one junction reached in one leg: the worthiest, and the worthiest that passes
/// a join on the way (`f64::NEG_INFINITY` where none does), each by its first road.
#[derive(Clone, Copy)]
struct Downstream {
    any: (f64, Option<RoadId>),
    joined: (f64, Option<RoadId>),
}

/// Whether the route, arriving at `next`, passes a join there: one is there and the route goes on from it.
fn passes_join(joins: &HashSet<JunctionId>, next: JunctionId, after: &Downstream) -> bool {
    joins.contains(&next) && after.any.1.is_some()
}

type Memo = HashMap<(JunctionId, Leg), Downstream>;

fn downstream_from(
    g: &LaneGraph,
    j: JunctionId,
    leg: Leg,
    allowed: &dyn Fn(&Road) -> bool,
    joins: &HashSet<JunctionId>,
    memo: &mut Memo,
    in_progress: &mut HashSet<JunctionId>,
) -> Downstream {
    if let Some(&d) = memo.get(&(j, leg)) {
        return d;
    }
    let mut best = Downstream {
        any: (0.0, None),
        joined: (f64::NEG_INFINITY, None),
    };
    let Some(junction) = g.junction(j) else {
        return best;
    };
    in_progress.insert(j);
    for &rid in &junction.outgoing {
        let road = g.road(rid).unwrap();
        let next = road.to;
        let Some(next_leg) = leg.then(road) else {
            continue;
        };
        if !allowed(road) || in_progress.contains(&next) || next == j {
            continue;
        }
        let after = downstream_from(g, next, next_leg, allowed, joins, memo, in_progress);
        let any = worth(road) + after.any.0;
        if any > best.any.0 {
            best.any = (any, Some(rid));
        }
        let joined = worth(road)
            + if passes_join(joins, next, &after) {
                after.any.0
            } else {
                after.joined.0
            };
        if joined > best.joined.0 {
            best.joined = (joined, Some(rid));
        }
    }
    in_progress.remove(&j);
    memo.insert((j, leg), best);
    best
}

/// The default main road: the worthiest through route over allowed roads (its length, links counting little and
/// never between two stretches of through road) that passes a junction in `joins` (where another road comes in,
/// so the corridor can have a merge), else the worthiest through route of all. Returns the roads in driving order
/// and whether the route passes a join.
pub fn best_through_route(
    g: &LaneGraph,
    allowed: &dyn Fn(&Road) -> bool,
    joins: &HashSet<JunctionId>,
) -> Result<(Vec<RoadId>, bool), TransformError> {
    let mut memo = Memo::new();
    let mut best_any: (f64, Option<JunctionId>) = (0.0, None);
    let mut best_joined: (f64, Option<JunctionId>) = (f64::NEG_INFINITY, None);
    for j in &g.junctions {
        let d = downstream_from(
            g,
            j.id,
            Leg::Before,
            allowed,
            joins,
            &mut memo,
            &mut HashSet::new(),
        );
        if d.any.0 > best_any.0 {
            best_any = (d.any.0, Some(j.id));
        }
        if d.joined.1.is_some() && d.joined.0 > best_joined.0 {
            best_joined = (d.joined.0, Some(j.id));
        }
    }
    let (start, mut want_join) = match (best_joined.1, best_any.1) {
        (Some(s), _) => (s, true),
        (None, Some(s)) => (s, false),
        (None, None) => {
            return Err(TransformError::NoRoute(
                "no road of the allowed classes (or, where roads have no class, as fast as a ramp) in this map"
                    .into(),
            ));
        }
    };
    let joined = want_join;
    let mut roads = Vec::new();
    let mut cur = start;
    let mut leg = Leg::Before;
    let mut seen = HashSet::from([start]);
    while let Some(d) = memo.get(&(cur, leg)) {
        let Some(r) = (if want_join { d.joined.1 } else { d.any.1 }) else {
            break;
        };
        let road = g.road(r).unwrap();
        let next = road.to;
        leg = leg
            .then(road)
            .expect("the memo holds only routes a leg may take");
        if want_join
            && memo
                .get(&(next, leg))
                .is_some_and(|after| passes_join(joins, next, after))
        {
            want_join = false;
        }
        if !seen.insert(next) {
            break;
        }
        roads.push(r);
        cur = next;
    }
    Ok((roads, joined))
}

/// `J12 (osm:61862553)` or `J12 (gneJ18)`.
pub fn describe_junction(g: &LaneGraph, j: JunctionId) -> String {
    match g.junction(j) {
        Some(junction) => match (
            junction.provenance.osm_nodes.first(),
            junction.provenance.sumo_ids.first(),
        ) {
            (Some(n), _) => format!("{j} (osm:{n})"),
            (None, Some(s)) => format!("{j} ({s})"),
            (None, None) => j.to_string(),
        },
        None => j.to_string(),
    }
}

pub fn apply(c: &mut Corridor, opts: &SimplifyOptions) -> Result<String, TransformError> {
    let allowed = |r: &Road| map_merges::main_road_allowed(r, &|class| opts.class_allowed(class));
    let mut passes_join = true;
    let route = if opts.via.is_empty() {
        let joins = map_merges::joins(&c.graph, opts.minor_roads);
        let (route, joined) = best_through_route(&c.graph, &allowed, &joins)?;
        passes_join = joined;
        route
    } else {
        let waypoints = opts
            .via
            .iter()
            .map(|v| resolve_via(&c.graph, v))
            .collect::<Result<Vec<_>, _>>()?;
        route_through(&c.graph, &waypoints, &allowed)?
    };
    for r in &route {
        mark(&mut c.graph.road_mut(*r).unwrap().provenance, NAME);
    }
    c.main = route;
    let g = &c.graph;
    let first = g.road(c.main[0]).unwrap().from;
    let last = g.road(*c.main.last().unwrap()).unwrap().to;
    let how = if opts.via.is_empty() {
        format!(
            "the longest through route {}over {} (and roads of no class as fast as a ramp; link roads count a \
             twentieth of their length, and only before or after the through road)",
            if passes_join {
                "past a junction where another road joins "
            } else {
                "(no route passes a junction where another road joins) "
            },
            opts.classes.join("/")
        )
    } else {
        format!("through --via {}", opts.via.join(", "))
    };
    Ok(format!(
        "main road {how}: {} roads, {:.1} m, from {} to {}",
        c.main.len(),
        Corridor::chain_length_m(g, &c.main),
        describe_junction(g, first),
        describe_junction(g, last)
    ))
}
