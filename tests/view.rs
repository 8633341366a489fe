//! `mapc view` end to end: the page's figures against `mapc sim` and `mapc eval` on the same seed, its size and
//! self-containment, the bare map, the server, and bad input.

use serde_json::Value;
use std::io::{BufRead, BufReader, Read, Write};
use std::path::Path;

mod common;

use common::{assert_success, run_mapc as mapc, scratch_dir};

fn json_of(out: &std::process::Output) -> Value {
    assert_success(out);
    serde_json::from_slice(&out.stdout).expect("--json prints JSON")
}

fn s(p: &Path) -> &str {
    p.to_str().unwrap()
}

/// `mapc sim` of the Simple Merge's seed `seed`, its trace written to `trace`: its report.
fn simple_merge_trace(seed: u64, trace: &Path) -> Value {
    json_of(&mapc(&[
        "sim",
        "--scenario",
        "simple_merge",
        "--seeds",
        "1",
        "--first-seed",
        &seed.to_string(),
        "--trace",
        s(trace),
        "--json",
    ]))
}

/// The page's figures at its last frame, as `mapc view --json` reports them.
fn pane(summary: &Value, i: usize) -> (f64, f64, f64) {
    let p = &summary["panes"][i];
    (
        p["outflow_veh_h"].as_f64().unwrap(),
        p["inflow_veh_h"].as_f64().unwrap(),
        p["avg_speed_mps"].as_f64().unwrap(),
    )
}

#[test]
fn a_simple_merge_replay_is_self_contained_small_and_shows_the_simulators_figures() {
    let dir = scratch_dir("view-sm");
    let page = dir.join("replay.html");
    let summary = json_of(&mapc(&[
        "view",
        "simple_merge",
        "--seed",
        "3",
        "-o",
        s(&page),
        "--json",
    ]));
    // the same seed run by `mapc sim`, its trace kept
    let trace = dir.join("seed3.csv");
    let sim = simple_merge_trace(3, &trace);
    let run = &sim["runs"][0];
    let (outflow, inflow, speed) = pane(&summary, 0);
    // the page keeps f32; the trace rounds speeds to the centimetre per second
    assert!((outflow - run["outflow_veh_h"].as_f64().unwrap()).abs() < 0.01);
    assert!((inflow - run["inflow_veh_h"].as_f64().unwrap()).abs() < 0.01);
    assert!((speed - run["avg_speed_mps"].as_f64().unwrap()).abs() < 0.01);
    assert_eq!(summary["panes"][0]["frames"], 2001);
    assert_eq!(summary["panes"][0]["decimation"], 1);

    let html = std::fs::read_to_string(&page).unwrap();
    assert_eq!(summary["bytes"].as_u64().unwrap() as usize, html.len());
    assert!(
        html.len() < 2_000_000,
        "a 2000-step replay is {} bytes",
        html.len()
    );
    // everything inline: no file or address to fetch
    for outside in ["<script src", "<link", "http://", "https://", "@import"] {
        assert!(
            !html.contains(outside),
            "the page refers outside itself: {outside}"
        );
    }
    let start = html.find("id=\"mapc-data\">").unwrap() + "id=\"mapc-data\">".len();
    let end = start + html[start..].find("</script>").unwrap();
    let data: Value = serde_json::from_str(&html[start..end]).unwrap();
    assert_eq!(data["format"], "mapc-view");
    assert_eq!(data["network"]["roads"].as_array().unwrap().len(), 5);
    assert_eq!(data["replays"][0]["frames"], 2001);

    // that trace plays as the same run (its figures from the trace's frames: f32, speeds to the cm/s)
    let replayed = json_of(&mapc(&[
        "view",
        "simple_merge",
        "--trace",
        s(&trace),
        "-o",
        s(&dir.join("trace.html")),
        "--json",
    ]));
    let (from_trace, from_run) = (pane(&replayed, 0), pane(&summary, 0));
    assert!(
        (from_trace.0 - from_run.0).abs() < 0.01,
        "{from_trace:?} {from_run:?}"
    );
    assert!(
        (from_trace.1 - from_run.1).abs() < 0.01,
        "{from_trace:?} {from_run:?}"
    );
    assert!(
        (from_trace.2 - from_run.2).abs() < 0.01,
        "{from_trace:?} {from_run:?}"
    );
    assert_eq!(
        replayed["panes"][0]["vehicle_steps"],
        summary["panes"][0]["vehicle_steps"]
    );

    // two traces play side by side (a policy's beside ALINEA's, say): each its own pane, in the order given
    let other = dir.join("seed4.csv");
    simple_merge_trace(4, &other);
    let two = json_of(&mapc(&[
        "view",
        "simple_merge",
        "--trace",
        s(&trace),
        "--trace",
        s(&other),
        "-o",
        s(&dir.join("two.html")),
        "--json",
    ]));
    assert_eq!(two["panes"].as_array().unwrap().len(), 2);
    assert_eq!(pane(&two, 0), pane(&replayed, 0));
    assert_ne!(pane(&two, 1), pane(&replayed, 0));
    let three = mapc(&[
        "view",
        "simple_merge",
        "--trace",
        s(&trace),
        "--trace",
        s(&other),
        "--trace",
        s(&other),
        "-o",
        s(&dir.join("three.html")),
    ]);
    assert_eq!(three.status.code(), Some(2));
    assert!(!dir.join("three.html").exists());

    // a run larger than the page holds keeps every k-th step, and says so; its last frame is the run's
    let steps = summary["panes"][0]["vehicle_steps"].as_u64().unwrap();
    let small = json_of(&mapc(&[
        "view",
        "simple_merge",
        "--seed",
        "3",
        "--max-rows",
        &(steps / 4).to_string(),
        "-o",
        s(&dir.join("small.html")),
        "--json",
    ]));
    assert_eq!(small["panes"][0]["decimation"], 5);
    assert_eq!(small["panes"][0]["frames"], 401);
    let kept = small["panes"][0]["vehicle_steps"].as_u64().unwrap();
    assert!(kept <= steps / 4 && kept > steps / 6, "{kept} of {steps}");
    assert_eq!(pane(&small, 0), pane(&summary, 0));
}

