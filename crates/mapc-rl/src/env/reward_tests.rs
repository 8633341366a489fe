//! The outflow reward on the shipped scenarios: the network's end on the Simple Merge, the window's end in the
//! I-696 window.

use crate::env::Env;
use crate::env::merge::{MergeEnv, MergeEnvConfig, RewardKind};
use mapc_sim::SimSpec;
use std::collections::HashSet;
use std::path::Path;

fn spec(file: &str) -> SimSpec {
    let path = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../..")
        .join(file);
    let scenario = mapc_scenario::ResolvedScenario::load(path.to_str().unwrap()).unwrap();
    mapc_sim::spec_from_scenario(&scenario).unwrap()
}

/// In the window the reward counts the vehicles that leave the window (each once), long before any vehicle of
/// the flows reaches the corridor's end 5 km further on.
#[test]
fn window_outflow_counts_vehicles_leaving_the_window() {
    let spec = spec("scenarios/i696_window.toml");
    let region: HashSet<_> = spec.control_region.clone().unwrap().into_iter().collect();
    let mut env = MergeEnv::new(spec, MergeEnvConfig::paper(RewardKind::Outflow, 5)).unwrap();
    env.reset(1).unwrap();
    let (mut reward, mut arrived) = (0.0f64, 0usize);
    let mut was_inside: HashSet<u32> = HashSet::new();
    // 200 s: the first vehicles of the flows leave the window after about 55 s, and need about 200 s more to
    // reach the corridor's end.
    for _ in 0..400 {
        let t = env.step(&[2.6; 5]).unwrap();
        reward += t.reward as f64;
        let sim = env.simulation().unwrap();
        arrived += sim.arrived_last_step().len();
        for id in sim.active_ids() {
            if region.contains(&sim.vehicle(id).unwrap().road) {
                was_inside.insert(id);
            }
        }
    }
    // Counted here from the roads: those that were on a road of the window and are now past it (a vehicle on
    // the connection out of the window is in neither count's "inside", so allow one step of difference).
    let sim = env.simulation().unwrap();
    let past: usize = was_inside
        .iter()
        .filter(|&&id| {
            sim.vehicle(id).is_none_or(|v| {
                v.status != mapc_sim::VehicleStatus::Active || !region.contains(&v.road)
            })
        })
        .count();
    assert!(
        past >= 20,
        "only {past} vehicles passed the window in 200 s"
    );
    assert!(
        (reward - past as f64).abs() <= 1.0,
        "reward {reward}, vehicles past the window {past}"
    );
    assert!(
        arrived <= 5,
        "{arrived} vehicles reached the corridor's end"
    );
}

/// Without a control region (the Simple Merge) the reward is the vehicles that left the network, step by step.
#[test]
fn simple_merge_outflow_counts_arrivals() {
    let spec = spec("scenarios/simple_merge.toml");
    assert!(spec.control_region.is_none());
    let mut env = MergeEnv::new(spec, MergeEnvConfig::paper(RewardKind::Outflow, 5)).unwrap();
    env.reset(0).unwrap();
    let mut total = 0.0f32;
    for _ in 0..300 {
        let t = env.step(&[0.5; 5]).unwrap();
        let arrived = env.simulation().unwrap().arrived_last_step().len();
        assert_eq!(t.reward, arrived as f32);
        total += t.reward;
    }
    assert!(total > 10.0, "{total}");
}
