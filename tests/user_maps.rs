//! What a user meets running mapc on a map of their own: a report that says first when an entry cannot take its
//! demand, the pipeline from any folder with a policy that does not lose on other maps, errors that say their
//! cause once, `mapc view`'s figures on a thinned replay, and help that sets nothing up and says what the commands
//! do.

mod common;

use common::{
    assert_success, edited_scenario, fresh_path, mapc_json, refused, root, run_mapc, scratch_dir,
};
use serde_json::Value;

/// Runs `python3` with `args` in `dir` (a tool of tools/, standard library only).
fn python3_run(dir: &std::path::Path, args: &[&std::ffi::OsStr]) -> std::process::Output {
    std::process::Command::new("python3")
        .args(args)
        .current_dir(dir)
        .output()
        .unwrap()
}

/// A tool's command line: the script `tool`, then `args`.
fn args_of<'a>(tool: &'a std::path::Path, args: &[&'a str]) -> Vec<&'a std::ffi::OsStr> {
    let mut all = vec![tool.as_os_str()];
    all.extend(args.iter().map(|&a| std::ffi::OsStr::new(a)));
    all
}

/// [`python3_run`], which must succeed: its standard output.
fn python3(dir: &std::path::Path, args: &[&std::ffi::OsStr]) -> String {
    let out = python3_run(dir, args);
    assert_success(&out);
    String::from_utf8_lossy(&out.stdout).into_owned()
}

/// The Simple Merge with 4000 human veh/h on its one-lane main road: far more than the road takes.
fn blocked_simple_merge(name: &str) -> String {
    let path = edited_scenario("simple_merge.toml", name, |t| {
        t.replace("vehs_per_hour = 1800.0", "vehs_per_hour = 4000.0")
    });
    path.to_str().unwrap().to_string()
}

/// The entry of `entries` on `road`.
fn entry<'a>(entries: &'a Value, road: &str) -> &'a Value {
    entries
        .as_array()
        .unwrap()
        .iter()
        .find(|e| e["road"] == road)
        .unwrap_or_else(|| panic!("no entry {road} in {entries}"))
}

#[test]
fn a_blocked_entry_is_said_first_with_its_demand_and_what_it_took() {
    let scenario = blocked_simple_merge("blocked-entry");
    let out = run_mapc(&["sim", "--scenario", &scenario, "--seeds", "2"]);
    assert_success(&out);
    let text = String::from_utf8_lossy(&out.stdout);
    // the line after the title, before any figure
    let second = text.lines().nth(1).unwrap_or_default();
    assert!(
        second.contains("entry R0 took") && second.contains("vehicles that wanted to depart"),
        "{text}"
    );
    // the ramp takes its 200 veh/h
    assert!(!text.contains("entry R2 took"), "{text}");

    let v = mapc_json(&["sim", "--scenario", &scenario, "--seeds", "2", "--json"]);
    for entries in [&v["entries"], &v["regime"]["entries"]] {
        let main = entry(entries, "R0");
        let (demand, inserted, waiting) = (
            main["demand"].as_f64().unwrap(),
            main["inserted"].as_f64().unwrap(),
            main["waiting"].as_f64().unwrap(),
        );
        assert_eq!(main["blocked"], true, "{main}");
        // 4200 veh/h over 1000 s is about 1167 vehicles; the road takes about 2000 veh/h
        assert!(demand > 1100.0 && demand < 1200.0, "{main}");
        assert!(waiting > 400.0, "{main}");
        assert_eq!(demand, inserted + waiting, "{main}");
        assert_eq!(entry(entries, "R2")["blocked"], false, "{entries}");
    }
    // per run too, counted by the simulator
    let run = entry(&v["runs"][0]["entries"], "R0");
    assert_eq!(
        run["demand"].as_u64().unwrap(),
        run["inserted"].as_u64().unwrap() + run["waiting"].as_u64().unwrap()
    );
}

