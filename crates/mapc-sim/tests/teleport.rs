//! Teleports (`time_to_teleport_s`): on the Simple Merge with a ramp (the major road) so busy that the yielding
//! main road's first driver waits minutes for a gap, drivers standing longer than the bound are taken off and
//! come back past the merge, counted; without teleports the run says how many stood still to its end.

use mapc_scenario::ResolvedScenario;
use mapc_sim::{SimSpec, Simulation, spec_from_scenario};

/// The Simple Merge, humans only, 2000 veh/h on the ramp and 1800 on the main road.
fn jammed_merge(time_to_teleport_s: f64) -> SimSpec {
    let rs = ResolvedScenario::load("simple_merge").unwrap();
    let mut spec = spec_from_scenario(&rs).unwrap();
    let main = spec.flows[0].from;
    spec.flows
        .retain(|f| !spec.vehicle_types[f.vehicle_type].controlled);
    for f in &mut spec.flows {
        if f.from != main {
            f.vehs_per_hour = 2000.0;
        }
    }
    spec.time_to_teleport_s = time_to_teleport_s;
    spec
}

#[test]
fn drivers_standing_past_the_bound_are_teleported_past_the_merge_and_counted() {
    let mut sim = Simulation::from_spec(jammed_merge(60.0), 3).unwrap();
    // no two vehicles overlap at any step, teleported ones back included
    sim.set_invariant_checks(true);
    let m = sim.run().unwrap();
    assert!(m.teleports > 0, "{m:?}");
    assert_eq!(m.stuck, 0);
}

#[test]
fn without_teleports_the_drivers_standing_to_the_end_are_counted() {
    let mut sim = Simulation::from_spec(jammed_merge(0.0), 3).unwrap();
    let m = sim.run().unwrap();
    assert_eq!(m.teleports, 0);
    assert!(m.stuck > 0, "{m:?}");
    let lines = mapc_sim::standstill_lines(&[m]);
    assert!(lines[0].contains("stood still for over 300 s"), "{lines:?}");
}