#[test]
fn compare_plays_the_humans_and_the_policy_as_mapc_eval_scores_them() {
    let dir = scratch_dir("view-compare");
    let page = dir.join("i696.html");
    let policy = "policies/simple_merge_outflow.json";
    let scenario = "scenarios/i696_window.toml";
    let summary = json_of(&mapc(&[
        "view",
        scenario,
        "--policy",
        policy,
        "--compare",
        "-o",
        s(&page),
        "--json",
    ]));
    let eval = json_of(&mapc(&[
        "eval",
        "--policy",
        policy,
        "--scenario",
        scenario,
        "--seeds",
        "1",
        "--json",
    ]));
    assert_eq!(summary["panes"].as_array().unwrap().len(), 2);
    assert_eq!(summary["windows"], 1);
    let (human_out, human_in, _) = pane(&summary, 0);
    let (policy_out, policy_in, _) = pane(&summary, 1);
    assert!((human_out - eval["baseline"]["outflow"]["mean"].as_f64().unwrap()).abs() < 0.01);
    assert!((human_in - eval["baseline"]["inflow"]["mean"].as_f64().unwrap()).abs() < 0.01);
    assert!((policy_out - eval["outflow"]["mean"].as_f64().unwrap()).abs() < 0.01);
    assert!((policy_in - eval["inflow"]["mean"].as_f64().unwrap()).abs() < 0.01);
    assert_ne!(human_out, policy_out, "the two panes are different runs");
    // the corridor's run is about 400 000 vehicle-steps, kept whole
    let steps = summary["panes"][1]["vehicle_steps"].as_u64().unwrap();
    assert!(steps > 300_000, "{steps}");
    assert_eq!(summary["panes"][1]["decimation"], 1);
    let html = std::fs::read_to_string(&page).unwrap();
    assert!(
        html.contains("osm:61862553"),
        "the window's merge keeps its OSM id"
    );
}