/// Run from a folder outside the repository on a map that is not the paper's: the shipped policy is found, it is
/// the one whose rule leaves unlike merges to the humans, and the pipeline says why.
#[test]
fn the_pipeline_runs_from_any_folder_with_the_policy_that_never_loses() {
    let elsewhere = fresh_path("pipeline-elsewhere");
    std::fs::create_dir_all(&elsewhere).unwrap();
    let map = root().join("maps/rongwu.net.xml");
    let run = std::process::Command::new(env!("CARGO_BIN_EXE_mapc"))
        .current_dir(&elsewhere)
        .arg("pipeline")
        .arg(&map)
        .args(["--seeds", "2", "-o", "out"])
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&run.stderr);
    assert!(run.status.success(), "pipeline failed:\n{stderr}");
    assert!(
        stderr.contains("merge_robust_congested")
            && stderr.contains("leaves the others to the humans"),
        "{stderr}"
    );
    let policy = elsewhere.join("out/merge_robust_congested.json");
    assert_eq!(
        std::fs::read(&policy).unwrap(),
        std::fs::read(root().join("policies/merge_robust_congested.json")).unwrap()
    );
    assert!(
        stderr.contains("$ mapc eval --policy out/merge_robust_congested.json"),
        "{stderr}"
    );
    std::fs::remove_dir_all(&elsewhere).unwrap();
}

/// An error that carries its cause in its own message (`{path}: {source}`) says the cause once.
#[test]
fn a_missing_file_is_said_once() {
    for args in [
        &[
            "eval",
            "--policy",
            "nonesuch.json",
            "--scenario",
            "simple_merge",
            "--seeds",
            "1",
        ][..],
        &["import", "nonesuch.osm", "-o", "nonesuch.graph.json"][..],
    ] {
        let stderr = refused(args, &["nonesuch."]);
        assert_eq!(
            stderr.matches("No such file or directory").count(),
            1,
            "{stderr}"
        );
    }
}

/// A replay thinned to every 3rd step drops the run's last frames: the figures shown are still the run's.
#[test]
fn a_thinned_replay_shows_the_runs_figures_and_says_every_3rd_step() {
    let dir = fresh_path("view-thinned");
    std::fs::create_dir_all(&dir).unwrap();
    let page = dir.join("replay.html");
    let page = page.to_str().unwrap();
    let sim = mapc_json(&[
        "sim",
        "--scenario",
        "simple_merge",
        "--seeds",
        "1",
        "--first-seed",
        "3",
        "--json",
    ]);
    let run = &sim["runs"][0];
    let whole = mapc_json(&["view", "simple_merge", "--seed", "3", "-o", page, "--json"]);
    let steps = whole["panes"][0]["vehicle_steps"].as_u64().unwrap();
    let max_rows = (steps / 3 + 1).to_string();
    let args = [
        "view",
        "simple_merge",
        "--seed",
        "3",
        "--max-rows",
        &max_rows,
        "-o",
        page,
    ];
    let thinned = mapc_json(&[&args[..], &["--json"]].concat());
    let pane = &thinned["panes"][0];
    assert_eq!(pane["decimation"], 3);
    for (shown, measured) in [
        ("outflow_veh_h", "outflow_veh_h"),
        ("inflow_veh_h", "inflow_veh_h"),
        ("avg_speed_mps", "avg_speed_mps"),
    ] {
        assert_eq!(pane[shown], run[measured], "{shown}: {pane} against {run}");
    }
    let out = run_mapc(&args);
    assert_success(&out);
    let text = String::from_utf8_lossy(&out.stdout);
    assert!(text.contains("(every 3rd step kept)"), "{text}");
    std::fs::remove_dir_all(&dir).unwrap();
}

