//! End-to-end tests of the built-in lane-drop bottleneck (`lane_drop`), of lane changes by reason in
//! `mapc sim --json`, and of a `depart_lane` the entry road does not have.

mod common;

use common::{assert_success, mapc_command as mapc, mapc_json, scratch_dir};

fn sim_json(scenario: &str, seeds: &str) -> serde_json::Value {
    mapc_json(&["sim", "--scenario", scenario, "--seeds", seeds, "--json"])
}

/// The same on `threads` threads (given, not the machine's count: a one-core runner would compare one thread
/// with itself).
fn sim_json_on_threads(scenario: &str, seeds: &str, threads: &str) -> serde_json::Value {
    mapc_json(&[
        "sim",
        "--scenario",
        scenario,
        "--seeds",
        seeds,
        "--json",
        "--threads",
        threads,
    ])
}

/// Every vehicle that departs on the lane that ends must leave it by a strategic change before the drop, and no
/// vehicle collides or is left at the lane's end: the run's strategic changes are at least the vehicles of that
/// lane that got past the drop, and the lane changes by reason add up to the lane changes.
#[test]
fn lane_drop_sends_the_ending_lane_over_by_strategic_changes() {
    let v = sim_json("lane_drop", "3");
    for r in v["runs"].as_array().unwrap() {
        let total = r["lane_changes"].as_u64().unwrap();
        let by = &r["lane_changes_by_reason"];
        let sum: u64 = ["strategic", "cooperative", "speed_gain", "keep_right"]
            .iter()
            .map(|k| by[k].as_u64().unwrap())
            .sum();
        assert_eq!(sum, total, "{r}");
        // a third of the demand departs on the ending lane; most of it reaches the downstream road in 1000 s
        let departed = r["departed"].as_u64().unwrap();
        assert!(
            by["strategic"].as_u64().unwrap() * 4 > departed,
            "{r}: strategic changes for a third of {departed} vehicles"
        );
        let outflow = r["outflow_veh_h"].as_f64().unwrap();
        assert!(outflow > 2000.0, "{r}");
    }
    // the same seeds give the same run, whatever the thread count
    let one = sim_json_on_threads("lane_drop", "3", "1");
    let two = sim_json_on_threads("lane_drop", "3", "2");
    assert_eq!(one["runs"], v["runs"]);
    assert_eq!(two["runs"], v["runs"]);
}

/// One-lane roads change no lanes, for any reason.
#[test]
fn one_lane_runs_report_no_lane_changes_by_reason() {
    let v = sim_json("simple_merge", "1");
    let by = &v["runs"][0]["lane_changes_by_reason"];
    for k in ["strategic", "cooperative", "speed_gain", "keep_right"] {
        assert_eq!(by[k], 0, "{v}");
    }
}

/// A flow departing on a lane its entry road does not have is refused when the scenario loads, naming the file
/// and the key, exit code 2.
#[test]
fn a_depart_lane_the_road_does_not_have_is_refused_with_the_file_and_key() {
    let dir = scratch_dir("depart-lane");
    let path = dir.join("bad_lane.toml");
    let mut scenario = mapc_scenario::Scenario::lane_drop();
    scenario.flows[1].depart_lane = Some("3".into());
    scenario.save(&path).unwrap();
    let out = mapc()
        .args(["sim", "--scenario", path.to_str().unwrap()])
        .output()
        .unwrap();
    assert_eq!(out.status.code(), Some(2));
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(
        err.contains("bad_lane.toml")
            && err.contains("flows[1].depart_lane")
            && err.contains("3 lane(s)"),
        "{err}"
    );
    let out = mapc()
        .args([
            "export",
            path.to_str().unwrap(),
            "--sumo",
            dir.join("sumo").to_str().unwrap(),
        ])
        .output()
        .unwrap();
    assert_eq!(out.status.code(), Some(2));
    assert!(!dir.join("sumo").exists());
    std::fs::remove_dir_all(dir).unwrap();
}

/// `depart_lane` `free` and `random`: the runs repeat whatever the thread count, and the SUMO export writes
/// them as SUMO's `departLane` values.
#[test]
fn free_and_random_depart_lanes_run_deterministically_and_export_as_sumo_values() {
    let dir = scratch_dir("depart-lane-modes");
    for mode in ["free", "random"] {
        let path = format!("scenarios/lane_drop_{mode}.toml");
        let v = sim_json_on_threads(&path, "2", "2");
        let one = sim_json_on_threads(&path, "2", "1");
        assert_eq!(one["runs"], v["runs"], "{mode}");
        for r in v["runs"].as_array().unwrap() {
            assert!(r["departed"].as_u64().unwrap() > 800, "{mode}: {r}");
        }
        let out = dir.join(mode);
        let export = mapc()
            .args(["export", &path, "--sumo", out.to_str().unwrap()])
            .output()
            .unwrap();
        assert_success(&export);
        let routes = std::fs::read_dir(&out)
            .unwrap()
            .map(|e| e.unwrap().path())
            .find(|p| p.to_string_lossy().ends_with(".rou.xml"))
            .expect("a routes file");
        let text = std::fs::read_to_string(routes).unwrap();
        assert!(
            text.contains(&format!("departLane=\"{mode}\"")),
            "{mode}: {text}"
        );
    }
    std::fs::remove_dir_all(dir).unwrap();
}

/// A `depart_lane` that is none of SUMO's values mapc knows is refused when the scenario loads, naming the file,
/// the key and the flow, exit code 2.
#[test]
fn an_unknown_depart_lane_is_refused_with_the_file_key_and_flow() {
    let dir = scratch_dir("depart-lane-unknown");
    let path = dir.join("unknown_lane.toml");
    let mut scenario = mapc_scenario::Scenario::lane_drop();
    scenario.flows[2].depart_lane = Some("allowed_free".into());
    scenario.save(&path).unwrap();
    for args in [
        vec!["sim", "--scenario", path.to_str().unwrap()],
        vec![
            "export",
            path.to_str().unwrap(),
            "--sumo",
            dir.join("sumo").to_str().unwrap(),
        ],
    ] {
        let out = mapc().args(&args).output().unwrap();
        assert_eq!(out.status.code(), Some(2), "{args:?}");
        let err = String::from_utf8_lossy(&out.stderr);
        assert!(
            err.contains("unknown_lane.toml")
                && err.contains("flows[2].depart_lane")
                && err.contains("`lane2`")
                && err.contains("`allowed_free`")
                && err.lines().filter(|l| !l.trim().is_empty()).count() == 1,
            "{err}"
        );
    }
    assert!(!dir.join("sumo").exists());
    std::fs::remove_dir_all(dir).unwrap();
}
