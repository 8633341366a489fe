//! The adjacent lanes' leaders and followers, and merges onto a road through an acceleration lane, on the two-lane
//! merge.

use super::*;
use crate::models::lc::Side;
use crate::runs::scenario::spec_from_scenario;

fn two_lane_merge() -> Simulation {
    let rs = mapc_scenario::ResolvedScenario::load("two_lane_merge").expect("built-in scenario");
    Simulation::from_spec(spec_from_scenario(&rs).expect("simulator spec"), 3).unwrap()
}

#[test]
fn side_neighbours_are_the_nearest_vehicles_on_the_adjacent_lane() {
    let mut sim = two_lane_merge();
    let (mut leaders, mut followers, mut missing) = (0, 0, 0);
    for _ in 0..500 {
        sim.step().unwrap();
        let ids: Vec<VehicleId> = sim.active_ids().collect();
        for id in ids {
            let v = &sim.veh[id as usize];
            let lane = sim.lane_at(v.lane as usize);
            for side in [Side::Right, Side::Left] {
                let got = sim.side_neighbors(id, side, 1000.0);
                let n = match side {
                    Side::Right => lane.right,
                    Side::Left => lane.left,
                };
                let Some(n) = n else {
                    // no lane there (or inside a junction): nothing
                    assert!(got.is_none());
                    missing += 1;
                    continue;
                };
                let got = got.expect("a lane on that side");
                // by hand, on the adjacent lane itself: the nearest front ahead, the nearest at or behind
                let on_lane = sim.lane_veh[n as usize]
                    .iter()
                    .map(|&o| (o, &sim.veh[o as usize]));
                let ahead = on_lane
                    .clone()
                    .filter(|(_, o)| o.pos > v.pos)
                    .min_by(|a, b| a.1.pos.total_cmp(&b.1.pos));
                let behind = on_lane
                    .filter(|(_, o)| o.pos <= v.pos)
                    .max_by(|a, b| a.1.pos.total_cmp(&b.1.pos));
                if let Some((o, ov)) = ahead {
                    let l = got.leader.expect("a leader on the lane");
                    assert_eq!((l.id, l.gap_m), (o, ov.pos - ov.length - v.pos));
                    leaders += 1;
                }
                if let Some((o, ov)) = behind {
                    let f = got.follower.expect("a follower on the lane");
                    assert_eq!((f.id, f.gap_m), (o, v.pos - v.length - ov.pos));
                    followers += 1;
                }
                // found across the lane's end or start: its front beyond the lane's end, or behind its start
                if ahead.is_none()
                    && let Some(l) = got.leader
                {
                    let front = l.gap_m + sim.veh[l.id as usize].length;
                    assert!(front >= sim.lane_at(n as usize).length - v.pos - 1e-9);
                }
                if behind.is_none()
                    && let Some(f) = got.follower
                {
                    assert!(f.gap_m >= v.pos - v.length - 1e-9);
                }
            }
        }
    }
    assert!(
        leaders > 1000 && followers > 1000 && missing > 1000,
        "{leaders} {followers} {missing}"
    );
}

#[test]
fn a_merge_through_an_acceleration_lane_is_a_merge() {
    // the ramp ends on a lane of its own: no connection has foes, yet the main road's vehicles approach a merge
    // and see the ramp's vehicles about to join
    let mut sim = two_lane_merge();
    assert!(sim.net.links.iter().all(|l| l.foes.is_empty()));
    let main = sim
        .spec
        .graph
        .find_roads(mapc_scenario::generator::MAIN_PRE_MERGE)
        .unwrap()[0];
    let (mut on_main, mut foes_seen) = (0, 0);
    for _ in 0..400 {
        sim.step().unwrap();
        let ids: Vec<VehicleId> = sim.active_ids().collect();
        for id in ids {
            let v = sim.vehicle(id).unwrap();
            if v.road != main || v.in_junction {
                continue;
            }
            on_main += 1;
            let (d, _) = sim.distance_to_next_merge(id).expect("the merge ahead");
            let to_end = sim.lane_at(sim.veh[id as usize].lane as usize).length - v.pos_m;
            assert!((d - to_end).abs() < 1e-9, "{d} {to_end}");
            if let Some(f) = sim.nearest_merge_foe(id, 300.0) {
                assert_ne!(sim.vehicle(f.id).unwrap().road, main);
                assert!(f.dist_to_merge_m >= 0.0);
                foes_seen += 1;
            }
        }
    }
    assert!(on_main > 1000 && foes_seen > 100, "{on_main} {foes_seen}");
}
