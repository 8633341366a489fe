//! `mapc plot timespace` and `mapc plot training` end to end, and their errors.

use mapc_viz::pngstats::{count_near, read_png};
use std::fmt::Write;
use std::path::Path;

mod common;

use common::{run_mapc as mapc, scratch_dir};

fn s(p: &Path) -> &str {
    p.to_str().unwrap()
}

const HEADER: &str =
    "time_s,vehicle_id,vehicle_type,road,pos_on_road_m,corridor_x_m,speed_mps,controlled";

/// 40 vehicles on a 600 m corridor through a jam that moves upstream; every tenth is an AV.
fn wave_trace() -> String {
    let mut out = format!("{HEADER}\n");
    for v in 0..40 {
        let (mut x, mut t) = (0.0f64, v as f64 * 2.5);
        while x < 600.0 {
            let jam = 550.0 - 4.0 * t;
            let speed = if (x - jam).abs() < 40.0 { 1.0 } else { 22.0 };
            let controlled = v % 10 == 0;
            writeln!(
                out,
                "{t:.2},{v},{},R1,{x:.3},{x:.3},{speed:.3},{controlled}",
                if controlled { "av" } else { "human" }
            )
            .unwrap();
            x += 0.5 * speed;
            t += 0.5;
        }
    }
    out
}

#[test]
fn timespace_diagram_shows_the_jam() {
    let dir = scratch_dir("ts");
    let trace = dir.join("trace.csv");
    std::fs::write(&trace, wave_trace()).unwrap();
    let png = dir.join("ts.png");
    let out = mapc(&["plot", "timespace", s(&trace), "-o", s(&png), "--json"]);
    common::assert_success(&out);
    let summary: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    assert_eq!(summary["vehicles"], 40);
    assert_eq!(summary["controlled_vehicles"], 4);
    let (stats, pixels) = read_png(&png).unwrap();
    assert_eq!((stats.width, stats.height), (1400, 800));
    let slow = mapc_viz::colors::speed_color(1.0 / summary["speed_max_mps"].as_f64().unwrap());
    assert!(
        count_near(&pixels, [slow.0, slow.1, slow.2], 12) > 200,
        "the jam is not drawn red"
    );
    let svg = dir.join("ts.svg");
    let out = mapc(&[
        "plot",
        "timespace",
        s(&trace),
        "-o",
        s(&svg),
        "--road-filter",
        "R1",
    ]);
    common::assert_success(&out);
    assert!(
        std::fs::read_to_string(&svg)
            .unwrap()
            .contains("speed (m/s)")
    );
    std::fs::remove_dir_all(dir).unwrap();
}

#[test]
fn bad_traces_exit_2_naming_file_line_and_column() {
    let dir = scratch_dir("ts-bad");
    let trace = dir.join("trace.csv");
    let png = dir.join("ts.png");
    let mut text = wave_trace();
    let line = text.lines().count() + 1;
    text.push_str("9.00,3,human,R1,1.0,1.0,1.2.3,false\n");
    std::fs::write(&trace, text).unwrap();
    let out = mapc(&["plot", "timespace", s(&trace), "-o", s(&png)]);
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(2), "{err}");
    assert!(
        err.contains("trace.csv")
            && err.contains(&format!("line {line}"))
            && err.contains("speed_mps"),
        "{err}"
    );

    std::fs::write(&trace, "time_s,vehicle_id,speed_mps\n1,2,3\n").unwrap();
    let out = mapc(&["plot", "timespace", s(&trace), "-o", s(&png)]);
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(2), "{err}");
    assert!(
        err.contains("missing columns") && err.contains("corridor_x_m"),
        "{err}"
    );

    let out = mapc(&["plot", "timespace", s(&dir.join("none.csv")), "-o", s(&png)]);
    assert_eq!(out.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&out.stderr).contains("none.csv"));
    assert!(!png.exists());
    std::fs::remove_dir_all(dir).unwrap();
}

#[test]
fn training_curves_of_two_runs_with_a_baseline() {
    let dir = scratch_dir("training");
    for (run, rows) in [("a", 30), ("b", 20)] {
        let d = dir.join(run);
        std::fs::create_dir_all(&d).unwrap();
        let mut text = String::from(
            "iteration,env_steps,wall_s,mean_return,mean_outflow,mean_speed,policy_loss,value_loss,kl,entropy,kl_coeff\n",
        );
        for i in 1..=rows {
            let f = i as f64;
            writeln!(
                text,
                "{i},{},{:.3},{},{},{},{},{},0.01,1.2,0.2",
                i * 1000,
                f * 2.0,
                50.0 + f,
                1400.0 + 3.0 * f,
                9.0,
                -0.01,
                10.0 / f
            )
            .unwrap();
        }
        std::fs::write(d.join("progress.csv"), text).unwrap();
    }
    let png = dir.join("curves.png");
    let out = mapc(&[
        "plot",
        "training",
        s(&dir.join("a")),
        s(&dir.join("b")),
        "-o",
        s(&png),
        "--baseline-outflow",
        "1420",
        "--json",
    ]);
    common::assert_success(&out);
    let summary: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    assert_eq!(summary["runs"].as_array().unwrap().len(), 2);
    assert_eq!(summary["runs"][0]["rows"], 30);
    let (stats, _) = read_png(&png).unwrap();
    assert!(stats.colors > 20, "{stats:?}");

    std::fs::write(
        dir.join("a/progress.csv"),
        "iteration,mean_return\n1,5\n2,x\n",
    )
    .unwrap();
    let out = mapc(&["plot", "training", s(&dir.join("a")), "-o", s(&png)]);
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(2), "{err}");
    assert!(
        err.contains("progress.csv") && err.contains("line 3") && err.contains("mean_return"),
        "{err}"
    );
    std::fs::remove_dir_all(dir).unwrap();
}
