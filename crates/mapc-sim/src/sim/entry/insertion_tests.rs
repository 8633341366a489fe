//! Insertion with an adaptable speed (`departSpeed="max"`) as SUMO 1.8's `MSLane::isInsertionSuccess` with
//! `patchSpeed`: the speed is lowered for the leader first, and the follower is checked at that speed.

use super::*;
use crate::models::cf::CarFollowModel;
use crate::runs::scenario::spec_from_scenario;

/// The lane drop with one flow from its upstream road, departing at the speed `max` (adapted to the road ahead).
fn sim_with_max_depart_speed() -> Simulation {
    let rs = mapc_scenario::ResolvedScenario::load("lane_drop").expect("built-in scenario");
    let mut spec = spec_from_scenario(&rs).expect("simulator spec");
    spec.flows.truncate(1);
    spec.flows[0].depart_speed = DEPART_SPEED_MAX;
    Simulation::from_spec(spec, 0).unwrap()
}

/// A vehicle of type 0 on lane 0 of the entry road, placed with its front at `pos` driving at `speed`.
fn driving(sim: &mut Simulation, pos: f64, speed: f64) -> VehicleId {
    let from = sim.spec.flows[0].from;
    let r = sim.add_route(from, &[], None, Some(0)).unwrap();
    let id = sim.create_vehicle(0, r, speed);
    let l = sim.routes[r as usize].lanes[0];
    sim.place(id, l, pos, speed, false).unwrap();
    id
}

/// A vehicle of type 0 waiting to enter lane 0 of the entry road at the speed `max`.
fn waiting(sim: &mut Simulation) -> VehicleId {
    let from = sim.spec.flows[0].from;
    let r = sim.add_route(from, &[], None, Some(0)).unwrap();
    sim.create_vehicle(0, r, DEPART_SPEED_MAX)
}

/// A waiting vehicle's desired speed on its entry lane, where its adapted speed starts.
fn desired(sim: &Simulation, id: VehicleId) -> f64 {
    let (lane, _, _) = sim.entry_place(id, None);
    sim.desired_speed(&sim.veh[id as usize], lane)
}

/// The place `at` of a vehicle waiting to enter behind a leader 20 m ahead at 5 m/s, with the speed SUMO adapts
/// its insertion to (the insertion follow speed from the desired speed), and the gaps a follower at
/// `FOLLOWER_SPEED` needs behind it at that speed and standing still.
struct Case {
    sim: Simulation,
    id: VehicleId,
    at: f64,
    expected: f64,
    gap_adapted: f64,
    gap_standing: f64,
}

const FOLLOWER_SPEED: f64 = 15.0;

fn behind_a_slow_leader() -> Case {
    let mut sim = sim_with_max_depart_speed();
    let at = 250.0;
    let id = waiting(&mut sim);
    let p = sim.types[0];
    let length = sim.veh[id as usize].length;
    driving(&mut sim, at + 20.0 + p.min_gap + length, 5.0);
    let des = desired(&sim, id);
    let expected = p.insertion_follow_speed(des, 20.0, 5.0, des);
    assert!(
        expected > 0.0 && expected < des,
        "the leader lowers the speed"
    );
    let gap_adapted = p.secure_gap(FOLLOWER_SPEED, expected);
    let gap_standing = p.secure_gap(FOLLOWER_SPEED, 0.0);
    assert!(0.0 < gap_adapted && gap_adapted < gap_standing);
    Case {
        sim,
        id,
        at,
        expected,
        gap_adapted,
        gap_standing,
    }
}

/// Puts the follower at `gap` (bumper to bumper less its min gap) behind the place.
fn follower_at(c: &mut Case, gap: f64) {
    let (length, min_gap) = (c.sim.veh[c.id as usize].length, c.sim.types[0].min_gap);
    driving(&mut c.sim, c.at - length - min_gap - gap, FOLLOWER_SPEED);
}

