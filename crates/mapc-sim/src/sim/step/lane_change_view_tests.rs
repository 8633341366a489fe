//! What the lane-change pass shows LC2013, as SUMO 1.8's lane changer does: the neighbours on the lane beside
//! (split at the ego's front), the leader past the end of a lane (only within the braking distance), and the
//! memory cleared on a lane without a lane changer (a junction connection). On the two-lane merge.

use super::*;
use crate::models::lc::NeighbourLane;
use crate::network::best_lanes::BestLane;
use crate::runs::scenario::spec_from_scenario;

fn two_lane_merge(seed: u64) -> Simulation {
    let rs = mapc_scenario::ResolvedScenario::load("two_lane_merge").expect("built-in scenario");
    Simulation::from_spec(spec_from_scenario(&rs).expect("simulator spec"), seed).unwrap()
}

/// The best lanes the pass hands LC2013 for `id` where it is now.
fn best_lanes_now(sim: &mut Simulation, id: VehicleId) -> Vec<BestLane> {
    let (route, route_pos, vtype) = {
        let v = &sim.veh[id as usize];
        (v.route, v.route_pos, v.vtype)
    };
    let k = sim.routes[route as usize].road_k[route_pos as usize] as usize;
    let best_i = sim.best_lanes_at(route, k, vtype);
    sim.best_cache.store[best_i as usize].clone()
}

fn on_road(sim: &Simulation, id: VehicleId) -> bool {
    matches!(
        sim.lane_at(sim.veh[id as usize].lane as usize).kind,
        LaneKind::Road(_)
    )
}

/// Steps `sim` `steps` times and after each step calls `f` for every vehicle on a road and each lane beside it,
/// with the best lanes the pass hands LC2013 for that vehicle.
fn each_side_lane(
    sim: &mut Simulation,
    steps: usize,
    mut f: impl FnMut(&Simulation, VehicleId, LaneIdx, &[BestLane]),
) {
    for _ in 0..steps {
        sim.step().unwrap();
        let ids: Vec<VehicleId> = sim.active_ids().filter(|&id| on_road(sim, id)).collect();
        for id in ids {
            let best = best_lanes_now(sim, id);
            let own = sim.lane_at(sim.veh[id as usize].lane as usize);
            for n in [own.right, own.left].into_iter().flatten() {
                f(sim, id, n, &best);
            }
        }
    }
}

#[test]
fn a_neighbour_alongside_is_the_follower_not_the_leader() {
    let mut sim = two_lane_merge(3);
    let (mut leaders, mut followers, mut alongside) = (0, 0, 0);
    each_side_lane(&mut sim, 500, |sim, id, n, best| {
        let mut got = NeighbourLane::default();
        let n_is_right = sim.lc_lane(n).0 < sim.lc_lane(sim.veh[id as usize].lane).0;
        sim.neighbours(&sim.types, id, n, best, usize::MAX, n_is_right, &mut got);
        let v = &sim.veh[id as usize];
        let n_is_right =
            sim.lane_at(n as usize).index < sim.lane_at(sim.veh[id as usize].lane as usize).index;
        // by hand: the pass visits the largest position first, the right lane first on a tie; the leader
        // is the nearest vehicle visited before the ego, the follower the nearest after it
        let visited_before = |p: f64| p > v.pos || (p == v.pos && n_is_right);
        let on_lane = sim.lane_veh[n as usize]
            .iter()
            .map(|&o| (o, &sim.veh[o as usize]));
        let ahead = on_lane
            .clone()
            .filter(|(_, o)| visited_before(o.pos))
            .min_by(|a, b| a.1.pos.total_cmp(&b.1.pos));
        let behind = on_lane
            .filter(|(_, o)| !visited_before(o.pos))
            .max_by(|a, b| a.1.pos.total_cmp(&b.1.pos));
        let min_gap = sim.types[v.vtype as usize].min_gap;
        if let Some((o, ov)) = ahead {
            let l = got.leader.expect("a leader on the lane");
            assert_eq!(
                (l.id, l.gap),
                (o as u64, ov.pos - ov.length - v.pos - min_gap)
            );
            leaders += 1;
        }
        if let Some((o, ov)) = behind {
            let f = got.follower.expect("a follower on the lane");
            let f_min_gap = sim.types[ov.vtype as usize].min_gap;
            assert_eq!(
                (f.id, f.gap),
                (o as u64, v.pos - v.length - ov.pos - f_min_gap)
            );
            followers += 1;
            if ov.pos > v.pos - v.length {
                // its front beside the ego: a follower that overlaps, which blocks the change
                assert!(f.gap < 0.0);
                alongside += 1;
            }
        }
    });
    assert!(
        leaders > 1000 && followers > 1000 && alongside > 100,
        "{leaders} {followers} {alongside}"
    );
}

#[test]
fn a_leader_past_the_lane_end_is_seen_only_within_the_braking_distance() {
    let mut sim = two_lane_merge(0);
    let (mut beyond, mut within) = (0, 0);
    for _ in 0..600 {
        sim.step().unwrap();
        let ids: Vec<VehicleId> = sim.active_ids().filter(|&id| on_road(&sim, id)).collect();
        for id in ids {
            let v = &sim.veh[id as usize];
            if sim.lane_veh[v.lane as usize].first() != Some(&id) {
                continue;
            }
            let p = &sim.types[v.vtype as usize];
            let seen = sim.lane_at(v.lane as usize).length - v.pos;
            let reach = p.brake_gap(v.speed, p.decel, p.tau) + p.min_gap;
            let r = &sim.routes[v.route as usize];
            // the next vehicle on the route's next lanes (the junction connection, then the next road)
            let next = r.lanes.0[v.route_pos as usize + 1..]
                .iter()
                .take(2)
                .find_map(|&l| sim.lane_veh[l as usize].last().copied());
            let got = sim.own_leader(&sim.types, id, usize::MAX);
            if seen > reach {
                // SUMO's getRealLeader: beyond the braking distance plus min gap there is no leader to change for
                assert!(
                    got.is_none(),
                    "vehicle {id}: {seen} m to the end, reach {reach}"
                );
                beyond += usize::from(next.is_some());
            } else if let Some(o) = next {
                assert_eq!(got.map(|l| l.id), Some(o as u64));
                within += 1;
            }
        }
    }
    assert!(beyond > 100 && within > 100, "{beyond} {within}");
}

