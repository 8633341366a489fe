//! `window`: cut the piece of a corridor around one merge whose lengths equal a source scenario's (upstream main
//! road, merging road, downstream), and make a scenario of the whole corridor with that piece as the controlled
//! region and the source's demand.
//!
//! A window boundary falls exactly at the asked distance from the merge: the road there is cut in two
//! ([`crate::transform::cut_road`]) unless an existing junction lies within [`SNAP_M`] of the point.

use crate::transform::{self, CorridorRoles, TransformError, pick_route::describe_junction};
use crate::{Control, Flow, NetworkSpec, ResolvedScenario, SCENARIO_VERSION, Scenario, WindowInfo};
use mapc_graph::{JunctionId, JunctionKind, LaneGraph, RoadId};
use serde::Serialize;
use std::collections::HashSet;

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

/// A corridor cut for a window.
#[derive(Clone, Debug)]
pub struct WindowCut {
    pub graph: LaneGraph,
    pub roles: CorridorRoles,
    pub junction: JunctionId,
    /// The roads inside the window: main road before the merge, merging road, main road after.
    pub upstream_roads: Vec<RoadId>,
    pub merge_roads: Vec<RoadId>,
    pub downstream_roads: Vec<RoadId>,
    pub upstream_m: f64,
    pub merge_m: f64,
    pub downstream_m: f64,
    /// Where main-road and merging-road traffic enters the corridor.
    pub main_entry: RoadId,
    pub merge_entry: RoadId,
    /// One line per boundary: where it fell and whether a road was cut.
    pub notes: Vec<String>,
}

