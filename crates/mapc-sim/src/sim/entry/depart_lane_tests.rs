//! Depart lanes chosen at insertion (`random`, `free`) on the lane drop's three-lane entry road, in cases worked
//! by hand and checked in SUMO 1.8.0 (docs/sumo_check.md).

use super::*;
use crate::runs::scenario::spec_from_scenario;
use crate::spec::DepartLane;

/// The lane drop with its demand as one flow from the upstream road departing on `mode`.
fn lane_drop_spec(mode: DepartLane) -> SimSpec {
    let rs = mapc_scenario::ResolvedScenario::load("lane_drop").expect("built-in scenario");
    let mut spec = spec_from_scenario(&rs).expect("simulator spec");
    spec.flows.truncate(1);
    spec.flows[0].vehs_per_hour = 4500.0;
    spec.flows[0].depart_lane = mode;
    spec
}

/// The upstream road's lanes, rightmost first.
fn entry_lanes(sim: &Simulation) -> Vec<LaneIdx> {
    let from = sim.spec.flows[0].from;
    let r = sim.net.road_ids.iter().position(|&id| id == from).unwrap();
    sim.net.road_lanes[r].clone()
}

/// Puts a standing vehicle of the flow's type with its front at `pos` on lane `lane` of the entry road.
fn stand(sim: &mut Simulation, lane: u8, pos: f64) -> VehicleId {
    let from = sim.spec.flows[0].from;
    let r = sim.add_route(from, &[], None, Some(lane)).unwrap();
    let id = sim.create_vehicle(0, r, 0.0);
    let l = sim.routes[r as usize].lanes[0];
    sim.place(id, l, pos, 0.0, false).unwrap();
    id
}

/// Runs the insertion of the flow's first departure (due at its begin) without moving anyone.
fn insert_first_departure(sim: &mut Simulation) {
    sim.time_s = sim.spec.flows[0].begin_s + sim.spec.step_s;
    sim.insert_departures();
}

#[test]
fn brutto_occupancy_counts_lengths_with_min_gaps_over_the_lane() {
    let mut sim = Simulation::from_spec(lane_drop_spec(DepartLane::Free), 0).unwrap();
    let lanes = entry_lanes(&sim);
    let len = sim.net.lanes[lanes[0] as usize].length;
    assert_eq!(len, 600.0);
    assert_eq!(sim.brutto_occupancy(lanes[1]), 0.0);
    stand(&mut sim, 1, 300.0);
    stand(&mut sim, 1, 320.0);
    // two vehicles of 5 m with 2.5 m min gaps
    assert_eq!(sim.brutto_occupancy(lanes[1]), 15.0 / 600.0);
    // the last vehicle's 2 m behind the lane's start are not on it
    stand(&mut sim, 2, 3.0);
    assert_eq!(sim.brutto_occupancy(lanes[2]), (7.5 - 2.0) / 600.0);
}

/// SUMO 1.8.0, two lanes, one standing vehicle on the right lane at 50 m, three on the left at 300-340 m: the
/// `free` vehicle takes the right lane (the least occupied), not the left one whose last vehicle is further away.
#[test]
fn free_takes_the_least_occupied_lane_and_the_rightmost_on_a_tie() {
    let mut sim = Simulation::from_spec(lane_drop_spec(DepartLane::Free), 0).unwrap();
    let lanes = entry_lanes(&sim);
    for pos in [300.0, 320.0, 340.0] {
        stand(&mut sim, 0, pos);
    }
    // lanes 1 and 2 tie at one vehicle each; lane 2's is further from the start
    stand(&mut sim, 1, 100.0);
    stand(&mut sim, 2, 400.0);
    insert_first_departure(&mut sim);
    assert_eq!(sim.departed_last.len(), 1);
    let id = sim.departed_last[0];
    assert_eq!(sim.veh[id as usize].lane, lanes[1]);
    let from = sim.spec.flows[0].from;
    let lane1_route = sim.add_route(from, &[], None, Some(1)).unwrap();
    assert_eq!(sim.veh[id as usize].route, lane1_route);
    assert_eq!(sim.waiting_to_enter(), 0);
}

