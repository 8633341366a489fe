//! End-to-end tests of `mapc sim` and `mapc bench`.

mod common;

use common::mapc_command as mapc;

#[test]
fn sim_json_has_mean_and_ci_per_metric() {
    let out = mapc()
        .args([
            "sim",
            "--scenario",
            "simple_merge",
            "--seeds",
            "4",
            "--json",
        ])
        .output()
        .unwrap();
    common::assert_success(&out);
    let v: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    assert_eq!(v["seeds"], 4);
    for key in ["outflow", "inflow", "speed", "travel_time", "delay"] {
        assert!(v[key]["mean"].as_f64().unwrap() > 0.0, "{key}: {v}");
        assert!(v[key]["ci95"].as_f64().unwrap() >= 0.0, "{key}: {v}");
    }
    let outflow = v["outflow"]["mean"].as_f64().unwrap();
    assert!(outflow > 1000.0 && outflow < 2200.0, "{outflow}");
    // the same seeds on one thread give the same numbers
    let one = mapc()
        .args([
            "sim",
            "--scenario",
            "simple_merge",
            "--seeds",
            "4",
            "--json",
            "--threads",
            "1",
        ])
        .output()
        .unwrap();
    let w: serde_json::Value = serde_json::from_slice(&one.stdout).unwrap();
    assert_eq!(v["outflow"], w["outflow"]);
    assert_eq!(v["runs"], w["runs"]);
}

#[test]
fn sim_trace_writes_the_csv_header_and_rows() {
    let dir = common::scratch_dir("sim-cli-trace");
    let trace = dir.join("trace.csv");
    let out = mapc()
        .args([
            "sim",
            "--scenario",
            "simple_merge",
            "--seeds",
            "1",
            "--trace",
        ])
        .arg(&trace)
        .output()
        .unwrap();
    common::assert_success(&out);
    let text = std::fs::read_to_string(&trace).unwrap();
    let mut lines = text.lines();
    assert_eq!(
        lines.next().unwrap(),
        "time_s,vehicle_id,vehicle_type,road,pos_on_road_m,corridor_x_m,speed_mps,controlled,lane"
    );
    let rows: Vec<Vec<&str>> = lines.map(|l| l.split(',').collect()).collect();
    assert!(rows.len() > 50_000, "{} rows", rows.len());
    assert!(rows.iter().all(|r| r.len() == 9 && r[8] == "0"));
    // main-line vehicles have a corridor position, ramp vehicles none
    assert!(rows.iter().any(|r| r[5].is_empty()));
    assert!(
        rows.iter()
            .any(|r| r[5].parse::<f64>().is_ok_and(|x| x > 600.0))
    );
    assert!(rows.iter().any(|r| r[7] == "true"));
    std::fs::remove_dir_all(dir).unwrap();
}

#[test]
fn sim_bad_scenario_exits_2_and_names_it() {
    let out = mapc()
        .args(["sim", "--scenario", "no/such/scenario.toml"])
        .output()
        .unwrap();
    assert_eq!(out.status.code(), Some(2));
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(err.contains("no/such/scenario.toml"), "{err}");
}

#[test]
fn bench_reports_vehicle_steps_per_second() {
    let out = mapc()
        .args([
            "bench",
            "--scenario",
            "simple_merge",
            "--single-core-seeds",
            "1",
            "--seeds",
            "2",
            "--no-sumo",
            "--json",
        ])
        .output()
        .unwrap();
    common::assert_success(&out);
    let v: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    assert!(v["single_core"]["vehicle_steps_per_s"].as_f64().unwrap() > 0.0);
    assert_eq!(v["baseline"]["seeds"], 2);
    let peak = v["peak_rss_mib"].as_f64().unwrap();
    assert!(peak > 1.0 && peak < 4096.0, "{peak}");
}

/// `mapc bench` runs SUMO's command line on the exported scenario right after mapc when SUMO is found (SUMO 1.8
/// where tools/sumo_check installs it), and says so when it is not; a `--sumo` that is not there is refused.
#[test]
fn bench_measures_sumo_beside_mapc_or_says_it_is_absent() {
    let out = mapc()
        .args([
            "bench",
            "--scenario",
            "two_lane_merge",
            "--single-core-seeds",
            "1",
            "--seeds",
            "1",
            "--sumo-seeds",
            "1",
            "--json",
        ])
        .output()
        .unwrap();
    common::assert_success(&out);
    let v: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    assert!(v["single_core"]["cpu_s"].as_f64().unwrap() > 0.0, "{v}");
    let sumo = &v["sumo"];
    if let Some(why) = sumo["absent"].as_str() {
        assert!(why.contains("not found"), "{v}");
    } else {
        assert!(sumo["version"].as_str().unwrap().contains("SUMO"), "{v}");
        // two_lane_merge carries some 60 000 vehicle-steps per run
        let steps = sumo["vehicle_steps"].as_f64().unwrap();
        assert!((2e4..2e5).contains(&steps), "{v}");
        assert!(
            sumo["mapc_speedup_per_cpu_s"].as_f64().unwrap() > 0.0,
            "{v}"
        );
        assert!(sumo["peak_rss_mib"].as_f64().unwrap() > 1.0, "{v}");
    }
    let missing = mapc()
        .args(["bench", "--single-core-seeds", "1", "--seeds", "1"])
        .args(["--sumo", "no/such/sumo"])
        .output()
        .unwrap();
    assert_eq!(missing.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&missing.stderr).contains("no/such/sumo"));
}

