//! End to end: `mapc pipeline` on the shipped I-696 map writes every stage's file and evaluates the shipped policy.

mod common;

use common::{fresh_path, mapc_command};

/// The last JSON document the pipeline prints (before the time-space diagram's and the replay's lines) is the
/// evaluation against the human baseline, on `seeds` seeds, with both outflows plausible.
fn assert_the_evaluation_ran(stdout: &str, seeds: u64) {
    let start = stdout.rfind("\n{\n").map_or(0, |i| i + 1);
    let eval: serde_json::Value = serde_json::Deserializer::from_str(&stdout[start..])
        .into_iter()
        .next()
        .expect("a JSON document")
        .expect("eval JSON last");
    assert_eq!(eval["seeds"], seeds);
    let policy = eval["outflow"]["mean"].as_f64().unwrap();
    let human = eval["baseline"]["outflow"]["mean"].as_f64().unwrap();
    assert!(
        policy > 500.0 && human > 500.0,
        "policy {policy}, human {human}"
    );
}

#[test]
fn pipeline_runs_every_stage_on_the_real_map() {
    let out = fresh_path("pipeline");
    let run = mapc_command()
        .args(["pipeline", "--seeds", "3", "--json", "-o"])
        .arg(&out)
        .output()
        .unwrap();
    let stdout = String::from_utf8_lossy(&run.stdout);
    let stderr = String::from_utf8_lossy(&run.stderr);
    assert!(run.status.success(), "pipeline failed:\n{stderr}");
    for file in [
        "i696.graph.json",
        "i696.png",
        "i696.corridor.graph.json",
        "i696_window.toml",
        "i696_window.graph.json",
        "i696_window.png",
        "i696_window_human_trace.csv",
        "i696_window_policy_trace.csv",
        "i696_window_timespace.png",
        "i696_window_replay.html",
    ] {
        let meta = std::fs::metadata(out.join(file)).unwrap_or_else(|e| panic!("{file}: {e}"));
        assert!(meta.len() > 100, "{file} is nearly empty");
    }
    // Each step is shown as the command a user would type.
    assert!(
        stderr.contains("$ mapc window") && stderr.contains("--junction osm:61862553"),
        "{stderr}"
    );
    // the paper's map takes the paper's corridor and merge, as before, with nothing more to say about it
    assert!(
        stderr.contains("--via osm-way:59440544 --via osm-way:8667198 --via osm-way:8708084")
            && !stderr.contains("is not the paper's I-696 map"),
        "{stderr}"
    );
    assert_the_evaluation_ran(&stdout, 3);
    std::fs::remove_dir_all(&out).unwrap();
}

#[test]
fn pipeline_names_a_missing_map() {
    let out = fresh_path("pipeline-missing");
    let run = mapc_command()
        .args(["pipeline", "maps/nonesuch.osm", "-o"])
        .arg(&out)
        .output()
        .unwrap();
    assert_eq!(run.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&run.stderr).contains("nonesuch.osm"));
    // it fails before writing anything, its output folder included
    assert!(!out.exists());
}

/// On a map other than I-696 the paper's `--via` and `--junction` do not apply: the pipeline takes the default
/// corridor, cuts a window at every merge that fits, says so, and runs to the evaluation.
#[test]
fn pipeline_on_another_map_takes_the_default_corridor() {
    let out = fresh_path("pipeline-rongwu");
    let run = mapc_command()
        .args(["pipeline", "maps/rongwu.net.xml", "--seeds", "2", "-o"])
        .arg(&out)
        .output()
        .unwrap();
    let stdout = String::from_utf8_lossy(&run.stdout);
    let stderr = String::from_utf8_lossy(&run.stderr);
    assert!(run.status.success(), "pipeline failed:\n{stderr}");
    // what it chose, before the steps that use it
    let chose = stderr
        .find("is not the paper's I-696 map")
        .expect("the pipeline says what it chose");
    assert!(
        stderr[chose..].contains("`mapc simplify`'s default route")
            && stderr[chose..].contains("every merge of it that fits"),
        "{stderr}"
    );
    let simplify = stderr.find("$ mapc simplify").unwrap();
    assert!(chose < simplify, "{stderr}");
    assert!(!stderr.contains("osm-way:59440544"), "{stderr}");
    assert!(
        stderr.contains("$ mapc window") && stderr.contains(" --all --fit "),
        "{stderr}"
    );
    // the corridor passes the expressway's one merge, and the window is cut there
    assert!(stdout.contains("window at J5 (gneJ12)"), "{stdout}");
    for file in [
        "rongwu.graph.json",
        "rongwu.corridor.graph.json",
        "rongwu_window.toml",
        "rongwu_window_human_trace.csv",
        "rongwu_window_policy_trace.csv",
        "rongwu_window_timespace.png",
        "rongwu_window_replay.html",
    ] {
        let meta = std::fs::metadata(out.join(file)).unwrap_or_else(|e| panic!("{file}: {e}"));
        assert!(meta.len() > 100, "{file} is nearly empty");
    }
    assert!(
        stdout.contains("2 seeds") || stdout.contains("seeds: 2"),
        "{stdout}"
    );
    std::fs::remove_dir_all(&out).unwrap();
}

