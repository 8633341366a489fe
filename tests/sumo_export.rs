//! `mapc export --sumo` end to end: what it writes, its help, and bad input (exit code 2, one message naming the
//! file, nothing half-written).

mod common;
use common::*;

fn leftovers(dir: &std::path::Path) -> Vec<String> {
    std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .filter(|n| n.ends_with(".tmp") || n.ends_with(".old"))
        .collect()
}

#[test]
fn exports_the_i696_window_and_replaces_an_old_export_whole() {
    let dir = scratch_dir("sumo-export");
    let out = dir.join("i696");
    std::fs::create_dir_all(&out).unwrap();
    std::fs::write(out.join("stale.txt"), "from an earlier run").unwrap();
    let run = run_mapc(&[
        "export",
        "scenarios/i696_window.toml",
        "--sumo",
        out.to_str().unwrap(),
        "--json",
    ]);
    assert_success(&run);
    let summary: serde_json::Value = serde_json::from_slice(&run.stdout).unwrap();
    assert_eq!(summary["sumo_version"], "1.8.0");
    assert_eq!(summary["flows"], 3);
    let mut files: Vec<String> = std::fs::read_dir(&out)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    files.sort();
    assert_eq!(
        files,
        [
            "i696_window.mapc.json",
            "i696_window.net.xml",
            "i696_window.rou.xml",
            "i696_window.sumocfg"
        ]
    );
    let manifest: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("i696_window.mapc.json")).unwrap())
            .unwrap();
    assert_eq!(manifest["control_edges"].as_array().unwrap().len(), 3);
    // The merge's two connections join roads of the window: their internal edges are in the region too.
    assert_eq!(
        manifest["control_internal_edges"].as_array().unwrap().len(),
        2
    );
    assert!(leftovers(&dir).is_empty());
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn a_users_induction_loops_are_exported_for_sumo() {
    // the ramp game with the loops of its additional file: SUMO writes their intervals from the export as it
    // would from the user's own files (checked by hand with SUMO 1.8; SUMO is not a dependency of the tests)
    let out = export_for_sumo(
        "scenarios/sumo/ramp_game_alinea/ramp_alinea.sumocfg",
        "sumo-export-loops",
        &[],
    );
    let add = std::fs::read_to_string(out.join("ramp_alinea.add.xml")).unwrap();
    let loops: Vec<&str> = add
        .lines()
        .filter(|l| l.trim_start().starts_with("<inductionLoop"))
        .collect();
    assert_eq!(loops.len(), 6, "{add}");
    for (id, lane, pos) in [
        ("ramps_0", "gneE18_0", "60.00"),
        ("merge_2", "gneE7_2", "80.00"),
        ("drop_1", "gneE8_1", "60.00"),
    ] {
        let l = loops
            .iter()
            .find(|l| l.contains(&format!("id=\"{id}\"")))
            .unwrap();
        assert!(l.contains(&format!("lane=\"{lane}\"")), "{l}");
        assert!(l.contains(&format!("pos=\"{pos}\"")), "{l}");
        assert!(l.contains("freq=\"60.00\""), "{l}");
        assert!(l.contains("file=\"ramp_alinea.e1.xml\""), "{l}");
    }
    // each loop's lane is a lane of the exported network
    let net = std::fs::read_to_string(out.join("ramp_alinea.net.xml")).unwrap();
    for l in &loops {
        let lane = l
            .split("lane=\"")
            .nth(1)
            .unwrap()
            .split('"')
            .next()
            .unwrap();
        assert!(net.contains(&format!("<lane id=\"{lane}\"")), "{lane}");
    }
    let cfg = std::fs::read_to_string(out.join("ramp_alinea.sumocfg")).unwrap();
    assert!(
        cfg.contains("<additional-files value=\"ramp_alinea.add.xml\"/>"),
        "{cfg}"
    );
    std::fs::remove_dir_all(&out).unwrap();
}

#[test]
fn help_names_the_sumo_version() {
    let run = run_mapc(&["export", "--help"]);
    assert_success(&run);
    let text = String::from_utf8_lossy(&run.stdout);
    assert!(text.contains("SUMO 1.8.0"), "{text}");
}

fn assert_refused(run: &std::process::Output, needles: &[&str]) {
    assert_eq!(
        run.status.code(),
        Some(2),
        "{}",
        String::from_utf8_lossy(&run.stderr)
    );
    let err = String::from_utf8_lossy(&run.stderr);
    assert_eq!(err.trim().lines().count(), 1, "one line: {err}");
    for n in needles {
        assert!(err.contains(n), "`{n}` not in: {err}");
    }
}