/// The shipped Simple Merge with `edit` applied to its text, written to a scratch file.
fn edited_simple_merge(name: &str, edit: impl Fn(String) -> String) -> std::path::PathBuf {
    common::edited_scenario("simple_merge.toml", name, edit)
}

/// `mapc ARGS` with its address space limited to 1 GiB (a machine has 24 GB: a run that grows with its demand
/// reaches the limit within a few dozen steps and aborts instead of finishing).
fn mapc_within_1_gib(args: &[&str]) -> std::process::Output {
    std::process::Command::new("sh")
        .arg("-c")
        .arg("ulimit -v 1048576 && exec \"$0\" \"$@\"")
        .arg(env!("CARGO_BIN_EXE_mapc"))
        .args(args)
        .current_dir(common::root())
        // one malloc arena per thread would reserve 64 MiB of address space each
        .env("MALLOC_ARENA_MAX", "2")
        .output()
        .unwrap()
}

#[test]
fn an_absurd_demand_is_refused_within_a_small_memory_budget() {
    let path = edited_simple_merge("huge-demand", |t| {
        t.replace("vehs_per_hour = 1800.0", "vehs_per_hour = 1e9")
    });
    let p = path.to_str().unwrap();
    let out = mapc_within_1_gib(&["sim", "--scenario", p, "--seeds", "4", "--threads", "2"]);
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(2), "{err}");
    assert!(
        err.contains(p) && err.contains("`main_human`") && err.contains("7200 veh/h"),
        "{err}"
    );
    assert!(!err.contains("panicked"), "{err}");
}

#[test]
fn an_entry_loaded_to_its_limit_runs_long_within_a_small_memory_budget() {
    // 7000 + 200 veh/h into a road that passes about 2000, for 4 h: thousands wait, the run stays small
    let path = edited_simple_merge("full-entry", |t| {
        t.replace("vehs_per_hour = 1800.0", "vehs_per_hour = 7000.0")
            .replace("horizon_steps = 2000", "horizon_steps = 28800")
    });
    let out = mapc_within_1_gib(&[
        "sim",
        "--scenario",
        path.to_str().unwrap(),
        "--seeds",
        "2",
        "--threads",
        "2",
        "--json",
    ]);
    common::assert_success(&out);
    let v: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    let inflow = v["inflow"]["mean"].as_f64().unwrap();
    assert!(inflow > 1500.0 && inflow < 2500.0, "{inflow}");
    // the regime report sees the backlog
    assert!(
        v["regime"]["waiting_to_enter"].as_f64().unwrap() > 10_000.0,
        "{}",
        v["regime"]
    );
}

#[test]
fn an_absurd_horizon_is_refused_with_the_limit_named() {
    let path = edited_simple_merge("huge-horizon", |t| {
        t.replace("horizon_steps = 2000", "horizon_steps = 4000000000")
    });
    let out = mapc_within_1_gib(&["sim", "--scenario", path.to_str().unwrap()]);
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(2), "{err}");
    assert!(
        err.contains("horizon_steps") && err.contains("168 h"),
        "{err}"
    );
}

/// A flow beginning at -1e308 once made `mapc sim` run forever (its departure times stood still), and one at -1e6
/// sent 555 556 vehicles in the first step: both are refused with the file, the key, the value and the range.
#[test]
fn a_flow_beginning_outside_the_run_is_refused_with_the_range() {
    for (begin, shown) in [
        ("-1e308", "-1e308"),
        ("-1e6", "-1e6"),
        ("inf", "inf"),
        ("nan", "NaN"),
    ] {
        let path = edited_simple_merge("far-begin", |t| {
            t.replacen("begin_s = 1.0", &format!("begin_s = {begin}"), 1)
        });
        let out = std::process::Command::new("timeout")
            .args(["60", env!("CARGO_BIN_EXE_mapc"), "sim", "--scenario"])
            .arg(&path)
            .args(["--seeds", "1"])
            .current_dir(common::root())
            .output()
            .unwrap();
        let err = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(2), "begin_s = {begin}: {err}");
        let expected = format!(
            "{}: flows[0].begin_s: {shown} is outside the allowed range [0, 604800] s",
            path.display()
        );
        assert!(err.contains(&expected), "{err}");
    }
}

