//! `simplify`: a highway map becomes a single-lane corridor with the roads that merge into it (or, with
//! `keep_lanes`, one that keeps every lane), by the ordered steps of [`crate::transform`]. Lengths reported here
//! are sums of road lengths (geodesic for OSM input); the internal length of a junction that remains (a merge) is
//! not counted, that of a removed joint is part of the joined road.

use crate::transform::pick_route::describe_junction;
use crate::transform::{
    self, Corridor, CorridorRoles, SimplifyOptions, StepReport, TransformError,
};
use mapc_graph::{JunctionId, LaneGraph, LookupError, RoadId, Source, SourceFormat};
use serde::Serialize;

pub use crate::transform::SimplifyOptions as Options;

/// A simplified corridor and what each step did.
#[derive(Clone, Debug)]
pub struct Simplified {
    pub graph: LaneGraph,
    pub roles: CorridorRoles,
    pub steps: Vec<StepReport>,
    /// The raw map's merges as `mapc junctions --kind merge` finds them, named by [`describe_junction`].
    pub map_merges: Vec<String>,
}

/// One merge on the corridor, with the lengths around it.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct MergeSummary {
    pub junction: String,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub osm_node: Option<i64>,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub sumo_id: Option<String>,
    /// Main road from the corridor's start to the merge.
    pub main_before_m: f64,
    /// The merging road, from where it starts to the merge.
    pub merge_m: f64,
    /// Main road from the merge to the corridor's end.
    pub main_after_m: f64,
    /// The merging road's first and last roads (one road once chains are joined).
    pub merging_roads: Vec<String>,
    pub merging_label: String,
    /// Whether the merging road has the right of way over the main road there.
    pub merging_is_major: bool,
}

/// Run every step of `simplify` on a map's graph.
pub fn simplify(raw: &LaneGraph, opts: &SimplifyOptions) -> Result<Simplified, TransformError> {
    if let Some(l) = opts.feeder_length_m
        && !(l.is_finite() && l > 0.0)
    {
        return Err(TransformError::NoRoute(format!(
            "--feeder-length must be a positive length, not {l}"
        )));
    }
    let mut corridor = Corridor::new(raw.clone());
    corridor.graph.source = Source {
        file: raw.source.file.clone(),
        format: SourceFormat::Derived,
    };
    let steps = transform::simplify_steps(opts);
    let reports = transform::run_steps(&mut corridor, &steps, opts)?;
    let roles = CorridorRoles {
        main: corridor.main,
        feeders: corridor.feeders,
        exits: corridor.exits,
    };
    for query in &opts.via {
        check_via(&corridor.graph, &roles, query)?;
    }
    let map_merges = transform::map_merges::merges(raw, opts.minor_roads)
        .into_iter()
        .map(|j| describe_junction(raw, j))
        .collect();
    Ok(Simplified {
        graph: corridor.graph,
        roles,
        steps: reports,
        map_merges,
    })
}

/// How many of the map's merges a warning names before it says how many more there are.
const MERGES_NAMED: usize = 5;

/// What to say when the corridor of `map` has no merge (so `mapc window` has nothing to cut): the map's merges,
/// if it has any, and how to list them and choose a corridor through one. `None` where the corridor has a merge.
pub fn no_merge_warning(s: &Simplified, map: &std::path::Path) -> Option<String> {
    if !corridor_merges(&s.graph, &s.roles).is_empty() {
        return None;
    }
    let map = map.display();
    let how = format!(
        "list them with `mapc junctions {map} --kind merge` and choose a corridor through one with `mapc simplify {map} --via JUNCTION` (or `--via ROAD`, a road into it)"
    );
    Some(if s.map_merges.is_empty() {
        format!(
            "the corridor's main road passes no merge, and the map has none that `mapc junctions {map} --kind merge` finds; choose another route with `--via`"
        )
    } else {
        let mut named = s.map_merges[..s.map_merges.len().min(MERGES_NAMED)].join(", ");
        if s.map_merges.len() > MERGES_NAMED {
            named.push_str(&format!(" and {} more", s.map_merges.len() - MERGES_NAMED));
        }
        format!(
            "the corridor's main road passes no merge, but the map has {} ({named}): {how}",
            s.map_merges.len()
        )
    })
}

