//! The export read back with mapc's own SUMO importer (no SUMO needed): lane lengths, internal lengths and right
//! of way survive, for scenarios (the Simple Merge, the I-696 window) and for SUMO nets imported and exported again.

use mapc_graph::{LaneGraph, RightOfWay};
use mapc_scenario::ResolvedScenario;
use mapc_sumo::names::SumoNames;
use std::collections::HashMap;
use std::path::{Path, PathBuf};

fn repo(rel: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../..")
        .join(rel)
}

fn scratch(name: &str) -> PathBuf {
    PathBuf::from(env!("CARGO_TARGET_TMPDIR"))
        .join(format!("mapc-sumo-{name}-{}", std::process::id()))
}

fn read_back(dir: &Path, file: &str) -> LaneGraph {
    mapc_import::import_path(&dir.join(file), &mapc_import::ImportOptions::default())
        .unwrap_or_else(|e| panic!("mapc cannot read its own export back: {e}"))
}

/// One connection, by SUMO ids: (from edge, from lane, to edge, to lane) -> (internal length, right of way).
type Links = HashMap<(String, u8, String, u8), (f64, RightOfWay)>;

fn links(g: &LaneGraph, edge_of: &dyn Fn(&LaneGraph, usize) -> String) -> Links {
    let index = |id| {
        g.roads
            .binary_search_by_key(&id, |r: &mapc_graph::Road| r.id)
            .unwrap()
    };
    g.connections
        .iter()
        .map(|c| {
            (
                (
                    edge_of(g, index(c.from_road)),
                    c.from_lane,
                    edge_of(g, index(c.to_road)),
                    c.to_lane,
                ),
                (c.via_length_m, c.right_of_way),
            )
        })
        .collect()
}

fn sumo_id(g: &LaneGraph, i: usize) -> String {
    g.roads[i].provenance.sumo_ids[0].clone()
}

/// Compare `original` (its roads named as the export names them) with `back`, read from the export.
fn assert_same(original: &LaneGraph, back: &LaneGraph, lane_tol_m: f64, via_tol_m: f64) -> usize {
    let names = SumoNames::of(original);
    assert_eq!(back.roads.len(), original.roads.len(), "roads");
    let back_roads: HashMap<String, &mapc_graph::Road> = back
        .roads
        .iter()
        .map(|r| (r.provenance.sumo_ids[0].clone(), r))
        .collect();
    let mut lanes = 0;
    for (road, name) in original.roads.iter().zip(&names.edges) {
        let b = back_roads
            .get(name)
            .unwrap_or_else(|| panic!("edge {name} lost"));
        assert_eq!(b.lanes.len(), road.lanes.len(), "{name}: lanes");
        assert!(
            (b.length_m - road.length_m).abs() <= lane_tol_m,
            "{name}: {} m against {} m",
            b.length_m,
            road.length_m
        );
        for (x, y) in road.lanes.iter().zip(&b.lanes) {
            assert!(
                (x.length_m - y.length_m).abs() <= lane_tol_m,
                "{name} lane {}: {} m against {} m",
                x.index,
                y.length_m,
                x.length_m
            );
            assert!(
                (x.speed_mps - y.speed_mps).abs() <= 0.005,
                "{name} lane {}: speed",
                x.index
            );
            lanes += 1;
        }
        assert_eq!(b.priority, road.priority, "{name}: priority");
    }
    let named = |_: &LaneGraph, i: usize| names.edges[i].clone();
    let expected = links(original, &named);
    let got = links(back, &sumo_id);
    assert_eq!(got.len(), expected.len(), "connections");
    for (key, (via, row)) in &expected {
        let (b_via, b_row) = got
            .get(key)
            .unwrap_or_else(|| panic!("connection {key:?} lost"));
        assert_eq!(b_row, row, "{key:?}: right of way");
        assert!(
            (b_via - via.max(mapc_sim::network::MIN_VIA_LENGTH_M)).abs() <= via_tol_m,
            "{key:?}: internal length {b_via} against {via}"
        );
    }
    lanes
}

/// The net with every connection's `state` removed: right of way then comes from the junctions' request tables.
fn without_states(net: &str) -> String {
    let mut out = String::with_capacity(net.len());
    let mut rest = net;
    while let Some(i) = rest.find(" state=\"") {
        out.push_str(&rest[..i]);
        let after = &rest[i + 8..];
        rest = &after[after.find('"').unwrap() + 1..];
    }
    out.push_str(rest);
    out
}

