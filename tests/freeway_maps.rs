//! Multi-lane freeway maps nobody here drew (`maps/ATTRIBUTION.md`): a zipper merge whose streams take turns,
//! and its export, which SUMO reads as a zipper again.

mod common;

use common::{assert_success, mapc_json, run_mapc, scratch_dir};
use serde_json::Value;
use std::path::Path;

fn path(p: &Path) -> &str {
    p.to_str().unwrap()
}

/// The Eccles zipper merge (a three-lane road and a one-lane ramp, SUMO `zipper` junction J4) cut into a window
/// with `main_vph` on the main road; returns the scenario's path.
fn eccles_merge_window(dir: &Path, main_vph: &str) -> String {
    let graph = dir.join("g.json");
    let corridor = dir.join("s.json");
    let scenario = dir.join("w.toml");
    assert_success(&run_mapc(&[
        "import",
        "maps/eccles_merge.net.xml",
        "-o",
        path(&graph),
    ]));
    // the net's edges have no road type: the corridor is named
    assert_success(&run_mapc(&[
        "simplify",
        path(&graph),
        "--keep-lanes",
        "--via",
        "E2",
        "--via",
        "E4",
        "-o",
        path(&corridor),
    ]));
    assert_success(&run_mapc(&[
        "window",
        path(&corridor),
        "--junction",
        "J3",
        "--fit",
        "--fit-floor",
        "0.05",
        "--keep-lanes",
        "--main-vph",
        main_vph,
        "-o",
        path(&scenario),
    ]));
    path(&scenario).to_string()
}

fn entry<'a>(v: &'a Value, road: &str) -> &'a Value {
    v["entries"]
        .as_array()
        .unwrap()
        .iter()
        .find(|e| e["road"] == road)
        .unwrap_or_else(|| panic!("no entry {road}: {}", v["entries"]))
}

#[test]
fn the_streams_of_a_zipper_merge_take_turns() {
    let dir = scratch_dir("zipper-merge");
    for main_vph in ["3000", "4500"] {
        let scenario = eccles_merge_window(&dir, main_vph);
        // the import keeps the zipper
        let g = std::fs::read_to_string(dir.join("g.json")).unwrap();
        assert!(g.contains("\"zipper\""), "no zipper connection imported");
        let v = mapc_json(&["sim", "--scenario", &scenario, "--seeds", "2", "--json"]);
        // both streams enter (the ramp's vehicles stood at the merge from t = 14 s to the end when both zipper
        // links yielded to each other: 4 of its 56 entered)
        for road in ["R0", "R1"] {
            let e = entry(&v, road);
            assert_eq!(e["waiting"].as_f64(), Some(0.0), "{main_vph}: {e}");
        }
        let inflow = v["inflow"]["mean"].as_f64().unwrap();
        let past = v["merges"][0]["flow"]["mean"].as_f64().unwrap();
        assert!(
            past > 0.97 * inflow,
            "{main_vph}: {past} of {inflow} veh/h past the merge"
        );
        let regime = &v["regime"]["merges"][0];
        assert_eq!(regime["zipper"], true, "{regime}");
    }
    let text = String::from_utf8_lossy(
        &run_mapc(&[
            "sim",
            "--scenario",
            path(&dir.join("w.toml")),
            "--seeds",
            "1",
        ])
        .stdout,
    )
    .into_owned();
    assert!(text.contains("the roads take turns (zipper)"), "{text}");
}

#[test]
fn a_zipper_is_exported_as_a_zipper() {
    let dir = scratch_dir("zipper-export");
    let scenario = eccles_merge_window(&dir, "3000");
    let out = dir.join("export");
    assert_success(&run_mapc(&["export", &scenario, "--sumo", path(&out)]));
    let net = std::fs::read_dir(&out)
        .unwrap()
        .map(|e| e.unwrap().path())
        .find(|p| p.to_string_lossy().ends_with(".net.xml"))
        .expect("a net.xml");
    let text = std::fs::read_to_string(&net).unwrap();
    assert!(text.contains("type=\"zipper\""), "no zipper junction");
    assert!(text.contains("state=\"Z\""), "no zipper link");
    // and read back, the links are zipper links again
    let back = dir.join("back.json");
    assert_success(&run_mapc(&["import", path(&net), "-o", path(&back)]));
    let g: Value = serde_json::from_str(&std::fs::read_to_string(&back).unwrap()).unwrap();
    let zippers = g["connections"]
        .as_array()
        .unwrap()
        .iter()
        .filter(|c| c["right_of_way"] == "zipper")
        .count();
    assert!(zippers >= 2, "{zippers} zipper connections read back");
}

