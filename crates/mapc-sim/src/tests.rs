//! Crate tests on the paper's Simple Merge.

use crate::spec::*;
use crate::*;

/// The paper's Simple Merge, as mapc's scenario generator builds it.
pub(crate) fn simple_merge_spec() -> SimSpec {
    let rs = mapc_scenario::ResolvedScenario::load("simple_merge").expect("built-in scenario");
    spec_from_scenario(&rs).expect("simulator spec")
}

fn human_spec() -> SimSpec {
    let mut s = simple_merge_spec();
    for t in &mut s.vehicle_types {
        t.controlled = false;
    }
    s
}

#[test]
fn one_run_is_collision_free_and_congested() {
    let mut sim = Simulation::from_spec(human_spec(), 0).unwrap();
    sim.set_invariant_checks(true);
    let m = sim.run().unwrap();
    eprintln!("{m:?}");
    assert!(m.arrived > 300, "{m:?}");
    assert!(m.avg_speed_mps > 2.0 && m.avg_speed_mps < 25.0, "{m:?}");
}

#[test]
fn same_seed_same_metrics_different_seed_different() {
    let a = Simulation::from_spec(human_spec(), 7).unwrap().run().unwrap();
    let b = Simulation::from_spec(human_spec(), 7).unwrap().run().unwrap();
    let c = Simulation::from_spec(human_spec(), 8).unwrap().run().unwrap();
    assert_eq!(a, b);
    assert_ne!(a, c);
}

#[test]
fn calibration_band_on_simple_merge() {
    let seeds: Vec<u64> = (0..100).collect();
    let runs = run_baseline_spec(&human_spec(), &seeds).unwrap();
    let s = Summary::of(&runs);
    eprintln!(
        "outflow {:.1} ± {:.1}, inflow {:.1} ± {:.1}, speed {:.3} ± {:.3}",
        s.outflow.mean, s.outflow.ci95, s.inflow.mean, s.inflow.ci95, s.speed.mean, s.speed.ci95
    );
    assert!((s.outflow.mean / 1559.3 - 1.0).abs() <= 0.03, "outflow {:?}", s.outflow);
    assert!((s.inflow.mean / 1726.3 - 1.0).abs() <= 0.03, "inflow {:?}", s.inflow);
    assert!((s.speed.mean / 7.25 - 1.0).abs() <= 0.10, "speed {:?}", s.speed);
}

#[test]
#[ignore]
fn debug_profile() {
    let mut sim = Simulation::from_spec(human_spec(), 0).unwrap();
    let mut prof = vec![(0.0, 0u64); 21];
    let mut entries = vec![];
    let mut last_lane = std::collections::HashMap::new();
    let mut mins = std::collections::HashMap::new();
    let mut rmins = std::collections::HashMap::new();
    while !sim.is_done() {
        sim.step().unwrap();
        if sim.time_s() < 300.0 { continue; }
        for id in sim.active_ids().collect::<Vec<_>>() {
            let v = sim.vehicle(id).unwrap();
            let lane = sim.network().lane_names[sim.veh_lane(id) as usize].clone();
            if lane == "R1" { let b = (v.pos_m / 25.0) as usize; prof[b].0 += v.speed; prof[b].1 += 1; }
            if lane == "R1" && v.pos_m > 470.0 { let e = mins.entry(id).or_insert(99.0f64); *e = e.min(v.speed); }
            if lane == "R4" && v.pos_m > 50.0 { let e = rmins.entry(id).or_insert(99.0f64); *e = e.min(v.speed); }
            if lane == "R1>R2" && last_lane.get(&id) == Some(&"R1".to_string()) { entries.push((sim.time_s(), v.speed)); }
            last_lane.insert(id, lane);
        }
    }
    for (i, (s, n)) in prof.iter().enumerate() { eprintln!("{} {:.2} {}", i * 25, s / *n as f64, n); }
    let hw: Vec<f64> = entries.windows(2).map(|w| w[1].0 - w[0].0).collect();
    eprintln!("entries {} mean hw {:.2} mean entry speed {:.2}", entries.len(), hw.iter().sum::<f64>() / hw.len() as f64, entries.iter().map(|e| e.1).sum::<f64>() / entries.len() as f64);
    eprintln!("{:?}", sim.metrics());
    let m: Vec<f64> = mins.values().copied().collect();
    eprintln!("main n {} min<1 {} min<3 {} mean min {:.2}", m.len(), m.iter().filter(|x| **x < 1.0).count(), m.iter().filter(|x| **x < 3.0).count(), m.iter().sum::<f64>() / m.len() as f64);
    let r: Vec<f64> = rmins.values().copied().collect();
    eprintln!("ramp n {} min<1 {} mean min {:.2}", r.len(), r.iter().filter(|x| **x < 1.0).count(), r.iter().sum::<f64>() / r.len() as f64);
}
