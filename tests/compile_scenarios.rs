//! End-to-end tests of `mapc simplify` and `mapc window` on the real maps, with golden outputs in
//! `tests/golden/<map>/{simplify,window}.json`. `MAPC_BLESS=1 cargo test --test compile_scenarios` rewrites them
//! (the same convention as the import goldens); paths of written files are left out of the goldens.

use serde_json::Value;
use std::path::{Path, PathBuf};

mod common;

use common::{PAPER_VIA, check_golden, mapc_json, root, run_mapc};

fn scratch(name: &str) -> PathBuf {
    common::scratch_dir(&format!("compile-{name}"))
}

fn mapc(args: &[&str]) -> (i32, String, String) {
    let out = run_mapc(args);
    (
        out.status.code().unwrap_or(-1),
        String::from_utf8_lossy(&out.stdout).into_owned(),
        String::from_utf8_lossy(&out.stderr).into_owned(),
    )
}

/// Compare with `tests/golden/<map>/<name>.json`, leaving out the paths of written files.
/// Simplifies maps/i696.osm to the paper's corridor, written to `out`.
fn paper_corridor(out: &Path) -> PathBuf {
    let mut args = vec!["simplify", "maps/i696.osm", "-o", out.to_str().unwrap()];
    args.extend(PAPER_VIA);
    assert_eq!(mapc(&args).0, 0);
    out.to_path_buf()
}

fn golden(map: &str, name: &str, mut value: Value) {
    // regime: simulated figures, checked by the simulator's own tests
    for key in ["output", "scenario", "graph", "render", "map", "regime"] {
        value.as_object_mut().unwrap().remove(key);
    }
    check_golden(
        &root()
            .join("tests/golden")
            .join(map)
            .join(format!("{name}.json")),
        &value,
    );
}

fn the_merge(report: &Value, node: i64) -> &Value {
    report["merges"]
        .as_array()
        .unwrap()
        .iter()
        .find(|m| m["osm_node"] == node)
        .expect("merge on the corridor")
}

#[test]
fn i696_simplify_gives_the_papers_merge() {
    let dir = scratch("simplify");
    let out = dir.join("i696.corridor.graph.json");
    let mut args = vec![
        "simplify",
        "maps/i696.osm",
        "-o",
        out.to_str().unwrap(),
        "--json",
    ];
    args.extend(PAPER_VIA);
    let report = mapc_json(&args);
    let m = the_merge(&report, 61862553);
    let f = |k: &str| m[k].as_f64().unwrap();
    assert!((f("main_before_m") - 3187.0).abs() < 20.0, "{m}");
    assert!((1900.0..=2450.0).contains(&f("merge_m")), "{m}");
    assert!((f("main_after_m") - 5034.0).abs() < 25.0, "{m}");
    assert_eq!(m["merging_is_major"], true);
    let names: Vec<String> = report["steps"]
        .as_array()
        .unwrap()
        .iter()
        .map(|s| s["step"].as_str().unwrap().to_string())
        .collect();
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
    // The corridor file is a sound single-lane graph.
    let g = mapc_graph::LaneGraph::load(&out).unwrap();
    assert!(g.invariant_violations().is_empty());
    assert!(g.roads.iter().all(|r| r.lanes.len() == 1));
    golden("i696", "simplify", report);

    // --explain names every step.
    let mut args = vec![
        "simplify",
        "maps/i696.osm",
        "-o",
        out.to_str().unwrap(),
        "--explain",
    ];
    args.extend(PAPER_VIA);
    let (code, stdout, _) = mapc(&args);
    assert_eq!(code, 0);
    for step in names {
        assert!(stdout.contains(&format!("{step}: ")), "{stdout}");
    }
    std::fs::remove_dir_all(dir).unwrap();
}