/// A policy whose deployment rule leaves the merge to the humans (the main road has priority there): its pane is the
/// humans' run, and the page says why.
#[test]
fn a_withheld_window_plays_the_humans_and_says_why() {
    let dir = scratch_dir("view-withheld");
    let page = dir.join("arizona.html");
    let summary = json_of(&mapc(&[
        "view",
        "scenarios/merges/arizona_5134463770.toml",
        "--policy",
        "policies/merge_robust.json",
        "--compare",
        "-o",
        s(&page),
        "--json",
    ]));
    assert_eq!(pane(&summary, 0), pane(&summary, 1));
    let html = std::fs::read_to_string(&page).unwrap();
    assert!(
        html.contains(
            "left to the humans (the main road has priority at merge J15 (osm:5134463770))"
        ),
        "the page names the withheld merge"
    );
}

#[test]
fn a_bare_map_shows_its_roads_and_junctions_with_provenance() {
    let dir = scratch_dir("view-map");
    let page = dir.join("map.html");
    let summary = json_of(&mapc(&["view", "maps/i696.osm", "-o", s(&page), "--json"]));
    let graph = dir.join("i696.graph.json");
    let import = json_of(&mapc(&[
        "import",
        "maps/i696.osm",
        "-o",
        s(&graph),
        "--json",
    ]));
    assert_eq!(summary["roads"], import["roads"]);
    assert_eq!(summary["junctions"], import["junctions"]);
    assert!(summary["panes"].as_array().unwrap().is_empty());
    let html = std::fs::read_to_string(&page).unwrap();
    assert!(html.contains("osm:61862553") && html.contains("osm-way:124433709"));
}

#[test]
fn serve_answers_the_page_and_its_data_on_loopback() {
    let mut child = common::mapc_command()
        .args(["view", "simple_merge", "--serve", "--max-requests", "3"])
        .stdout(std::process::Stdio::piped())
        .spawn()
        .unwrap();
    let mut first = String::new();
    BufReader::new(child.stdout.take().unwrap())
        .read_line(&mut first)
        .unwrap();
    let addr = first
        .split("http://")
        .nth(1)
        .and_then(|r| r.split('/').next())
        .unwrap_or_else(|| panic!("no address in `{first}`"))
        .to_string();
    assert!(addr.starts_with("127.0.0.1:"), "{addr}");
    let get = |path: &str| {
        let mut stream = std::net::TcpStream::connect(&addr).unwrap();
        write!(stream, "GET {path} HTTP/1.1\r\nHost: {addr}\r\n\r\n").unwrap();
        let mut answer = String::new();
        stream.read_to_string(&mut answer).unwrap();
        answer
    };
    let page = get("/");
    assert!(page.starts_with("HTTP/1.1 200"), "{}", &page[..40]);
    assert!(page.contains("fetch(\"data.json\")") && !page.contains("id=\"mapc-data\""));
    // the page's Content-Security-Policy comes as a header too, the same as its <meta>; it may fetch data.json
    let (head, body) = page.split_once("\r\n\r\n").unwrap();
    let policy = head
        .lines()
        .find_map(|l| l.strip_prefix("Content-Security-Policy: "))
        .unwrap_or_else(|| panic!("no Content-Security-Policy header: {head}"));
    assert!(body.contains(&format!(
        "<meta http-equiv=\"Content-Security-Policy\" content=\"{policy}\">"
    )));
    assert!(
        policy.starts_with("default-src 'none'; script-src 'sha256-")
            && policy.contains("connect-src 'self'"),
        "{policy}"
    );
    assert!(head.contains("X-Content-Type-Options: nosniff"));
    let data = get("/data.json");
    assert!(data.starts_with("HTTP/1.1 200"));
    let body = &data[data.find("\r\n\r\n").unwrap() + 4..];
    let json: Value = serde_json::from_str(body).unwrap();
    assert_eq!(json["replays"].as_array().unwrap().len(), 1);
    assert!(get("/secret").starts_with("HTTP/1.1 404"));
    // three requests served: the server stops by itself
    assert!(child.wait().unwrap().success());
}

