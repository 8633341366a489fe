//! SUMO 1.8's junction rules, vehicle by vehicle against SUMO's own run of small networks made for them
//! (`tests/data/sumo_rules/`, built by SUMO 1.8's netconvert; the figures below are SUMO's FCD, seed 0).

use mapc_scenario::ResolvedScenario;
use mapc_sim::{Simulation, spec_from_scenario};

fn simulation(cfg: &str) -> Simulation {
    let path = format!("{}/tests/data/sumo_rules/{cfg}", env!("CARGO_MANIFEST_DIR"));
    let rs = ResolvedScenario::load(&path).unwrap();
    Simulation::from_spec(spec_from_scenario(&rs).unwrap(), 0).unwrap()
}

/// After `n` steps, (in the junction, position, speed) of vehicle `id`: SUMO's FCD at time `n - 1` (it stamps a
/// step with its start).
fn after(sim: &mut Simulation, n: u64, id: u32) -> (bool, f64, f64) {
    while sim.step_index() < n {
        sim.step().unwrap();
    }
    let v = sim.vehicle(id).expect("on the network");
    (v.in_junction, v.pos_m, v.speed)
}

/// Vehicle `id` of the configuration `cfg` against SUMO's FCD: (steps done, in the junction, position, speed).
fn matches_sumo(cfg: &str, id: u32, recorded: &[(u64, bool, f64, f64)]) {
    let mut sim = simulation(cfg);
    for &(n, inside, pos, speed) in recorded {
        let (got_inside, got_pos, got_speed) = after(&mut sim, n, id);
        assert_eq!(got_inside, inside, "{cfg}, step {n}");
        assert!(
            (got_pos - pos).abs() < 0.01,
            "{cfg}, step {n}: at {got_pos}, SUMO {pos}"
        );
        assert!(
            (got_speed - speed).abs() < 0.01,
            "{cfg}, step {n}: {got_speed} m/s, SUMO {speed}"
        );
    }
}

#[test]
fn a_driver_approaching_an_open_minor_link_keeps_able_to_stop_until_it_sees_the_foes() {
    // `side` joins `main` at a priority junction; no one else drives. SUMO's driver slows as if to stop at the
    // line until it is within the foe visibility distance (4.5 m), though the link is open all along: 13.89 m/s
    // 21.7 m before the line, 11.71 at 14.0 m, 7.21 at 2.8 m, then across at the connection's 6.51 m/s
    matches_sumo(
        "minor_link/minor.sumocfg",
        0,
        &[
            (13, false, 171.08, 13.89),
            (14, false, 182.79, 11.71),
            (15, false, 189.99, 7.21),
            (16, true, 3.70, 6.51),
        ],
    );
}

#[test]
fn a_driver_before_its_minor_link_waits_for_a_merging_car_that_entered_the_junction_first() {
    // A car on `main` enters the junction at 21 s; SUMO's car on `side` must not enter beside it, whether it stands
    // at its line already (departing at 5 s: the car on `main` is farther from the merge point, yet SUMO's
    // `MSLink::isLeader` makes it the leader, having entered first) or arrives as it enters (7 s: the car on
    // `main` is nearer the merge point but overlaps it, a negative gap): it stops before entering, and goes in
    // the step after the car on `main` has left the connection. mapc's car went in a step early in both.
    matches_sumo(
        "minor_link/behind5.sumocfg",
        1,
        &[
            (22, false, 192.70, 0.0),
            (23, false, 192.70, 0.0),
            (24, true, 2.50, 2.60),
        ],
    );
    matches_sumo(
        "minor_link/behind7.sumocfg",
        1,
        &[(23, false, 192.70, 2.71), (24, true, 5.21, 5.31)],
    );
}