#[test]
fn i696_window_matches_the_simple_merge() {
    let dir = scratch("window");
    let corridor = paper_corridor(&dir.join("i696.corridor.graph.json"));
    let scenario = dir.join("w.toml");
    let report = mapc_json(&[
        "window",
        corridor.to_str().unwrap(),
        "--junction",
        "osm:61862553",
        "--match",
        "simple_merge",
        "-o",
        scenario.to_str().unwrap(),
        "--json",
    ]);
    for (k, want) in [
        ("upstream_m", 600.0),
        ("merge_m", 200.0),
        ("downstream_m", 100.0),
    ] {
        assert!(
            (report[k].as_f64().unwrap() - want).abs() <= 0.5,
            "{k}: {report}"
        );
    }
    assert_eq!(report["osm_node"], 61862553);
    // The scenario loads, round-trips through TOML exactly, and its region is the window.
    let resolved = mapc_scenario::ResolvedScenario::load(scenario.to_str().unwrap()).unwrap();
    let s = &resolved.scenario;
    assert_eq!(
        mapc_scenario::Scenario::from_toml(&s.to_toml(), &scenario).unwrap(),
        *s
    );
    assert_eq!(s.flows.len(), 3);
    assert_eq!(
        resolved.region_roads.len(),
        report["region"].as_array().unwrap().len()
    );
    assert!(dir.join("w.graph.json").exists());
    golden("i696", "window", report);

    // A raw map is simplified first; the result is the same window.
    let raw_toml = dir.join("raw.toml");
    let mut args = vec![
        "window",
        "maps/i696.osm",
        "--junction",
        "osm:61862553",
        "-o",
        raw_toml.to_str().unwrap(),
        "--json",
    ];
    args.extend(PAPER_VIA);
    let raw = mapc_json(&args);
    assert_eq!(raw["upstream_m"], 600.0);
    std::fs::remove_dir_all(dir).unwrap();
}

#[test]
fn proxy_net_window_at_gnej18() {
    let dir = scratch("proxy");
    let scenario = dir.join("p.toml");
    let report = mapc_json(&[
        "window",
        "maps/i696_onelane_proxy.net.xml",
        "--junction",
        "gneJ18",
        "--match",
        "simple_merge",
        "-o",
        scenario.to_str().unwrap(),
        "--json",
    ]);
    for (k, want) in [
        ("upstream_m", 600.0),
        ("merge_m", 200.0),
        ("downstream_m", 100.0),
    ] {
        assert!(
            (report[k].as_f64().unwrap() - want).abs() <= 0.5,
            "{k}: {report}"
        );
    }
    assert_eq!(report["sumo_id"], "gneJ18");
    golden("i696_onelane_proxy", "window", report);
    let corridor = dir.join("p.corridor.graph.json");
    let simplified = mapc_json(&[
        "simplify",
        "maps/i696_onelane_proxy.net.xml",
        "--via",
        "gneJ18",
        "-o",
        corridor.to_str().unwrap(),
        "--json",
    ]);
    golden("i696_onelane_proxy", "simplify", simplified);
    std::fs::remove_dir_all(dir).unwrap();
}

#[test]
fn bad_junctions_are_clear_errors() {
    let dir = scratch("errors");
    let corridor = paper_corridor(&dir.join("c.graph.json"));
    let c = corridor.to_str().unwrap();
    let (code, _, stderr) = mapc(&[
        "window",
        c,
        "--junction",
        "osm:1",
        "-o",
        dir.join("x.toml").to_str().unwrap(),
    ]);
    assert_eq!(code, 2);
    assert!(stderr.contains("osm:1"), "{stderr}");
    let (code, _, stderr) = mapc(&[
        "window",
        c,
        "--junction",
        "osm:61862553",
        "--match",
        "nonesuch",
    ]);
    assert_eq!(code, 2);
    assert!(stderr.contains("nonesuch"), "{stderr}");
    let (code, _, stderr) = mapc(&["simplify", "maps/i696.osm", "--via", "osm-way:1", "-o", c]);
    assert_eq!(code, 2);
    assert!(stderr.contains("osm-way:1"), "{stderr}");
    std::fs::remove_dir_all(dir).unwrap();
}