/// `sumo_check --help` prints its usage with the standard library only: no SUMO environment is made for it.
#[test]
fn sumo_checks_help_sets_nothing_up() {
    let venv = fresh_path("sumo-venv");
    let out = std::process::Command::new(root().join("tools/sumo_check/sumo_check"))
        .arg("--help")
        .env("MAPC_SUMO_VENV", &venv)
        // were anything installed, it would fail at once rather than reach for the network
        .env("PIP_NO_INDEX", "1")
        .output()
        .unwrap();
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    assert!(
        stdout.contains("usage:") && stdout.contains("baseline"),
        "{stdout}"
    );
    assert!(!venv.exists(), "a virtual environment was made for --help");
}

/// sumo_check's ALINEA (tools/sumo_check/alinea.py) follows mapc's law on a hand-worked case, run with the
/// standard library against a stand-in for TraCI: loops reading 30 % occupancy with a 20 % set-point and
/// K_R = 70 take the rate from 1 800 to 1 800 + 70 (20 - 30) = 1 100 veh/h after the first 2 s interval, then to
/// 400; the light then runs 2 s green and 3600 / 1100 - 2 s red.
#[test]
fn sumo_checks_alinea_follows_the_law_mapc_runs() {
    let script = r#"
import sys
sys.path.insert(0, sys.argv[1])
from alinea import Alinea

class Light:
    class Logic:
        def __init__(self, program, kind, index, phases):
            self.phases = phases
    class Phase:
        def __init__(self, duration, state):
            self.duration, self.state = duration, state
    def __init__(self):
        self.programs = []
    def getRedYellowGreenState(self, light):
        return "GG"
    def setProgramLogic(self, light, logic):
        self.programs.append([(p.duration, p.state) for p in logic.phases])
    def setProgram(self, light, name):
        pass
    def setPhase(self, light, index):
        pass

class Loops:
    def getLastStepOccupancy(self, loop):
        return 30.0

class Conn:
    trafficlight, inductionloop = Light(), Loops()

conn = Conn()
cfg = dict(light="m", detectors=["a", "b"], periods={"a": 2.0, "b": 2.0}, setpoint=0.2, gain_veh_h=70.0,
           green_s=2.0, min_rate_veh_h=200.0, max_rate_veh_h=1800.0)
meter = Alinea(conn, cfg, 0.5)
for _ in range(8):
    meter.after_step()
print(meter.rates)
print(conn.trafficlight.programs[1])
"#;
    let out = std::process::Command::new("python3")
        .args(["-c", script])
        .arg(root().join("tools/sumo_check"))
        .output()
        .unwrap();
    common::assert_success(&out);
    let stdout = String::from_utf8_lossy(&out.stdout);
    let lines: Vec<&str> = stdout.lines().collect();
    assert_eq!(lines[0], "[1100.0, 400.0]");
    // the program after the first interval: 1 100 veh/h, a cycle of 3600 / 1100 s
    assert_eq!(lines[1], "[(2.0, 'GG'), (1.272727272727273, 'rr')]");
}

#[test]
fn the_help_says_what_simplify_and_export_do() {
    let out = run_mapc(&["--help"]);
    assert_success(&out);
    let help = String::from_utf8_lossy(&out.stdout);
    let line = |command: &str| {
        help.lines()
            .find(|l| l.trim_start().starts_with(command))
            .unwrap_or_else(|| panic!("no {command} in {help}"))
            .to_string()
    };
    let simplify = line("simplify");
    assert!(
        !simplify.contains("single-lane") && simplify.contains("--keep-lanes"),
        "{simplify}"
    );
    let export = line("export");
    assert!(
        export.contains("GeoJSON") && export.contains("SUMO"),
        "{export}"
    );
}

#[test]
fn several_windows_report_their_timing_and_regime_as_one_window_does() {
    let dir = scratch_dir("windows-regime");
    let out = dir.join("w.toml");
    let report = mapc_json(&[
        "window",
        "scenarios/i696.corridor.graph.json",
        "--all",
        "-o",
        out.to_str().unwrap(),
        "--json",
    ]);
    // the warm-up picked (null: the source's timing kept) and each merge's regime under the window's demand
    assert!(report.get("timing").is_some(), "{report}");
    let merges = report["regime"]["merges"]
        .as_array()
        .expect("a regime per merge");
    assert!(!merges.is_empty(), "{report}");
    let text = run_mapc(&[
        "window",
        "scenarios/i696.corridor.graph.json",
        "--all",
        "-o",
        out.to_str().unwrap(),
    ]);
    assert!(String::from_utf8_lossy(&text.stdout).contains("regime (3 seeds)"));
    std::fs::remove_dir_all(dir).unwrap();
}

