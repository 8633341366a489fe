//! Hostile input files and outputs end to end: values no road has in a map, graph files that break what the
//! importers guarantee, endless inputs, control characters bound for an SVG, and `mapc window` failing after it
//! began writing. Each is refused with one message naming the file and the place, exit code 2, and leaves nothing.

mod common;

use common::{mapc_command, refused, root, run_mapc, scratch_dir};
use std::path::{Path, PathBuf};

/// `maps/simple_merge.net.xml` with `edit` applied to its text, written as `<name>.net.xml` in a scratch folder.
fn edited_net(name: &str, edit: impl Fn(String) -> String) -> PathBuf {
    let text = std::fs::read_to_string(root().join("maps/simple_merge.net.xml")).unwrap();
    let edited = edit(text.clone());
    assert_ne!(edited, text, "the edit changed nothing");
    let path = scratch_dir(name).join(format!("{name}.net.xml"));
    std::fs::write(&path, edited).unwrap();
    path
}

/// The Simple Merge's lane `bottom_0` with `key="old"` set to `value`.
fn bottom_lane(key: &str, old: &str, value: &str) -> impl Fn(String) -> String {
    let (key, old, value) = (key.to_string(), old.to_string(), value.to_string());
    move |text: String| {
        let lane = text
            .lines()
            .find(|l| l.contains("<lane id=\"bottom_0\""))
            .unwrap()
            .to_string();
        let edited = lane.replacen(
            &format!("{key}=\"{old}\""),
            &format!("{key}=\"{value}\""),
            1,
        );
        text.replacen(&lane, &edited, 1)
    }
}

/// The names in `dir`, sorted.
fn names_in(dir: &Path) -> Vec<String> {
    let mut names: Vec<String> = std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    names.sort();
    names
}

fn s(p: &Path) -> &str {
    p.to_str().unwrap()
}

#[test]
fn a_lane_speed_no_road_has_is_refused_at_import_naming_the_file_line_and_lane() {
    let net = edited_net("speed-tiny", bottom_lane("speed", "30.00", "1e-300"));
    let out = net.with_file_name("x.graph.json");
    refused(
        &["import", s(&net), "-o", s(&out)],
        &[
            "speed-tiny.net.xml: line 49",
            "lane `bottom_0`: speed 1e-300 is outside [0.1, 1000] m/s",
        ],
    );
    assert!(!out.exists());
}

#[test]
fn window_on_a_lane_of_1e308_m_refuses_at_import_and_writes_nothing() {
    let net = edited_net("length-huge", bottom_lane("length", "100.00", "1e308"));
    let dir = net.parent().unwrap().to_path_buf();
    let out = dir.join("w.toml");
    refused(
        &["window", s(&net), "--junction", "center", "-o", s(&out)],
        &[
            "length-huge.net.xml: line 49",
            "lane `bottom_0`: length 1e308",
        ],
    );
    assert_eq!(names_in(&dir), vec!["length-huge.net.xml"]);
}

#[test]
fn window_that_fails_after_making_its_files_writes_neither() {
    let dir = scratch_dir("window-n-av");
    let out = dir.join("w.toml");
    let map = "scenarios/i696.corridor.graph.json";
    refused(
        &[
            "window",
            map,
            "--junction",
            "osm:61862553",
            "--n-av",
            "4294967295",
            "-o",
            s(&out),
        ],
        // the flag's own range refuses it before any work
        &["--n-av", "0..=1000"],
    );
    assert!(names_in(&dir).is_empty(), "{:?}", names_in(&dir));
    // `-o` naming a folder: the graph beside it is not written either
    let folder = dir.join("taken.toml");
    std::fs::create_dir(&folder).unwrap();
    refused(
        &[
            "window",
            map,
            "--junction",
            "osm:61862553",
            "-o",
            s(&folder),
        ],
        &["taken.toml", "is a directory", "nothing written"],
    );
    assert_eq!(names_in(&dir), vec!["taken.toml"]);
}

