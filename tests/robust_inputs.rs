//! Inputs that hold across stages: files mapc wrote are read back by their content whatever their name, junction
//! and road ids listed on a map are accepted (or refused with the reason) by every later command, a `--via` the
//! corridor does not honour is an error, and statistics never claim an interval from one seed.

mod common;

use common::{assert_success, mapc_json as json_of, refused, root, run_mapc, scratch_dir};
use serde_json::Value;
use std::path::Path;

fn s(p: &Path) -> &str {
    p.to_str().unwrap()
}

#[test]
fn a_graph_reads_back_whatever_its_name() {
    let dir = scratch_dir("graph-names");
    let from_map = run_mapc(&["junctions", "maps/simple_merge.net.xml", "--json"]);
    assert_success(&from_map);
    for name in ["x.graph", "x.txt", "x", "x.osm"] {
        let graph = dir.join(name);
        if name == "x.osm" {
            // a graph under a map's name is recognised, not parsed as OSM XML
            std::fs::copy(dir.join("x.graph"), &graph).unwrap();
        } else {
            assert_success(&run_mapc(&[
                "import",
                "maps/simple_merge.net.xml",
                "-o",
                s(&graph),
            ]));
        }
        let listed = run_mapc(&["junctions", s(&graph), "--json"]);
        assert_success(&listed);
        assert_eq!(listed.stdout, from_map.stdout, "{name}");
        // and the next stages take it too
        assert_success(&run_mapc(&[
            "export",
            s(&graph),
            "--geojson",
            s(&dir.join(format!("{name}.geojson"))),
        ]));
    }
    // A graph is not a map to import, and another JSON file is named for what it is.
    refused(
        &["import", s(&dir.join("x.txt")), "-o", s(&dir.join("y"))],
        &["x.txt", "is a mapc graph, not a map to import"],
    );
    refused(
        &["junctions", "policies/simple_merge_flow.json"],
        &["simple_merge_flow.json", "a mapc policy"],
    );
    refused(
        &["junctions", "scenarios/simple_merge.toml"],
        &["simple_merge.toml", "a mapc scenario, not a map or a graph"],
    );
    std::fs::remove_dir_all(dir).unwrap();
}

#[test]
fn a_scenario_and_a_policy_read_back_whatever_their_name() {
    let dir = scratch_dir("other-names");
    let scenario = dir.join("simple_merge.json");
    std::fs::copy(root().join("scenarios/simple_merge.toml"), &scenario).unwrap();
    // a scenario named .json is drawn as a scenario (its network), not refused as a graph
    let drawn = json_of(&[
        "render",
        s(&scenario),
        "-o",
        s(&dir.join("s.png")),
        "--json",
    ]);
    assert!(drawn["roads_drawn"].as_u64().unwrap() > 0, "{drawn}");
    let policy = dir.join("flow.bin");
    std::fs::copy(root().join("policies/simple_merge_flow.json"), &policy).unwrap();
    let out = run_mapc(&[
        "eval",
        "--policy",
        s(&policy),
        "--scenario",
        s(&scenario),
        "--seeds",
        "1",
    ]);
    assert_success(&out);
    let text = String::from_utf8_lossy(&out.stdout);
    // one seed: a mean, never "± 0.00" nor a verdict on intervals
    assert!(text.contains("n = 1, no CI"), "{text}");
    assert!(!text.contains('±') && !text.contains("disjoint"), "{text}");
    let sim = run_mapc(&["sim", "--scenario", s(&scenario), "--seeds", "1"]);
    assert_success(&sim);
    let text = String::from_utf8_lossy(&sim.stdout);
    assert!(
        text.contains("n = 1, no CI") && !text.contains('±'),
        "{text}"
    );
    // a graph or a policy given as a scenario is named for what it is
    refused(
        &["sim", "--scenario", "scenarios/i696_window.graph.json"],
        &["i696_window.graph.json", "is a mapc graph, not a scenario"],
    );
    refused(
        &["sim", "--scenario", s(&policy)],
        &["flow.bin", "is a mapc policy, not a scenario"],
    );
    refused(
        &["eval", "--policy", s(&scenario), "--seeds", "1"],
        &["simple_merge.json", "is a mapc scenario, not a policy"],
    );
    std::fs::remove_dir_all(dir).unwrap();
}