/// tools/sumo_replay/roads.py, standard library only, on a hand-made FCD and trace of one vehicle each: SUMO's
/// drives 3 s on edge `a` (changing to lane 1 at 25 m) and 2 s on `b`; mapc's trace, stamped a step later, 2 s on
/// `a` (road R1) and 3 s on `b` (R2), named through the graph's provenance.
#[test]
fn sumo_replays_roads_counts_vehicle_seconds_per_road_and_where_a_lane_is_left() {
    let dir = scratch_dir("roads_py");
    std::fs::write(
        dir.join("g.json"),
        r#"{"roads": [{"id": "R1", "provenance": {"sumo_ids": ["a"]}}, {"id": "R2", "provenance": {"sumo_ids": ["b"]}}]}"#,
    )
    .unwrap();
    let mut fcd = String::from("<fcd-export>\n");
    for (t, lane, pos) in [
        (0, "a_0", 5),
        (1, "a_0", 15),
        (2, "a_1", 25),
        (3, "b_0", 5),
        (4, "b_0", 15),
    ] {
        fcd += &format!(
            "<timestep time=\"{t}.00\"><vehicle id=\"v\" lane=\"{lane}\" pos=\"{pos}.00\" speed=\"10.00\"/></timestep>\n"
        );
    }
    fcd += "</fcd-export>\n";
    std::fs::write(dir.join("fcd.xml"), fcd).unwrap();
    let mut trace = String::from(
        "time_s,vehicle_id,vehicle_type,road,pos_on_road_m,corridor_x_m,speed_mps,controlled,lane\n",
    );
    for (t, road, pos) in [
        (1, "R1", 5),
        (2, "R1", 15),
        (3, "R2", 5),
        (4, "R2", 15),
        (5, "R2", 25),
    ] {
        trace += &format!("{t}.00,1,car,{road},{pos}.000,,10.000,false,0\n");
    }
    std::fs::write(dir.join("trace.csv"), trace).unwrap();
    let roads = |args: &[&str]| {
        let tool = root().join("tools/sumo_replay/roads.py");
        python3(&dir, &args_of(&tool, args))
    };
    let time = roads(&["time", "g.json", "fcd.xml", "trace.csv"]);
    let row = |edge: &str| -> Vec<String> {
        time.lines()
            .find(|l| l.split_whitespace().next() == Some(edge))
            .unwrap_or_else(|| panic!("no row for {edge}: {time}"))
            .split_whitespace()
            .map(str::to_string)
            .collect()
    };
    assert!(time.contains("vehicle-seconds: SUMO 5, mapc 5"), "{time}");
    assert_eq!(row("a")[1..3], ["3", "2"]);
    assert_eq!(row("b")[1..3], ["2", "3"]);
    let leave = roads(&[
        "leave",
        "g.json",
        "fcd.xml",
        "trace.csv",
        "a",
        "--lane",
        "0",
        "--from",
        "a",
    ]);
    assert!(
        leave.contains("SUMO: 1 vehicles leave lane 0 of a; per 20 m from its start: 0, 1, 0"),
        "{leave}"
    );
    assert!(
        leave.contains("mapc: 0 vehicles leave lane 0 of a"),
        "{leave}"
    );
    // per 20 m and lane of `a`: both at 10 m/s on lane 0 in the first 20 m (two samples each), SUMO's alone on
    // lane 1 past 20 m; and each vehicle first seen on lane 0 of `a`, 5 m in
    let speeds = roads(&[
        "speeds",
        "g.json",
        "fcd.xml",
        "trace.csv",
        "a",
        "--bucket",
        "20",
    ]);
    assert!(
        speeds.contains("     0  L0  10.0/ 10.0 (2/2)  L1     -/    - (0/0)"),
        "{speeds}"
    );
    assert!(
        speeds.contains("    20  L0     -/    - (0/0)  L1     -/ 10.0 (0/1)"),
        "{speeds}"
    );
    let inserted = roads(&["inserted", "g.json", "fcd.xml", "trace.csv", "a"]);
    assert!(inserted.contains("SUMO: per lane of a"), "{inserted}");
    assert_eq!(
        inserted.matches("L0 1 at 5.0, 10.00").count(),
        2,
        "{inserted}"
    );
    // `places`: two floating-car data files at the same step, lane and place; one point 0.5 m off, one angle
    // 3 degrees off where the back is behind the lane's start, and a row at another place, not compared
    let row = |t: u32, lane: &str, pos: &str, x: &str, angle: &str| {
        format!(
            "<timestep time=\"{t}.00\"><vehicle id=\"v\" x=\"{x}\" y=\"0.00\" angle=\"{angle}\" \
             lane=\"{lane}\" pos=\"{pos}\" speed=\"10.00\"/></timestep>\n"
        )
    };
    let sumo = [
        row(0, "a_0", "3.00", "3.00", "90.00"),
        row(1, "a_0", "13.00", "13.00", "90.00"),
        row(2, "a_0", "23.00", "23.00", "90.00"),
    ];
    let mapc = [
        row(0, "a_0", "3.00", "3.00", "93.00"),
        row(1, "a_0", "13.00", "13.50", "90.00"),
        row(2, "a_0", "24.00", "24.00", "90.00"),
    ];
    std::fs::write(
        dir.join("s.xml"),
        format!("<fcd-export>\n{}</fcd-export>\n", sumo.concat()),
    )
    .unwrap();
    std::fs::write(
        dir.join("m.xml"),
        format!("<fcd-export>\n{}</fcd-export>\n", mapc.concat()),
    )
    .unwrap();
    let places = roads(&["places", "s.xml", "m.xml"]);
    assert!(
        places.contains("distance between the points: 2 rows, median 0.500 m"),
        "{places}"
    );
    assert!(
        places.contains("back on the same lane: 1 rows, median 0.000"),
        "{places}"
    );
    assert!(
        places.contains("below 5.0 m): 1 rows, median 3.000 degrees"),
        "{places}"
    );
}