/// The multi-window cut on the shipped corridor: `mapc window` with three merges (two cut shorter upstream)
/// writes exactly `scenarios/i696_3merge.toml`; each window's lengths are the asked ones to 0.5 m; two windows
/// that overlap are refused naming both merges and the overlap; `--all` keeps J43, J37 and J60 and says which
/// merges it skipped.
#[test]
fn i696_three_merges_as_several_windows() {
    let dir = scratch("multi");
    let corridor = "scenarios/i696.corridor.graph.json";
    let out = dir.join("i696_3merge.toml");
    let report = mapc_json(&[
        "window",
        corridor,
        "--junction",
        "osm:61862553",
        "--junction",
        "osm:62339771",
        "--junction",
        "osm:61860453",
        "--upstream-m",
        "osm:62339771=340",
        "--upstream-m",
        "osm:61860453=240",
        "-o",
        out.to_str().unwrap(),
        "--json",
    ]);
    let windows = report["windows"].as_array().unwrap();
    let names: Vec<&str> = windows
        .iter()
        .map(|w| w["name"].as_str().unwrap())
        .collect();
    assert_eq!(names, ["osm:61862553", "osm:62339771", "osm:61860453"]);
    let mut end_before = f64::NEG_INFINITY;
    for (w, up) in windows.iter().zip([600.0, 340.0, 240.0]) {
        let f = |k: &str| w[k].as_f64().unwrap();
        assert!((f("upstream_m") - up).abs() <= 0.5, "{w}");
        assert!(
            (w["merge_m"][0].as_f64().unwrap() - 200.0).abs() <= 0.5,
            "{w}"
        );
        assert!((f("downstream_m") - 100.0).abs() <= 0.5, "{w}");
        assert!((f("end_m") - f("start_m") - up - 100.0).abs() <= 0.5, "{w}");
        assert!(f("start_m") >= end_before, "windows overlap: {report}");
        end_before = f("end_m");
    }
    // The written scenario and graph are the shipped ones, byte for byte.
    for name in ["i696_3merge.toml", "i696_3merge.graph.json"] {
        let written = std::fs::read(dir.join(name)).unwrap();
        let shipped = std::fs::read(root().join("scenarios").join(name)).unwrap();
        assert!(written == shipped, "{name} differs from scenarios/{name}");
    }
    // Demand on every merging road; three controlled regions with disjoint roads.
    let resolved = mapc_scenario::ResolvedScenario::load(out.to_str().unwrap()).unwrap();
    assert_eq!(resolved.scenario.flows.len(), 2 + 5);
    assert_eq!(resolved.windows.len(), 3);
    let roads: usize = resolved.windows.iter().map(|w| w.roads.len()).sum();
    assert_eq!(roads, resolved.region_roads.len());

    let (code, _, stderr) = mapc(&[
        "window",
        corridor,
        "--junction",
        "osm:61862553",
        "--junction",
        "osm:62339771",
        "-o",
        dir.join("x.toml").to_str().unwrap(),
    ]);
    assert_eq!(code, 2);
    assert!(
        stderr.contains("J43 (osm:61862553)")
            && stderr.contains("J59 (osm:62339771)")
            && stderr.contains("overlap by 254.0 m"),
        "{stderr}"
    );
    assert!(!dir.join("x.toml").exists());

    let all = mapc_json(&[
        "window",
        corridor,
        "--all",
        "-o",
        dir.join("all.toml").to_str().unwrap(),
        "--json",
    ]);
    let kept: Vec<&str> = all["windows"]
        .as_array()
        .unwrap()
        .iter()
        .map(|w| w["name"].as_str().unwrap())
        .collect();
    assert_eq!(kept, ["osm:61862553", "osm:61860453", "osm:62339791"]);
    let skipped = all["skipped"].as_array().unwrap();
    assert_eq!(skipped.len(), 2, "{all}");
    assert!(
        skipped[0]
            .as_str()
            .unwrap()
            .starts_with("J59 (osm:62339771)")
    );
    assert!(
        skipped[1]
            .as_str()
            .unwrap()
            .starts_with("J61 (osm:62339796)")
    );

    let (code, _, stderr) = mapc(&[
        "window",
        corridor,
        "--all",
        "--ramp-vph",
        "R54=100",
        "-o",
        dir.join("y.toml").to_str().unwrap(),
    ]);
    assert_eq!(code, 2);
    assert!(
        stderr.contains("--ramp-vph R54") && stderr.contains("not on a merging road"),
        "{stderr}"
    );
    std::fs::remove_dir_all(dir).unwrap();
}

