//! Pictures drawn from generated graphs, traces and logs, read back and checked; and the errors bad input gets.

use crate::pngstats::{count_near, read_png};
use crate::timespace::{RoadFilter, TimeSpaceOptions, plot_timespace, read_trace};
use crate::training::{TrainingPlotOptions, plot_training, read_log};
use crate::{Highlight, VizError, geojson, render_map};
use mapc_graph::{JunctionId, JunctionKind, LaneGraph, Projection, RoadId};
use mapc_scenario::SimpleMergeParams;
use mapc_scenario::generator::simple_merge;
use std::fmt::Write;
use std::path::PathBuf;

fn temp_dir(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("mapc-viz-{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
}

fn merge_graph() -> LaneGraph {
    simple_merge(&SimpleMergeParams::default()).unwrap()
}

/// The Simple Merge placed near the I-696 corridor, in a UTM 17N frame.
fn geographic_merge() -> LaneGraph {
    let mut g = merge_graph();
    g.projection = Projection::utm_around(-83.3429, 42.5261);
    g
}

#[test]
fn simple_merge_renders_to_png_with_classes_and_labels() {
    let dir = temp_dir("render-png");
    let out = dir.join("merge.png");
    let g = merge_graph();
    let s = render_map(&g, &Highlight::default(), &out).unwrap();
    let merges = g.count_kind(JunctionKind::Merge);
    assert_eq!(s.merges, merges);
    assert_eq!(s.labels_drawn, merges, "{s:?}");
    assert_eq!(s.labels_skipped, 0);
    let (stats, pixels) = read_png(&out).unwrap();
    assert_eq!((stats.width, stats.height), (s.width_px, s.height_px));
    assert!(stats.colors > 20, "{stats:?}");
    assert!(stats.ink_fraction > 0.05, "{stats:?}");
    // Both road classes are drawn in their legend colours.
    let cc =
        crate::colors::class_colors(&g.roads.iter().map(|r| r.class.clone()).collect::<Vec<_>>());
    for (class, c) in cc {
        assert!(
            count_near(&pixels, [c.0, c.1, c.2], 2) > 200,
            "class {class} hardly drawn"
        );
    }
    // The scale bar is a 1-2-5 length and about a fifth of the plot.
    let bar_px = s.scale_bar_m / s.metres_per_px;
    assert!(
        bar_px > 0.08 * s.width_px as f64 && bar_px < 0.25 * s.width_px as f64,
        "{s:?}"
    );
    // No temporary file is left beside the picture.
    let left: Vec<_> = std::fs::read_dir(&dir)
        .unwrap()
        .map(|e| e.unwrap().file_name())
        .collect();
    assert_eq!(left.len(), 1, "{left:?}");
    std::fs::remove_dir_all(dir).unwrap();
}

#[test]
fn svg_render_carries_labels_and_highlight() {
    let dir = temp_dir("render-svg");
    let out = dir.join("merge.svg");
    let g = merge_graph();
    let merge = g
        .junctions
        .iter()
        .find(|j| j.kind == JunctionKind::Merge)
        .unwrap()
        .id;
    let h = Highlight::window([RoadId(1), RoadId(4)], [JunctionId(0)]);
    let s = render_map(&g, &h, &out).unwrap();
    assert_eq!(s.roads_highlighted, 2);
    let svg = std::fs::read_to_string(&out).unwrap();
    assert!(svg.starts_with("<svg"), "{}", &svg[..60]);
    assert!(
        svg.contains(&format!("\n{merge}\n")),
        "merge label {merge} missing"
    );
    assert!(svg.contains("\nJ0\n"), "asked-for label missing");
    assert!(svg.contains("transfer window"));
    assert!(svg.contains("\nN\n"), "north arrow missing");
    std::fs::remove_dir_all(dir).unwrap();
}

#[test]
fn zoomed_render_shows_less_than_the_whole_map() {
    let dir = temp_dir("render-zoom");
    let g = merge_graph();
    let whole = render_map(&g, &Highlight::default(), &dir.join("a.png")).unwrap();
    let h = Highlight {
        junctions: [JunctionId(5)].into(),
        zoom_to_highlight: true,
        ..Highlight::default()
    };
    let zoom = render_map(&g, &h, &dir.join("b.png")).unwrap();
    assert!(
        zoom.metres_per_px < whole.metres_per_px,
        "{zoom:?} vs {whole:?}"
    );
    std::fs::remove_dir_all(dir).unwrap();
}

#[test]
fn render_refuses_bad_requests() {
    let dir = temp_dir("render-bad");
    let g = merge_graph();
    let err = render_map(&g, &Highlight::default(), &dir.join("map.jpg")).unwrap_err();
    assert!(matches!(err, VizError::PictureType { .. }), "{err}");
    let h = Highlight::window([RoadId(99)], []);
    let err = render_map(&g, &h, &dir.join("map.png")).unwrap_err();
    assert!(err.to_string().contains("R99"), "{err}");
    let mut empty = g.clone();
    empty.roads.clear();
    let err = render_map(&empty, &Highlight::default(), &dir.join("map.png")).unwrap_err();
    assert!(err.to_string().contains("no roads"), "{err}");
    assert!(!dir.join("map.png").exists());
    std::fs::remove_dir_all(dir).unwrap();
}

#[test]
fn geojson_has_a_feature_per_road_and_junction() {
    let g = geographic_merge();
    let (v, bbox) = geojson::to_geojson(&g);
    assert_eq!(v["type"], "FeatureCollection");
    let features = v["features"].as_array().unwrap();
    assert_eq!(features.len(), g.roads.len() + g.junctions.len());
    let lines = features
        .iter()
        .filter(|f| f["geometry"]["type"] == "LineString")
        .count();
    let points = features
        .iter()
        .filter(|f| f["geometry"]["type"] == "Point")
        .count();
    assert_eq!((lines, points), (g.roads.len(), g.junctions.len()));
    // WGS84 around the point the frame was made at, lon first.
    assert!(
        bbox[0] > -83.36 && bbox[2] < -83.32 && bbox[1] > 42.51 && bbox[3] < 42.54,
        "{bbox:?}"
    );
    let road = &features[0];
    for key in [
        "id",
        "class",
        "name",
        "ref",
        "lanes",
        "speed_mps",
        "length_m",
        "osm_ways",
        "sumo_ids",
    ] {
        assert!(
            road["properties"].get(key).is_some(),
            "road property {key} missing"
        );
    }
    assert_eq!(road["properties"]["sumo_ids"][0], "inflow_highway");
    let junction = features
        .iter()
        .find(|f| f["properties"]["kind"] == "merge")
        .unwrap();
    assert!(junction["properties"]["sumo_id"].is_string());
    assert_eq!(v["mapc_coordinates"], "wgs84");
    // Lengths survive the round trip through longitude/latitude to within a metre.
    let coords = road["geometry"]["coordinates"].as_array().unwrap();
    let p = |i: usize| -> [f64; 2] {
        let c = coords[i].as_array().unwrap();
        g.projection
            .to_local(c[0].as_f64().unwrap(), c[1].as_f64().unwrap())
            .unwrap()
    };
    let (a, b) = (p(0), p(coords.len() - 1));
    let len = (b[0] - a[0]).hypot(b[1] - a[1]);
    assert!(
        (len - g.roads[0].length_m).abs() < 1.0,
        "{len} vs {}",
        g.roads[0].length_m
    );
}

#[test]
fn geojson_of_a_plane_graph_says_it_is_in_metres() {
    let dir = temp_dir("geojson");
    let out = dir.join("sub/merge.geojson");
    let g = merge_graph();
    let s = geojson::write_geojson(&g, &out).unwrap();
    assert_eq!(s.coordinates, "local_metres");
    let v: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&out).unwrap()).unwrap();
    assert_eq!(v["mapc_coordinates"], "local_metres");
    assert!(v["mapc_note"].as_str().unwrap().contains("metres"));
    assert!(v.get("crs").is_none());
    assert!(s.bbox[2] - s.bbox[0] > 500.0, "{:?}", s.bbox);
    std::fs::remove_dir_all(dir).unwrap();
}

