//! Crate tests on the paper's Simple Merge (built here exactly as SUMO 1.8's net for it reads).

use crate::spec::*;
use crate::*;
use mapc_graph::*;

/// The Simple Merge of `maps/simple_merge.net.xml`: main 100 + 500 m, ramp 100 + 100 m, 100 m after; internal
/// lanes 24.53 m (main, 30 m/s) and 22.95 m (ramp, 15.67 m/s), 0.1 m at the shape junctions; the ramp is major.
pub(crate) fn simple_merge_graph() -> LaneGraph {
    let mut g = LaneGraph::new(
        Source { file: "simple_merge (test fixture)".into(), format: SourceFormat::Generator },
        Projection::Plane { offset: [0.0, 0.0] },
    );
    let pts = [[0.0, 141.42], [100.0, 141.42], [600.0, 141.42], [700.0, 141.42], [458.58, 0.0], [529.29, 70.71]];
    g.junctions = pts
        .iter()
        .enumerate()
        .map(|(i, &pos)| Junction {
            id: JunctionId(i as u32),
            pos,
            kind: JunctionKind::Through,
            incoming: vec![],
            outgoing: vec![],
            provenance: Provenance::default(),
        })
        .collect();
    let road = |id: u32, from: u32, to: u32, len: f64, prio: i32| Road {
        id: RoadId(id),
        from: JunctionId(from),
        to: JunctionId(to),
        class: "highway".into(),
        name: None,
        ref_: None,
        priority: prio,
        lanes: vec![Lane { index: 0, speed_mps: 30.0, width_m: 3.2, length_m: len }],
        geometry: vec![pts[from as usize], pts[to as usize]],
        length_m: len,
        provenance: Provenance::default(),
    };
    g.roads = vec![
        road(0, 0, 1, 100.0, -1), // inflow_highway
        road(1, 1, 2, 500.0, -1), // left
        road(2, 2, 3, 100.0, -1), // center
        road(3, 4, 5, 100.0, 1),  // inflow_merge
        road(4, 5, 2, 100.0, 1),  // bottom
    ];
    let conn = |j: u32, from: u32, to: u32, len: f64, speed: f64, row| Connection {
        junction: JunctionId(j),
        from_road: RoadId(from),
        from_lane: 0,
        to_road: RoadId(to),
        to_lane: 0,
        via_length_m: len,
        via_speed_mps: Some(speed),
        right_of_way: row,
        right_of_way_overridden: false,
        provenance: Provenance::default(),
    };
    g.connections = vec![
        conn(1, 0, 1, 0.1, 30.0, RightOfWay::Major),
        conn(5, 3, 4, 0.1, 30.0, RightOfWay::Major),
        conn(2, 4, 2, 22.95, 15.67, RightOfWay::Major),
        conn(2, 1, 2, 24.53, 30.0, RightOfWay::Minor),
    ];
    g.rebuild_junction_links();
    g
}

pub(crate) fn simple_merge_spec() -> SimSpec {
    let human = VehicleTypeSpec::paper_human("human");
    let mut av = VehicleTypeSpec::paper_human("av");
    av.controlled = true;
    let flow = |from: u32, vph: f64, t: usize, speed: f64| FlowSpec {
        from: RoadId(from),
        to: None,
        vehs_per_hour: vph,
        vehicle_type: t,
        depart_speed: speed,
        begin_s: 1.0,
        end_s: 86400.0,
    };
    let init = |road: u32, pos: f64| InitialVehicleSpec { road: RoadId(road), pos_m: pos, speed: 0.0, vehicle_type: 0 };
    SimSpec {
        graph: simple_merge_graph(),
        vehicle_types: vec![human, av],
        flows: vec![flow(0, 1800.0, 0, 10.0), flow(0, 200.0, 1, 10.0), flow(3, 200.0, 0, 7.5)],
        initial: vec![init(0, 0.0), init(1, 79.9), init(1, 259.9), init(1, 439.9), init(2, 97.4)],
        step_s: 0.5,
        horizon_steps: 2000,
        start_time_s: 1.0,
        control_region: None,
        main_line: vec![],
    }
}

fn human_spec() -> SimSpec {
    let mut s = simple_merge_spec();
    s.vehicle_types[1].controlled = false;
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
