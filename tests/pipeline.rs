//! End to end: `mapc pipeline` on the shipped I-696 map writes every stage's file and evaluates the shipped policy.

use std::path::Path;
use std::process::Command;

#[test]
fn pipeline_runs_every_stage_on_the_real_map() {
    let out = std::env::temp_dir().join(format!("mapc-pipeline-{}", std::process::id()));
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let run = Command::new(env!("CARGO_BIN_EXE_mapc"))
        .current_dir(root)
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
    // The last JSON document printed is the evaluation against the human baseline.
    let start = stdout.rfind("\n{\n").map_or(0, |i| i + 1);
    let eval: serde_json::Value =
        serde_json::from_str(&stdout[start..]).expect("eval JSON at the end");
    assert_eq!(eval["seeds"], 3);
    let policy = eval["outflow"]["mean"].as_f64().unwrap();
    let human = eval["baseline"]["outflow"]["mean"].as_f64().unwrap();
    assert!(
        policy > 500.0 && human > 500.0,
        "policy {policy}, human {human}"
    );
    std::fs::remove_dir_all(&out).unwrap();
}

#[test]
fn pipeline_names_a_missing_map() {
    let out = std::path::Path::new(env!("CARGO_TARGET_TMPDIR")).join("mapc-pipeline-missing");
    std::fs::remove_dir_all(&out).ok();
    let run = Command::new(env!("CARGO_BIN_EXE_mapc"))
        .current_dir(env!("CARGO_MANIFEST_DIR"))
        .args(["pipeline", "maps/nonesuch.osm", "-o"])
        .arg(&out)
        .output()
        .unwrap();
    assert_eq!(run.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&run.stderr).contains("nonesuch.osm"));
    // it fails before writing anything, its output folder included
    assert!(!out.exists());
}
