//! `mapc eval --controller alinea`: ramp metering on a SUMO user's scenario with its own meter and detectors,
//! reported beside the humans; a set-point, light or detector that does not hold is refused with exit 2.

mod common;
use common::*;

const RAMP_METERING: &str = "scenarios/sumo/ramp_metering_1x3/1ramp_1x3.sumocfg";
const RAMP_GAME_ALINEA: &str = "scenarios/sumo/ramp_game_alinea/ramp_alinea.sumocfg";

/// `mapc eval --controller alinea --scenario SCENARIO ... --json`, with `rest` between.
fn alinea_json(scenario: &str, rest: &[&str]) -> serde_json::Value {
    let mut args = vec!["eval", "--controller", "alinea", "--scenario", scenario];
    args.extend_from_slice(rest);
    args.push("--json");
    mapc_json(&args)
}

#[test]
fn alinea_meters_the_scenarios_own_light_from_the_loops_past_the_merge() {
    let j = alinea_json(RAMP_METERING, &["--seeds", "2"]);
    assert_eq!(j["light"], "ramp_meter");
    // the loops on the acceleration area, past the merge (not the ramp's own passage loops)
    let detectors: Vec<&str> = j["detectors"]
        .as_array()
        .unwrap()
        .iter()
        .map(|d| d.as_str().unwrap())
        .collect();
    assert_eq!(
        detectors,
        [
            "bottle_neck_sens_0",
            "bottle_neck_sens_1",
            "bottle_neck_sens_2",
            "bottle_neck_sens_3"
        ]
    );
    let rate = j["mean_rate_veh_h"].as_f64().unwrap();
    assert!((200.0..=1800.0).contains(&rate), "{j}");
    // the same seeds' humans run under the scenario's fixed program
    assert_eq!(j["humans"]["outflow"]["n"], 2);
    assert!(j["alinea"]["outflow"]["mean"].as_f64().unwrap() > 0.0);
}

#[test]
fn alinea_without_the_baseline_runs_no_humans_and_reports_each_metered_run() {
    let j = alinea_json(RAMP_GAME_ALINEA, &["--seeds", "2", "--no-baseline"]);
    assert!(j["humans"].is_null(), "{}", j["humans"]);
    let runs = j["alinea_runs"].as_array().unwrap();
    assert_eq!(runs.len(), 2);
    // the per-run figures the summary is made of (sumo_check's lane-change columns read them)
    let departed: f64 = runs.iter().map(|r| r["departed"].as_f64().unwrap()).sum();
    assert!(departed > 0.0);
    assert!(runs.iter().all(|r| r["lane_changes"].as_u64().is_some()));
    let mean_outflow = runs
        .iter()
        .map(|r| r["outflow_veh_h"].as_f64().unwrap())
        .sum::<f64>()
        / 2.0;
    let summary = j["alinea"]["outflow"]["mean"].as_f64().unwrap();
    assert!(
        (mean_outflow - summary).abs() < 1e-6 * summary.max(1.0),
        "{mean_outflow} vs {summary}"
    );
}

#[test]
fn alinea_on_the_ramp_game_reads_the_first_loops_past_its_meter_and_writes_its_trace() {
    // SUMO's ramp game, metered from loops this project added (scenarios/sumo/ramp_game_alinea)
    let dir = scratch_dir("alinea-trace");
    let trace = dir.join("alinea.csv");
    let j = alinea_json(
        RAMP_GAME_ALINEA,
        &["--seeds", "1", "--trace", trace.to_str().unwrap()],
    );
    assert_eq!(j["light"], "gneJ16");
    assert_eq!(j["detectors"], serde_json::json!(["ramps_0"]));
    let rows = std::fs::read_to_string(&trace).expect("the trace under ALINEA");
    assert!(
        rows.starts_with("time_s,vehicle_id"),
        "{}",
        &rows[..80.min(rows.len())]
    );
    assert!(rows.lines().count() > 1000, "{} rows", rows.lines().count());
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn a_bad_alinea_setting_is_refused_with_exit_2() {
    for (flag, value, expected) in [
        ("--alinea-setpoint", "1.5", "set-point 1.5 is not in (0, 1)"),
        ("--alinea-light", "nope", "no traffic light `nope`"),
        ("--alinea-detectors", "gone", "no detector `gone`"),
    ] {
        refused(
            &[
                "eval",
                "--controller",
                "alinea",
                "--scenario",
                RAMP_METERING,
                "--seeds",
                "1",
                flag,
                value,
            ],
            &[expected],
        );
    }
    refused(
        &["eval", "--controller", "alinea", "--seeds", "1"],
        &["no traffic light to meter"],
    );
}