/// A trace with a stop-and-go wave: vehicles drive 25 m/s on a 1 km corridor but crawl near a slow spot that moves
/// upstream at 5 m/s; every fifth vehicle is an AV; a ramp vehicle has no corridor position.
fn wave_trace() -> String {
    let mut s = crate::timespace::TRACE_COLUMNS.join(",");
    s.push('\n');
    let dt = 0.5;
    for v in 0..60 {
        let depart = v as f64 * 2.0;
        let mut x = 0.0;
        let mut t = depart;
        while x < 1000.0 && t < 200.0 {
            let wave_at = 900.0 - 5.0 * t;
            let speed = if (x - wave_at).abs() < 60.0 {
                2.0
            } else {
                25.0
            };
            let controlled = v % 5 == 0;
            let vtype = if controlled { "av" } else { "human" };
            writeln!(
                s,
                "{t:.2},{v},{vtype},R2,{x:.3},{x:.3},{speed:.3},{controlled}"
            )
            .unwrap();
            x += speed * dt;
            t += dt;
        }
    }
    writeln!(s, "3.00,999,human,R4,12.000,,20.000,false").unwrap();
    s
}

#[test]
fn timespace_shows_slow_and_fast_traffic() {
    let dir = temp_dir("timespace");
    let trace = dir.join("trace.csv");
    std::fs::write(&trace, wave_trace()).unwrap();
    let out = dir.join("ts.png");
    let s = plot_timespace(&trace, &out, &TimeSpaceOptions::default()).unwrap();
    assert_eq!(s.vehicles, 60, "the ramp vehicle has no corridor position");
    assert_eq!(s.controlled_vehicles, 12);
    assert!(s.speed_max_mps >= 25.0);
    assert!(
        s.polylines < s.samples_drawn / 3,
        "runs of equal speed are joined: {s:?}"
    );
    let (stats, pixels) = read_png(&out).unwrap();
    assert_eq!((stats.width, stats.height), (1400, 800));
    let red = crate::colors::speed_color(2.0 / s.speed_max_mps);
    let green = crate::colors::speed_color(25.0 / s.speed_max_mps);
    assert!(
        count_near(&pixels, [red.0, red.1, red.2], 12) > 300,
        "slow band missing"
    );
    assert!(
        count_near(&pixels, [green.0, green.1, green.2], 12) > 3000,
        "free flow missing"
    );
    // SVG too; the ramp road alone when asked.
    let s2 = plot_timespace(
        &trace,
        &dir.join("ts.svg"),
        &TimeSpaceOptions {
            filter: RoadFilter::Roads(vec!["R4".into()]),
            ..TimeSpaceOptions::default()
        },
    )
    .unwrap();
    assert_eq!((s2.vehicles, s2.samples_drawn), (1, 1));
    std::fs::remove_dir_all(dir).unwrap();
}

