//! Tests of what bounds a run (demand, horizon, waiting vehicles, records) and of the measurement points.

use crate::tests::simple_merge_spec;
use crate::*;

fn human_spec() -> SimSpec {
    let mut s = simple_merge_spec();
    for t in &mut s.vehicle_types {
        t.controlled = false;
    }
    s
}

#[test]
fn demand_above_one_insertion_per_step_and_absurd_horizons_are_refused() {
    let mut spec = human_spec();
    spec.flows[0].vehs_per_hour = 1e9;
    let err = Simulation::from_spec(spec, 0).err().unwrap().to_string();
    assert!(
        err.contains("`main_human`") && err.contains("7200 veh/h"),
        "{err}"
    );
    let mut spec = human_spec();
    spec.horizon_steps = 10_000_000;
    let err = Simulation::from_spec(spec, 0).err().unwrap().to_string();
    assert!(err.contains("168 h"), "{err}");
}

#[test]
fn an_overloaded_entry_counts_its_queue_and_forgets_old_records() {
    // 7200 veh/h at an entry that passes about 2000: the queue grows by thousands, the road stays as it is
    let mut spec = human_spec();
    spec.flows[0].vehs_per_hour = 7000.0;
    spec.horizon_steps = 24_000; // 12 000 s
    let mut sim = Simulation::from_spec(spec, 3).unwrap();
    sim.set_invariant_checks(false);
    let m = sim.run().unwrap();
    let due = (7200.0 * 11_999.0 / 3600.0) as usize;
    assert!(
        sim.waiting_to_enter() > due / 2,
        "{}",
        sim.waiting_to_enter()
    );
    // built: the inserted ones and at most the cap of waiting ones, not every due vehicle
    assert!(sim.vehicle_count() < m.departed as usize + 1100 + 5);
    // held: a bounded window, not every vehicle of the run
    assert!(sim.vehicle_count() > 5000, "{}", sim.vehicle_count());
    assert!(
        sim.vehicle_records() < 3 * 1024 + 200,
        "{} of {}",
        sim.vehicle_records(),
        sim.vehicle_count()
    );
    // the queue still drains in order: departures kept coming all along
    assert!(m.inflow_veh_h > 1500.0, "{m:?}");
}

#[test]
fn flows_past_the_merge_and_the_end_are_counted_after_the_warmup() {
    let mut spec = human_spec();
    spec.warmup_steps = 400;
    let mut sim = Simulation::from_spec(spec.clone(), 0).unwrap();
    sim.record_passages();
    let m = sim.run().unwrap();
    assert_eq!(m.steps, spec.horizon_steps);
    assert_eq!(spec.measure_points.len(), 1, "{:?}", spec.measure_points);
    // the counts are the passages after the warm-up, and every vehicle counted at the end passed the merge
    let secs = spec.horizon_steps as f64 * spec.step_s;
    let counted = |point: Option<usize>| -> Vec<VehicleId> {
        sim.passages()
            .iter()
            .filter(|p| p.counted && p.point == point)
            .map(|p| p.vehicle)
            .collect()
    };
    let (at_merge, at_end) = (counted(Some(0)), counted(None));
    assert_eq!(
        m.merge_flows_veh_h[0],
        3600.0 * at_merge.len() as f64 / secs
    );
    assert_eq!(m.end_flow_veh_h, 3600.0 * at_end.len() as f64 / secs);
    assert!(
        sim.passages().iter().any(|p| !p.counted),
        "none in the warm-up"
    );
    for id in at_end {
        assert!(
            sim.passages()
                .iter()
                .any(|p| p.vehicle == id && p.point == Some(0)),
            "vehicle {id} left without passing the merge"
        );
    }
    // on the Simple Merge every vehicle leaves at the corridor's end
    assert_eq!(m.end_flow_veh_h, m.outflow_veh_h);
    let merge = m.merge_flows_veh_h[0];
    // all traffic crosses the merge: about the outflow, give or take the vehicles between merge and end
    assert!((merge - m.outflow_veh_h).abs() < 100.0, "{m:?}");
    assert!(merge > 1000.0, "{m:?}");
}

#[test]
fn initial_vehicles_that_do_not_fit_are_refused_with_the_count_that_would() {
    let mut rs = mapc_scenario::ResolvedScenario::load("simple_merge").unwrap();
    // 900 m of roads (the junctions' inner lanes aside): at 7.5 m a vehicle (length + min gap), at most 120
    rs.scenario.initial_vehicles.as_mut().unwrap().count = 200;
    let err = spec_from_scenario(&rs).err().unwrap().to_string();
    assert!(
        err.contains("initial_vehicles.count = 200") && err.contains("at most 120 fit"),
        "{err}"
    );
    rs.scenario.initial_vehicles.as_mut().unwrap().count = 100;
    assert!(spec_from_scenario(&rs).is_ok());
}

/// Departure times that could not advance (a begin of -1e308 once made `mapc sim` run forever) are refused by the
/// simulator itself, and a period too long to be a number departs once: each run ends, within a timeout.
#[test]
fn departure_times_always_advance_or_are_refused() {
    let within = |spec: SimSpec| {
        let (tx, rx) = std::sync::mpsc::channel();
        std::thread::spawn(move || {
            let run = Simulation::from_spec(spec, 1).and_then(|mut sim| sim.run());
            let _ = tx.send(run.map(|m| m.departed).map_err(|e| e.to_string()));
        });
        rx.recv_timeout(std::time::Duration::from_secs(60))
            .expect("the run ends")
    };
    for begin in [-1e308, -1e6, f64::NAN, f64::NEG_INFINITY, 1e308] {
        let mut spec = human_spec();
        spec.horizon_steps = 50;
        spec.flows[1].begin_s = begin;
        let err = within(spec).unwrap_err();
        assert!(
            err.contains("flow 1: begin_s") && err.contains("[0, 604800] s"),
            "{begin}: {err}"
        );
    }
    let mut spec = human_spec();
    spec.flows[1].end_s = spec.flows[1].begin_s;
    assert!(within(spec).unwrap_err().contains("is not after begin_s"));
    // 5e-324 veh/h: one departure at begin, the next one never
    let mut spec = human_spec();
    spec.horizon_steps = 50;
    spec.flows.truncate(1);
    spec.initial.clear();
    spec.flows[0].vehs_per_hour = 5e-324;
    assert_eq!(within(spec), Ok(1));
}
