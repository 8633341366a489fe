//! The per-step overlap check at a merge: a road's last vehicle whose tail still lies on a merging (foe)
//! connection runs beside a follower on the other connection until the follower reaches the conflict point
//! ([`CONFLICT_POINT_SHARE`] of the shorter connection before its end); past it, or behind a leader that came
//! the follower's own way, an overlap is a collision.

use super::*;
use crate::runs::scenario::spec_from_scenario;

/// The Simple Merge (connections of 24.53 m from the main road and 22.95 m from the ramp into the merge road)
/// with the leader 20 m long: it can reach back onto its connection further than the conflict point lies.
struct Merge {
    sim: Simulation,
    /// The merge road's lane, on each of the two flows' routes.
    merge_lane: LaneIdx,
    main: RoadId,
    ramp: RoadId,
    /// Where the merge road lies on the main route and on the ramp route.
    main_k: usize,
    ramp_k: usize,
}

const LONG: usize = 0;

fn merge() -> Merge {
    let rs = mapc_scenario::ResolvedScenario::load("simple_merge").expect("built-in scenario");
    let mut spec = spec_from_scenario(&rs).expect("simulator spec");
    spec.vehicle_types[LONG].length = 20.0;
    let main = spec.flows[0].from;
    let ramp = spec
        .flows
        .iter()
        .map(|f| f.from)
        .find(|&r| r != main)
        .unwrap();
    let mut sim = Simulation::from_spec(spec, 0).unwrap();
    let main_route = sim.add_route(main, &[], None, None).unwrap();
    let ramp_route = sim.add_route(ramp, &[], None, None).unwrap();
    let lanes = |r: u32| sim.routes[r as usize].lanes.0.clone();
    let (main_lanes, ramp_lanes) = (lanes(main_route), lanes(ramp_route));
    let ramp_k = ramp_lanes
        .iter()
        .position(|l| main_lanes.contains(l))
        .expect("the routes merge");
    let merge_lane = ramp_lanes[ramp_k];
    let main_k = main_lanes.iter().position(|&l| l == merge_lane).unwrap();
    Merge {
        sim,
        merge_lane,
        main,
        ramp,
        main_k,
        ramp_k,
    }
}

impl Merge {
    /// The length of the connection before the merge road on the route from `from` (`k`: the road's place).
    fn via_length(&self, from: RoadId, k: usize) -> f64 {
        let r = self.sim.routes.iter().position(|r| {
            r.lanes.0.first() == self.sim.net.road_lanes[self.road(from)].first()
                && r.lanes.0.get(k) == Some(&self.merge_lane)
        });
        let via = self.sim.routes[r.unwrap()].lanes[k - 1];
        self.sim.lane_at(via as usize).length
    }

    fn road(&self, id: RoadId) -> usize {
        self.sim.net.road_ids.iter().position(|&r| r == id).unwrap()
    }

    /// The 20 m leader's front 1 m onto the merge road, having come from `from` (its tail 19 m back on the
    /// connection), and a follower on the main road's connection `to_end` m before its end.
    fn place(&mut self, leader_from: RoadId, to_end: f64) -> Result<(), SimError> {
        let k = if leader_from == self.main {
            self.main_k
        } else {
            self.ramp_k
        };
        self.sim
            .place_replica(LONG, leader_from, k, 1.0, 10.0, 1.0, 0.0)?;
        let main_via = self.via_length(self.main, self.main_k);
        let follower_type = 1;
        self.sim.place_replica(
            follower_type,
            self.main,
            self.main_k - 1,
            main_via - to_end,
            10.0,
            1.0,
            0.0,
        )?;
        Ok(())
    }
}

#[test]
fn a_follower_beside_a_leaders_tail_on_the_foe_connection_overlaps_only_past_the_conflict_point() {
    let m = merge();
    assert_ne!(m.sim.spec.vehicle_types[1].length, 20.0);
    let (main_via, ramp_via) = (
        m.via_length(m.main, m.main_k),
        m.via_length(m.ramp, m.ramp_k),
    );
    assert_eq!((main_via, ramp_via), (24.53, 22.95));
    let conflict = CONFLICT_POINT_SHARE * ramp_via; // 8.03 m before the connections' ends
    // short of the conflict point: beside the leader's tail (a gap of about -9 m counts for nothing)
    let mut m = merge();
    m.place(m.ramp, conflict + 2.0).unwrap();
    m.sim.check_no_overlap().unwrap();
    // past it: the follower's front lies 13 m inside the leader
    let mut m = merge();
    m.place(m.ramp, conflict - 2.0).unwrap();
    match m.sim.check_no_overlap() {
        Err(SimError::Collision { gap_m, .. }) => {
            assert!(
                (gap_m - (1.0 - 20.0 + conflict - 2.0)).abs() < 1e-9,
                "{gap_m}"
            )
        }
        other => panic!("no collision reported: {other:?}"),
    }
    // a leader that came the follower's own way is never beside it
    let mut m = merge();
    m.place(m.main, conflict + 2.0).unwrap();
    assert!(matches!(
        m.sim.check_no_overlap(),
        Err(SimError::Collision { .. })
    ));
}

/// Two vehicles standing inside the Simple Merge's junction: one from the yielding main road 10 m into its
/// connection (14.53 m before the merge, short of the conflict point), one from the ramp (the major road) just
/// in, 22.95 m before the merge and so fully behind the first. The ramp's driver cannot pass beside it and follows
/// it; the main road's driver must then not wait for the ramp's (each waited for the other to the end of the
/// run).
#[test]
fn a_yielding_driver_ahead_inside_the_junction_goes_before_the_major_driver_behind_it() {
    let m = merge();
    let mut spec = m.sim.spec.clone();
    spec.flows.clear();
    let mut sim = Simulation::from_spec(spec, 0).unwrap();
    let human = 1;
    let main_via = m.via_length(m.main, m.main_k);
    let minor = sim
        .place_replica(human, m.main, m.main_k - 1, 10.0, 0.0, 1.0, 0.0)
        .unwrap();
    let major = sim
        .place_replica(human, m.ramp, m.ramp_k - 1, 0.0, 0.0, 1.0, 0.0)
        .unwrap();
    assert!(main_via - 10.0 > CONFLICT_POINT_SHARE * 22.95);
    for _ in 0..40 {
        sim.step().unwrap();
        sim.check_no_overlap().unwrap();
    }
    for id in [minor, major] {
        let v = sim.vehicle(id);
        assert!(
            v.as_ref().is_none_or(|v| !v.in_junction),
            "vehicle {id} still in the junction after 20 s: {v:?}"
        );
    }
}