#[test]
fn the_memory_is_cleared_on_a_junction_connection_and_kept_on_a_road_with_lanes() {
    let mut sim = two_lane_merge(0);
    let (mut on_via, mut on_lanes) = (None, None);
    while on_via.is_none() || on_lanes.is_none() {
        sim.step().unwrap();
        for id in sim.active_ids() {
            let l = sim.lane_at(sim.veh[id as usize].lane as usize);
            match l.kind {
                LaneKind::Via(_) => on_via = on_via.or(Some(id)),
                LaneKind::Road(_) if l.left.is_some() || l.right.is_some() => {
                    on_lanes = on_lanes.or(Some(id))
                }
                _ => {}
            }
        }
    }
    for (id, cleared) in [(on_via.unwrap(), true), (on_lanes.unwrap(), false)] {
        let (speed, vtype, lane) = {
            let v = &sim.veh[id as usize];
            (v.speed, v.vtype as usize, v.lane)
        };
        let mem = &mut sim.veh[id as usize].lc.as_mut().unwrap().mem;
        mem.speed_gain_probability = 0.5;
        mem.keep_right_probability = -0.7;
        mem.look_ahead_speed = 20.0;
        // no advice and no blocked wish: the car-following speed passes unchanged, the memory as told
        let next = sim.patch_lc_speed(id, speed, vtype, lane, 30.0, 0.0, 10.0, 15.0);
        assert_eq!(next, 10.0);
        let mem = &sim.veh[id as usize].lc.as_ref().unwrap().mem;
        let got = (
            mem.speed_gain_probability,
            mem.keep_right_probability,
            mem.look_ahead_speed,
        );
        if cleared {
            // SUMO's patchSpeed on an edge without a lane changer calls changed(): the wishes start afresh
            assert_eq!(got, (0.0, 0.0, 0.0), "vehicle {id} in a junction");
        } else {
            assert_eq!(got, (0.5, -0.7, 20.0), "vehicle {id} on a road of lanes");
        }
    }
}

#[test]
fn a_neighbour_leader_is_looked_for_along_the_lanes_best_continuation_past_a_short_road() {
    // the I-210 window: the acceleration lane's road (92 m) is followed by an 8 m road, then R196; near its end a
    // neighbour lane's leader may lie two roads ahead, within the braking distance (getLeaderOnConsecutive)
    let rs = mapc_scenario::ResolvedScenario::load("../../scenarios/i210_window_lanes.toml")
        .expect("scenario file");
    let mut sim = Simulation::from_spec(spec_from_scenario(&rs).unwrap(), 0).unwrap();
    let mut two_roads_ahead = 0;
    each_side_lane(&mut sim, 400, |sim, id, n, best| {
        let v = &sim.veh[id as usize];
        let nl = sim.lane_at(n as usize);
        if sim.lane_veh[n as usize]
            .iter()
            .any(|&o| sim.veh[o as usize].pos > v.pos)
        {
            return;
        }
        let Some(link) = best[nl.index as usize].next_link else {
            return;
        };
        let first = sim.link_at(link as usize);
        let next_two = [first.via_lane, first.to_lane];
        let mut got = NeighbourLane::default();
        let n_is_right = sim.lc_lane(n).0 < sim.lc_lane(sim.veh[id as usize].lane).0;
        sim.neighbours(&sim.types, id, n, best, usize::MAX, n_is_right, &mut got);
        let Some(l) = got.leader else {
            return;
        };
        let ol = sim.veh[l.id as usize].lane;
        if ol == n || next_two.contains(&ol) {
            return;
        }
        // by hand: the connections and road lanes of the continuation with the distance to each's start
        let cont = &best[nl.index as usize].continuation;
        let mut chain = vec![(first.via_lane, nl.length - v.pos)];
        let mut start = nl.length - v.pos + sim.lane_at(first.via_lane as usize).length;
        for (j, &c) in cont.iter().enumerate() {
            chain.push((c, start));
            start += sim.lane_at(c as usize).length;
            let Some(&to) = cont.get(j + 1) else { break };
            let k = sim
                .lane_at(c as usize)
                .out_links
                .iter()
                .copied()
                .find(|&k| sim.link_at(k as usize).to_lane == to)
                .unwrap();
            let via = sim.link_at(k as usize).via_lane;
            chain.push((via, start));
            start += sim.lane_at(via as usize).length;
        }
        let &(_, seen) = chain
            .iter()
            .find(|&&(c, _)| c == ol)
            .expect("on the continuation");
        let ov = &sim.veh[l.id as usize];
        let min_gap = sim.types[v.vtype as usize].min_gap;
        assert!((l.gap - (seen + ov.pos - ov.length - min_gap)).abs() < 1e-9);
        let p = &sim.types[v.vtype as usize];
        assert!(nl.length - v.pos <= p.brake_gap(v.speed, p.decel, p.tau) + p.min_gap);
        two_roads_ahead += 1;
    });
    assert!(two_roads_ahead > 0);
}