/// sumo_check's `--sumo-runs` (tools/sumo_check/recorded.py) gives back the recorded runs only for the same SUMO
/// inputs and seeds, and stops with a message otherwise; `--split-trip` counts the runs on each side of a trip time.
#[test]
fn sumo_checks_recorded_runs_are_reused_only_for_the_same_inputs_and_seeds() {
    let dir = scratch_dir("recorded_runs");
    let json = dir.join("runs.json");
    std::fs::write(
        &json,
        r#"{"inputs_sha256": "abc", "sumo_runs": [{"seed": 0, "speed": 10.5}, {"seed": 1, "speed": 11.0}]}"#,
    )
    .unwrap();
    let script = r#"
import sys
sys.path.insert(0, sys.argv[1])
import recorded
path = sys.argv[2]
print(recorded.reuse(path, "inputs_sha256", "abc", "sumo_runs", [0, 1], "inputs"))
for digest, seeds in (("abd", [0, 1]), ("abc", [0, 2])):
    try:
        recorded.reuse(path, "inputs_sha256", digest, "sumo_runs", seeds, "inputs")
        print("reused")
    except SystemExit as e:
        print("refused:", e)
import scenario
scenario.print_split(75, [("mapc", [{"duration": 70.0}, {"duration": 80.0}, {"duration": 90.0}])])
"#;
    let out = std::process::Command::new("python3")
        .args(["-c", script])
        .arg(root().join("tools/sumo_check"))
        .arg(&json)
        .output()
        .unwrap();
    common::assert_success(&out);
    let stdout = String::from_utf8_lossy(&out.stdout);
    let lines: Vec<&str> = stdout.lines().collect();
    assert_eq!(
        lines[0],
        "[{'seed': 0, 'speed': 10.5}, {'seed': 1, 'speed': 11.0}]"
    );
    assert!(
        lines[1].starts_with("refused:") && lines[1].contains("other SUMO inputs"),
        "{stdout}"
    );
    assert!(
        lines[2].starts_with("refused:") && lines[2].contains("other seeds"),
        "{stdout}"
    );
    // `--split-trip 75`: one run at most 75 s, two above, with their means
    assert_eq!(
        lines[4].split_whitespace().collect::<Vec<_>>().join(" "),
        "mapc 1 runs, 70.0 s / 2 runs, 85.0 s"
    );
}