/// SUMO 1.8.0, two lanes, a standing vehicle at 6 m on the right lane and two far ahead on the left: the `free`
/// vehicle picks the right lane, is refused there, and waits (it does not try the left lane).
#[test]
fn free_waits_when_the_least_occupied_lane_refuses_it() {
    let mut sim = Simulation::from_spec(lane_drop_spec(DepartLane::Free), 0).unwrap();
    stand(&mut sim, 0, 6.0);
    for lane in [1, 2] {
        stand(&mut sim, lane, 300.0);
        stand(&mut sim, lane, 320.0);
    }
    insert_first_departure(&mut sim);
    assert!(sim.departed_last.is_empty());
    assert_eq!(sim.waiting_to_enter(), 1);
}

#[test]
fn random_departs_on_every_lane_alike_and_repeats_with_its_seed() {
    let lanes_of_departures = |seed: u64| {
        let mut sim = Simulation::from_spec(lane_drop_spec(DepartLane::Random), seed).unwrap();
        let lanes = entry_lanes(&sim);
        let mut per_lane = [0usize; 3];
        let mut order = Vec::new();
        for _ in 0..600 {
            sim.step().unwrap();
            for &id in &sim.departed_last {
                let k = lanes
                    .iter()
                    .position(|&l| l == sim.veh[id as usize].lane)
                    .unwrap();
                per_lane[k] += 1;
                order.push(k);
            }
        }
        (per_lane, order, sim.metrics())
    };
    let (per_lane, order, m) = lanes_of_departures(3);
    let n: usize = per_lane.iter().sum();
    assert!(n > 300, "{per_lane:?}");
    for c in per_lane {
        // a third each, within about four standard deviations
        let share = c as f64 / n as f64;
        assert!((share - 1.0 / 3.0).abs() < 0.09, "{per_lane:?}");
    }
    let (per_lane2, order2, m2) = lanes_of_departures(3);
    assert_eq!((per_lane, &order), (per_lane2, &order2));
    assert_eq!(format!("{m:?}"), format!("{m2:?}"));
    let (_, order3, _) = lanes_of_departures(4);
    assert_ne!(order, order3);
}

/// A demand far beyond what the road takes: past [`crate::demand::waiting::BUILT_WAITING_CAP`] waiting vehicles the queue
/// only counts them and builds each when it is tried, and still a random vehicle refused on its lane lets the ones
/// behind it try theirs, so a step ends with a queue left only once every lane of the road refused a vehicle.
#[test]
fn random_vehicles_behind_a_refused_one_try_their_lanes_past_the_built_cap() {
    let mut spec = lane_drop_spec(DepartLane::Random);
    spec.flows[0].vehs_per_hour = 21_600.0; // the most the entry check allows: a vehicle per lane and step
    let mut sim = Simulation::from_spec(spec, 1).unwrap();
    let lanes = entry_lanes(&sim);
    // fill the queue past the cap, then let its built part drain (it keeps only vehicles refused in a step)
    let mut steps = 0;
    while sim.road_entries[0].queue.built_at(8).is_some()
        || sim.waiting_to_enter() <= crate::demand::waiting::BUILT_WAITING_CAP
    {
        sim.step().unwrap();
        steps += 1;
        assert!(steps < 5000, "the built part never drained");
    }
    let mut entered_on = [0usize; 3];
    for _ in 0..200 {
        sim.step().unwrap();
        assert!(sim.waiting_to_enter() > crate::demand::waiting::BUILT_WAITING_CAP);
        for l in &lanes {
            assert!(sim.refused_lanes.contains(l), "lane {l} never tried");
        }
        for &id in &sim.departed_last {
            let k = lanes
                .iter()
                .position(|&l| l == sim.veh[id as usize].lane)
                .unwrap();
            entered_on[k] += 1;
        }
    }
    // every lane takes vehicles (the middle one fewest: the ending right lane's vehicles merge into it)
    assert!(entered_on.iter().all(|&n| n > 0), "{entered_on:?}");
    assert!(entered_on.iter().sum::<usize>() > 100, "{entered_on:?}");
}