/// I-210's merge at osm:1686590993 has only 530.1 m of main road before it on the map: the Simple Merge's 600 m
/// window is refused, naming `--fit`; with `--fit` the window takes the 530.1 m there are, says so against the
/// source's lengths and what it does to the observation (not rescaled: the policy's L is kept; the controlled
/// region is shorter), and the scenario written is the fitted window.
#[test]
fn i210_merge_short_of_600_m_is_fitted() {
    let dir = scratch("fit");
    let scenario = dir.join("f.toml");
    let base = [
        "window",
        "maps/i210.net.xml",
        "--junction",
        "osm:1686590993",
        "-o",
        scenario.to_str().unwrap(),
    ];
    let (code, _, stderr) = mapc(&base);
    assert_eq!(code, 2, "{stderr}");
    assert!(
        stderr.contains(
            "the main road before J19 (osm:1686590993) is 530.1 m long; the window needs 600.0 m (69.9 m short; \
             `--fit` cuts what the map has down to 300.0 m)"
        ),
        "{stderr}"
    );
    assert!(!scenario.exists());
    let report = mapc_json(&[&base[..], &["--fit", "--json"]].concat());
    assert!(
        (report["upstream_m"].as_f64().unwrap() - 530.1).abs() < 0.05,
        "{report}"
    );
    assert_eq!(report["merge_m"], 200.0);
    assert_eq!(report["downstream_m"], 100.0);
    let fitted = report["fitted"].as_array().unwrap();
    assert_eq!(fitted.len(), 1, "{report}");
    assert_eq!(fitted[0]["part"], "upstream");
    assert_eq!(fitted[0]["junction"], "osm:1686590993");
    assert!((fitted[0]["short_by_m"].as_f64().unwrap() - 69.9).abs() < 0.05);
    let lengths = report["lengths"].as_array().unwrap();
    assert_eq!(lengths[0]["source_m"], 600.0);
    assert_eq!(lengths[0]["fitted"], true);
    assert!(
        (lengths[0]["ratio"].as_f64().unwrap() - 0.8835).abs() < 1e-3,
        "{report}"
    );
    assert_eq!(lengths[1]["ratio"], 1.0);
    let obs = &report["observation"];
    assert_eq!(obs["rescaled"], false);
    assert_eq!(obs["centralized_norm"]["length_m"], 947.68);
    assert!(
        (obs["control_region_m"].as_f64().unwrap() - 830.1).abs() < 0.05,
        "{obs}"
    );
    assert_eq!(obs["source_control_region_m"], 900.0);
    // The scenario is the fitted window: its recorded lengths and its region's roads.
    let resolved = mapc_scenario::ResolvedScenario::load(scenario.to_str().unwrap()).unwrap();
    let control = resolved.scenario.control.as_ref().unwrap();
    let window = control.window.as_ref().unwrap();
    assert_eq!(window.upstream_m, report["upstream_m"].as_f64().unwrap());
    let region_m: f64 = resolved
        .region_roads
        .iter()
        .map(|r| resolved.graph.road(*r).unwrap().length_m)
        .sum();
    assert!((region_m - 830.1).abs() < 0.05, "{region_m}");
    assert!(
        resolved
            .scenario
            .description
            .contains("Fitted to the map: upstream 530.1 m of 600.0 m")
    );
    // The text report says it too.
    let (code, stdout, stderr) = mapc(&[&base[..], &["--fit"]].concat());
    assert_eq!(code, 0, "{stderr}");
    assert!(
        stdout.contains("against simple_merge's: upstream 530.1 m of 600.0 m (0.88, fitted)")
            && stdout.contains("fitted (--fit): upstream 69.9 m short, the map has no more")
            && stdout.contains("observation: not rescaled"),
        "{stdout}"
    );
    // Below the floor: I-210's osm:1842086610 has 13.6 m after the merge, 0.14 of 100 m.
    let (code, _, stderr) = mapc(&[
        "window",
        "maps/i210.net.xml",
        "--junction",
        "osm:1842086610",
        "--fit",
        "-o",
        dir.join("g.toml").to_str().unwrap(),
    ]);
    assert_eq!(code, 2, "{stderr}");
    assert!(
        stderr.contains(
            "below the --fit floor of 50.0 m, 0.5 of it; `--fit-floor 0.13` would cut it"
        ),
        "{stderr}"
    );
    // --fit-floor outside (0, 1] is refused; without --fit it is a usage error.
    let (code, _, stderr) = mapc(&[&base[..], &["--fit", "--fit-floor", "1.5"]].concat());
    assert_eq!(code, 2, "{stderr}");
    assert!(stderr.contains("--fit-floor"), "{stderr}");
    let (code, _, _) = mapc(&[&base[..], &["--fit-floor", "0.5"]].concat());
    assert_eq!(code, 2);
    std::fs::remove_dir_all(dir).unwrap();
}