/// `mapc pipeline --keep-lanes`: the whole job multi-lane on the I-696 map, its outputs named apart, the window
/// cut with its lanes, vehicles changing lanes in the run, one lane drawn in the time-space diagram.
#[test]
fn pipeline_keeps_the_lanes_end_to_end() {
    let out = fresh_path("pipeline-lanes");
    let run = mapc_command()
        .args([
            "pipeline",
            "--keep-lanes",
            "--lane",
            "1",
            "--seeds",
            "2",
            "--json",
            "-o",
        ])
        .arg(&out)
        .output()
        .unwrap();
    let stdout = String::from_utf8_lossy(&run.stdout);
    let stderr = String::from_utf8_lossy(&run.stderr);
    assert!(run.status.success(), "pipeline failed:\n{stderr}");
    assert!(
        stderr.contains("--via osm-way:8708084 --keep-lanes")
            && stderr.contains("--junction osm:61862553")
            && stderr.contains("i696_lanes_window_timespace.png --lane 1"),
        "{stderr}"
    );
    for file in [
        "i696.graph.json",
        "i696_lanes.corridor.graph.json",
        "i696_lanes_window.toml",
        "i696_lanes_window.graph.json",
        "i696_lanes_window.png",
        "i696_lanes_window_human_trace.csv",
        "i696_lanes_window_policy_trace.csv",
        "i696_lanes_window_timespace.png",
        "i696_lanes_window_replay.html",
    ] {
        let meta = std::fs::metadata(out.join(file)).unwrap_or_else(|e| panic!("{file}: {e}"));
        assert!(meta.len() > 100, "{file} is nearly empty");
    }
    // the one-lane run's names are left alone
    assert!(!out.join("i696_window.toml").exists());
    // the window keeps the corridor's lanes: 3 after the merge, 2 on I-696
    let g = mapc_graph::LaneGraph::load(&out.join("i696_lanes_window.graph.json")).unwrap();
    let most = g.roads.iter().map(|r| r.lanes.len()).max().unwrap();
    assert!(most >= 3, "at most {most} lanes");
    // vehicles drive on several lanes and change between them: some vehicle is seen on two lanes of one road
    let trace = std::fs::read_to_string(out.join("i696_lanes_window_human_trace.csv")).unwrap();
    let mut seen: std::collections::BTreeMap<(&str, &str), std::collections::BTreeSet<&str>> =
        Default::default();
    for row in trace.lines().skip(1) {
        let f: Vec<&str> = row.split(',').collect();
        seen.entry((f[1], f[3])).or_default().insert(f[8]);
    }
    let lanes: std::collections::BTreeSet<&str> = seen.values().flatten().copied().collect();
    assert!(lanes.len() >= 3, "{lanes:?}");
    let changed = seen.values().filter(|l| l.len() > 1).count();
    assert!(changed > 50, "{changed} vehicles changed lanes on a road");
    assert_the_evaluation_ran(&stdout, 2);
    std::fs::remove_dir_all(&out).unwrap();
}

/// `mapc eval --human-trace`: the humans' first seed written from the baseline's own run, the same rows a run of
/// its own writes; a policy whose rule leaves every window to the humans gets that same run as its trace; and the
/// report is the one `eval` gives without traces.
#[test]
fn eval_writes_the_humans_trace_from_its_own_baseline_run() {
    let dir = fresh_path("eval-human-trace");
    std::fs::create_dir_all(&dir).unwrap();
    let (humans, policy, alone) = (
        dir.join("humans.csv"),
        dir.join("policy.csv"),
        dir.join("alone.csv"),
    );
    // two lanes: the policy's rule (one lane on every road) leaves the window to the humans
    let eval = |seeds: &str, extra: &[&std::ffi::OsStr]| {
        let out = mapc_command()
            .args([
                "eval",
                "--policy",
                "policies/merge_robust_congested.json",
                "--scenario",
                "scenarios/two_lane_merge_jam_av.toml",
                "--json",
                "--seeds",
                seeds,
            ])
            .args(extra)
            .output()
            .unwrap();
        common::assert_success(&out);
        let mut v: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
        v["wall_s"] = serde_json::Value::Null;
        v
    };
    let traced = eval(
        "2",
        &[
            "--trace".as_ref(),
            policy.as_os_str(),
            "--human-trace".as_ref(),
            humans.as_os_str(),
        ],
    );
    assert!(
        !traced["withheld"].as_array().unwrap().is_empty(),
        "{traced}"
    );
    assert_eq!(traced, eval("2", &[]));
    let rows = std::fs::read_to_string(&humans).unwrap();
    assert!(rows.lines().count() > 1000, "{} rows", rows.lines().count());
    assert_eq!(std::fs::read(&policy).unwrap(), rows.as_bytes());
    // the trace of a run of its own (the policy's, without a baseline to take it from): the same rows
    eval(
        "1",
        &[
            "--no-baseline".as_ref(),
            "--trace".as_ref(),
            alone.as_os_str(),
        ],
    );
    assert_eq!(std::fs::read(&alone).unwrap(), rows.as_bytes());
    std::fs::remove_dir_all(&dir).unwrap();
}
