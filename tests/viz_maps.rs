//! `mapc render` and `mapc export` on the real I-696 map and the Simple Merge, and their errors.

use mapc_viz::pngstats::read_png;
use std::path::Path;
use std::process::Output;

mod common;

use common::{run_mapc as mapc, scratch_dir};

fn json_of(out: &Output) -> serde_json::Value {
    assert!(
        out.status.success(),
        "mapc failed: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    serde_json::from_slice(&out.stdout)
        .unwrap_or_else(|e| panic!("{e}: {}", String::from_utf8_lossy(&out.stdout)))
}

fn s(p: &Path) -> &str {
    p.to_str().unwrap()
}

#[test]
fn i696_renders_to_a_real_png() {
    let dir = scratch_dir("i696-png");
    let png = dir.join("i696.png");
    let summary = json_of(&mapc(&["render", "maps/i696.osm", "-o", s(&png), "--json"]));
    let merges = summary["merges"].as_u64().unwrap();
    assert!(merges >= 5, "the I-696 corridor has many merges: {summary}");
    assert!(summary["labels_drawn"].as_u64().unwrap() >= 5, "{summary}");
    assert!(summary["roads_drawn"].as_u64().unwrap() > 50, "{summary}");
    let (stats, pixels) = read_png(&png).unwrap();
    assert_eq!(stats.width, 1600);
    assert_eq!(stats.height as u64, summary["height_px"].as_u64().unwrap());
    assert!(std::fs::metadata(&png).unwrap().len() > 20_000);
    assert!(stats.colors > 50, "{stats:?}");
    assert!(stats.ink_fraction > 0.1, "{stats:?}");
    // Motorways are drawn in their class colour (196, 30, 58).
    assert!(
        mapc_viz::pngstats::count_near(&pixels, [196, 30, 58], 3) > 2_000,
        "no motorway pixels"
    );
    // The corridor is some 10 km long: a 1-2-5 scale bar of a few km.
    let bar = summary["scale_bar_m"].as_f64().unwrap();
    assert!((500.0..=5000.0).contains(&bar), "{summary}");
    std::fs::remove_dir_all(dir).unwrap();
}

#[test]
fn i696_exports_to_geojson_in_michigan() {
    let dir = scratch_dir("i696-geojson");
    let out = dir.join("i696.geojson");
    let summary = json_of(&mapc(&[
        "export",
        "maps/i696.osm",
        "--geojson",
        s(&out),
        "--json",
    ]));
    assert_eq!(summary["coordinates"], "wgs84");
    let v: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&out).unwrap()).unwrap();
    assert_eq!(v["type"], "FeatureCollection");
    let features = v["features"].as_array().unwrap();
    let roads = summary["roads"].as_u64().unwrap() as usize;
    let junctions = summary["junctions"].as_u64().unwrap() as usize;
    assert_eq!(features.len(), roads + junctions);
    let bbox: Vec<f64> = v["bbox"]
        .as_array()
        .unwrap()
        .iter()
        .map(|x| x.as_f64().unwrap())
        .collect();
    // West of Detroit, around the I-696 / I-275 interchange.
    assert!(
        bbox[0] > -83.7 && bbox[2] < -83.0 && bbox[1] > 42.3 && bbox[3] < 42.7,
        "{bbox:?}"
    );
    let road = features
        .iter()
        .find(|f| f["properties"]["class"] == "motorway")
        .expect("a motorway");
    assert!(
        !road["properties"]["osm_ways"]
            .as_array()
            .unwrap()
            .is_empty()
    );
    assert!(road["geometry"]["coordinates"].as_array().unwrap().len() >= 2);
    let merge = features
        .iter()
        .find(|f| f["properties"]["kind"] == "merge")
        .expect("a merge");
    assert!(merge["properties"]["osm_node"].is_i64(), "{merge}");
    std::fs::remove_dir_all(dir).unwrap();
}

#[test]
fn simple_merge_renders_svg_and_exports_local_metres() {
    let dir = scratch_dir("merge");
    let svg = dir.join("merge.svg");
    let out = mapc(&[
        "render",
        "simple_merge",
        "-o",
        s(&svg),
        "--label",
        "J0",
        "--highlight",
        "R4",
    ]);
    common::assert_success(&out);
    let text = std::fs::read_to_string(&svg).unwrap();
    assert!(text.starts_with("<svg") && text.contains("\nJ0\n"));
    let gj = dir.join("merge.geojson");
    let summary = json_of(&mapc(&[
        "export",
        "simple_merge",
        "--geojson",
        s(&gj),
        "--json",
    ]));
    assert_eq!(summary["coordinates"], "local_metres");
    std::fs::remove_dir_all(dir).unwrap();
}

#[test]
fn bad_map_requests_exit_2_with_the_reason() {
    let dir = scratch_dir("bad");
    let cases: [(Vec<String>, &str); 4] = [
        (
            vec![
                "render".into(),
                "maps/no_such.osm".into(),
                "-o".into(),
                s(&dir.join("a.png")).into(),
            ],
            "no_such.osm",
        ),
        (
            vec![
                "render".into(),
                "simple_merge".into(),
                "-o".into(),
                s(&dir.join("a.jpg")).into(),
            ],
            "a.jpg",
        ),
        (
            vec![
                "render".into(),
                "simple_merge".into(),
                "-o".into(),
                s(&dir.join("a.png")).into(),
                "--label".into(),
                "J99".into(),
            ],
            "J99",
        ),
        (
            vec![
                "export".into(),
                "maps/no_such.osm".into(),
                "--geojson".into(),
                s(&dir.join("a.geojson")).into(),
            ],
            "no_such.osm",
        ),
    ];
    for (args, needle) in cases {
        let args: Vec<&str> = args.iter().map(String::as_str).collect();
        let out = mapc(&args);
        let err = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(2), "{args:?}: {err}");
        assert!(err.contains(needle), "{args:?}: {err}");
        assert!(!err.contains("panicked"), "{err}");
    }
    assert_eq!(
        std::fs::read_dir(&dir).unwrap().count(),
        0,
        "nothing written on failure"
    );
    std::fs::remove_dir_all(dir).unwrap();
}