fn check_scenario(arg: &str, stem: &str) {
    // A file of the repository, or a built-in name.
    let path = repo(arg);
    let rs = if path.exists() {
        ResolvedScenario::load(path.to_str().unwrap())
    } else {
        ResolvedScenario::load(arg)
    }
    .unwrap();
    let dir = scratch(stem);
    let summary = mapc_sumo::export_scenario(&rs, &dir).unwrap();
    assert_eq!(summary.files.len(), 4);
    let net = format!("{stem}.net.xml");
    let back = read_back(&dir, &net);
    let lanes = assert_same(&rs.graph, &back, 0.1, 1e-3);
    assert_eq!(
        lanes,
        rs.graph.roads.iter().map(|r| r.lanes.len()).sum::<usize>()
    );
    // The request tables say the same as the states.
    let text = std::fs::read_to_string(dir.join(&net)).unwrap();
    std::fs::write(dir.join("stateless.net.xml"), without_states(&text)).unwrap();
    assert!(
        !std::fs::read_to_string(dir.join("stateless.net.xml"))
            .unwrap()
            .contains("state=")
    );
    assert_same(&rs.graph, &read_back(&dir, "stateless.net.xml"), 0.1, 1e-3);
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn simple_merge_lanes_read_back_within_a_tenth_of_a_metre() {
    check_scenario("simple_merge", "simple_merge");
}

#[test]
fn i696_window_lanes_read_back_within_a_tenth_of_a_metre() {
    check_scenario("scenarios/i696_window.toml", "i696_window");
}

fn check_sumo_round_trip(map: &str) {
    let original =
        mapc_import::import_path(&repo(map), &mapc_import::ImportOptions::default()).unwrap();
    let dir = scratch(map.replace('/', "_").as_str());
    mapc_sumo::export_network(&original, "net", &dir).unwrap();
    let back = read_back(&dir, "net.net.xml");
    // SUMO ids are kept, so the round trip is compared id by id.
    assert_eq!(
        SumoNames::of(&original).edges,
        original
            .roads
            .iter()
            .map(|r| r.provenance.sumo_ids[0].clone())
            .collect::<Vec<_>>()
    );
    assert_same(&original, &back, 0.5, 0.01);
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn simple_merge_net_round_trip_keeps_lengths_and_right_of_way() {
    check_sumo_round_trip("maps/simple_merge.net.xml");
}

#[test]
fn i696_proxy_net_round_trip_keeps_lengths_and_right_of_way() {
    check_sumo_round_trip("maps/i696_onelane_proxy.net.xml");
}

#[test]
fn routes_follow_mapc_sims_routes_and_flows() {
    let rs = ResolvedScenario::load("simple_merge").unwrap();
    let dir = scratch("routes");
    mapc_sumo::export_scenario(&rs, &dir).unwrap();
    let routes = std::fs::read_to_string(dir.join("simple_merge.rou.xml")).unwrap();
    for needle in [
        r#"<flow id="main_human" type="human" begin="1.0000" end="86400.0000" vehsPerHour="1800.0000" departLane="free" departSpeed="10.0000">"#,
        r#"<flow id="ramp_human" type="human" begin="1.0000" end="86400.0000" vehsPerHour="200.0000" departLane="free" departSpeed="7.5000">"#,
        r#"<route edges="inflow_merge bottom center"/>"#,
        r#"<vehicle id="initial_1" type="human" depart="0.50" departLane="0" departPos="79.9000" departSpeed="0.0000">"#,
        r#"impatience="0.5000""#,
        r#"speedDev="0.1000""#,
    ] {
        assert!(routes.contains(needle), "missing {needle}");
    }
    let cfg = std::fs::read_to_string(dir.join("simple_merge.sumocfg")).unwrap();
    for needle in [
        r#"<step-length value="0.5000"/>"#,
        r#"<time-to-teleport value="-1"/>"#,
        r#"<end value="1001.00"/>"#,
    ] {
        assert!(cfg.contains(needle), "missing {needle}");
    }
    let manifest: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(dir.join("simple_merge.mapc.json")).unwrap())
            .unwrap();
    assert_eq!(manifest["n_av"], 5);
    assert_eq!(manifest["av_types"], serde_json::json!(["av"]));
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn a_stepping_sumo_18_cannot_express_is_refused_before_anything_is_written() {
    let mut scenario = mapc_scenario::Scenario::simple_merge();
    scenario.vehicle_types.get_mut("av").unwrap().idm_stepping_s = 0.1;
    let rs = ResolvedScenario::resolve(scenario, Path::new("."), "odd.toml").unwrap();
    let dir = scratch("stepping");
    let err = mapc_sumo::export_scenario(&rs, &dir)
        .unwrap_err()
        .to_string();
    assert!(
        err.starts_with("odd.toml: ") && err.contains("`av`") && err.contains("0.1"),
        "{err}"
    );
    assert!(!dir.exists());
}