/// `--all --fit` on the paper's corridor: where `--all` keeps J43, J37 and J60, fitting keeps J43, J59 (from where
/// J43's window ends, 346.0 m before J59), J60 and J61 (27.7 m short), skips J37 (245.7 m left, below the 300 m
/// floor) and says which windows were fitted and by how much.
#[test]
fn all_with_fit_on_the_i696_corridor() {
    let dir = scratch("all-fit");
    let scenario = dir.join("a.toml");
    let report = mapc_json(&[
        "window",
        "scenarios/i696.corridor.graph.json",
        "--all",
        "--fit",
        "-o",
        scenario.to_str().unwrap(),
        "--json",
    ]);
    let windows = report["windows"].as_array().unwrap();
    let names: Vec<&str> = windows
        .iter()
        .map(|w| w["name"].as_str().unwrap())
        .collect();
    assert_eq!(
        names,
        [
            "osm:61862553",
            "osm:62339771",
            "osm:62339791",
            "osm:62339796"
        ]
    );
    let short: Vec<Vec<f64>> = windows
        .iter()
        .map(|w| {
            w["fitted"]
                .as_array()
                .unwrap()
                .iter()
                .map(|f| f["short_by_m"].as_f64().unwrap())
                .collect()
        })
        .collect();
    assert!(short[0].is_empty() && short[2].is_empty(), "{short:?}");
    assert!(
        (short[1][0] - 254.0).abs() < 0.05 && (short[3][0] - 27.7).abs() < 0.05,
        "{short:?}"
    );
    assert_eq!(windows[1]["observation"]["rescaled"], false);
    let skipped = report["skipped"].as_array().unwrap();
    assert_eq!(skipped.len(), 1, "{skipped:?}");
    assert!(
        skipped[0]
            .as_str()
            .unwrap()
            .contains("--fit would leave it 245.7 m, below its floor of 300.0 m"),
        "{skipped:?}"
    );
    let resolved = mapc_scenario::ResolvedScenario::load(scenario.to_str().unwrap()).unwrap();
    let control = resolved.scenario.control.as_ref().unwrap();
    assert_eq!(control.windows.len(), 4);
    assert!((control.windows[1].upstream_m - 346.0).abs() < 0.05);
    std::fs::remove_dir_all(dir).unwrap();
}

/// Without `--keep-lanes` the paper's outputs are what they were: the shipped I-696 window cut from the shipped
/// corridor is the same byte for byte; the corridor simplified from the raw map and two windows of the merge set
/// cut from the raw maps (Flow's I-210 net, the Arizona OSM map) are the shipped scenarios byte for byte and the
/// shipped graphs but for what the graph files written since carry in addition (`joined` ids in provenance, the
/// importer's warnings, the SUMO net's lane and internal-lane shapes), which the shipped files predate.
#[test]
fn shipped_corridors_and_windows_are_unchanged_without_keep_lanes() {
    let dir = scratch("unchanged");
    let same = |written: &Path, shipped: &str| {
        let a = std::fs::read(written).unwrap();
        let b = std::fs::read(root().join(shipped)).unwrap();
        assert!(a == b, "{} differs from {shipped}", written.display());
    };
    let same_graph = |written: &Path, shipped: &str| {
        let strip = |text: String| {
            let mut v: Value = serde_json::from_str(&text).unwrap();
            v.as_object_mut().unwrap().remove("warnings");
            for r in v["roads"].as_array_mut().unwrap() {
                r["provenance"].as_object_mut().unwrap().remove("joined");
                for l in r["lanes"].as_array_mut().unwrap() {
                    l.as_object_mut().unwrap().remove("shape");
                }
            }
            for c in v["connections"].as_array_mut().unwrap() {
                c.as_object_mut().unwrap().remove("via_lanes");
            }
            v
        };
        let a = strip(std::fs::read_to_string(written).unwrap());
        let b = strip(std::fs::read_to_string(root().join(shipped)).unwrap());
        assert!(a == b, "{} differs from {shipped}", written.display());
    };
    let corridor = paper_corridor(&dir.join("i696.corridor.graph.json"));
    same_graph(&corridor, "scenarios/i696.corridor.graph.json");
    let window = dir.join("i696_window.toml");
    let (code, _, stderr) = mapc(&[
        "window",
        "scenarios/i696.corridor.graph.json",
        "--junction",
        "osm:61862553",
        "--match",
        "simple_merge",
        "-o",
        window.to_str().unwrap(),
    ]);
    assert_eq!(code, 0, "{stderr}");
    same(&window, "scenarios/i696_window.toml");
    same(
        &dir.join("i696_window.graph.json"),
        "scenarios/i696_window.graph.json",
    );
    for (name, map, junction) in [
        ("i210_300944078", "maps/i210.net.xml", "osm:300944078"),
        (
            "arizona_5134463770",
            "maps/arizona_highways.osm",
            "osm:5134463770",
        ),
    ] {
        let out = dir.join(format!("{name}.toml"));
        let (code, _, stderr) = mapc(&[
            "window",
            map,
            "--junction",
            junction,
            "--match",
            "simple_merge",
            "-o",
            out.to_str().unwrap(),
        ]);
        assert_eq!(code, 0, "{stderr}");
        same(&out, &format!("scenarios/merges/{name}.toml"));
        same_graph(
            &dir.join(format!("{name}.graph.json")),
            &format!("scenarios/merges/{name}.graph.json"),
        );
    }
    std::fs::remove_dir_all(dir).unwrap();
}