/// The default corridor (`mapc simplify MAP`) stays on one motorway as a driver would: link roads only where it
/// starts or ends (an on-ramp onto the motorway, an off-ramp from it), never between two stretches of motorway,
/// and no merge where the corridor comes in on a link while a motorway joins it. (On the Eccles Interchange the
/// corridor left the M60 onto 975 m of link roads and took the M60 itself for a merging road; on the I-5 extract
/// it took the 112.9 m on-ramp for the main road because the motorway's piece before the merge was 112.1 m.)
#[test]
fn the_default_corridor_follows_the_motorway_on_every_map() {
    let dir = scratch_dir("default-corridor-motorway");
    for map in [
        "a2_braunschweig.osm",
        "arizona_highways.osm",
        "eccles_interchange.net.xml",
        "i210.net.xml",
        "i5_exit_ramp.osm",
        "i696.osm",
        "lust_motorway.net.xml",
        "rongwu.net.xml",
    ] {
        let out = dir.join(format!("{map}.corridor.json"));
        let report = mapc_json(&[
            "simplify",
            &format!("maps/{map}"),
            "--json",
            "-o",
            path(&out),
        ]);
        let g: Value = serde_json::from_str(&std::fs::read_to_string(&out).unwrap()).unwrap();
        let class = |id: &str| -> String {
            g["roads"]
                .as_array()
                .unwrap()
                .iter()
                .find(|r| r["id"] == id)
                .unwrap_or_else(|| panic!("{map}: no road {id}"))["class"]
                .as_str()
                .unwrap()
                .to_string()
        };
        let is_link = |c: &str| c.ends_with("_link");
        let main: Vec<String> = report["main_road"]["roads"]
            .as_array()
            .unwrap()
            .iter()
            .map(|r| class(r.as_str().unwrap()))
            .collect();
        let through: Vec<usize> = (0..main.len()).filter(|&i| !is_link(&main[i])).collect();
        let (first, last) = (through[0], *through.last().unwrap());
        assert!(
            main[first..=last].iter().all(|c| !is_link(c)),
            "{map}: the main road leaves the motorway: {main:?}"
        );
        // the motorway carries most of the corridor
        let main_m = report["main_road"]["length_m"].as_f64().unwrap();
        assert!(main_m > 1000.0, "{map}: {main_m} m");
        let road = |id: &str| -> &Value {
            g["roads"]
                .as_array()
                .unwrap()
                .iter()
                .find(|r| r["id"] == id)
                .unwrap()
        };
        for m in report["merges"].as_array().unwrap() {
            let into = report["main_road"]["roads"]
                .as_array()
                .unwrap()
                .iter()
                .map(|r| road(r.as_str().unwrap()))
                .find(|r| r["to"] == m["junction"])
                .unwrap();
            let merging = road(m["merging_roads"][0].as_str().unwrap());
            assert!(
                !is_link(into["class"].as_str().unwrap())
                    || is_link(merging["class"].as_str().unwrap()),
                "{map}: the corridor comes into merge {} on a link and the motorway joins it",
                m["junction"]
            );
        }
    }
}

/// A scenario's `time_to_teleport_s` outside [0, a week] is refused naming the key.
#[test]
fn a_time_to_teleport_out_of_range_is_refused() {
    for bad in ["-1.0", "nan", "1e9"] {
        let scenario = common::edited_scenario("simple_merge.toml", &format!("ttt{bad}"), |t| {
            t.replacen(
                "step_s = 0.5",
                &format!("step_s = 0.5\ntime_to_teleport_s = {bad}"),
                1,
            )
        });
        common::refused(
            &[
                "sim",
                "--scenario",
                scenario.to_str().unwrap(),
                "--seeds",
                "1",
            ],
            &["time_to_teleport_s"],
        );
    }
}

/// The A-7 from Alicante to Murcia (95 km, 59 zippers) as a one-lane corridor with a window at every merge, the
/// map where a junction once held two drivers waiting for each other to the end: every merge passes traffic and no
/// driver stands still at the end. A guard on the public map; the mechanism's own test, which fails without the
/// fix, is `sim/step/overlap_tests.rs`.
#[test]
fn the_a7_corridor_keeps_every_merge_flowing() {
    let dir = scratch_dir("a7-one-lane");
    let (graph, corridor, scenario) = (dir.join("g.json"), dir.join("s.json"), dir.join("w.toml"));
    assert_success(&run_mapc(&[
        "import",
        "maps/alicante_murcia_a7.net.xml",
        "-o",
        path(&graph),
    ]));
    assert_success(&run_mapc(&[
        "simplify",
        path(&graph),
        "-o",
        path(&corridor),
    ]));
    assert_success(&run_mapc(&[
        "window",
        path(&corridor),
        "--all",
        "--fit",
        "-o",
        path(&scenario),
    ]));
    let v = mapc_json(&[
        "sim",
        "--scenario",
        path(&scenario),
        "--seeds",
        "1",
        "--json",
    ]);
    let merges = v["merges"].as_array().unwrap();
    assert!(merges.len() > 20, "{} merges", merges.len());
    for m in merges {
        let flow = m["flow"]["mean"].as_f64().unwrap();
        assert!(flow > 100.0, "{}: {flow} veh/h", m["name"]);
    }
    let run = &v["runs"][0];
    assert!(run.get("stuck").is_none(), "{run}");
}
