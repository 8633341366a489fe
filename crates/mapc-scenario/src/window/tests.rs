use super::*;
use crate::Scenario;
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
    let cut = cut_one(&g, "osm:1002", &shape).unwrap();
    let w = &cut.regions[0];
    assert!((w.upstream_m - 600.0).abs() < 1e-9 && (w.merge_m[0] - 200.0).abs() < 1e-9);
    assert!((w.downstream_m - 100.0).abs() < 1e-9);
    assert_eq!(cut.notes.len(), 3);
    assert!(cut.graph.invariant_violations().is_empty());
    assert!((cut.graph.total_lane_length_m() - g.total_lane_length_m()).abs() < 1e-6);
    // Three cuts: three new roads above the largest id, three new through junctions.
    assert_eq!(cut.graph.roads.len(), g.roads.len() + 3);
    assert_eq!(cut.main_entry, RoadId(0));
    let (scenario, _) = window_of(&cut, &source, &shape, &DemandOverride::default());
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
            (w.merge_entries[0].to_string().as_str(), 200.0)
        ]
    );
    let control = scenario.control.as_ref().unwrap();
    assert_eq!(control.n_av, 5);
    assert_eq!(control.region.len(), w.roads().len());
    // The scenario comes back from TOML exactly, and resolves against its graph.
    let back = Scenario::from_toml(&scenario.to_toml(), std::path::Path::new("w.toml")).unwrap();
    assert_eq!(back, scenario);
    let dir = std::env::temp_dir().join(format!("mapc-window-test-{}", std::process::id()));
    cut.graph.save(&dir.join("w.graph.json")).unwrap();
    let resolved = ResolvedScenario::resolve(scenario, &dir, "w.toml").unwrap();
    assert_eq!(resolved.region_roads, w.roads());
    std::fs::remove_dir_all(dir).unwrap();
}

#[test]
fn shortfalls_and_non_merges_are_named() {
    let g = corridor();
    let source = ResolvedScenario::load("simple_merge").unwrap();
    let mut shape = SourceShape::of(&source).unwrap();
    shape.upstream_m = 1600.0;
    let err = cut_one(&g, "J2", &shape).unwrap_err().to_string();
    assert!(
        err.contains("main road before J2") && err.contains("100.0 m short"),
        "{err}"
    );
    shape.upstream_m = 600.0;
    shape.merge_m = 2000.0;
    let err = cut_one(&g, "J2", &shape).unwrap_err().to_string();
    assert!(err.contains("merging road into J2"), "{err}");
    let err = cut_one(&g, "J0", &shape).unwrap_err().to_string();
    assert!(
        err.contains("not inside the corridor's main road") && err.contains("J2 (osm:1002)"),
        "{err}"
    );
    let err = cut_one(&g, "osm:77", &shape).unwrap_err().to_string();
    assert!(err.contains("osm:77"), "{err}");
}