/// A map given as a scenario or a policy is named for what it is (by its content, whatever its name), with the
/// commands that make a scenario of it, instead of a TOML or JSON syntax error.
#[test]
fn a_map_given_as_a_scenario_or_a_policy_says_what_it_is_and_how_to_make_one() {
    let dir = scratch_dir("map-as-scenario");
    let renamed = dir.join("merge.toml");
    std::fs::copy(root().join("maps/simple_merge.net.xml"), &renamed).unwrap();
    for (map, what) in [
        ("maps/i696.osm", "is an OSM XML map, not a scenario"),
        ("maps/i696.osm.pbf", "is an OSM PBF map, not a scenario"),
        (s(&renamed), "is a SUMO network (net.xml), not a scenario"),
    ] {
        let said = refused(
            &["sim", "--scenario", map, "--seeds", "1"],
            &[
                map,
                what,
                &format!("`mapc pipeline {map}`"),
                &format!("`mapc window {map} --junction J"),
            ],
        );
        assert!(!said.contains("TOML parse error"), "{said}");
        assert_eq!(said.trim_end().lines().count(), 1, "{said}");
    }
    refused(
        &["eval", "--policy", "maps/i696.osm", "--seeds", "1"],
        &[
            "maps/i696.osm",
            "is an OSM XML map, not a policy",
            "mapc train",
        ],
    );
    std::fs::remove_dir_all(dir).unwrap();
}

/// The I-696 merge's id as `mapc junctions` lists it on the raw map.
fn listed_id(map: &str, node: i64) -> String {
    let listing = json_of(&["junctions", map, "--kind", "merge", "--json"]);
    listing
        .as_array()
        .unwrap()
        .iter()
        .find(|j| j["provenance"] == format!("osm:{node}"))
        .expect("the merge is listed")["id"]
        .as_str()
        .unwrap()
        .to_string()
}

#[test]
fn a_junction_id_from_the_map_holds_through_simplify_and_window() {
    let dir = scratch_dir("ids");
    let id = listed_id("maps/i696.osm", 61862553);
    let corridor = dir.join("c.graph.json");
    let report = json_of(&[
        "simplify",
        "maps/i696.osm",
        "--via",
        &id,
        "-o",
        s(&corridor),
        "--json",
    ]);
    let merges = report["merges"].as_array().unwrap();
    assert!(
        merges
            .iter()
            .any(|m| m["junction"] == id.as_str() && m["osm_node"] == 61862553),
        "{report}"
    );
    // no junction is listed twice
    let mut named: Vec<&str> = merges
        .iter()
        .map(|m| m["junction"].as_str().unwrap())
        .collect();
    named.sort();
    let n = named.len();
    named.dedup();
    assert_eq!(named.len(), n, "{report}");
    // the same id on the raw map and on the corridor, for window
    for input in ["maps/i696.osm", s(&corridor)] {
        let w = json_of(&[
            "window",
            input,
            "--junction",
            &id,
            "-o",
            s(&dir.join("w.toml")),
            "--json",
        ]);
        assert_eq!(w["junction"], id.as_str(), "{w}");
        assert_eq!(w["osm_node"], 61862553, "{w}");
    }
    std::fs::remove_dir_all(dir).unwrap();
}

#[test]
fn a_joined_junction_is_named_and_a_via_off_the_corridor_is_refused() {
    let dir = scratch_dir("joined");
    let corridor = dir.join("c.graph.json");
    let mut args = vec!["simplify", "maps/i696.osm"];
    args.extend(common::PAPER_VIA);
    args.extend(["-o", s(&corridor)]);
    assert_success(&run_mapc(&args));
    let g = mapc_graph::LaneGraph::load(&corridor).unwrap();
    // a joint of the raw map is a road of the corridor now: every lookup says which
    let (road, joint) = g
        .roads
        .iter()
        .find_map(|r| {
            r.provenance
                .joined
                .iter()
                .find(|id| id.starts_with('J'))
                .map(|j| (r.id.to_string(), j.clone()))
        })
        .expect("join_chains joined something");
    refused(
        &[
            "window",
            s(&corridor),
            "--junction",
            &joint,
            "-o",
            s(&dir.join("w.toml")),
        ],
        &[&format!("`{joint}` is no longer a junction"), &road],
    );
    // --via points the corridor cannot pass in that order: refused, nothing written
    let never = dir.join("never.graph.json");
    refused(
        &[
            "simplify",
            "maps/i696.osm",
            "--via",
            "osm-way:8708084",
            "--via",
            "osm-way:59440544",
            "-o",
            s(&never),
        ],
        &["--via"],
    );
    assert!(!never.exists());
    // a --via the corridor passes through a joined junction is honoured
    assert_success(&run_mapc(&[
        "simplify",
        s(&corridor),
        "--via",
        &joint,
        "-o",
        s(&dir.join("again.graph.json")),
    ]));
    std::fs::remove_dir_all(dir).unwrap();
}

