//! The initial vehicles of every shipped scenario (scenarios/, merges/, fitted/) stand apart: no two on the same spot, none inside another
//! (its length plus the minimum gap behind the one ahead on its road); the Simple Merge's are Flow's positions.

use mapc_scenario::ResolvedScenario;
use mapc_sim::{Simulation, spec_from_scenario};
use std::path::{Path, PathBuf};

fn shipped_scenarios_with_initial_vehicles() -> Vec<PathBuf> {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../scenarios");
    let mut files = Vec::new();
    for dir in [root.clone(), root.join("merges"), root.join("fitted")] {
        for entry in std::fs::read_dir(&dir).unwrap() {
            let path = entry.unwrap().path();
            if path.extension().is_some_and(|e| e == "toml")
                && std::fs::read_to_string(&path)
                    .unwrap()
                    .contains("[initial_vehicles]")
            {
                files.push(path);
            }
        }
    }
    files.sort();
    files
}

#[test]
fn initial_vehicles_of_shipped_scenarios_do_not_overlap() {
    let files = shipped_scenarios_with_initial_vehicles();
    assert!(files.len() >= 10, "{files:?}");
    assert!(files.iter().any(|f| f.ends_with("i696_window.toml")));
    for file in &files {
        let rs = ResolvedScenario::load(file.to_str().unwrap()).unwrap();
        let spec = spec_from_scenario(&rs).unwrap_or_else(|e| panic!("{}: {e}", file.display()));
        let count = rs.scenario.initial_vehicles.as_ref().unwrap().count as usize;
        assert_eq!(spec.initial.len(), count, "{}", file.display());
        for (i, a) in spec.initial.iter().enumerate() {
            let room = spec.vehicle_types[a.vehicle_type].length
                + spec.vehicle_types[a.vehicle_type].min_gap;
            for (j, b) in spec.initial.iter().enumerate().skip(i + 1) {
                assert!(
                    a.road != b.road || (a.pos_m - b.pos_m).abs() >= room,
                    "{}: initial vehicles {i} and {j} overlap on road {}: {} m and {} m",
                    file.display(),
                    a.road,
                    a.pos_m,
                    b.pos_m
                );
            }
        }
    }
}

#[test]
fn the_i696_window_spreads_its_initial_vehicles_over_the_feeders() {
    let rs = ResolvedScenario::load(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../../scenarios/i696_window.toml"
    ))
    .unwrap();
    let spec = spec_from_scenario(&rs).unwrap();
    // Before, vehicles 3 and 4 both stood at the end of the main line's last road.
    let on_main = |r| spec.main_line.contains(r);
    assert!(
        spec.initial.iter().any(|v| !on_main(&v.road)),
        "{:?}",
        spec.initial
    );
    for v in &spec.initial {
        let len = rs.graph.road(v.road).unwrap().length_m;
        assert!(v.pos_m < len, "{v:?} stands at the end of its road");
    }
}

#[test]
fn the_simple_merge_keeps_flows_uniform_positions() {
    let spec = spec_from_scenario(&ResolvedScenario::load("simple_merge").unwrap()).unwrap();
    // x = 0, 180, 360, 540, 720 m along the main line (inflow 100 m, internal 0.1 m, pre-merge 500 m, internal
    // 24.53 m, where Flow's edge starts count 22.5 m: its fifth vehicle stands at 97.4 m of the post-merge road).
    let at: Vec<(String, f64)> = spec
        .initial
        .iter()
        .map(|v| {
            let road = rs_road_name(&spec, v.road);
            (road, (v.pos_m * 10.0).round() / 10.0)
        })
        .collect();
    let positions: Vec<f64> = at.iter().map(|(_, p)| *p).collect();
    assert_eq!(positions, vec![0.0, 79.9, 259.9, 439.9, 95.4], "{at:?}");
    assert_eq!(at[1].0, at[2].0);
    assert_eq!(at[2].0, at[3].0);
}

fn rs_road_name(spec: &mapc_sim::SimSpec, road: mapc_graph::RoadId) -> String {
    spec.graph.road(road).unwrap().id.to_string()
}

#[test]
fn overlapping_initial_vehicles_are_refused_naming_both() {
    let mut spec = spec_from_scenario(&ResolvedScenario::load("simple_merge").unwrap()).unwrap();
    let first = spec.initial[1].clone();
    let mut close = first.clone();
    close.pos_m += 3.0;
    spec.initial.push(close);
    let err = Simulation::from_spec(spec.clone(), 0)
        .err()
        .unwrap()
        .to_string();
    assert!(
        err.contains("initial vehicles 1 and 5 overlap") && err.contains("3.00 m ahead"),
        "{err}"
    );
    // Across a junction: one at the very end of the first road, one just past its start on the next.
    let mut spec = spec_from_scenario(&ResolvedScenario::load("simple_merge").unwrap()).unwrap();
    let entry = spec.initial[0].road;
    let entry_len = spec.graph.road(entry).unwrap().length_m;
    spec.initial[0].pos_m = entry_len;
    spec.initial[1].pos_m = 1.0;
    let err = Simulation::from_spec(spec, 0).err().unwrap().to_string();
    assert!(err.contains("initial vehicles 0 and 1 overlap"), "{err}");
}