#[test]
fn window_all_on_a_raw_map_simplifies_it_first() {
    let dir = scratch_dir("window-all-raw");
    let out = dir.join("w.toml");
    let run = run_mapc(&["window", "maps/i696.osm", "--all", "-o", s(&out)]);
    assert!(
        run.status.success(),
        "{}",
        String::from_utf8_lossy(&run.stderr)
    );
    assert_eq!(names_in(&dir), vec!["w.graph.json", "w.toml"]);
}

#[test]
fn control_characters_of_an_edge_type_do_not_reach_the_svg() {
    let net = edited_net("ctrl-type", |t| {
        t.replace("type=\"mergeType\"", "type=\"merge\u{1b}[31m\u{7}Type\"")
    });
    let svg = net.with_file_name("map.svg");
    let run = run_mapc(&["render", s(&net), "-o", s(&svg)]);
    assert!(
        run.status.success(),
        "{}",
        String::from_utf8_lossy(&run.stderr)
    );
    let text = std::fs::read_to_string(&svg).unwrap();
    assert!(
        text.contains("merge\\u001b[31m\\u0007Type"),
        "the type is not shown"
    );
    let forbidden: Vec<char> = text
        .chars()
        .filter(|&c| !mapc_graph::markup::allowed_in_xml(c))
        .collect();
    assert!(forbidden.is_empty(), "{forbidden:?}");
}

/// The shipped one-window graph with `edit` applied to its JSON, as `bad.graph.json` in a scratch folder.
fn edited_graph(name: &str, edit: impl Fn(&mut serde_json::Value)) -> PathBuf {
    let text = std::fs::read_to_string(root().join("scenarios/i696_window.graph.json")).unwrap();
    let mut graph: serde_json::Value = serde_json::from_str(&text).unwrap();
    edit(&mut graph);
    let path = scratch_dir(name).join("bad.graph.json");
    std::fs::write(&path, serde_json::to_string_pretty(&graph).unwrap()).unwrap();
    path
}

#[test]
fn a_graph_file_that_breaks_what_the_importers_guarantee_is_refused() {
    use serde_json::json;
    let missing_junction = edited_graph("graph-to", |g| g["roads"][0]["to"] = json!("J9999"));
    refused(
        &["junctions", s(&missing_junction)],
        &["bad.graph.json: line ", "names missing junction J9999"],
    );
    let negative = edited_graph("graph-length", |g| g["roads"][1]["length_m"] = json!(-1.0));
    refused(
        &["junctions", s(&negative)],
        &["bad.graph.json: line ", "has length_m -1"],
    );
    let twice = edited_graph("graph-twice", |g| {
        let id = g["roads"][0]["id"].clone();
        g["roads"][1]["id"] = id;
    });
    refused(
        &["junctions", s(&twice)],
        &["bad.graph.json", "appears twice"],
    );
}

#[test]
fn a_huge_number_is_shown_short() {
    let scenario = common::edited_scenario("simple_merge.toml", "angle-huge", |t| {
        t.replace("angle_deg = 45.0", "angle_deg = 1e308")
    });
    let said = refused(&["scenario", "show", s(&scenario)], &["angle_deg", "1e308"]);
    assert!(!said.contains("0000000000"), "{said}");
}

/// `mapc ARGS` with the input cap at 1 MB: refused as [`refused`] checks.
fn refused_capped(args: &[&str], expected: &[&str]) {
    let out = mapc_command()
        .env("MAPC_MAX_INPUT_MB", "1")
        .args(args)
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(2), "mapc {args:?}: {stderr}");
    for e in expected {
        assert!(stderr.contains(e), "expected `{e}` in: {stderr}");
    }
}

