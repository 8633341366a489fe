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
    let dir = std::env::temp_dir().join(format!("mapc-sim-cli-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
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
        "time_s,vehicle_id,vehicle_type,road,pos_on_road_m,corridor_x_m,speed_mps,controlled"
    );
    let rows: Vec<Vec<&str>> = lines.map(|l| l.split(',').collect()).collect();
    assert!(rows.len() > 50_000, "{} rows", rows.len());
    assert!(rows.iter().all(|r| r.len() == 8));
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
            "--json",
        ])
        .output()
        .unwrap();
    common::assert_success(&out);
    let v: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    assert!(v["single_core"]["vehicle_steps_per_s"].as_f64().unwrap() > 0.0);
    assert_eq!(v["baseline"]["seeds"], 2);
}