#[test]
fn a_scenario_naming_a_missing_graph_is_refused_and_writes_nothing() {
    let dir = scratch_dir("sumo-missing-graph");
    let scenario = dir.join("broken.toml");
    let text = std::fs::read_to_string(root().join("scenarios/i696_window.toml"))
        .unwrap()
        .replace("i696_window.graph.json", "gone.graph.json");
    std::fs::write(&scenario, text).unwrap();
    let out = dir.join("out");
    let run = run_mapc(&[
        "export",
        scenario.to_str().unwrap(),
        "--sumo",
        out.to_str().unwrap(),
    ]);
    assert_refused(&run, &["broken.toml", "gone.graph.json"]);
    assert!(!out.exists());
    assert!(leftovers(&dir).is_empty());
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn an_output_path_that_cannot_be_written_is_refused() {
    let dir = scratch_dir("sumo-unwritable");
    let file = dir.join("a_file");
    std::fs::write(&file, "not a directory").unwrap();
    // The output is an existing file.
    let run = run_mapc(&["export", "simple_merge", "--sumo", file.to_str().unwrap()]);
    assert_refused(&run, &["a_file", "not a directory"]);
    assert_eq!(std::fs::read_to_string(&file).unwrap(), "not a directory");
    // The output lies under a file.
    let under = file.join("out");
    let run = run_mapc(&["export", "simple_merge", "--sumo", under.to_str().unwrap()]);
    assert_refused(&run, &["a_file"]);
    assert!(leftovers(&dir).is_empty());
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn a_map_that_is_not_a_network_is_refused() {
    let dir = scratch_dir("sumo-bad-map");
    let map = dir.join("bad.net.xml");
    std::fs::write(&map, "<net>\n  <edge id=\"a\" from=\"x\" to=\"y\">\n    <lane id=\"a_0\" index=\"0\" speed=\"fast\" length=\"1\" shape=\"0,0 1,0\"/>\n  </edge>\n</net>\n").unwrap();
    let out = dir.join("out");
    let run = run_mapc(&[
        "export",
        map.to_str().unwrap(),
        "--sumo",
        out.to_str().unwrap(),
    ]);
    assert_refused(&run, &["bad.net.xml", "speed"]);
    assert!(!out.exists());
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn a_users_ramp_meter_is_exported_with_the_program_mapc_runs() {
    // ramp_metering_1x3's meter runs the additional file's program `rl` (5 s green, 5 s red), not the net's
    let dir = export_for_sumo(
        "scenarios/sumo/ramp_metering_1x3/1ramp_1x3.sumocfg",
        "sumo-export-light",
        &[],
    );
    let net = std::fs::read_to_string(dir.join("1ramp_1x3.net.xml")).unwrap();
    let at = net
        .find("<tlLogic id=\"ramp_meter\"")
        .expect("the meter's program");
    let logic = &net[at..at + net[at..].find("</tlLogic>").unwrap()];
    assert!(
        logic.contains("type=\"static\" programID=\"rl\""),
        "{logic}"
    );
    let phases: Vec<&str> = logic
        .lines()
        .skip(1)
        .map(str::trim)
        .filter(|l| !l.is_empty())
        .collect();
    assert_eq!(
        phases,
        [
            "<phase duration=\"5.00\" state=\"G\"/>",
            "<phase duration=\"5.00\" state=\"r\"/>"
        ]
    );
    assert!(net.contains("<junction id=\"ramp_meter\" type=\"traffic_light\""));
    // the ramp's link is the light's link 0, its state the light's
    assert!(
        net.contains("from=\"on_ramp\" to=\"passage_area\" fromLane=\"0\" toLane=\"0\" via=\":ramp_meter_0_0\" tl=\"ramp_meter\" linkIndex=\"0\""),
        "the ramp's link is not under the light"
    );
    let _ = std::fs::remove_dir_all(&dir);
    // a program named `off` (SUMO's name for a light switched off) goes as a static program of another name
    let dir = export_for_sumo(
        "scenarios/flow_bottleneck_metered.toml",
        "sumo-export-light-off",
        &[],
    );
    let net = std::fs::read_to_string(dir.join("flow_bottleneck_metered.net.xml")).unwrap();
    assert!(
        net.contains("<tlLogic id=\"3\" type=\"static\" programID=\"always_green\""),
        "no program for light 3"
    );
    let _ = std::fs::remove_dir_all(&dir);
}
