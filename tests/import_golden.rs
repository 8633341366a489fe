//! `mapc import` and `mapc junctions` on the real maps, compared with the golden files in `tests/golden/<map>/`.
//! `MAPC_BLESS=1 cargo test --test import_golden` rewrites them; with `CI` set, a set `MAPC_BLESS` is an error.

use std::path::PathBuf;
use std::process::Command;

/// (input, golden folder, summary file): one folder per map, named by its stem as the other goldens are; the PBF
/// copy of i696 has its own summary beside the XML's.
const MAPS: [(&str, &str, &str); 5] = [
    ("i696.osm", "i696", "summary.json"),
    ("i696.osm.pbf", "i696", "summary.pbf.json"),
    (
        "i696_onelane_proxy.net.xml",
        "i696_onelane_proxy",
        "summary.json",
    ),
    ("simple_merge.net.xml", "simple_merge", "summary.json"),
    ("us_merge.net.xml", "us_merge", "summary.json"),
];

mod common;

use common::{blessing, check_golden, root, run_mapc};

fn scratch(name: &str) -> PathBuf {
    common::scratch_dir("import-golden").join(name)
}

fn mapc(args: &[&str]) -> String {
    let out = run_mapc(args);
    assert!(
        out.status.success(),
        "mapc {args:?} failed: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    String::from_utf8(out.stdout).unwrap()
}

#[test]
fn import_summaries_match_the_goldens() {
    for (map, folder, summary_file) in MAPS {
        let input = format!("maps/{map}");
        let out = scratch(&format!("{map}.graph.json"));
        let mut summary: serde_json::Value = serde_json::from_str(&mapc(&[
            "import",
            &input,
            "-o",
            out.to_str().unwrap(),
            "--json",
        ]))
        .unwrap();
        assert_eq!(summary["output"], out.to_str().unwrap());
        summary.as_object_mut().unwrap().remove("output");
        let folder = root().join("tests/golden").join(folder);
        check_golden(&folder.join(summary_file), &summary);
        // The golden folder points at its inputs rather than copying them.
        let pointer =
            folder.join(format!("{summary_file}.input.txt").replace(".json.input", ".input"));
        if blessing() {
            std::fs::write(&pointer, format!("../../../maps/{map}\n")).unwrap();
        }
        let named = std::fs::read_to_string(&pointer).unwrap();
        assert!(
            folder.join(named.trim()).exists(),
            "{} names a missing file",
            pointer.display()
        );
        // The written graph loads and agrees with the summary.
        let graph: serde_json::Value =
            serde_json::from_str(&std::fs::read_to_string(&out).unwrap()).unwrap();
        assert_eq!(
            graph["junctions"].as_array().unwrap().len() as u64,
            summary["junctions"].as_u64().unwrap()
        );
    }
}

#[test]
fn merge_listings_match_the_goldens() {
    for (map, folder, summary_file) in MAPS {
        if summary_file != "summary.json" {
            continue; // the PBF gives the same graph, so the same listing
        }
        let listing: serde_json::Value = serde_json::from_str(&mapc(&[
            "junctions",
            &format!("maps/{map}"),
            "--kind",
            "merge",
            "--json",
        ]))
        .unwrap();
        for j in listing.as_array().unwrap() {
            assert_eq!(j["kind"], "merge");
            assert_eq!(j["incoming"].as_array().unwrap().len(), 2);
        }
        check_golden(
            &root().join("tests/golden").join(folder).join("merges.json"),
            &listing,
        );
    }
}

#[test]
fn junctions_reads_a_saved_graph_like_the_map() {
    let out = scratch("simple_merge.graph.json");
    mapc(&[
        "import",
        "maps/simple_merge.net.xml",
        "-o",
        out.to_str().unwrap(),
    ]);
    let from_graph = mapc(&["junctions", out.to_str().unwrap(), "--json"]);
    let from_map = mapc(&["junctions", "maps/simple_merge.net.xml", "--json"]);
    assert_eq!(from_graph, from_map);
    let text = mapc(&["junctions", "maps/simple_merge.net.xml", "--kind", "merge"]);
    assert!(
        text.contains("(center)") && text.contains("left") && text.contains("bottom"),
        "{text}"
    );
}

#[test]
fn i696_merges_named_in_the_issue_are_listed() {
    let listing: serde_json::Value = serde_json::from_str(&mapc(&[
        "junctions",
        "maps/i696.osm",
        "--kind",
        "merge",
        "--json",
    ]))
    .unwrap();
    for (node, way) in [
        (61862553, 124433709),
        (61860453, 8666737),
        (62339796, 178253095),
    ] {
        let j = listing
            .as_array()
            .unwrap()
            .iter()
            .find(|j| j["provenance"] == format!("osm:{node}"))
            .unwrap_or_else(|| panic!("no merge at node {node}"));
        assert!(
            j["incoming"]
                .as_array()
                .unwrap()
                .iter()
                .any(|r| r["osm_ways"][0] == way),
            "{j}"
        );
        assert!(j["lat"].as_f64().unwrap() > 42.4 && j["lon"].as_f64().unwrap() < -83.3);
    }
}

#[test]
fn default_output_is_the_stem_in_the_current_directory() {
    let dir = scratch("cwd");
    std::fs::create_dir_all(&dir).unwrap();
    let map = root().join("maps/us_merge.net.xml");
    let out = Command::new(env!("CARGO_BIN_EXE_mapc"))
        .args(["import", map.to_str().unwrap()])
        .current_dir(&dir)
        .output()
        .unwrap();
    common::assert_success(&out);
    assert!(dir.join("us_merge.graph.json").exists());
    let text = String::from_utf8(out.stdout).unwrap();
    assert!(
        text.contains("junctions") && text.contains("merges"),
        "{text}"
    );
}