/// That the finished corridor's main road passes a `--via` point: the junction is on it (or was joined into one
/// of its roads), or every road the point names is part of it. A point the result does not honour is an error,
/// never a corridor that quietly goes elsewhere.
pub fn check_via(g: &LaneGraph, roles: &CorridorRoles, query: &str) -> Result<(), TransformError> {
    let on_main = |r: &RoadId| roles.main.contains(r);
    let not_honoured = |why: String| TransformError::ViaNotHonoured {
        query: query.to_string(),
        why,
    };
    let junction_syntax = query.starts_with("osm:") || query.parse::<JunctionId>().is_ok();
    if !junction_syntax && let Ok(roads) = g.find_roads(query) {
        let off: Vec<String> = roads
            .iter()
            .filter(|r| !on_main(r))
            .map(|r| r.to_string())
            .collect();
        return if off.is_empty() {
            Ok(())
        } else {
            Err(not_honoured(format!(
                "the corridor's main road does not use {} of the roads it names ({})",
                off.len(),
                off.join(", ")
            )))
        };
    }
    match g.find_junction(query) {
        Ok(j) => {
            let passes = roles
                .main
                .iter()
                .filter_map(|r| g.road(*r))
                .any(|r| r.from == j || r.to == j);
            if passes {
                Ok(())
            } else {
                Err(not_honoured(format!(
                    "the corridor's main road does not pass {}",
                    describe_junction(g, j)
                )))
            }
        }
        Err(LookupError::JoinedInto { road, .. }) => {
            if road.parse::<RoadId>().is_ok_and(|r| on_main(&r)) {
                Ok(())
            } else {
                Err(not_honoured(format!(
                    "it became part of road {road}, which is not on the corridor's main road"
                )))
            }
        }
        Err(e) => Err(not_honoured(format!(
            "the corridor has no such point ({e})"
        ))),
    }
}

fn road_sum(g: &LaneGraph, roads: &[RoadId]) -> f64 {
    roads
        .iter()
        .filter_map(|r| g.road(*r))
        .map(|r| r.length_m)
        .sum()
}

/// Every merge on the corridor's main road, in driving order: a junction where exactly one merging road joins
/// it (a junction where several join is not a merge, and is listed by [`corridor_complex_junctions`]), so no
/// junction is listed twice.
pub fn corridor_merges(g: &LaneGraph, roles: &CorridorRoles) -> Vec<MergeSummary> {
    let mut out = Vec::new();
    for (i, rid) in roles.main.iter().enumerate().skip(1) {
        let j: JunctionId = g.road(*rid).unwrap().from;
        let joining: Vec<&Vec<RoadId>> = roles
            .feeders
            .iter()
            .filter(|f| g.road(*f.last().unwrap()).unwrap().to == j)
            .collect();
        if joining.len() != 1 {
            continue;
        }
        for feeder in joining {
            let junction = g.junction(j).unwrap();
            let last = *feeder.last().unwrap();
            let row = |from: RoadId| {
                g.connections
                    .iter()
                    .find(|k| k.from_road == from && k.to_road == *rid)
                    .map(|k| k.right_of_way)
            };
            out.push(MergeSummary {
                junction: j.to_string(),
                osm_node: junction.provenance.osm_nodes.first().copied(),
                sumo_id: junction.provenance.sumo_ids.first().cloned(),
                main_before_m: road_sum(g, &roles.main[..i]),
                merge_m: road_sum(g, feeder),
                main_after_m: road_sum(g, &roles.main[i..]),
                merging_roads: if feeder.len() == 1 {
                    vec![feeder[0].to_string()]
                } else {
                    vec![feeder[0].to_string(), last.to_string()]
                },
                merging_label: g.road(last).unwrap().label(),
                merging_is_major: row(last) == Some(mapc_graph::RightOfWay::Major)
                    && row(roles.main[i - 1]) != Some(mapc_graph::RightOfWay::Major),
            });
        }
    }
    out
}

