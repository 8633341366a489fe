//! A merge where neither road yields (the LuST motorway net's J55, osm:-22284: a motorway and the corridor both
//! enter a link road with the right of way). Vehicles entering side by side run beside each other on their own
//! connections up to the conflict point; the one behind waits there for the other's tail. The simulator's
//! per-step overlap check (on in debug builds, so in this test's binary) once took that for a collision and
//! stopped the run at t = 934 s of seed 0.

mod common;

use common::{run_mapc, scratch_dir};

#[test]
fn vehicles_beside_each_other_at_a_both_major_merge_are_not_a_collision() {
    let dir = scratch_dir("both-major");
    let corridor = dir.join("lust.corridor.graph.json");
    let window = dir.join("lust_window.toml");
    let out = run_mapc(&[
        "simplify",
        "maps/lust_motorway.net.xml",
        "-o",
        corridor.to_str().unwrap(),
    ]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let out = run_mapc(&[
        "window",
        corridor.to_str().unwrap(),
        "--all",
        "--match",
        "simple_merge",
        "-o",
        window.to_str().unwrap(),
    ]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let out = run_mapc(&[
        "sim",
        "--scenario",
        window.to_str().unwrap(),
        "--seeds",
        "3",
        "--json",
    ]);
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success(), "{stderr}");
    assert!(!stderr.contains("collision"), "{stderr}");
    let report: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    assert_eq!(
        report["runs"].as_array().map(Vec::len),
        Some(3),
        "{report:#}"
    );
    assert!(
        report["outflow"]["mean"].as_f64().unwrap() > 1000.0,
        "{report:#}"
    );
    std::fs::remove_dir_all(&dir).ok();
}