impl WindowCut {
    pub fn region(&self) -> Vec<RoadId> {
        let mut r: Vec<RoadId> = self
            .upstream_roads
            .iter()
            .chain(&self.merge_roads)
            .chain(&self.downstream_roads)
            .copied()
            .collect();
        r.sort();
        r
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

/// Cut the window around merge `junction` (any id `find_junction` takes) of a corridor graph.
pub fn cut_window(
    corridor: &LaneGraph,
    junction: &str,
    shape: &SourceShape,
) -> Result<WindowCut, TransformError> {
    let mut g = corridor.clone();
    let roles = CorridorRoles::of(&g)?;
    let j = g
        .find_junction(junction)
        .map_err(|e| TransformError::NotACorridor(format!("--junction: {e}")))?;
    let name = describe_junction(&g, j);
    let Some(i) = roles
        .main
        .iter()
        .position(|r| g.road(*r).unwrap().from == j)
        .filter(|i| *i > 0)
    else {
        return Err(TransformError::NotACorridor(format!(
            "{name} is not inside the corridor's main road; merges on this corridor: {}",
            merge_list(&g, &roles)
        )));
    };
    let feeders: Vec<&Vec<RoadId>> = roles
        .feeders
        .iter()
        .filter(|f| g.road(*f.last().unwrap()).unwrap().to == j)
        .collect();
    if feeders.len() != 1 {
        let kind = g.junction(j).unwrap().kind;
        return Err(TransformError::NotACorridor(format!(
            "{name} is a {kind:?} junction with {} merging roads, not a merge; merges on this corridor: {}",
            feeders.len(),
            merge_list(&g, &roles)
        )));
    }
    let before: Vec<RoadId> = roles.main[..i].to_vec();
    let after: Vec<RoadId> = roles.main[i..].to_vec();
    let feeder = feeders[0].clone();
    let short = |what: &str, have: f64, need: f64| {
        TransformError::Cut(format!(
            "{what} {name} is {have:.1} m long; the window needs {need:.1} m ({:.1} m short)",
            need - have
        ))
    };
    let up = boundary_upstream(&g, &before, shape.upstream_m)
        .ok_or_else(|| short("the main road before", sum(&g, &before), shape.upstream_m))?;
    let mb = boundary_upstream(&g, &feeder, shape.merge_m)
        .ok_or_else(|| short("the merging road into", sum(&g, &feeder), shape.merge_m))?;
    let down = boundary_downstream(&g, &after, shape.downstream_m)
        .ok_or_else(|| short("the main road after", sum(&g, &after), shape.downstream_m))?;
    let mut notes = Vec::new();
    for (what, chain, b) in [
        ("upstream", &before, up),
        ("merging road", &feeder, mb),
        ("downstream", &after, down),
    ] {
        match b {
            Boundary::Inside(k, offset) => {
                let (_, _, nj) = transform::cut_road(&mut g, chain[k], offset)?;
                notes.push(format!(
                    "{what}: cut road {} at {offset:.2} m from its start (new junction {nj})",
                    chain[k]
                ));
            }
            Boundary::AtStartOf(k) => {
                let at = g.road(chain[k]).unwrap().from;
                notes.push(format!(
                    "{what}: boundary at junction {}",
                    describe_junction(&g, at)
                ));
            }
            Boundary::AtEndOf(k) => {
                let at = g.road(chain[k]).unwrap().to;
                notes.push(format!(
                    "{what}: boundary at junction {}",
                    describe_junction(&g, at)
                ));
            }
        }
    }
    let problems = g.invariant_violations();
    if !problems.is_empty() {
        return Err(TransformError::Invariant {
            step: transform::CUT_AT.into(),
            violations: problems,
        });
    }
    // Read the roles again (cut pieces carry their road's role) and collect the roads within the boundaries.
    let roles = CorridorRoles::of(&g)?;
    let i = roles
        .main
        .iter()
        .position(|r| g.road(*r).unwrap().from == j)
        .unwrap();
    let feeder = roles
        .feeders
        .iter()
        .find(|f| g.road(*f.last().unwrap()).unwrap().to == j)
        .unwrap()
        .clone();
    let take_back = |chain: &[RoadId], limit: f64| -> Vec<RoadId> {
        let mut acc = 0.0;
        let mut out = Vec::new();
        for r in chain.iter().rev() {
            let len = g.road(*r).unwrap().length_m;
            if acc + len > limit + SNAP_M {
                break;
            }
            acc += len;
            out.insert(0, *r);
        }
        out
    };
    let upstream_roads = take_back(&roles.main[..i], shape.upstream_m);
    let merge_roads = take_back(&feeder, shape.merge_m);
    let mut acc = 0.0;
    let mut downstream_roads = Vec::new();
    for r in &roles.main[i..] {
        let len = g.road(*r).unwrap().length_m;
        if acc + len > shape.downstream_m + SNAP_M {
            break;
        }
        acc += len;
        downstream_roads.push(*r);
    }
    let pieces = mapc_graph::Topology::new(&g).component_count();
    if pieces != 1 {
        return Err(TransformError::Invariant {
            step: transform::CUT_AT.into(),
            violations: vec![format!("the cut corridor falls into {pieces} pieces")],
        });
    }
    Ok(WindowCut {
        upstream_m: sum(&g, &upstream_roads),
        merge_m: sum(&g, &merge_roads),
        downstream_m: sum(&g, &downstream_roads),
        main_entry: roles.main[0],
        merge_entry: feeder[0],
        junction: j,
        upstream_roads,
        merge_roads,
        downstream_roads,
        roles,
        graph: g,
        notes,
    })
}

/// How the window scenario's demand differs from the source's.
#[derive(Clone, Debug, Default)]
pub struct DemandOverride {
    /// Total main-road demand (veh/h), split among vehicle types as in the source.
    pub main_vph: Option<f64>,
    /// Total merging-road demand (veh/h).
    pub merge_vph: Option<f64>,
    /// Controlled AVs at once (default: the source's).
    pub n_av: Option<u32>,
}

/// The window scenario: the whole cut corridor (saved as `graph_file`, relative to the scenario), the source's
/// vehicle types, step, horizon and initial vehicles, its flows moved to the corridor's entries, and the window
/// as the controlled region.
pub fn window_scenario(
    cut: &WindowCut,
    source: &ResolvedScenario,
    shape: &SourceShape,
    name: &str,
    graph_file: &str,
    demand: &DemandOverride,
) -> Result<Scenario, TransformError> {
    let s = &source.scenario;
    let main_set: HashSet<RoadId> = shape.main_roads.iter().copied().collect();
    let merge_set: HashSet<RoadId> = shape.merge_roads.iter().copied().collect();
    let mut flows = Vec::new();
    let mut totals = [0.0f64; 2];
    let mut roles = Vec::new();
    for (f, (from, _)) in s.flows.iter().zip(&source.flow_roads) {
        let role = if main_set.contains(from) {
            0
        } else if merge_set.contains(from) {
            1
        } else {
            return Err(TransformError::NotACorridor(format!(
                "{}: flow `{}` enters at `{}`, which is neither the main road nor the merging road",
                source.origin, f.id, f.from
            )));
        };
        totals[role] += f.vehs_per_hour;
        roles.push(role);
    }
    for (f, role) in s.flows.iter().zip(roles) {
        let wanted = if role == 0 {
            demand.main_vph
        } else {
            demand.merge_vph
        };
        let vph = match wanted {
            Some(total) if totals[role] > 0.0 => f.vehs_per_hour * total / totals[role],
            _ => f.vehs_per_hour,
        };
        let entry = if role == 0 {
            cut.main_entry
        } else {
            cut.merge_entry
        };
        flows.push(Flow {
            from: entry.to_string(),
            to: None,
            vehs_per_hour: vph,
            ..f.clone()
        });
    }
    let n_av = demand
        .n_av
        .or(s.control.as_ref().map(|c| c.n_av))
        .unwrap_or(0);
    let junction = cut.graph.junction(cut.junction).unwrap();
    let junction_name = junction
        .provenance
        .osm_nodes
        .first()
        .map(|n| format!("osm:{n}"))
        .or_else(|| junction.provenance.sumo_ids.first().cloned())
        .unwrap_or_else(|| cut.junction.to_string());
    let matched_to = source
        .origin
        .strip_prefix("builtin:")
        .unwrap_or(&source.origin)
        .to_string();
    Ok(Scenario {
        version: SCENARIO_VERSION,
        name: name.to_string(),
        description: format!(
            "The corridor of {} with a window around merge {} ({junction_name}) matched to {matched_to}: \
             {:.1} m of main road before the merge, {:.1} m of merging road, {:.1} m after.",
            cut.graph.source.file, cut.junction, cut.upstream_m, cut.merge_m, cut.downstream_m
        ),
        step_s: s.step_s,
        horizon_steps: s.horizon_steps,
        warmup_steps: s.warmup_steps,
        network: NetworkSpec::Graph(graph_file.into()),
        vehicle_types: s.vehicle_types.clone(),
        flows,
        initial_vehicles: s.initial_vehicles.clone(),
        control: Some(Control {
            n_av,
            region: cut.region().iter().map(|r| r.to_string()).collect(),
            window: Some(WindowInfo {
                junction: junction_name,
                matched_to,
                upstream_m: cut.upstream_m,
                merge_m: cut.merge_m,
                downstream_m: cut.downstream_m,
            }),
        }),
        measure: None,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::simplify::simplify;
    use crate::transform::SimplifyOptions;
    use crate::transform::test_maps::{build, highway};
    use proptest::prelude::*;

    fn corridor() -> LaneGraph {
        simplify(&highway(), &SimplifyOptions::default())
            .unwrap()
            .graph
    }

    #[test]
    fn simple_merge_shape_is_600_200_100() {
        let source = ResolvedScenario::load("simple_merge").unwrap();
        let shape = SourceShape::of(&source).unwrap();
        assert_eq!(
            (shape.upstream_m, shape.merge_m, shape.downstream_m),
            (600.0, 200.0, 100.0)
        );
        let names = |rs: &[RoadId]| -> Vec<String> {
            rs.iter()
                .map(|r| source.graph.road(*r).unwrap().name.clone().unwrap())
                .collect()
        };
        assert_eq!(names(&shape.main_roads), ["inflow_highway", "left"]);
        assert_eq!(names(&shape.merge_roads), ["inflow_merge", "bottom"]);
    }

    #[test]
    fn window_cuts_exactly_and_keeps_the_corridor() {
        let g = corridor();
        let source = ResolvedScenario::load("simple_merge").unwrap();
        let shape = SourceShape::of(&source).unwrap();
        let cut = cut_window(&g, "osm:1002", &shape).unwrap();
        assert!((cut.upstream_m - 600.0).abs() < 1e-9 && (cut.merge_m - 200.0).abs() < 1e-9);
        assert!((cut.downstream_m - 100.0).abs() < 1e-9);
        assert_eq!(cut.notes.len(), 3);
        assert!(cut.graph.invariant_violations().is_empty());
        assert!((cut.graph.total_lane_length_m() - g.total_lane_length_m()).abs() < 1e-6);
        // Three cuts: three new roads above the largest id, three new through junctions.
        assert_eq!(cut.graph.roads.len(), g.roads.len() + 3);
        assert_eq!(cut.main_entry, RoadId(0));
        let scenario = window_scenario(
            &cut,
            &source,
            &shape,
            "w",
            "w.graph.json",
            &DemandOverride::default(),
        )
        .unwrap();
        let flows: Vec<(&str, f64)> = scenario
            .flows
            .iter()
            .map(|f| (f.from.as_str(), f.vehs_per_hour))
            .collect();
        assert_eq!(
            flows,
            [
                ("R0", 1800.0),
                ("R0", 200.0),
                (cut.merge_entry.to_string().as_str(), 200.0)
            ]
        );
        let control = scenario.control.as_ref().unwrap();
        assert_eq!(control.n_av, 5);
        assert_eq!(control.region.len(), cut.region().len());
        // The scenario comes back from TOML exactly, and resolves against its graph.
        let back =
            Scenario::from_toml(&scenario.to_toml(), std::path::Path::new("w.toml")).unwrap();
        assert_eq!(back, scenario);
        let dir = std::env::temp_dir().join(format!("mapc-window-test-{}", std::process::id()));
        cut.graph.save(&dir.join("w.graph.json")).unwrap();
        let resolved = ResolvedScenario::resolve(scenario, &dir, "w.toml").unwrap();
        assert_eq!(resolved.region_roads, cut.region());
        std::fs::remove_dir_all(dir).unwrap();
    }

    #[test]
    fn shortfalls_and_non_merges_are_named() {
        let g = corridor();
        let source = ResolvedScenario::load("simple_merge").unwrap();
        let mut shape = SourceShape::of(&source).unwrap();
        shape.upstream_m = 1600.0;
        let err = cut_window(&g, "J2", &shape).unwrap_err().to_string();
        assert!(
            err.contains("main road before J2") && err.contains("100.0 m short"),
            "{err}"
        );
        shape.upstream_m = 600.0;
        shape.merge_m = 2000.0;
        let err = cut_window(&g, "J2", &shape).unwrap_err().to_string();
        assert!(err.contains("merging road into J2"), "{err}");
        let err = cut_window(&g, "J0", &shape).unwrap_err().to_string();
        assert!(
            err.contains("not inside the corridor's main road") && err.contains("J2 (osm:1002)"),
            "{err}"
        );
        let err = cut_window(&g, "osm:77", &shape).unwrap_err().to_string();
        assert!(err.contains("osm:77"), "{err}");
    }

    #[test]
    fn a_boundary_near_a_junction_snaps_to_it() {
        let g = corridor();
        let source = ResolvedScenario::load("simple_merge").unwrap();
        let mut shape = SourceShape::of(&source).unwrap();
        shape.upstream_m = 1499.8; // the corridor's start is 1500 m before the merge
        let cut = cut_window(&g, "J2", &shape).unwrap();
        assert_eq!(cut.upstream_m, 1500.0);
        assert!(
            cut.notes[0].contains("boundary at junction J0"),
            "{:?}",
            cut.notes
        );
    }

    proptest! {
        #[test]
        fn a_cut_keeps_total_length_and_connectivity(
            bends in proptest::collection::vec((0.0f64..500.0, -50.0f64..50.0), 0..6),
            at in 0.001f64..0.999,
        ) {
            let mut pts: Vec<[f64; 2]> = bends.iter().map(|&(x, y)| [x, y]).collect();
            pts.sort_by(|a, b| a[0].total_cmp(&b[0]));
            let g = build(&[[-100.0, 0.0], [600.0, 0.0], [700.0, 0.0]], &[
                (0, 1, "motorway", 2, &pts),
                (1, 2, "motorway", 1, &[]),
            ]);
            let mut cut = g.clone();
            let length = g.roads[0].length_m;
            let (a, b, j) = crate::transform::cut_road(&mut cut, RoadId(0), at * length).unwrap();
            prop_assert!(cut.invariant_violations().is_empty(), "{:?}", cut.invariant_violations());
            prop_assert_eq!(mapc_graph::Topology::new(&cut).component_count(), 1);
            let (ra, rb) = (cut.road(a).unwrap(), cut.road(b).unwrap());
            prop_assert!((ra.length_m + rb.length_m - length).abs() < 1e-9);
            prop_assert!((cut.total_lane_length_m() - g.total_lane_length_m()).abs() < 1e-6);
            prop_assert_eq!(ra.to, j);
            prop_assert_eq!(rb.from, j);
            prop_assert_eq!(cut.junction(j).unwrap().kind, JunctionKind::Through);
            prop_assert_eq!(ra.geometry.last(), rb.geometry.first());
            // The rest of the road still leads on to R1.
            prop_assert_eq!(cut.shortest_route(JunctionId(0), JunctionId(2)).unwrap(), vec![a, b, RoadId(1)]);
        }
    }
}