/// `simplify --keep-lanes` on the paper's I-696 corridor (OSM: lane connections derived) and on Flow's I-210 net
/// (SUMO: the net's own): the lanes per road, lane connections, acceleration lanes and drops are pinned by
/// `tests/golden/<map>/keep_lanes.json`; the written graph keeps every lane, sound, with every lane continuing or
/// recorded as ending.
#[test]
fn keep_lanes_corridors_match_the_goldens() {
    let dir = scratch("keep-lanes");
    for (map, folder, via) in [
        ("maps/i696.osm", "i696", &PAPER_VIA[..]),
        ("maps/i210.net.xml", "i210", &[][..]),
    ] {
        let out = dir.join(format!("{folder}.graph.json"));
        let mut args = vec![
            "simplify",
            map,
            "--keep-lanes",
            "-o",
            out.to_str().unwrap(),
            "--json",
        ];
        args.extend(via);
        let report = mapc_json(&args);
        let steps: Vec<&str> = report["steps"]
            .as_array()
            .unwrap()
            .iter()
            .map(|s| s["step"].as_str().unwrap())
            .collect();
        assert!(
            steps.contains(&"connect_lanes") && !steps.contains(&"collapse_lanes"),
            "{steps:?}"
        );
        let g = mapc_graph::LaneGraph::load(&out).unwrap();
        assert!(g.invariant_violations().is_empty(), "{map}");
        assert!(g.lane_continuity_violations().is_empty(), "{map}");
        let most = g.roads.iter().map(|r| r.lanes.len()).max().unwrap();
        assert!(
            most >= 3,
            "{map}: the freeway keeps its lanes ({most} at most)"
        );
        let lanes = &report["lanes"];
        assert_eq!(
            lanes["per_road"].as_object().unwrap().len(),
            g.roads.len(),
            "{map}"
        );
        assert_eq!(lanes["connections"], g.connections.len(), "{map}");
        golden(folder, "keep_lanes", report);
    }
    std::fs::remove_dir_all(dir).unwrap();
}

/// `mapc window --keep-lanes` on a raw map cuts the multi-lane corridor at the same lengths and names the lanes
/// of each road of the window; the scenario it writes runs on every lane, with lane changes.
#[test]
fn keep_lanes_window_is_cut_and_simulated_on_every_lane() {
    let dir = scratch("keep-lanes-window");
    let out = dir.join("w.toml");
    let report = mapc_json(&[
        "window",
        "maps/i210.net.xml",
        "--keep-lanes",
        "--junction",
        "osm:300944078",
        "--match",
        "simple_merge",
        "-o",
        out.to_str().unwrap(),
        "--json",
    ]);
    for (k, want) in [
        ("upstream_m", 600.0),
        ("merge_m", 200.0),
        ("downstream_m", 100.0),
    ] {
        assert!(
            (report[k].as_f64().unwrap() - want).abs() <= 0.5,
            "{k}: {report}"
        );
    }
    let per_road = report["lanes"]["per_road"].as_object().unwrap();
    let region = report["region"].as_array().unwrap();
    assert_eq!(per_road.len(), region.len(), "{report}");
    assert!(
        per_road.values().any(|n| n.as_u64().unwrap() > 1),
        "{report}"
    );
    assert!(report.get("regime").is_some(), "{report}");
    let g = mapc_graph::LaneGraph::load(&dir.join("w.graph.json")).unwrap();
    assert!(g.lane_continuity_violations().is_empty());

    let (code, stdout, _) = mapc(&[
        "window",
        "maps/i210.net.xml",
        "--keep-lanes",
        "--junction",
        "osm:300944078",
        "-o",
        out.to_str().unwrap(),
    ]);
    assert_eq!(code, 0);
    assert!(stdout.contains("lanes: R"), "{stdout}");

    let sim = mapc_json(&[
        "sim",
        "--scenario",
        out.to_str().unwrap(),
        "--seeds",
        "2",
        "--json",
    ]);
    assert!(sim["outflow"]["mean"].as_f64().unwrap() > 0.0, "{sim}");
    assert!(sim["lane_changes"]["mean"].as_f64().unwrap() > 0.0, "{sim}");
    std::fs::remove_dir_all(dir).unwrap();
}

