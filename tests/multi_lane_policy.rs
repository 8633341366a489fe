//! End-to-end: policies on a multi-lane road (`scenarios/two_lane_merge_av.toml`, the two-lane merge with AVs):
//! the shipped Simple Merge policy evaluated and viewed there, and tiny centralized and distributed trainings
//! with the adjacent-lanes observation (`--features lanes`) whose policies `mapc eval` reads back.

use std::path::PathBuf;

mod common;

use common::mapc_command as mapc;

const TWO_LANES: &str = "scenarios/two_lane_merge_av.toml";

fn tmp(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("mapc-lanes-e2e-{}-{name}", std::process::id()));
    std::fs::remove_dir_all(&d).ok();
    d
}

fn json(out: &std::process::Output) -> serde_json::Value {
    common::assert_success(out);
    serde_json::from_slice(&out.stdout).expect("JSON on stdout")
}

/// A few iterations of 600 steps (episodes of 300) on the two-lane merge with the fast preset.
fn tiny_train(dir: &PathBuf, setting: &[&str]) -> std::process::Output {
    mapc()
        .current_dir(common::root())
        .args(["train", "--scenario", TWO_LANES, "--preset", "fast"])
        .args(setting)
        .args(["--iters", "2", "--batch", "600", "--minibatch", "200"])
        .args(["--horizon", "300", "--epochs", "2", "--json", "-o"])
        .arg(dir)
        .output()
        .unwrap()
}

fn eval(policy: &std::path::Path, scenario: &str, seeds: &str) -> serde_json::Value {
    json(
        &mapc()
            .current_dir(common::root())
            .args([
                "eval",
                "--scenario",
                scenario,
                "--seeds",
                seeds,
                "--json",
                "--policy",
            ])
            .arg(policy)
            .output()
            .unwrap(),
    )
}

fn spec_of(dir: &std::path::Path) -> serde_json::Value {
    let ck: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(dir.join("checkpoint.json")).unwrap())
            .unwrap();
    ck["spec"].clone()
}

#[test]
fn the_shipped_policy_drives_avs_on_both_main_lanes() {
    let dir = tmp("shipped");
    std::fs::create_dir_all(&dir).unwrap();
    let trace = dir.join("trace.csv");
    let out = mapc()
        .current_dir(common::root())
        .args([
            "eval",
            "--policy",
            "policies/simple_merge_outflow.json",
            "--scenario",
            TWO_LANES,
        ])
        .args(["--seeds", "2", "--json", "--trace"])
        .arg(&trace)
        .output()
        .unwrap();
    let report = json(&out);
    let (policy, human) = (
        report["outflow"]["mean"].as_f64().unwrap(),
        report["baseline"]["outflow"]["mean"].as_f64().unwrap(),
    );
    assert!(policy > 1000.0 && human > 1000.0, "{report}");
    assert_ne!(policy, human, "the policy's AVs acted");
    // the controlled AVs drive on both main lanes (lane changes are the model's, not the policy's)
    let text = std::fs::read_to_string(&trace).unwrap();
    let mut rows = text.lines();
    let header: Vec<&str> = rows.next().unwrap().split(',').collect();
    let col = |name: &str| header.iter().position(|&h| h == name).unwrap();
    let (controlled, lane, road) = (col("controlled"), col("lane"), col("road"));
    let mut lanes = std::collections::BTreeSet::new();
    for row in rows {
        let f: Vec<&str> = row.split(',').collect();
        if f[controlled] == "1" || f[controlled] == "true" {
            lanes.insert((f[road].to_string(), f[lane].to_string()));
        }
    }
    let on = |l: &str| lanes.iter().any(|(_, x)| x == l);
    assert!(on("0") && on("1"), "{lanes:?}");
    std::fs::remove_dir_all(&dir).ok();
}

#[test]
fn the_shipped_policy_is_viewed_on_two_lanes_as_eval_scores_it() {
    let dir = tmp("view");
    std::fs::create_dir_all(&dir).unwrap();
    let policy = "policies/simple_merge_outflow.json";
    let summary = json(
        &mapc()
            .current_dir(common::root())
            .args([
                "view",
                TWO_LANES,
                "--policy",
                policy,
                "--compare",
                "--json",
                "-o",
            ])
            .arg(dir.join("page.html"))
            .output()
            .unwrap(),
    );
    let report = eval(std::path::Path::new(policy), TWO_LANES, "1");
    let outflow = |i: usize| summary["panes"][i]["outflow_veh_h"].as_f64().unwrap();
    assert!((outflow(0) - report["baseline"]["outflow"]["mean"].as_f64().unwrap()).abs() < 0.01);
    assert!((outflow(1) - report["outflow"]["mean"].as_f64().unwrap()).abs() < 0.01);
    std::fs::remove_dir_all(&dir).ok();
}

#[test]
fn a_centralized_policy_observes_the_adjacent_lanes_and_eval_reads_it_back() {
    let dir = tmp("central-lanes");
    let report = json(&tiny_train(
        &dir,
        &["--reward", "outflow", "--features", "lanes"],
    ));
    assert!(report.is_object());
    let spec = spec_of(&dir);
    // 5 AVs x (the paper's 5 values + 2 lanes x 5)
    assert_eq!(
        (spec["lanes"].as_bool(), spec["obs_dim"].as_u64()),
        (Some(true), Some(75)),
        "{spec}"
    );
    let run = dir.join("checkpoint.json");
    for scenario in [TWO_LANES, "simple_merge"] {
        // on one lane the sides read as missing lanes: the policy still runs
        let r = eval(&run, scenario, "1");
        assert!(
            r["outflow"]["mean"].as_f64().unwrap() > 0.0,
            "{scenario}: {r}"
        );
    }
    // without the option, the paper's observation and file (no `lanes` field)
    let plain = tmp("central-plain");
    json(&tiny_train(&plain, &["--reward", "outflow"]));
    let spec = spec_of(&plain);
    assert!(
        spec.get("lanes").is_none() && spec["obs_dim"] == 25,
        "{spec}"
    );
    // a centralized policy has no distributed augmentations
    let out = tiny_train(&tmp("central-bad"), &["--features", "lanes,dist"]);
    assert_eq!(out.status.code(), Some(2));
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(
        err.contains("--features") && err.contains("--distributed"),
        "{err}"
    );
    for d in [dir, plain] {
        std::fs::remove_dir_all(d).ok();
    }
}

#[test]
fn a_distributed_policy_trains_on_two_lanes_with_the_adjacent_lanes() {
    let dir = tmp("dist-lanes");
    json(&tiny_train(
        &dir,
        &["--distributed", "--features", "full,lanes"],
    ));
    let spec = spec_of(&dir);
    assert_eq!(spec["obs_dim"], 19, "{spec}");
    assert_eq!(spec["distributed"]["features"]["lanes"], true, "{spec}");
    let r = eval(&dir.join("checkpoint.json"), TWO_LANES, "1");
    assert!(r["outflow"]["mean"].as_f64().unwrap() > 0.0, "{r}");
    std::fs::remove_dir_all(&dir).ok();
}