#[test]
fn a_max_speed_vehicle_enters_at_its_leaders_speed_when_the_follower_is_safe_at_that_speed() {
    let mut c = behind_a_slow_leader();
    // safe behind a vehicle at the adapted speed, not behind a standing one: a check at a standstill refused
    // this insertion, where SUMO makes it
    let gap = 0.5 * (c.gap_adapted + c.gap_standing);
    follower_at(&mut c, gap);
    let (id, at) = (c.id, c.at);
    let des = desired(&c.sim, id);
    assert_eq!(
        c.sim.adapted_insertion_speed(id, Some(at), des),
        Some(c.expected)
    );
    assert!(c.sim.try_insert_at(id, Some(at)));
    assert_eq!(c.sim.veh[id as usize].speed, c.expected);
    assert_eq!(c.sim.veh[id as usize].pos, at);
}

#[test]
fn a_max_speed_vehicle_is_refused_where_the_follower_is_not_safe_at_the_adapted_speed() {
    let mut c = behind_a_slow_leader();
    let gap = 0.5 * c.gap_adapted;
    follower_at(&mut c, gap);
    let (id, at) = (c.id, c.at);
    let des = desired(&c.sim, id);
    assert_eq!(c.sim.adapted_insertion_speed(id, Some(at), des), None);
    assert!(!c.sim.try_insert_at(id, Some(at)));
    assert_eq!(
        c.sim.veh[id as usize].depart_speed, DEPART_SPEED_MAX,
        "the rule stays for a later try"
    );
}

#[test]
fn a_max_speed_vehicle_overlapping_its_leader_is_refused() {
    let mut sim = sim_with_max_depart_speed();
    driving(&mut sim, 253.0, 15.0);
    let id = waiting(&mut sim);
    let des = desired(&sim, id);
    assert_eq!(sim.adapted_insertion_speed(id, Some(250.0), des), None);
}

/// Krauss, on ramp_metering_1x3's ramp: a vehicle put 3 m before the meter's line (a major link, its state `O`)
/// with a standing leader 10 m into the road past the meter. The leader lies beyond the ramp, within the braking
/// distance, so the speed is that leader's insertion follow speed, as SUMO's look-ahead along the next lanes
/// gives it; without the leader the vehicle enters at its desired speed (the next lanes' limits are the ramp's).
#[test]
fn a_max_speed_vehicle_slows_for_a_leader_on_the_road_ahead() {
    let cfg = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../../scenarios/sumo/ramp_metering_1x3/1ramp_1x3.sumocfg"
    );
    let rs = mapc_scenario::ResolvedScenario::load(cfg).unwrap();
    let ramp = rs.graph.find_roads("on_ramp").unwrap()[0];
    let passage = rs.graph.find_roads("passage_area").unwrap()[0];
    let spec = spec_from_scenario(&rs).unwrap();
    let mut sim = Simulation::from_spec(spec, 0).unwrap();
    // the meter green: an insertion at the end of the first step reads the light at the run's begin
    sim.time_s = sim.spec.start_time_s + sim.spec.step_s;
    let r = sim.add_route(ramp, &[], None, Some(0)).unwrap();
    let id = sim.create_vehicle(0, r, DEPART_SPEED_MAX);
    let lane = sim.routes[r as usize].lanes[0];
    let lane_len = sim.net.lanes[lane as usize].length;
    let at = lane_len - 3.0;
    let p = sim.types[0];
    assert!(matches!(p.kind, crate::models::cf::CfKind::Krauss(_)));
    let des = sim.desired_speed(&sim.veh[id as usize], lane);
    assert_eq!(sim.adapted_insertion_speed(id, Some(at), des), Some(des));
    // the leader, standing with its front 10 m into the road past the meter
    let lr = sim.add_route(passage, &[], None, Some(0)).unwrap();
    let leader = sim.create_vehicle(0, lr, 0.0);
    let leader_lane = sim.routes[lr as usize].lanes[0];
    sim.place(leader, leader_lane, 10.0, 0.0, false).unwrap();
    let via = sim.routes[r as usize].lanes[1];
    assert_eq!(sim.routes[r as usize].lanes[2], leader_lane);
    let gap = 3.0 + sim.net.lanes[via as usize].length + 10.0
        - sim.veh[leader as usize].length
        - p.min_gap;
    let expected = p.insertion_follow_speed(des, gap, 0.0, des);
    assert!(expected < 0.5 * des, "{expected} of {des}");
    assert_eq!(
        sim.adapted_insertion_speed(id, Some(at), des),
        Some(expected)
    );
}