#[test]
fn a_boundary_near_a_junction_snaps_to_it() {
    let g = corridor();
    let source = ResolvedScenario::load("simple_merge").unwrap();
    let mut shape = SourceShape::of(&source).unwrap();
    shape.upstream_m = 1499.8; // the corridor's start is 1500 m before the merge
    let cut = cut_one(&g, "J2", &shape).unwrap();
    let w = &cut.regions[0];
    assert_eq!(w.upstream_m, 1500.0);
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

/// The paper's I-696 corridor as shipped (`scenarios/i696.corridor.graph.json`): five merges, J43 (the paper's),
/// J59 446 m after it, J37 346 m after that, J60 and J61.
fn i696() -> LaneGraph {
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../../scenarios/i696.corridor.graph.json");
    LaneGraph::load(&path).unwrap()
}

fn simple_merge_shape() -> SourceShape {
    SourceShape::of(&ResolvedScenario::load("simple_merge").unwrap()).unwrap()
}

fn requests(junctions: &[(&str, Option<f64>)]) -> Vec<WindowRequest> {
    junctions
        .iter()
        .map(|&(j, up)| WindowRequest {
            junction: j.to_string(),
            upstream_m: up,
            fit: None,
        })
        .collect()
}

/// Regions' roads are disjoint, each region's lengths are what was asked for (to 0.5 m), and the main-road
/// intervals follow each other without overlap.
fn check_regions(cut: &WindowsCut, ups: &[f64], shape: &SourceShape) {
    let mut seen = std::collections::HashSet::new();
    for (r, up) in cut.regions.iter().zip(ups) {
        assert!((r.upstream_m - up).abs() <= SNAP_M, "{r:?}");
        assert!(
            (r.downstream_m - shape.downstream_m).abs() <= SNAP_M,
            "{r:?}"
        );
        for m in &r.merge_m {
            assert!((m - shape.merge_m).abs() <= SNAP_M, "{r:?}");
        }
        for road in r.roads() {
            assert!(seen.insert(road), "road {road} in two regions");
        }
        let main_len: f64 = r
            .upstream_roads
            .iter()
            .chain(&r.between_roads)
            .chain(&r.downstream_roads)
            .map(|x| cut.graph.road(*x).unwrap().length_m)
            .sum();
        assert!((main_len - (r.end_m() - r.start_m())).abs() < 1e-6);
    }
    for pair in cut.regions.windows(2) {
        assert!(pair[0].end_m() <= pair[1].start_m() + SNAP_M, "{pair:?}");
    }
    assert!(cut.graph.invariant_violations().is_empty());
}

#[test]
fn two_windows_that_overlap_are_refused_naming_both() {
    let shape = simple_merge_shape();
    let err = cut_windows(
        &i696(),
        &requests(&[("osm:61862553", None), ("osm:62339771", None)]),
        &shape,
        Overlap::Refuse,
    )
    .unwrap_err()
    .to_string();
    // J59 lies 446.0 m after J43: its 600 m before reach 254.0 m back past J43's end (100 m after J43).
    assert!(
        err.contains("J43 (osm:61862553)")
            && err.contains("J59 (osm:62339771)")
            && err.contains("overlap by 254.0 m"),
        "{err}"
    );
}

#[test]
fn all_keeps_the_first_of_overlapping_merges() {
    let g = i696();
    let shape = simple_merge_shape();
    let all: Vec<WindowRequest> =
        crate::simplify::corridor_merges(&g, &CorridorRoles::of(&g).unwrap())
            .iter()
            .map(|m| WindowRequest::at(&m.junction))
            .collect();
    let cut = cut_windows(&g, &all, &shape, Overlap::SkipLater).unwrap();
    let merges: Vec<String> = cut
        .regions
        .iter()
        .map(|r| r.merges[0].to_string())
        .collect();
    assert_eq!(merges, ["J43", "J37", "J60"]);
    assert_eq!(cut.skipped.len(), 2, "{:?}", cut.skipped);
    assert!(cut.skipped[0].starts_with("J59 (osm:62339771)") && cut.skipped[0].contains("J43"));
    assert!(cut.skipped[1].starts_with("J61 (osm:62339796)") && cut.skipped[1].contains("J60"));
    check_regions(&cut, &[600.0; 3], &shape);
    assert_eq!(cut.graph.roads.len(), g.roads.len() + 9);
}

#[test]
fn windows_cut_shorter_upstream_fit_three_close_merges() {
    let g = i696();
    let shape = simple_merge_shape();
    // Out of order on purpose: windows are cut in driving order.
    let cut = cut_windows(
        &g,
        &requests(&[
            ("osm:61860453", Some(240.0)),
            ("osm:61862553", None),
            ("osm:62339771", Some(340.0)),
        ]),
        &shape,
        Overlap::Refuse,
    )
    .unwrap();
    let merges: Vec<String> = cut
        .regions
        .iter()
        .map(|r| r.merges[0].to_string())
        .collect();
    assert_eq!(merges, ["J43", "J59", "J37"]);
    check_regions(&cut, &[600.0, 340.0, 240.0], &shape);
    // One metre more before J37 and its window reaches into J59's.
    let err = cut_windows(
        &g,
        &requests(&[("osm:62339771", Some(340.0)), ("osm:61860453", Some(247.0))]),
        &shape,
        Overlap::Refuse,
    )
    .unwrap_err()
    .to_string();
    assert!(err.contains("overlap by 1.3 m"), "{err}");
}

#[test]
fn joined_windows_make_one_region_over_three_merges() {
    let g = i696();
    let shape = simple_merge_shape();
    let cut = cut_windows(
        &g,
        &requests(&[("J43", None), ("J59", None), ("J37", None)]),
        &shape,
        Overlap::Join,
    )
    .unwrap();
    assert_eq!(cut.regions.len(), 1);
    let r = &cut.regions[0];
    assert_eq!(r.merges.len(), 3);
    check_regions(&cut, &[600.0], &shape);
    // From 600 m before J43 to 100 m after J37: 600 + 446.0 + 345.7 + 100 m of main road.
    let span = r.end_m() - r.start_m();
    assert!(
        (span - (600.0 + 3983.0886 - 3191.4065 + 100.0)).abs() < 0.01,
        "{span}"
    );
}

/// The test highway's merge J2 has 1500 m of main road before it, a 723.6 m merging road and 1523.1 m after.
fn fit_to(floor: f64) -> Option<Fit> {
    Some(Fit::new(floor).unwrap())
}

#[test]
fn a_short_length_is_refused_naming_fit_and_fitted_with_it() {
    let g = corridor();
    let mut shape = simple_merge_shape();
    shape.upstream_m = 1600.0;
    let err = cut_one(&g, "J2", &shape).unwrap_err().to_string();
    assert!(
        err.contains(
            "the main road before J2 (osm:1002) is 1500.0 m long; the window needs 1600.0 m (100.0 m short; \
             `--fit` cuts what the map has down to 800.0 m)"
        ),
        "{err}"
    );
    let cut = cut_one(&g, WindowRequest::at("J2").fitted(fit_to(0.5)), &shape).unwrap();
    let w = &cut.regions[0];
    assert_eq!(w.upstream_m, 1500.0);
    assert!((w.merge_m[0] - 200.0).abs() < 1e-9 && (w.downstream_m - 100.0).abs() < 1e-9);
    assert_eq!(w.fitted.len(), 1, "{:?}", w.fitted);
    let f = &w.fitted[0];
    assert_eq!(
        (f.part, f.asked_m, f.fitted_m),
        (Part::Upstream, 1600.0, 1500.0)
    );
    assert_eq!(f.short_by_m(), 100.0);
    // The window starts at the corridor's entry: its first road is the main road's first.
    assert!(w.upstream_roads.contains(&cut.main_entry), "{cut:?}");
    assert!(
        cut.notes[0].contains("boundary at junction J0"),
        "{:?}",
        cut.notes
    );
    assert!(cut.graph.invariant_violations().is_empty());
}

#[test]
fn a_fit_stops_at_its_floor() {
    let g = corridor();
    let mut shape = simple_merge_shape();
    // 1500 m is 0.48 of 3100 m: below the default floor.
    shape.upstream_m = 3100.0;
    let err = cut_one(&g, "J2", &shape).unwrap_err().to_string();
    assert!(
        err.contains("(1600.0 m short; `--fit` cuts what the map has down to 1550.0 m, `--fit-floor 0.48` down to 1500.0 m)"),
        "{err}"
    );
    let err = cut_one(&g, WindowRequest::at("J2").fitted(fit_to(0.5)), &shape)
        .unwrap_err()
        .to_string();
    assert!(
        err.contains(
            "below the --fit floor of 1550.0 m, 0.5 of it; `--fit-floor 0.48` would cut it"
        ),
        "{err}"
    );
    let cut = cut_one(&g, WindowRequest::at("J2").fitted(fit_to(0.48)), &shape).unwrap();
    let w = &cut.regions[0];
    assert_eq!(w.upstream_m, 1500.0);
    for bad in [0.0, -0.5, 1.5, f64::NAN] {
        let err = Fit::new(bad).unwrap_err().to_string();
        assert!(err.contains("--fit-floor"), "{err}");
    }
    assert_eq!(Fit::default().floor, 0.5);
}

#[test]
fn a_fit_takes_the_whole_merging_road_and_the_rest_of_the_corridor() {
    let g = corridor();
    let mut shape = simple_merge_shape();
    shape.merge_m = 800.0;
    shape.downstream_m = 1600.0;
    let err = cut_one(&g, "J2", &shape).unwrap_err().to_string();
    assert!(
        err.contains("merging road into J2") && err.contains("76.4 m short"),
        "{err}"
    );
    let cut = cut_one(&g, WindowRequest::at("J2").fitted(fit_to(0.5)), &shape).unwrap();
    let w = &cut.regions[0];
    let parts: Vec<Part> = w.fitted.iter().map(|f| f.part).collect();
    assert_eq!(parts, [Part::MergingRoad, Part::Downstream]);
    // Upstream fits as asked; the merging road is all of it, the main road after runs to the corridor's end.
    assert!((w.upstream_m - 600.0).abs() < 1e-9);
    let roles = CorridorRoles::of(&g).unwrap();
    let feeder: f64 = roles.feeders[0]
        .iter()
        .map(|r| g.road(*r).unwrap().length_m)
        .sum();
    assert!(
        (w.merge_m[0] - feeder).abs() < 1e-9 && (feeder - 723.6).abs() < 0.1,
        "{feeder}"
    );
    let j2 = g.find_junction("J2").unwrap();
    let after: f64 = roles
        .main
        .iter()
        .skip_while(|r| g.road(**r).unwrap().from != j2)
        .map(|r| g.road(*r).unwrap().length_m)
        .sum();
    assert!(after < 1600.0 && after > 1000.0, "{after}");
    assert_eq!(w.downstream_m, after);
    assert_eq!(w.merge_roads[0][0], w.merge_entries[0]);
    assert_eq!(w.downstream_roads.last(), cut.roles.main.last(), "{cut:?}");
    // Only the upstream boundary cuts a road: the others fall on the corridor's ends.
    assert_eq!(cut.graph.roads.len(), g.roads.len() + 1, "{:?}", cut.notes);
}

#[test]
fn a_fit_changes_nothing_where_the_map_has_the_lengths() {
    let g = corridor();
    let shape = simple_merge_shape();
    let plain = cut_one(&g, "J2", &shape).unwrap();
    let fitted = cut_one(&g, WindowRequest::at("J2").fitted(fit_to(0.5)), &shape).unwrap();
    assert!(fitted.regions[0].fitted.is_empty());
    assert_eq!(plain.graph, fitted.graph);
    assert_eq!(plain.regions[0].roads(), fitted.regions[0].roads());
}

#[test]
fn the_scenario_records_the_fitted_lengths() {
    let g = corridor();
    let source = ResolvedScenario::load("simple_merge").unwrap();
    let mut shape = SourceShape::of(&source).unwrap();
    shape.upstream_m = 1600.0;
    let cut = cut_one(&g, WindowRequest::at("J2").fitted(fit_to(0.5)), &shape).unwrap();
    let w = &cut.regions[0];
    let (scenario, _) = window_of(&cut, &source, &shape, &DemandOverride::default());
    let control = scenario.control.as_ref().unwrap();
    let window = control.window.as_ref().unwrap();
    assert_eq!(window.upstream_m, 1500.0);
    assert_eq!(control.region.len(), w.roads().len());
    assert!(
        scenario
            .description
            .contains("Fitted to the map: upstream 1500.0 m of 1600.0 m."),
        "{}",
        scenario.description
    );
}

#[test]
fn a_fitted_window_starts_where_the_one_before_ends() {
    let g = i696();
    let shape = simple_merge_shape();
    let asked = [("osm:61862553", None), ("osm:62339771", None)];
    // Without --fit the overlap is refused, and the refusal says what --fit does: J59 lies 446.0 m after J43,
    // whose window ends 100 m after it.
    let err = cut_windows(&g, &requests(&asked), &shape, Overlap::Refuse)
        .unwrap_err()
        .to_string();
    assert!(
        err.contains("`--fit` starts the second where the first ends, 346.0 m before its merge"),
        "{err}"
    );
    let fitted: Vec<WindowRequest> = requests(&asked)
        .into_iter()
        .map(|r| r.fitted(fit_to(0.5)))
        .collect();
    let cut = cut_windows(&g, &fitted, &shape, Overlap::Refuse).unwrap();
    check_regions(&cut, &[600.0, 346.0], &shape);
    assert!(cut.regions[0].fitted.is_empty());
    let f = &cut.regions[1].fitted;
    assert_eq!(f.len(), 1, "{f:?}");
    assert_eq!(f[0].part, Part::Upstream);
    assert!((f[0].fitted_m - 346.0).abs() < 0.05, "{f:?}");
    assert!(f[0].reason.contains("J43 (osm:61862553)"), "{f:?}");
    // The two regions touch: the first's end is the second's start.
    assert!((cut.regions[0].end_m() - cut.regions[1].start_m()).abs() < 1e-6);
    // Joined, a fit does not shorten: the two become one region from 600 m before J43.
    let joined = cut_windows(&g, &fitted, &shape, Overlap::Join).unwrap();
    assert_eq!(joined.regions.len(), 1);
    assert!(joined.regions[0].fitted.is_empty());
}

#[test]
fn all_with_fit_keeps_every_merge_that_fits_above_the_floor() {
    let g = i696();
    let shape = simple_merge_shape();
    let all: Vec<WindowRequest> =
        crate::simplify::corridor_merges(&g, &CorridorRoles::of(&g).unwrap())
            .iter()
            .map(|m| WindowRequest::at(&m.junction).fitted(fit_to(0.5)))
            .collect();
    let cut = cut_windows(&g, &all, &shape, Overlap::SkipLater).unwrap();
    let merges: Vec<String> = cut
        .regions
        .iter()
        .map(|r| r.merges[0].to_string())
        .collect();
    // J59 now fits after J43 (346.0 m before it); J37 would keep only 245.7 m after J59's window, below the
    // 300 m floor: skipped, saying so.
    assert!(
        merges.starts_with(&["J43".to_string(), "J59".to_string()]),
        "{merges:?}"
    );
    assert!(!merges.contains(&"J37".to_string()), "{merges:?}");
    let j37 = cut.skipped.iter().find(|s| s.starts_with("J37")).unwrap();
    assert!(
        j37.contains("--fit would leave it 245.7 m, below its floor of 300.0 m"),
        "{j37}"
    );
    for pair in cut.regions.windows(2) {
        assert!(pair[0].end_m() <= pair[1].start_m() + SNAP_M, "{pair:?}");
    }
    assert!(cut.graph.invariant_violations().is_empty());
    // Each fitted window says by how much.
    for r in &cut.regions {
        for f in &r.fitted {
            assert!(
                f.fitted_m >= 0.5 * f.asked_m && f.short_by_m() > SNAP_M,
                "{f:?}"
            );
        }
    }
}

/// Flow's I-210 corridor with every lane as shipped, its five-lane entry road narrowed to one lane.
fn i210_with_a_one_lane_entry() -> (LaneGraph, RoadId) {
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../../scenarios/i210_window_lanes.graph.json");
    let mut g = LaneGraph::load(&path).unwrap();
    let entry = g.find_roads("R190").unwrap()[0];
    g.connections
        .retain(|c| c.from_road != entry || c.from_lane == 0);
    let road = g.roads.iter_mut().find(|r| r.id == entry).unwrap();
    road.lanes.truncate(1);
    (g, entry)
}

#[test]
fn demand_is_sized_on_a_narrower_entry_road_and_an_entry_that_cannot_take_it_says_so() {
    let (g, entry) = i210_with_a_one_lane_entry();
    let source = ResolvedScenario::load("simple_merge").unwrap();
    let shape = SourceShape::of(&source).unwrap();
    let cut = cut_one(&g, WindowRequest::at("J59"), &shape).unwrap();
    assert_eq!(cut.main_entry, entry);
    let main_vph = |sc: &Scenario| -> f64 {
        sc.flows
            .iter()
            .filter(|f| f.from == entry.to_string())
            .map(|f| f.vehs_per_hour)
            .sum()
    };
    // the source's 2000 veh/h per lane once (the entry's one lane), not five times (the window's lanes)
    let (sc, notes) = window_of(&cut, &source, &shape, &DemandOverride::default());
    assert!((main_vph(&sc) - 2000.0).abs() < 1e-6, "{notes:?}");
    assert!(
        notes
            .iter()
            .any(|n| n.contains("narrower than the window's 5 lanes")),
        "{notes:?}"
    );
    assert!(!notes.iter().any(|n| n.starts_with("warning")), "{notes:?}");
    // asked for more than one lane takes in: said, naming the entry
    let demand = DemandOverride {
        main_vph: Some(6000.0),
        ..DemandOverride::default()
    };
    let (sc, notes) = window_of(&cut, &source, &shape, &demand);
    assert!((main_vph(&sc) - 6000.0).abs() < 1e-6);
    let warning = notes
        .iter()
        .find(|n| n.starts_with("warning"))
        .expect("a warning");
    assert!(
        warning.contains(&format!("entry {entry} (1 lane(s)"))
            && warning.contains("less than its demand of 6000 veh/h"),
        "{warning}"
    );
}

/// The cut of one window: a list of one.
fn cut_one(
    g: &LaneGraph,
    request: impl Into<WindowRequest>,
    shape: &SourceShape,
) -> Result<WindowsCut, TransformError> {
    cut_windows(g, &[request.into()], shape, Overlap::Refuse)
}

/// The one-window scenario of `cut` as `w` (its graph `w.graph.json`), with its demand lines.
fn window_of(
    cut: &WindowsCut,
    source: &ResolvedScenario,
    shape: &SourceShape,
    demand: &DemandOverride,
) -> (Scenario, Vec<String>) {
    windows_scenario(cut, source, shape, "w", "w.graph.json", demand, true).unwrap()
}