/// The demand of a multi-lane window is the source's per lane on every lane at the window (Flow's and SUMO's
/// convention: the Simple Merge's 2000 veh/h is one lane's): on I-210's five-lane main road 5 x 2000 veh/h, one
/// flow per entry lane and vehicle type, the one-lane ramp 200 veh/h; the report says so. The shipped multi-lane
/// windows are what these commands write.
#[test]
fn keep_lanes_windows_get_the_per_lane_demand_on_every_lane_and_are_the_shipped_ones() {
    let dir = scratch("lanes-demand");
    let i210 = dir.join("i210_window_lanes.toml");
    let report = mapc_json(&[
        "window",
        "maps/i210.net.xml",
        "--keep-lanes",
        "--junction",
        "osm:300944078",
        "-o",
        i210.to_str().unwrap(),
        "--json",
    ]);
    let demand: Vec<&str> = report["demand"]
        .as_array()
        .unwrap()
        .iter()
        .map(|d| d.as_str().unwrap())
        .collect();
    assert!(
        demand
            .iter()
            .any(|d| d.contains("10000 veh/h") && d.contains("2000 veh/h per lane x 5 lane(s)")),
        "{demand:?}"
    );
    let scenario = mapc_scenario::ResolvedScenario::load(i210.to_str().unwrap()).unwrap();
    let main_entry = report["main_entry"].as_str().unwrap();
    let main: Vec<&mapc_scenario::Flow> = scenario
        .scenario
        .flows
        .iter()
        .filter(|f| f.from == main_entry)
        .collect();
    assert_eq!(main.len(), 10, "two vehicle types on five lanes");
    let total: f64 = main.iter().map(|f| f.vehs_per_hour).sum();
    assert!((total - 10000.0).abs() < 1e-6, "{total}");
    let lanes: std::collections::BTreeSet<&str> = main
        .iter()
        .map(|f| f.depart_lane.as_deref().unwrap())
        .collect();
    assert_eq!(lanes.len(), 5);
    let ramp: f64 = scenario
        .scenario
        .flows
        .iter()
        .filter(|f| f.from != main_entry)
        .map(|f| f.vehs_per_hour)
        .sum();
    assert_eq!(ramp, 200.0);
    let same = |written: &Path, shipped: &str| {
        let a = std::fs::read(written).unwrap();
        let b = std::fs::read(root().join(shipped)).unwrap();
        assert!(a == b, "{} differs from {shipped}", written.display());
    };
    same(&i210, "scenarios/i210_window_lanes.toml");
    same(
        &dir.join("i210_window_lanes.graph.json"),
        "scenarios/i210_window_lanes.graph.json",
    );
    let i696 = dir.join("i696_window_lanes.toml");
    let mut args = vec![
        "window",
        "maps/i696.osm",
        "--keep-lanes",
        "--junction",
        "osm:61862553",
        "-o",
        i696.to_str().unwrap(),
    ];
    args.extend(PAPER_VIA);
    let (code, stdout, stderr) = mapc(&args);
    assert_eq!(code, 0, "{stderr}");
    assert!(stdout.contains("demand on the main road"), "{stdout}");
    same(&i696, "scenarios/i696_window_lanes.toml");
    same(
        &dir.join("i696_window_lanes.graph.json"),
        "scenarios/i696_window_lanes.graph.json",
    );
    std::fs::remove_dir_all(dir).unwrap();
}