#[test]
fn timespace_draws_one_lane_or_all() {
    let dir = temp_dir("timespace-lanes");
    // the wave trace with a `lane` column: odd vehicles on lane 1
    let mut two_lanes = String::new();
    for (i, line) in wave_trace().lines().enumerate() {
        let lane = if i == 0 {
            "lane".to_string()
        } else {
            let vid: u32 = line.split(',').nth(1).unwrap().parse().unwrap();
            (vid % 2).to_string()
        };
        writeln!(two_lanes, "{line},{lane}").unwrap();
    }
    let trace = dir.join("two_lanes.csv");
    std::fs::write(&trace, two_lanes).unwrap();
    let draw = |path: &std::path::Path, lane: Option<u8>| {
        plot_timespace(
            path,
            &dir.join("ts.png"),
            &TimeSpaceOptions {
                lane,
                ..TimeSpaceOptions::default()
            },
        )
    };
    let all = draw(&trace, None).unwrap();
    let right = draw(&trace, Some(0)).unwrap();
    let left = draw(&trace, Some(1)).unwrap();
    assert_eq!((all.vehicles, right.vehicles, left.vehicles), (60, 30, 30));
    assert_eq!(right.samples_drawn + left.samples_drawn, all.samples_drawn);
    // a trace written before lanes has every vehicle on lane 0
    let old = dir.join("old.csv");
    std::fs::write(&old, wave_trace()).unwrap();
    assert_eq!(draw(&old, Some(0)).unwrap().vehicles, 60);
    let none = draw(&old, Some(1)).unwrap_err().to_string();
    assert!(
        none.contains("in lane 1") && none.contains("old.csv"),
        "{none}"
    );
    std::fs::remove_dir_all(dir).unwrap();
}