#[test]
fn bad_input_is_one_message_with_exit_code_2_and_no_page() {
    let dir = scratch_dir("view-errors");
    let refused = |args: &[&str], needle: &str| {
        let out = mapc(args);
        let err = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(2), "{args:?}: {err}");
        assert!(err.contains(needle), "{args:?}: `{err}` lacks `{needle}`");
        assert!(!err.contains("panicked"), "{err}");
    };
    let page = dir.join("p.html");
    refused(&["view", "no_such.toml", "-o", s(&page)], "no_such.toml");
    refused(
        &[
            "view",
            "maps/i696.osm",
            "--policy",
            "policies/simple_merge_outflow.json",
            "-o",
            s(&page),
        ],
        "is a map, not a scenario",
    );
    // a trace whose vehicle skips a step
    let trace = dir.join("gap.csv");
    std::fs::write(
        &trace,
        "time_s,vehicle_id,vehicle_type,road,pos_on_road_m,corridor_x_m,speed_mps,controlled\n\
         1.00,0,human,R0,5.0,5.0,10.0,false\n1.50,0,human,R0,10.0,10.0,10.0,false\n\
         2.50,0,human,R0,20.0,20.0,10.0,false\n",
    )
    .unwrap();
    refused(
        &["view", "simple_merge", "--trace", s(&trace), "-o", s(&page)],
        "line 4",
    );
    // a road the scenario does not have
    std::fs::write(
        &trace,
        "time_s,vehicle_id,vehicle_type,road,pos_on_road_m,corridor_x_m,speed_mps,controlled\n\
         1.00,0,human,R99,5.0,,10.0,false\n",
    )
    .unwrap();
    refused(
        &["view", "simple_merge", "--trace", s(&trace), "-o", s(&page)],
        "road `R99`",
    );
    assert!(!page.exists(), "no page is written for bad input");
    // an output that cannot be written (a folder stands there) is named, and the folder is left as it was
    let folder = dir.join("taken");
    std::fs::create_dir_all(folder.join("inside")).unwrap();
    refused(&["view", "simple_merge", "-o", s(&folder)], "taken");
    assert!(folder.join("inside").is_dir());
    assert_eq!(
        std::fs::read_dir(&dir).unwrap().count(),
        2,
        "no temporary file is left"
    );
    let _ = std::fs::remove_dir_all(&dir);
}

/// A policy whose rule leaves every window to the humans drives their run: `--compare` shows that one run in both
/// panes (run once), with the figures `mapc eval` gives for the seed.
#[test]
fn compare_with_a_withheld_policy_shows_the_humans_run_in_both_panes() {
    let dir = scratch_dir("view-withheld");
    let page = dir.join("withheld.html");
    let args = [
        "--policy",
        "policies/merge_robust_congested.json",
        "--scenario",
        "scenarios/two_lane_merge_jam_av.toml",
    ];
    let summary = json_of(&mapc(&[
        "view",
        "scenarios/two_lane_merge_jam_av.toml",
        args[0],
        args[1],
        "--compare",
        "--json",
        "-o",
        s(&page),
    ]));
    let panes = summary["panes"].as_array().unwrap();
    assert_eq!(panes.len(), 2);
    assert!(panes[1]["label"].as_str().unwrap().starts_with("policy "));
    for k in ["frames", "vehicles", "vehicle_steps"] {
        assert_eq!(panes[0][k], panes[1][k], "{k}");
    }
    assert_eq!(pane(&summary, 0), pane(&summary, 1));
    let eval = json_of(&mapc(&[
        "eval", args[0], args[1], args[2], args[3], "--seeds", "1", "--json",
    ]));
    assert!(!eval["withheld"].as_array().unwrap().is_empty(), "{eval}");
    assert_eq!(
        pane(&summary, 1).0,
        eval["outflow"]["mean"].as_f64().unwrap()
    );
}