#[test]
fn footway_and_service_junctions_are_no_merges_unless_asked() {
    let listed = |extra: &[&str]| -> Vec<Value> {
        let mut args = vec!["junctions", "maps/i696_onelane_proxy.net.xml", "--json"];
        args.extend(extra);
        json_of(&args).as_array().unwrap().clone()
    };
    let minor = |j: &Value| {
        j["incoming"]
            .as_array()
            .unwrap()
            .iter()
            .chain(j["outgoing"].as_array().unwrap())
            .any(|r| mapc_graph::is_minor_class(r["class"].as_str().unwrap()))
    };
    let main = listed(&[]);
    assert!(!main.iter().any(minor), "service roads are left out");
    let all = listed(&["--minor-roads"]);
    assert!(all.iter().any(minor), "--minor-roads lists them");
    // Where a service road meets the motorway, the kind is that among the motorway roads.
    let kind_of = |rows: &[Value], id: &Value| {
        rows.iter()
            .find(|j| &j["id"] == id)
            .map(|j| j["kind"].clone())
    };
    let changed: Vec<&Value> = all
        .iter()
        .filter(|j| minor(j))
        .filter_map(|j| {
            kind_of(&main, &j["id"])
                .filter(|k| k != &j["kind"])
                .map(|_| &j["id"])
        })
        .collect();
    assert!(
        !changed.is_empty(),
        "some junction changes kind without its service roads"
    );
    // The corridor's merging roads leave them out too.
    let dir = scratch_dir("minor");
    let report = json_of(&[
        "simplify",
        "maps/i696_onelane_proxy.net.xml",
        "-o",
        s(&dir.join("c.graph.json")),
        "--json",
    ]);
    for m in report["merges"].as_array().unwrap() {
        assert_ne!(m["merging_label"], "highway.service", "{m}");
    }
    std::fs::remove_dir_all(dir).unwrap();
}

/// Every merge `mapc junctions` lists on a raw map is a merge `mapc window` can cut at, under the same id: the
/// corridor it builds keeps that junction a merge (at 62354802 the longest route comes in on the ramp, and the
/// I-696 road in would be a road that leaves and rejoins it; the route through the I-696 road is taken instead).
#[test]
fn every_listed_merge_windows_under_its_id() {
    let dir = scratch_dir("every-merge");
    for (map, only) in [
        ("maps/i696_onelane_proxy.net.xml", None),
        ("maps/i696.osm", Some("osm:62354802")),
    ] {
        let listing = json_of(&["junctions", map, "--kind", "merge", "--json"]);
        for j in listing.as_array().unwrap() {
            if only.is_some_and(|p| j["provenance"] != p) {
                continue;
            }
            let id = j["id"].as_str().unwrap();
            let w = json_of(&[
                "window",
                map,
                "--junction",
                id,
                "-o",
                s(&dir.join(format!("{id}.toml"))),
                "--json",
            ]);
            assert_eq!(w["junction"], id, "{map} {id}: {w}");
        }
    }
    std::fs::remove_dir_all(dir).unwrap();
}

/// A merge of reversible express lanes (I-5 in Seattle, osm2streets' test input): the importer drops the reversible
/// ways (a counted warning), so the junction is gone, and `mapc window` says so naming `--junction`, not the
/// `--via` it routes through.
#[test]
fn a_junction_the_import_dropped_is_named_as_the_window_asked() {
    let out = scratch_dir("dropped-junction");
    let scenario = out.join("w.toml");
    let msg = refused(
        &[
            "window",
            "maps/i5_exit_ramp.osm",
            "--junction",
            "osm:29545445",
            "-o",
            s(&scenario),
        ],
        &[
            "maps/i5_exit_ramp.osm",
            "--junction osm:29545445",
            "no junction",
        ],
    );
    assert!(!msg.contains("--via"), "{msg}");
    assert!(!scenario.exists());
    let import = run_mapc(&[
        "import",
        "maps/i5_exit_ramp.osm",
        "-o",
        s(&out.join("i5.graph.json")),
    ]);
    assert_success(&import);
    assert!(String::from_utf8_lossy(&import.stdout).contains("oneway_reversible_dropped"));
    std::fs::remove_dir_all(&out).ok();
}
