//! A vehicle whose move would take it past a red light stands at the stop line (SUMO 1.8's emergency stop at the
//! end of the lane in `MSVehicle::processLaneAdvances`).

use super::*;
use crate::runs::scenario::spec_from_scenario;

/// ramp_metering_1x3 without its flows (meter G 5 s, r 5 s from the run's begin), its meter's red phase showing
/// `red_letter`, and the ramp's road.
fn meter_without_flows(red_letter: &str) -> (Simulation, mapc_graph::RoadId) {
    let cfg = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../../scenarios/sumo/ramp_metering_1x3/1ramp_1x3.sumocfg"
    );
    let rs = mapc_scenario::ResolvedScenario::load(cfg).expect("shipped SUMO scenario");
    let ramp = rs.graph.find_roads("on_ramp").unwrap()[0];
    let mut spec = spec_from_scenario(&rs).expect("simulator spec");
    spec.flows.clear();
    let meter = spec
        .graph
        .lights
        .iter_mut()
        .find(|l| l.id == "ramp_meter")
        .unwrap();
    meter.phases[1].state = red_letter.to_string();
    (Simulation::from_spec(spec, 0).unwrap(), ramp)
}

/// Where a lone ramp vehicle of scenarios/sumo/ramp_metering_1x3 (meter G 5 s, r 5 s from the run's begin), put
/// 4.88 m before the line at the ramp's limit of 13.89 m/s, is after one step that starts with the light red
/// (`red`) or green: (its lane is still the ramp's, its place, its speed, the ramp's length).
fn one_step_at_the_line(red: bool) -> (bool, f64, f64, f64) {
    let (mut sim, ramp) = meter_without_flows("r");
    // the moves read the light at the step's start
    while ((sim.time_s - sim.spec.start_time_s).rem_euclid(10.0) >= 5.0) != red {
        sim.step().unwrap();
    }
    let r = sim.add_route(ramp, &[], None, Some(0)).unwrap();
    let lane = sim.routes[r as usize].lanes[0];
    let len = sim.lane_at(lane as usize).length;
    let id = sim.create_vehicle(0, r, 13.89);
    sim.place(id, lane, len - 4.88, 13.89, false).unwrap();
    sim.step().unwrap();
    let v = &sim.veh[id as usize];
    (v.lane == lane, v.pos, v.speed, len)
}

#[test]
fn a_vehicle_that_cannot_brake_before_a_red_light_stands_at_its_line() {
    // braking as hard as it may (9 m/s^2) still takes it a centimetre past the line: SUMO stops it there
    let (on_ramp, pos, speed, len) = one_step_at_the_line(true);
    assert!(on_ramp, "the vehicle crossed the red light");
    assert_eq!(pos, len);
    assert_eq!(speed, 0.0);
    // on green it drives on
    let (on_ramp, _, speed, _) = one_step_at_the_line(false);
    assert!(!on_ramp, "the vehicle stopped at a green light");
    assert!(speed > 10.0, "{speed}");
}

/// Where a ramp vehicle of ramp_metering_1x3 standing 2 m before the meter's line when its red phase begins is
/// after `steps` steps, with the red phase's letter `letter`: (still on the ramp, its place, the ramp's length).
fn standing_at_the_meter(letter: &str, steps: usize) -> (bool, f64, f64) {
    let (mut sim, ramp) = meter_without_flows(letter);
    while (sim.time_s - sim.spec.start_time_s).rem_euclid(10.0) != 5.0 {
        sim.step().unwrap();
    }
    let r = sim.add_route(ramp, &[], None, Some(0)).unwrap();
    let lane = sim.routes[r as usize].lanes[0];
    let len = sim.lane_at(lane as usize).length;
    let id = sim.create_vehicle(0, r, 0.0);
    sim.place(id, lane, len - 2.0, 0.0, false).unwrap();
    for _ in 0..steps {
        sim.step().unwrap();
    }
    let v = &sim.veh[id as usize];
    (v.lane == lane, v.pos, len)
}

#[test]
fn a_stop_letter_lets_a_driver_go_once_it_has_stood_at_its_line() {
    // SUMO's `s` (LINKSTATE_STOP, a right turn on red): stop at the line for a step, then drive on yielding to the
    // foes with priority; under `r` the driver waits for green (the meter's red lasts 5 s)
    let (on_ramp, pos, len) = standing_at_the_meter("s", 4);
    assert!(
        !on_ramp || pos > len - 1.0,
        "it waited out the stop: {pos} of {len}"
    );
    let (on_ramp, pos, len) = standing_at_the_meter("r", 4);
    assert!(
        on_ramp && pos <= len,
        "it passed the red light: {pos} of {len}"
    );
}