/// tools/sumo_replay/deterministic.py: its copy of ramp_game draws nothing at random (flows by period, one type
/// with sigma and speed deviation 0, no random departure places), so mapc's seeds 0 and 1 run alike; and `first`
/// finds the step where a hand-made trace parts from its FCD.
#[test]
fn sumo_replays_deterministic_copy_draws_nothing_and_first_finds_where_the_runs_part() {
    let dir = scratch_dir("deterministic_py");
    let tool = root().join("tools/sumo_replay/deterministic.py");
    let run = |args: &[&str]| python3(&dir, &args_of(&tool, args));
    // a copy refused: it says `says` and writes nothing
    let refused = |cfg: &str, out: &str, says: &str| {
        let r = python3_run(&dir, &args_of(&tool, &["copy", cfg, out]));
        assert!(!r.status.success());
        assert!(String::from_utf8_lossy(&r.stderr).contains(says));
        assert!(!dir.join(out).exists());
    };
    // a configuration that is missing, or a copy inside its own folder, is refused before anything is copied
    refused("nonesuch.sumocfg", "nothing", "nonesuch.sumocfg");
    refused("nothing/x.sumocfg", "nothing/inside", "x.sumocfg");
    std::fs::create_dir_all(dir.join("nothing")).unwrap();
    std::fs::write(
        dir.join("nothing/x.sumocfg"),
        "<configuration><input><route-files value=\"r.xml\"/></input></configuration>",
    )
    .unwrap();
    refused(
        "nothing/x.sumocfg",
        "nothing/inside",
        "lies inside the configuration's folder",
    );
    let cfg = root().join("scenarios/sumo/ramp_game/ramp.sumocfg");
    let copied = run(&["copy", cfg.to_str().unwrap(), "copy"]);
    assert!(copied.trim().ends_with("copy/ramp.sumocfg"), "{copied}");
    let routes = std::fs::read_to_string(dir.join("copy/ramp/ramp.rou.xml")).unwrap();
    assert!(
        !routes.contains("probability") && !routes.contains("\"random\""),
        "{routes}"
    );
    assert!(
        routes.contains("vehsPerHour=\"792\"") && routes.contains("sigma=\"0\""),
        "{routes}"
    );
    let copy_cfg = dir.join("copy/ramp.sumocfg");
    let sim = |seed: &str| {
        let v = mapc_json(&[
            "sim",
            copy_cfg.to_str().unwrap(),
            "--seeds",
            "1",
            "--first-seed",
            seed,
            "--json",
        ]);
        (v["outflow"]["mean"].clone(), v["speed"]["mean"].clone())
    };
    assert_eq!(sim("0"), sim("1"));
    // three vehicles; mapc's second (stamped a step later, as traces are) drives slower from its third step, and
    // its third enters on the other lane (matched by its first step and road alone: a difference from the start)
    std::fs::write(
        dir.join("g.json"),
        r#"{"roads": [{"id": "R1", "provenance": {"sumo_ids": ["a"]}}]}"#,
    )
    .unwrap();
    let mut fcd = String::from("<fcd-export>\n");
    let mut trace = String::from(
        "time_s,vehicle_id,vehicle_type,road,pos_on_road_m,corridor_x_m,speed_mps,controlled,lane\n",
    );
    for t in 0..4 {
        let (p1, p2) = (5 + 10 * t, 5 + 8 * t);
        fcd += &format!(
            "<timestep time=\"{t}.00\"><vehicle id=\"f.0\" lane=\"a_0\" pos=\"{p1}.00\" speed=\"10.00\"/>\
             <vehicle id=\"f.1\" lane=\"a_1\" pos=\"{p2}.00\" speed=\"8.00\"/></timestep>\n"
        );
        let (m2, s2) = if t < 2 { (p2, 8) } else { (p2 - 1, 7) };
        trace += &format!(
            "{}.00,7,car,R1,{p1}.000,,10.000,false,0\n{}.00,9,car,R1,{m2}.000,,{s2}.000,false,1\n",
            t + 1,
            t + 1
        );
    }
    fcd += "<timestep time=\"4.00\"><vehicle id=\"f.2\" lane=\"a_0\" pos=\"0.00\" speed=\"9.00\"/></timestep>\n";
    trace += "5.00,11,car,R1,0.000,,9.000,false,1\n";
    fcd += "</fcd-export>\n";
    std::fs::write(dir.join("fcd.xml"), fcd).unwrap();
    std::fs::write(dir.join("trace.csv"), trace).unwrap();
    let first = run(&["first", "g.json", "fcd.xml", "trace.csv"]);
    assert!(
        first.contains("3 SUMO vehicles matched (1 of them by their first step and road alone"),
        "{first}"
    );
    assert!(first.contains(", 0 not"), "{first}");
    assert!(
        first.contains("2.00  f.1")
            && first.contains("SUMO a 1 21.00 8.00")
            && first.contains("mapc a 1 20.00 7.00"),
        "{first}"
    );
    assert!(
        first.contains("4.00  f.2")
            && first.contains("SUMO a 0 0.00 9.00")
            && first.contains("mapc a 1 0.00 9.00"),
        "{first}"
    );
    assert_eq!(first.lines().count(), 3, "{first}");
    let follow = run(&["follow", "g.json", "fcd.xml", "trace.csv", "f.1"]);
    assert_eq!(follow.matches("<<").count(), 2, "{follow}");
    // mapc's own floating-car data in place of the trace: SUMO's names and time stamps, vehicles matched by name
    let mut mapc_fcd = String::from("<?xml version=\"1.0\"?>\n<fcd-export>\n");
    for t in 0..4 {
        let (p1, p2) = (5 + 10 * t, 5 + 8 * t);
        let (m2, s2) = if t < 2 { (p2, 8) } else { (p2 - 1, 7) };
        mapc_fcd += &format!(
            "<timestep time=\"{t}.00\"><vehicle id=\"f.0\" lane=\"a_0\" pos=\"{p1}.00\" speed=\"10.00\"/>\
             <vehicle id=\"f.1\" lane=\"a_1\" pos=\"{m2}.00\" speed=\"{s2}.00\"/></timestep>\n"
        );
    }
    mapc_fcd += "<timestep time=\"4.00\"><vehicle id=\"f.2\" lane=\"a_1\" pos=\"0.00\" speed=\"9.00\"/></timestep>\n</fcd-export>\n";
    std::fs::write(dir.join("mapc_fcd.xml"), mapc_fcd).unwrap();
    let by_name = run(&["first", "g.json", "fcd.xml", "mapc_fcd.xml"]);
    assert!(
        by_name.contains("3 SUMO vehicles matched (0 of them by their first step and road alone"),
        "{by_name}"
    );
    assert!(
        by_name.contains("2.00  f.1") && by_name.contains("mapc a 1 20.00 7.00"),
        "{by_name}"
    );
    assert!(
        by_name.contains("4.00  f.2") && by_name.contains("mapc a 1 0.00 9.00"),
        "{by_name}"
    );
}