/// Junctions of the main road where several merging roads join at once (not merges; `mapc window` refuses
/// them), in driving order, as `describe_junction` names them.
pub fn corridor_complex_junctions(g: &LaneGraph, roles: &CorridorRoles) -> Vec<String> {
    roles
        .main
        .iter()
        .skip(1)
        .map(|r| g.road(*r).unwrap().from)
        .filter(|&j| {
            roles
                .feeders
                .iter()
                .filter(|f| g.road(*f.last().unwrap()).unwrap().to == j)
                .count()
                > 1
        })
        .map(|j| describe_junction(g, j))
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::transform::test_maps::highway;

    fn close(a: f64, b: f64) -> bool {
        (a - b).abs() < 1e-6
    }

    #[test]
    fn default_route_is_the_longest_motorway_with_its_merge() {
        let raw = highway();
        let s = simplify(&raw, &SimplifyOptions::default()).unwrap();
        let names: Vec<&str> = s.steps.iter().map(|r| r.step.as_str()).collect();
        assert_eq!(
            names,
            [
                "pick_route",
                "keep_feeders",
                "drop_diverges",
                "prune",
                "collapse_lanes",
                "join_chains"
            ]
        );
        assert!(s.graph.invariant_violations().is_empty());
        assert!(s.graph.roads.iter().all(|r| r.lanes.len() == 1));
        // Main road R0+R1 (joint J1 gone) and R4+R6+R7: the bent collector R8 is longer than R6, but a link
        // road, and a driver stays on the motorway, so R8 (leaving and rejoining the route) goes with the exit.
        // The ramp R2+R3 is one road.
        assert_eq!(s.roles.main, vec![RoadId(0), RoadId(4)]);
        assert_eq!(s.roles.feeders, vec![vec![RoadId(2)]]);
        assert_eq!(s.graph.roads.len(), 3);
        let merges = corridor_merges(&s.graph, &s.roles);
        assert_eq!(merges.len(), 1);
        let m = &merges[0];
        assert_eq!((m.junction.as_str(), m.osm_node), ("J2", Some(1002)));
        let len = |i| raw.road(RoadId(i)).unwrap().length_m;
        let after = len(4) + len(6) + len(7);
        assert!(
            close(m.main_before_m, 1500.0)
                && close(m.merge_m, len(2) + len(3))
                && close(m.main_after_m, after),
            "{m:?}"
        );
        assert!(s.graph.road(RoadId(8)).is_none());
        // Joined roads keep every piece's provenance and say which steps made them.
        let main0 = s.graph.road(RoadId(0)).unwrap();
        assert_eq!(main0.provenance.osm_ways, vec![500, 501]);
        assert!(
            main0
                .provenance
                .made_by
                .contains(&"join_chains".to_string())
        );
        // The roles read back from the graph alone.
        assert_eq!(CorridorRoles::of(&s.graph).unwrap(), s.roles);
    }

    #[test]
    fn via_pins_the_route_and_exits_can_be_kept() {
        let raw = highway();
        let opts = SimplifyOptions {
            via: vec!["osm-way:506".into()],
            keep_exits: true,
            ..Default::default()
        };
        let s = simplify(&raw, &opts).unwrap();
        // Pinned through the shorter R6: the collector R8 leaves and rejoins the route (dropped); R5 is kept as an
        // exit, so J5 stays a diverge and the main road is R0+R1, R4, R6+R7.
        assert!(s.graph.road(RoadId(8)).is_none());
        assert_eq!(s.roles.main, vec![RoadId(0), RoadId(4), RoadId(6)]);
        assert_eq!(s.roles.exits, vec![vec![RoadId(5)]]);
        assert_eq!(s.steps[2].step, "keep_exits");
        let err = simplify(
            &raw,
            &SimplifyOptions {
                via: vec!["osm-way:42".into()],
                ..Default::default()
            },
        );
        assert!(err.unwrap_err().to_string().contains("osm-way:42"));
        let err = simplify(
            &raw,
            &SimplifyOptions {
                via: vec!["osm:42".into()],
                ..Default::default()
            },
        );
        assert!(err.unwrap_err().to_string().contains("osm:42"));
    }

    #[test]
    fn a_via_point_off_the_result_is_refused() {
        let s = simplify(&highway(), &SimplifyOptions::default()).unwrap();
        let g = &s.graph;
        // on the main road: its first junction, and a joint joined into a main road (J1 between R0 and R1)
        let start = g.road(s.roles.main[0]).unwrap().from;
        check_via(g, &s.roles, &start.to_string()).unwrap();
        assert!(g.junction(JunctionId(1)).is_none());
        check_via(g, &s.roles, "J1").unwrap();
        check_via(g, &s.roles, "R1").unwrap();
        // off it: where the merging road starts, the merging road itself, a road the corridor dropped
        let feeder = s.roles.feeders[0][0];
        let feeder_start = g.road(feeder).unwrap().from.to_string();
        for off in [feeder_start.as_str(), &feeder.to_string(), "R8"] {
            let e = check_via(g, &s.roles, off).unwrap_err().to_string();
            assert!(e.starts_with(&format!("--via `{off}`")), "{e}");
        }
    }

    #[test]
    fn feeder_length_trims_the_merging_road() {
        let opts = SimplifyOptions {
            feeder_length_m: Some(120.0),
            ..Default::default()
        };
        let s = simplify(&highway(), &opts).unwrap();
        assert_eq!(s.steps.last().unwrap().step, "trim_feeders");
        let m = &corridor_merges(&s.graph, &s.roles)[0];
        assert!(close(m.merge_m, 120.0), "{m:?}");
        assert!(s.graph.invariant_violations().is_empty());
    }

    #[test]
    fn keep_lanes_keeps_every_lane_with_its_drops_and_acceleration_lane() {
        use mapc_graph::LaneEnd;
        // As read from OSM: the builder's lane 0 to lane 0 connections are a guess, to be derived again.
        let mut raw = highway();
        raw.source.format = mapc_graph::SourceFormat::OsmXml;
        let opts = SimplifyOptions {
            keep_lanes: true,
            ..Default::default()
        };
        let s = simplify(&raw, &opts).unwrap();
        let names: Vec<&str> = s.steps.iter().map(|r| r.step.as_str()).collect();
        assert_eq!(names[4], "connect_lanes");
        let g = &s.graph;
        assert!(g.invariant_violations().is_empty());
        assert!(g.lane_continuity_violations().is_empty());
        // The joints where lanes change stay (J1: 3 -> 2 lanes, J6: 1 -> 2); the ramp's two pieces are joined.
        // (R6 and R7 have as many lanes: the joint at J6 goes once the collector R8 is dropped)
        assert_eq!(
            s.roles.main,
            vec![RoadId(0), RoadId(1), RoadId(4), RoadId(6)]
        );
        assert_eq!(s.roles.feeders, vec![vec![RoadId(2)]]);
        let lanes = |r: u32| g.road(RoadId(r)).unwrap().lanes.len();
        assert_eq!(
            [lanes(0), lanes(1), lanes(2), lanes(4), lanes(6)],
            [3, 2, 1, 3, 2]
        );
        // The merge J2: 2 + 1 lanes into 3, the ramp on the right takes lane 0 and the main road lanes 1 and 2.
        let links = |from: u32, to: u32| -> Vec<(u8, u8)> {
            g.connections
                .iter()
                .filter(|k| k.from_road == RoadId(from) && k.to_road == RoadId(to))
                .map(|k| (k.from_lane, k.to_lane))
                .collect()
        };
        assert_eq!(links(2, 4), [(0, 0)]);
        assert_eq!(links(1, 4), [(0, 1), (1, 2)]);
        // J1 loses the rightmost lane; J5 (the exit dropped) too.
        assert_eq!(links(0, 1), [(1, 0), (2, 1)]);
        assert_eq!(links(4, 6), [(1, 0), (2, 1)]);
        let end = |r: u32, l: usize| g.road(RoadId(r)).unwrap().lanes[l].end;
        assert_eq!(end(0, 0), Some(LaneEnd::Drop));
        assert_eq!(end(4, 0), Some(LaneEnd::Acceleration));
        assert_eq!(end(4, 1), None);
        assert_eq!(end(4, 2), None);
        // Lengths are kept as in the one-lane corridor.
        let one_lane = simplify(&raw, &SimplifyOptions::default()).unwrap();
        let main_len = |s: &Simplified| Corridor::chain_length_m(&s.graph, &s.roles.main);
        assert!(close(main_len(&s), main_len(&one_lane)));
        // A lane that stops without being recorded as ending breaks the invariants.
        let mut c = Corridor::new(g.clone());
        c.lanes_connected = true;
        c.graph.road_mut(RoadId(0)).unwrap().lanes[0].end = None;
        let err = crate::transform::check(&c, "broken", None)
            .unwrap_err()
            .to_string();
        assert!(err.contains("lane 0 of road R0 stops"), "{err}");
    }

    #[test]
    fn a_broken_step_is_caught_by_the_invariants() {
        let mut c = Corridor::new(highway());
        let opts = SimplifyOptions::default();
        let steps = crate::transform::simplify_steps(&opts);
        crate::transform::run_steps(&mut c, &steps, &opts).unwrap();
        let before = (
            Corridor::chain_length_m(&c.graph, &c.main),
            vec![Corridor::chain_length_m(&c.graph, &c.feeders[0])],
        );
        c.graph.roads[0].length_m += 5.0;
        let err = crate::transform::check(&c, "broken", Some(&before))
            .unwrap_err()
            .to_string();
        assert!(
            err.contains("broken") && err.contains("main road's length"),
            "{err}"
        );
        let lane = c.graph.roads[1].lanes[0].clone();
        c.graph.roads[1].lanes.push(lane);
        let err = crate::transform::check(&c, "broken", None)
            .unwrap_err()
            .to_string();
        assert!(err.contains("2 lanes"), "{err}");
    }
}