#[test]
fn a_free_insertion_behind_the_last_vehicle_takes_about_the_speed_of_the_lanes_first() {
    // SUMO 1.8's freeInsertion judges "behind the last one" by the lane's first vehicle (`getFirstFullVehicle`):
    // a fast last vehicle 150 m in, a slow first one 400 m in; the new vehicle enters at the lane's start at about
    // the slow one's speed, not the fast one's
    let mut sim = sim_with_max_depart_speed();
    let len = sim.lane_at(sim.routes[0].lanes[0] as usize).length;
    assert!(len > 420.0, "the entry road is long enough: {len}");
    driving(&mut sim, 400.0, 5.0);
    driving(&mut sim, 150.0, 25.0);
    let id = waiting(&mut sim);
    sim.veh[id as usize].depart_pos = DepartPos::Free;
    assert!(sim.try_insert(id));
    let v = &sim.veh[id as usize];
    assert_eq!(v.pos, 0.0);
    let p = sim.types[0];
    let expected = p
        .insertion_follow_speed(
            desired(&sim, id),
            p.secure_gap(5.0, 5.0) + p.min_gap,
            5.0,
            0.0,
        )
        .fmin(desired(&sim, id));
    assert!(v.speed < 8.0, "entered at {} m/s", v.speed);
    assert_eq!(v.speed, expected);
}

#[test]
fn a_max_speed_vehicle_entering_before_a_light_that_is_not_green_can_stop_at_its_line() {
    // scenarios/sumo/ramp_metering_1x3's meter (G 5 s, r 5 s from the run's begin): a ramp vehicle put 15 m before
    // the line enters at a speed from which it stops there while the light is red (SUMO's isInsertionSuccess
    // stops at a link that is not opened), and faster while it is green
    let cfg = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../../scenarios/sumo/ramp_metering_1x3/1ramp_1x3.sumocfg"
    );
    let rs = mapc_scenario::ResolvedScenario::load(cfg).expect("shipped SUMO scenario");
    let ramp = rs.graph.find_roads("on_ramp").unwrap()[0];
    let spec = spec_from_scenario(&rs).expect("simulator spec");
    let entered_at = |green: bool| {
        let mut sim = Simulation::from_spec(spec.clone(), 0).unwrap();
        // after a step, the light's clock of the step just run is time - step
        sim.step().unwrap();
        while ((sim.time_s - sim.spec.step_s - sim.spec.start_time_s).rem_euclid(10.0) < 5.0)
            != green
        {
            sim.step().unwrap();
        }
        let r = sim.add_route(ramp, &[], None, Some(0)).unwrap();
        let id = sim.create_vehicle(0, r, DEPART_SPEED_MAX);
        let lane = sim.routes[r as usize].lanes[0];
        let len = sim.lane_at(lane as usize).length;
        // the ramp's own vehicles out of the lane's queue, so that only the light constrains the insertion (the
        // simulation is not stepped again)
        sim.lane_veh[lane as usize].clear();
        assert!(sim.try_insert_at(id, Some(len - 15.0)));
        let p = sim.types[0];
        (
            sim.veh[id as usize].speed,
            p.stop_speed(15.0, desired(&sim, id), desired(&sim, id)),
        )
    };
    let (on_red, stop) = entered_at(false);
    let (on_green, _) = entered_at(true);
    assert!(
        on_red <= stop + 1e-9,
        "{on_red} against a stop speed of {stop}"
    );
    assert!(on_green > on_red + 1.0, "green {on_green}, red {on_red}");
}