#[cfg(unix)]
#[test]
fn endless_inputs_are_read_only_up_to_the_cap() {
    let too_large = "larger than 1 MB, the most mapc reads of an input (set MAPC_MAX_INPUT_MB";
    refused_capped(
        &["scenario", "show", "/dev/zero"],
        &["/dev/zero", too_large],
    );
    let scenario = common::edited_scenario("i696_window.toml", "graph-zero", |t| {
        t.replace(
            "graph = \"i696_window.graph.json\"",
            "graph = \"/dev/zero\"",
        )
    });
    refused_capped(
        &["scenario", "show", s(&scenario)],
        &["/dev/zero", too_large],
    );
    // a map from a device: read (up to the cap) and named for what it is not
    refused_capped(
        &["import", "/dev/zero"],
        &["/dev/zero", "not a map mapc reads"],
    );
    // a regular file over the cap is refused before it is read
    refused_capped(
        &["junctions", "maps/i696.osm"],
        &["maps/i696.osm", too_large],
    );
}

#[test]
fn a_killed_writers_temporary_is_removed_by_the_next_write() {
    let dir = scratch_dir("stale-temporary");
    let out = dir.join("x.graph.json");
    // no process has this id (Linux caps them at 2^22)
    let stale = dir.join(".x.graph.json.4000000000.tmp");
    std::fs::write(&stale, "half a graph").unwrap();
    let run = run_mapc(&["import", "maps/simple_merge.net.xml", "-o", s(&out)]);
    assert!(
        run.status.success(),
        "{}",
        String::from_utf8_lossy(&run.stderr)
    );
    assert_eq!(names_in(&dir), vec!["x.graph.json"]);
}

#[test]
fn an_output_that_cannot_be_written_is_refused_before_the_run() {
    // 100 000 seeds would run for hours: the refusal must come first, naming the file
    let dir = scratch_dir("unwritable-outputs");
    let folder = dir.join("taken.csv");
    std::fs::create_dir(&folder).unwrap();
    let file = dir.join("plain.txt");
    std::fs::write(&file, "").unwrap();
    let under_file = file.join("trips.xml");
    refused(
        &[
            "sim",
            "scenarios/simple_merge.toml",
            "--seeds",
            "100000",
            "--trace",
            s(&folder),
        ],
        &["taken.csv", "is a directory"],
    );
    refused(
        &[
            "sim",
            "scenarios/sumo/highway_ramp/highway-ramp.sumocfg",
            "--seeds",
            "100000",
            "--tripinfo-output",
            s(&under_file),
        ],
        &["plain.txt/trips.xml"],
    );
    // the loops' folder named where a file stands
    refused(
        &[
            "sim",
            "scenarios/sumo/ramp_metering_1x3/1ramp_1x3.sumocfg",
            "--seeds",
            "100000",
            "--detector-output",
            s(&file),
        ],
        &["plain.txt"],
    );
    for flag in ["--trace", "--human-trace"] {
        refused(
            &[
                "eval",
                "--policy",
                "policies/simple_merge_outflow.json",
                "--scenario",
                "scenarios/simple_merge.toml",
                "--seeds",
                "100000",
                flag,
                s(&folder),
            ],
            &["taken.csv", "is a directory"],
        );
    }
    // nothing left beside them
    assert_eq!(names_in(&dir), vec!["plain.txt", "taken.csv"]);
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn a_refused_input_leaves_no_output_folder() {
    // the outputs' folders, missing, are checked before loading but made only when their files are written: a
    // scenario refused at load leaves none of them
    let dir = scratch_dir("refused-no-folders");
    let cfg = dir.join("bad.sumocfg");
    std::fs::write(
        &cfg,
        "<configuration><input><net-file value=\"missing.net.xml\"/></input></configuration>",
    )
    .unwrap();
    let out = dir.join("out");
    refused(
        &[
            "sim",
            s(&cfg),
            "--seeds",
            "1",
            "--detector-output",
            s(&out.join("loops")),
            "--tripinfo-output",
            s(&out.join("trips").join("t.xml")),
            "--summary-output",
            s(&out.join("s.xml")),
        ],
        &["missing.net.xml"],
    );
    // the pipeline's folder too: its import makes it, and a map refused there leaves none
    let map = dir.join("bad.osm");
    std::fs::write(&map, "not a map").unwrap();
    refused(
        &["pipeline", s(&map), "-o", s(&out.join("job"))],
        &["bad.osm"],
    );
    assert_eq!(names_in(&dir), vec!["bad.osm", "bad.sumocfg"]);
}