#[test]
fn sim_reports_flows_past_points_the_regime_and_warns_on_a_short_horizon() {
    let out = mapc()
        .args([
            "sim",
            "--scenario",
            "simple_merge",
            "--seeds",
            "3",
            "--json",
        ])
        .output()
        .unwrap();
    common::assert_success(&out);
    assert!(!String::from_utf8_lossy(&out.stderr).contains("warning"));
    let v: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    assert_eq!(v["end_flow"]["mean"], v["outflow"]["mean"]);
    assert!(
        v["merges"][0]["name"]
            .as_str()
            .unwrap()
            .starts_with("merge J")
    );
    assert!(v["merges"][0]["flow"]["mean"].as_f64().unwrap() > 1000.0);
    let m = &v["regime"]["merges"][0];
    assert_eq!(m["approaches"].as_array().unwrap().len(), 2, "{m}");
    // the paper's merge: the ramp has priority and the main road is congested
    let main = m["approaches"]
        .as_array()
        .unwrap()
        .iter()
        .find(|a| a["main_line"] == true)
        .unwrap();
    assert_eq!(main["major"], false);
    assert_eq!(main["congestion"], "congested");

    // 20 s of horizon on an 800 m corridor: no vehicle can reach the end, and the user is told
    let path = edited_simple_merge("short-horizon", |t| {
        t.replace("horizon_steps = 2000", "horizon_steps = 40")
    });
    let out = mapc()
        .args(["sim", "--seeds", "2", "--scenario", path.to_str().unwrap()])
        .output()
        .unwrap();
    common::assert_success(&out);
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(
        err.contains("warning") && err.contains("no vehicle can reach the end"),
        "{err}"
    );
    let text = String::from_utf8_lossy(&out.stdout);
    assert!(
        text.contains("regime") && text.contains("has priority"),
        "{text}"
    );
}

#[test]
fn window_refuses_an_absurd_demand_and_writes_nothing() {
    let dir = common::scratch_dir("window-demand");
    let scenario = dir.join("w.toml");
    let out = mapc()
        .args(["window", "maps/i696.osm", "--junction", "osm:61862553"])
        .args(common::PAPER_VIA)
        .args(["--main-vph", "1e9", "-o"])
        .arg(&scenario)
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(2), "{err}");
    assert!(
        err.contains("--main-vph") && err.contains("7200 veh/h") && err.contains("nothing written"),
        "{err}"
    );
    assert!(!scenario.exists() && !dir.join("w.graph.json").exists());
}

#[test]
fn window_picks_a_warmup_when_the_corridor_is_long_for_the_source_horizon() {
    // a source of 200 s horizon: the paper's I-696 corridor (about 275 s at free flow) is too long for it
    let source = edited_simple_merge("short-source", |t| {
        t.replace("horizon_steps = 2000", "horizon_steps = 400")
    });
    let dir = common::scratch_dir("window-timing");
    let scenario = dir.join("w.toml");
    let out = mapc()
        .args(["window", "maps/i696.osm", "--junction", "osm:61862553"])
        .args(common::PAPER_VIA)
        .args(["--match"])
        .arg(&source)
        .arg("-o")
        .arg(&scenario)
        .output()
        .unwrap();
    common::assert_success(&out);
    let text = String::from_utf8_lossy(&out.stdout);
    assert!(text.contains("picked a warm-up of 400 s"), "{text}");
    assert!(
        text.contains("regime") && text.contains("has priority"),
        "{text}"
    );
    let written = mapc_scenario::Scenario::load(&scenario).unwrap();
    assert_eq!((written.warmup_steps, written.horizon_steps), (800, 400));
    // and the scenario it wrote runs without a warning
    let out = mapc()
        .args([
            "sim",
            "--seeds",
            "1",
            "--scenario",
            scenario.to_str().unwrap(),
        ])
        .output()
        .unwrap();
    common::assert_success(&out);
    assert!(!String::from_utf8_lossy(&out.stderr).contains("warning"));
}

#[test]
fn two_lane_merge_changes_lanes_and_reports_them() {
    let out = mapc()
        .args([
            "sim",
            "--scenario",
            "two_lane_merge",
            "--seeds",
            "3",
            "--json",
        ])
        .output()
        .unwrap();
    common::assert_success(&out);
    let v: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    // the figures the simulator's golden test pins for seeds 0-2
    let runs = v["runs"].as_array().unwrap();
    let changes: Vec<u64> = runs
        .iter()
        .map(|r| r["lane_changes"].as_u64().unwrap())
        .collect();
    assert_eq!(changes, vec![160, 153, 159], "{v}");
    let mean = v["lane_changes"]["mean"].as_f64().unwrap();
    assert!((mean - 472.0 / 3.0).abs() < 1e-9, "{mean}");
    assert!(v["lane_changes_per_veh_km"]["mean"].as_f64().unwrap() > 0.1);
    // one-lane roads change no lanes
    let one = mapc()
        .args([
            "sim",
            "--scenario",
            "simple_merge",
            "--seeds",
            "1",
            "--json",
        ])
        .output()
        .unwrap();
    let w: serde_json::Value = serde_json::from_slice(&one.stdout).unwrap();
    assert_eq!(w["runs"][0]["lane_changes"], 0);
}
