//! Where a vehicle's back lies when its front has just entered a lane (`Simulation::back_place`, read by the
//! floating-car data's angles): on the lane it came from, at the place its length reaches back to.

use mapc_scenario::ResolvedScenario;
use mapc_sim::{LaneRef, Simulation, spec_from_scenario};

#[test]
fn a_back_still_on_the_lane_before_is_found_there() {
    let cfg = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../../scenarios/sumo/highway_ramp/highway-ramp.sumocfg"
    );
    let rs = ResolvedScenario::load(cfg).unwrap();
    let mut sim = Simulation::from_spec(spec_from_scenario(&rs).unwrap(), 0).unwrap();
    let mut last_place = std::collections::HashMap::new();
    let (mut checked, mut unknown) = (0, 0);
    while !sim.is_done() && checked < 50 {
        sim.step().unwrap();
        let ids: Vec<_> = sim.active_ids().collect();
        for id in ids {
            let v = sim.vehicle(id).unwrap();
            let here = (v.road, v.lane_index);
            let back = sim.back_place(id);
            match last_place.insert(id, here) {
                // a step ago on another road (highway_ramp has no internal lanes: the simulator's connection
                // between has its least length), its back reaching behind the lane's start
                Some(before) if before.0 != here.0 && v.pos_m < v.length => {
                    let via = mapc_sim::network::MIN_VIA_LENGTH_M;
                    match back {
                        Some((LaneRef::Via { from, to }, at)) => {
                            assert_eq!((from, to), (before, here));
                            assert!((at - (via + v.pos_m - v.length)).abs() < 1e-9, "{at}");
                        }
                        Some((lane, at)) => {
                            let road = &sim.spec().graph.roads[before.0.0 as usize];
                            assert_eq!(
                                lane,
                                LaneRef::Road {
                                    road: before.0,
                                    lane: before.1
                                }
                            );
                            let length = road.lanes[before.1 as usize].length_m + via;
                            assert!((at - (length + v.pos_m - v.length)).abs() < 1e-9, "{at}");
                        }
                        // (a driver that changed lanes keeps only the connection it came by on its route)
                        None => unknown += 1,
                    }
                    checked += 1;
                }
                _ if v.pos_m >= v.length => assert_eq!(back, None),
                _ => {}
            }
        }
    }
    assert_eq!(checked, 50);
    assert!(unknown <= 10, "{unknown}");
}
