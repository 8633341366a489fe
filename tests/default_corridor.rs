//! The default corridor (`mapc simplify MAP` without `--via`) on real nets whose roads lack a type: it passes the
//! map's merge, and a corridor that passes none says so, naming the map's merges, how to list them and `--via`.

mod common;

use common::{assert_success, run_mapc, scratch_dir};
use serde_json::Value;

fn simplify_json(args: &[&str]) -> (Value, String) {
    let out = run_mapc(args);
    assert_success(&out);
    (
        serde_json::from_slice(&out.stdout).unwrap(),
        String::from_utf8_lossy(&out.stderr).into_owned(),
    )
}

fn merge_ids(report: &Value) -> Vec<String> {
    report["merges"]
        .as_array()
        .unwrap()
        .iter()
        .map(|m| m["sumo_id"].as_str().unwrap_or_default().to_string())
        .collect()
}

/// The Rongwu Expressway net: its edges after the on-ramp's merge (gneJ12) have no `type`. The default corridor
/// used to be the longest typed chain, 3.9 km before the merge, with no merge at all.
#[test]
fn the_default_corridor_passes_the_merge_where_roads_have_no_type() {
    let dir = scratch_dir("rongwu-default");
    let out = dir.join("rongwu.corridor.graph.json");
    let (report, stderr) = simplify_json(&[
        "simplify",
        "maps/rongwu.net.xml",
        "--json",
        "-o",
        out.to_str().unwrap(),
    ]);
    assert_eq!(merge_ids(&report), ["gneJ12"], "{report:#}");
    let merge = &report["merges"][0];
    // the whole expressway: 4.9 km before the merge, 1.4 km after it
    assert!(merge["main_before_m"].as_f64().unwrap() > 4500.0, "{merge}");
    assert!(merge["main_after_m"].as_f64().unwrap() > 1000.0, "{merge}");
    assert!(report.get("warning").is_none() && !stderr.contains("warning"));
    std::fs::remove_dir_all(&dir).ok();
}

/// The same holds on a net stripped of every edge type: the route goes by speed, and passes merges.
#[test]
fn the_default_corridor_does_not_need_types() {
    let dir = scratch_dir("untyped-lust");
    let text = std::fs::read_to_string(common::root().join("maps/lust_motorway.net.xml")).unwrap();
    let untyped: String = text
        .lines()
        .map(|l| {
            if l.trim_start().starts_with("<edge ") {
                let mut l = l.to_string();
                while let Some(at) = l.find(" type=\"") {
                    let end = at + 7 + l[at + 7..].find('"').unwrap() + 1;
                    l.replace_range(at..end, "");
                }
                l
            } else {
                l.to_string()
            }
        })
        .collect::<Vec<_>>()
        .join("\n");
    assert!(!untyped.contains("type=\"highway."));
    let net = dir.join("lust_untyped.net.xml");
    std::fs::write(&net, untyped).unwrap();
    let out = dir.join("lust_untyped.corridor.graph.json");
    let (report, _) = simplify_json(&[
        "simplify",
        net.to_str().unwrap(),
        "--json",
        "-o",
        out.to_str().unwrap(),
    ]);
    assert!(
        report["main_road"]["length_m"].as_f64().unwrap() > 10_000.0,
        "{report:#}"
    );
    assert!(!merge_ids(&report).is_empty(), "{report:#}");
    std::fs::remove_dir_all(&dir).ok();
}

/// Where the allowed roads cannot reach the merge (`--classes trunk` leaves only the untyped pieces after it), the
/// corridor has none, and `simplify` says so: the map's merge, how to list merges and how to choose a route.
#[test]
fn a_corridor_without_a_merge_says_how_to_choose_one() {
    let dir = scratch_dir("rongwu-no-merge");
    let out = dir.join("rongwu.corridor.graph.json");
    let args = [
        "simplify",
        "maps/rongwu.net.xml",
        "--classes",
        "trunk",
        "-o",
        out.to_str().unwrap(),
    ];
    let run = run_mapc(&args);
    assert_success(&run);
    let stderr = String::from_utf8_lossy(&run.stderr);
    for expected in [
        "warning: the corridor's main road passes no merge",
        "J5 (gneJ12)",
        "mapc junctions maps/rongwu.net.xml --kind merge",
        "mapc simplify maps/rongwu.net.xml --via JUNCTION",
    ] {
        assert!(
            stderr.contains(expected),
            "expected `{expected}` in: {stderr}"
        );
    }
    let (report, _) = simplify_json(&[&args[..], &["--json"]].concat());
    assert!(merge_ids(&report).is_empty(), "{report:#}");
    assert!(
        report["warning"].as_str().unwrap().contains("--via"),
        "{report:#}"
    );
    // and the route the warning points to has the merge
    let (report, _) = simplify_json(&[
        "simplify",
        "maps/rongwu.net.xml",
        "--via",
        "gneJ12",
        "--json",
        "-o",
        out.to_str().unwrap(),
    ]);
    assert_eq!(merge_ids(&report), ["gneJ12"], "{report:#}");
    std::fs::remove_dir_all(&dir).ok();
}