/// The paper's corridor on the real map (docs/reference.md sec. 6).
#[cfg(test)]
mod real_map_tests {
    use super::*;
    use std::path::Path;

    pub(crate) const PAPER_VIA: [&str; 3] =
        ["osm-way:59440544", "osm-way:8667198", "osm-way:8708084"];

    #[test]
    fn i696_paper_route_gives_the_papers_merge() {
        let map = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../maps/i696.osm");
        let raw = mapc_import::import_path(&map, &mapc_import::ImportOptions::default()).unwrap();
        let opts = SimplifyOptions {
            via: PAPER_VIA.map(String::from).to_vec(),
            ..Default::default()
        };
        let s = simplify(&raw, &opts).unwrap();
        let merges = corridor_merges(&s.graph, &s.roles);
        let m = merges
            .iter()
            .find(|m| m.osm_node == Some(61862553))
            .expect("the I-696 merge is on the corridor");
        // The importer's ellipsoidal lengths run ~0.1-0.25% above a spherical estimate (3187 / 2434 / 5034 m).
        assert!((m.main_before_m - 3187.0).abs() < 20.0, "{m:?}");
        assert!((m.merge_m - 2434.0).abs() < 15.0, "{m:?}");
        assert!((m.main_after_m - 5034.0).abs() < 25.0, "{m:?}");
        assert!(m.merging_is_major, "I-696 has the right of way: {m:?}");
        assert!(m.merging_label.contains("696"), "{m:?}");
    }
}