#[test]
fn bad_traces_are_reported_with_file_line_and_column() {
    let dir = temp_dir("timespace-bad");
    let path = dir.join("t.csv");
    let missing = read_trace(&dir.join("absent.csv"), &RoadFilter::Main).unwrap_err();
    assert!(missing.to_string().contains("absent.csv"), "{missing}");

    std::fs::write(&path, "time_s,vehicle_id,road,speed_mps\n0,1,R1,3\n").unwrap();
    let err = read_trace(&path, &RoadFilter::Main)
        .unwrap_err()
        .to_string();
    assert!(
        err.contains("t.csv") && err.contains("`corridor_x_m`") && err.contains("`controlled`"),
        "{err}"
    );

    let mut text = wave_trace();
    text.push_str("4.00,7,human,R2,1.0,1.0,fast,false\n");
    let bad_line = text.lines().count();
    std::fs::write(&path, &text).unwrap();
    let err = read_trace(&path, &RoadFilter::Main).unwrap_err();
    match &err {
        VizError::Field { line, column, .. } => {
            assert_eq!(
                (*line as usize, column.as_str()),
                (bad_line, "speed_mps"),
                "{err}"
            );
        }
        other => panic!("{other}"),
    }
    assert!(err.to_string().contains("`fast` is not a number"), "{err}");

    std::fs::write(
        &path,
        format!(
            "{}\n0,1,human,R1,2,2,3\n",
            crate::timespace::TRACE_COLUMNS.join(",")
        ),
    )
    .unwrap();
    let err = read_trace(&path, &RoadFilter::Main)
        .unwrap_err()
        .to_string();
    assert!(
        err.contains("line 2") && err.contains("7 fields where the header has 8"),
        "{err}"
    );

    std::fs::write(
        &path,
        format!(
            "{}\n0,1,human,R1,2,,3,false\n",
            crate::timespace::TRACE_COLUMNS.join(",")
        ),
    )
    .unwrap();
    let err = plot_timespace(&path, &dir.join("x.png"), &TimeSpaceOptions::default())
        .unwrap_err()
        .to_string();
    assert!(err.contains("no samples on the main line"), "{err}");
    std::fs::write(&path, "").unwrap();
    assert!(read_trace(&path, &RoadFilter::Main).is_err());
    std::fs::remove_dir_all(dir).unwrap();
}

fn write_log(dir: &std::path::Path, header: &str, rows: usize, scale: f64) {
    std::fs::create_dir_all(dir).unwrap();
    let cols: Vec<&str> = header.split(',').collect();
    let mut s = format!("{header}\n");
    for i in 0..rows {
        let f = i as f64;
        let row: Vec<String> = cols
            .iter()
            .map(|c| match *c {
                "iteration" => format!("{}", i + 1),
                "env_steps" => format!("{}", (i + 1) * 40_000),
                "wall_s" => format!("{:.3}", f * 31.5),
                "mean_return" => format!("{}", scale * (100.0 + 30.0 * (1.0 - (-f / 20.0).exp()))),
                "mean_outflow" => format!("{}", 1500.0 + 5.0 * f),
                "mean_speed" => format!("{}", 8.0 + 0.05 * f),
                "policy_loss" => format!("{}", -0.01 / (1.0 + f)),
                "value_loss" => format!("{}", 50.0 / (1.0 + f)),
                "kl" => format!("{}", 0.01 + 0.001 * (f * 0.7).sin()),
                "entropy" => format!("{}", 1.4 - 0.01 * f),
                "kl_coeff" => "0.2".to_string(),
                _ => "0".to_string(),
            })
            .collect();
        s.push_str(&row.join(","));
        s.push('\n');
    }
    std::fs::write(dir.join("progress.csv"), s).unwrap();
}

