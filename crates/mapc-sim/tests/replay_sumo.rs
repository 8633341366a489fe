//! mapc against SUMO 1.8, vehicle by vehicle: 41 recorded steps of SUMO's Simple Merge (tests/data/README.md) are
//! replayed one step at a time; every vehicle's next speed must match SUMO's.

use mapc_scenario::ResolvedScenario;
use mapc_sim::runs::replay::{ReplicaVehicle, parse_state_line, replay_simple_merge_step};
use mapc_sim::spec_from_scenario;
use std::collections::HashMap;

fn states() -> Vec<(f64, Vec<ReplicaVehicle>)> {
    let path = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/tests/data/sumo18_simple_merge_seed0_400s.jsonl"
    );
    std::fs::read_to_string(path)
        .unwrap()
        .lines()
        .enumerate()
        .map(|(n, l)| parse_state_line(l).unwrap_or_else(|e| panic!("{path}:{}: {e}", n + 1)))
        .collect()
}

#[test]
fn replay_matches_sumo() {
    let spec = spec_from_scenario(&ResolvedScenario::load("simple_merge").unwrap()).unwrap();
    let human = spec
        .vehicle_types
        .iter()
        .position(|t| t.name == "human")
        .unwrap();
    let states = states();
    assert_eq!(states.len(), 41);
    let (mut compared, mut matched) = (0usize, 0usize);
    let mut worst = (0.0f64, String::new());
    let mut junction_steps = 0usize;
    for pair in states.windows(2) {
        let (t, now) = (&pair[0].0, &pair[0].1);
        let sumo_next: HashMap<&str, f64> =
            pair[1].1.iter().map(|v| (v.id.as_str(), v.speed)).collect();
        for (id, speed) in replay_simple_merge_step(&spec, human, *t, now).unwrap() {
            let Some(&want) = sumo_next.get(id.as_str()) else {
                continue; // left the network in this step
            };
            compared += 1;
            let err = (speed - want).abs();
            if err <= 1e-3 {
                matched += 1;
            } else if err > worst.0 {
                worst = (
                    err,
                    format!("{id} at t = {t}: mapc {speed:.4}, SUMO {want:.4}"),
                );
            }
        }
        junction_steps += now.iter().filter(|v| v.lane.starts_with(":center")).count();
    }
    eprintln!("{matched} of {compared} vehicle-steps within 1e-3 m/s; worst: {worst:?}");
    // the window holds merges: vehicles inside the junction on both connections
    assert!(junction_steps > 30, "{junction_steps}");
    assert!(compared > 1500, "{compared}");
    assert_eq!(matched, compared, "worst {worst:?}");
}