#[test]
fn training_curves_overlay_runs_and_tolerate_missing_columns() {
    let dir = temp_dir("training");
    let full = crate::training::LOG_COLUMNS.join(",");
    write_log(&dir.join("run_a"), &full, 60, 1.0);
    write_log(
        &dir.join("run_b"),
        "iteration,mean_return,mean_outflow,kl",
        40,
        0.9,
    );
    let out = dir.join("curves.png");
    let opts = TrainingPlotOptions {
        baseline_outflow: Some(1550.0),
        ..TrainingPlotOptions::default()
    };
    // run_a's best.json was chosen by its row 30 (only `selected` is read; the weights are left out here)
    std::fs::write(
        dir.join("run_a/best.json"),
        r#"{"format_version":1,"selected":{"by":"outflow","score":1720.0,"row_iteration":30}}"#,
    )
    .unwrap();
    let plain = plot_training(&[dir.join("run_a")], &dir.join("plain.png"), &opts).unwrap();
    std::fs::remove_file(dir.join("run_a/best.json")).unwrap();
    let unmarked = plot_training(&[dir.join("run_a")], &dir.join("unmarked.png"), &opts).unwrap();
    assert_eq!(plain.runs[0].best_iteration, Some(30));
    assert_eq!(unmarked.runs[0].best_iteration, None);
    let near_black = |path: &std::path::Path| count_near(&read_png(path).unwrap().1, [0, 0, 0], 40);
    assert!(
        near_black(&dir.join("plain.png")) > near_black(&dir.join("unmarked.png")) + 8 * 20,
        "no best-row marker drawn on the eight panels"
    );
    // a best.json that is not the trainer's is named
    std::fs::write(dir.join("run_a/best.json"), "{\"selected\": 3}").unwrap();
    let err = plot_training(&[dir.join("run_a")], &dir.join("x.png"), &opts)
        .unwrap_err()
        .to_string();
    assert!(err.contains("best.json") && err.contains("line 1"), "{err}");
    std::fs::remove_file(dir.join("run_a/best.json")).unwrap();
    let s = plot_training(&[dir.join("run_a"), dir.join("run_b")], &out, &opts).unwrap();
    assert_eq!(s.runs.len(), 2);
    assert_eq!(s.runs[0].rows, 60);
    assert!(s.runs[0].missing_columns.is_empty());
    assert!(
        s.runs[1]
            .missing_columns
            .contains(&"value_loss".to_string())
    );
    assert!(s.empty_panels.is_empty(), "run_a fills every panel");
    assert!((s.runs[0].last["mean_outflow"] - 1795.0).abs() < 1e-9);
    let (stats, pixels) = read_png(&out).unwrap();
    assert_eq!((stats.width, stats.height), (1800, 900));
    for i in 0..2 {
        let c = crate::colors::run_color(i);
        assert!(
            count_near(&pixels, [c.0, c.1, c.2], 10) > 500,
            "run {i} curves missing"
        );
    }
    // A log of one run with only some columns leaves the others' panels empty.
    let s = plot_training(
        &[dir.join("run_b")],
        &dir.join("b.svg"),
        &TrainingPlotOptions::default(),
    )
    .unwrap();
    assert!(s.empty_panels.contains(&"value_loss".to_string()));
    assert!(!s.empty_panels.contains(&"kl".to_string()));
    std::fs::remove_dir_all(dir).unwrap();
}

#[test]
fn bad_training_logs_are_reported() {
    let dir = temp_dir("training-bad");
    let err = read_log(&dir.join("nope")).unwrap_err().to_string();
    assert!(err.contains("nope"), "{err}");
    std::fs::write(dir.join("progress.csv"), "iteration,foo\n1,2\n").unwrap();
    let err = read_log(&dir).unwrap_err().to_string();
    assert!(
        err.contains("none of the training log's value columns"),
        "{err}"
    );
    std::fs::write(
        dir.join("progress.csv"),
        "iteration,mean_return\n1,2\n2,abc\n",
    )
    .unwrap();
    let err = read_log(&dir).unwrap_err();
    assert!(
        matches!(&err, VizError::Field { line: 3, column, .. } if column == "mean_return"),
        "{err}"
    );
    std::fs::write(dir.join("progress.csv"), "iteration,mean_return\n").unwrap();
    let err = plot_training(
        std::slice::from_ref(&dir),
        &dir.join("c.png"),
        &TrainingPlotOptions::default(),
    )
    .unwrap_err();
    assert!(err.to_string().contains("no rows"), "{err}");
    std::fs::remove_dir_all(dir).unwrap();
}
