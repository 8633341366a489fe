//! A vehicle's state and its life: created from a flow or placed, with its route and speed factor.

use super::*;

/// Where a vehicle is in its life.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum VehicleStatus {
    /// Scheduled or waiting at its entry: not yet in the network.
    Pending,
    Active,
    /// Taken off a jammed lane after standing longer than the time to teleport; comes back further along its
    /// route ([`crate::SimSpec::time_to_teleport_s`]).
    Teleporting,
    Arrived,
}

#[derive(Clone, Debug)]
pub(super) struct Veh {
    pub(super) vtype: u16,
    pub(super) controlled: bool,
    pub(super) status: VehicleStatus,
    pub(super) lane: LaneIdx,
    pub(super) pos: f64,
    pub(super) speed: f64,
    pub(super) length: f64,
    pub(super) speed_factor: f64,
    pub(super) route: u32,
    pub(super) route_pos: u32,
    pub(super) waiting_s: f64,
    pub(super) depart_s: f64,
    /// When it was due to enter (a flow's vehicle: its departure time; NaN for others).
    pub(super) due_s: f64,
    pub(super) arrive_s: f64,
    /// Order of entering the network (0-based); `u64::MAX` while pending.
    pub(super) entry_order: u64,
    /// Acceleration for the next step (controlled vehicles), NaN when none was set.
    pub(super) accel_cmd: f64,
    pub(super) depart_speed: f64,
    pub(super) distance_m: f64,
    pub(super) free_flow_s: f64,
    /// Its lane-change record (multi-lane networks only: made at its first lane-change pass, dropped when it
    /// leaves).
    pub(super) lc: Option<lane_change::LcVeh>,
    /// The driver's own random draws (dawdling), independent of every other vehicle and of the thread count.
    pub(super) rng: DriverRng,
    /// Where it is inserted on its entry lane.
    pub(super) depart_pos: crate::spec::DepartPos,
}

#[derive(Clone, Debug)]
pub(super) struct Route {
    pub(super) lanes: Table<LaneIdx>,
    /// Distance from the route's start to the start of each lane.
    pub(super) start_m: Table<f64>,
    /// The route's roads (indices into the graph's roads), to its destination.
    pub(super) roads: Vec<usize>,
    /// The same for every route over the same roads (the best lanes are cached by it).
    pub(super) roads_id: u32,
    /// Per lane of `lanes`, the index in `roads` of its road (a via lane: of the road it leaves).
    pub(super) road_k: Vec<u32>,
    /// The lanes stop at a lane that does not continue on the route: the vehicle must change lanes before its
    /// end, or stop there.
    pub(super) dead_end: bool,
    /// For a dead end, the lanes on to the route's end past it ([`Network::past_dead_ends`]); else empty.
    pub(super) whole_lanes: Vec<LaneIdx>,
}

/// Values of one vehicle type that do not change during a run.
#[derive(Clone, Copy, Debug)]
pub(super) struct TypeConsts {
    pub(super) max_speed: f64,
    /// Brake distance from `max_speed` plus the min gap: the best lanes' look-ahead is at least this.
    pub(super) max_brake_dist: f64,
    pub(super) impatience: f64,
    /// Highest arrival speed at a minor link from the foe visibility point (a function of the type only).
    pub(super) max_arrival_from_visibility: f64,
    /// 1 / (2 decel), for [`TypeConsts::brake_gap_above`]; `None` where it is not positive and finite (the
    /// bound does not apply).
    pub(super) inv_two_decel: Option<f64>,
}

impl TypeConsts {
    /// A bound strictly above `CfModel::brake_gap(speed, decel, headway)` as computed in floating point: the
    /// Euler sum is a right Riemann sum of the continuous stop, so it never exceeds v^2 / 2b + v headway; the
    /// margin lies far above rounding. Infinite (no shortcut) where that does not apply. Comparisons against it
    /// decide the far cases without the exact gap, which is computed only when the bound cannot decide.
    #[inline]
    pub(super) fn brake_gap_above(&self, speed: f64, headway: f64) -> f64 {
        match self.inv_two_decel {
            Some(inv) if speed >= 0.0 && headway >= 0.0 => {
                (speed * speed * inv + speed * headway) * (1.0 + 1e-9) + 1e-6
            }
            _ => f64::INFINITY,
        }
    }
}

/// A vehicle's own generator (SplitMix64 over the run's seed and the vehicle's id): the draws of one driver do not
/// depend on how many other drivers drew, so a model's randomness adds nothing to the shared stream that decides
/// departures and speed factors.
#[derive(Clone, Copy, Debug)]
pub(super) struct DriverRng(u64);

impl DriverRng {
    pub(super) fn new(seed: u64, id: VehicleId) -> DriverRng {
        let mut r = DriverRng(seed ^ (id as u64).wrapping_mul(0xD1B5_4A32_D192_ED03));
        r.next_u64();
        r
    }

    fn next_u64(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^ (z >> 31)
    }

    /// Uniform in [0, 1), 53 bits.
    pub(super) fn uniform(&mut self) -> f64 {
        (self.next_u64() >> 11) as f64 * (1.0 / (1u64 << 53) as f64)
    }
}

impl Simulation {
    pub(super) fn create_vehicle(
        &mut self,
        vtype: usize,
        route: u32,
        depart_speed: f64,
    ) -> VehicleId {
        let t = &self.spec.vehicle_types[vtype];
        let factor = if t.speed_dev > 0.0 {
            // SUMO redraws until the factor lies in [0.2, 2] (at most 10 tries, then the mean).
            let normal = Normal::new(t.speed_factor, t.speed_dev).expect("validated deviation");
            let mut f = t.speed_factor;
            for _ in 0..10 {
                let x: f64 = normal.sample(&mut self.rng);
                if (0.2..=2.0).contains(&x) {
                    f = x;
                    break;
                }
            }
            f
        } else {
            t.speed_factor
        };
        let free_flow_s = self.free_flow_time(route, factor, t.max_speed);
        let id = self.veh.len() as VehicleId;
        self.veh.push(Veh {
            vtype: vtype as u16,
            controlled: t.controlled,
            status: VehicleStatus::Pending,
            lane: self.routes[route as usize].lanes[0],
            pos: 0.0,
            speed: 0.0,
            length: t.length,
            speed_factor: factor,
            route,
            route_pos: 0,
            waiting_s: 0.0,
            depart_s: f64::NAN,
            due_s: f64::NAN,
            arrive_s: f64::NAN,
            entry_order: u64::MAX,
            accel_cmd: f64::NAN,
            depart_speed,
            distance_m: 0.0,
            free_flow_s,
            lc: None,
            rng: DriverRng::new(self.seed, id),
            depart_pos: crate::spec::DepartPos::Base,
        });
        id
    }

    /// The time to drive `route` at the speed a driver of this speed factor and top speed keeps on each lane,
    /// to its end (past a dead end, as on the lanes the vehicle changes to).
    pub(super) fn free_flow_time(&self, route: u32, factor: f64, max_speed: f64) -> f64 {
        let r = &self.routes[route as usize];
        let lanes: &[LaneIdx] = if r.dead_end { &r.whole_lanes } else { &r.lanes };
        lanes
            .iter()
            .map(|&l| {
                let lane = self.lane_at(l as usize);
                lane.length / (lane.speed_limit * factor).fmin(max_speed)
            })
            .sum()
    }

    /// Give a waiting vehicle another route (its depart lane chosen at insertion).
    pub(super) fn set_route(&mut self, id: VehicleId, route: u32) {
        let v = &self.veh[id as usize];
        debug_assert_eq!(v.status, VehicleStatus::Pending);
        if v.route == route {
            return;
        }
        let max_speed = self.type_consts[v.vtype as usize].max_speed;
        let free_flow_s = self.free_flow_time(route, v.speed_factor, max_speed);
        let lane = self.routes[route as usize].lanes[0];
        let v = &mut self.veh[id as usize];
        v.route = route;
        v.lane = lane;
        v.free_flow_s = free_flow_s;
    }

    /// Put a vehicle into the network at the back of `lane`.
    pub(super) fn place(
        &mut self,
        id: VehicleId,
        lane: LaneIdx,
        pos: f64,
        speed: f64,
        counted: bool,
    ) -> Result<(), SimError> {
        let q = &mut self.lane_veh[lane as usize];
        // keep the lane sorted front-first
        let at = q
            .iter()
            .position(|&o| self.veh[o as usize].pos < pos)
            .unwrap_or(q.len());
        q.insert(at, id);
        self.in_network += 1;
        if self.keeps_active_lanes() {
            self.active_lanes.placed.push(lane);
        }
        let v = &mut self.veh[id as usize];
        v.status = VehicleStatus::Active;
        v.lane = lane;
        v.pos = pos;
        v.speed = speed;
        v.depart_s = self.time_s;
        v.entry_order = self.next_entry;
        self.next_entry += 1;
        if counted {
            self.metrics.departed += 1;
            self.departed_last.push(id);
        }
        Ok(())
    }

    /// Puts a vehicle into the network as another simulator saw it: on the route that starts at road `from`,
    /// `lane_in_route` lanes along it (roads and connections alternate), front at `pos` m on that lane, with its
    /// speed, speed factor and time spent halting. For vehicle-by-vehicle comparisons (docs/calibration.md):
    /// replay a SUMO state, take one step, compare every vehicle's next speed.
    #[allow(clippy::too_many_arguments)]
    pub fn place_replica(
        &mut self,
        vtype: usize,
        from: RoadId,
        lane_in_route: usize,
        pos: f64,
        speed: f64,
        speed_factor: f64,
        waiting_s: f64,
    ) -> Result<VehicleId, SimError> {
        if vtype >= self.spec.vehicle_types.len() {
            return Err(SimError::Spec(format!("no vehicle type {vtype}")));
        }
        let r = self.add_route(from, &[], None, None)?;
        let Some(&lane) = self.routes[r as usize].lanes.get(lane_in_route) else {
            return Err(SimError::Spec(format!(
                "the route from {from} has no lane {lane_in_route}"
            )));
        };
        let len = self.lane_at(lane as usize).length;
        if !(0.0..=len).contains(&pos) || !(speed >= 0.0) || !(speed_factor > 0.0) {
            return Err(SimError::Spec(format!(
                "replica on lane {lane_in_route} of the route from {from}: position {pos} m (lane {len} m), \
                 speed {speed}, speed factor {speed_factor}"
            )));
        }
        let id = self.create_vehicle(vtype, r, speed);
        let v = &mut self.veh[id as usize];
        v.speed_factor = speed_factor;
        v.route_pos = lane_in_route as u32;
        v.waiting_s = waiting_s;
        self.place(id, lane, pos, speed, false)?;
        Ok(id)
    }

    /// What a vehicle takes of its lane in SUMO's brutto occupancy: its length with its min gap.
    #[inline]
    pub(super) fn brutto_length(&self, id: VehicleId) -> f64 {
        let v = &self.veh[id as usize];
        v.length + self.types[v.vtype as usize].min_gap
    }

    pub(super) fn desired_speed(&self, v: &Veh, lane: LaneIdx) -> f64 {
        (self.lane_at(lane as usize).speed_limit * v.speed_factor)
            .fmin(self.type_consts[v.vtype as usize].max_speed)
    }

    /// The route from road `from` (to `to`, or the through roads), starting on the first road's lane `lane`
    /// (none: the rightmost of the lanes that go furthest).
    pub(super) fn add_route(
        &mut self,
        from: RoadId,
        via: &[RoadId],
        to: Option<RoadId>,
        lane: Option<u8>,
    ) -> Result<u32, SimError> {
        let asked = (from, via.to_vec(), to, lane);
        if let Some(&r) = self.route_asked.get(&asked) {
            return Ok(r);
        }
        let r = self.find_route(from, via, to, lane)?;
        self.route_asked.insert(asked, r);
        Ok(r)
    }

    /// [`Self::add_route`] on the network.
    fn find_route(
        &mut self,
        from: RoadId,
        via: &[RoadId],
        to: Option<RoadId>,
        lane: Option<u8>,
    ) -> Result<u32, SimError> {
        let Some(lane) = lane else {
            let (lanes, roads, dead_end) =
                self.net
                    .route_without_changes(&self.spec.graph, from, via, to)?;
            return Ok(self.add_lane_route(lanes, roads, dead_end));
        };
        let roads = self.net.route_roads(&self.spec.graph, from, via, to)?;
        let Some(&start) = self.net.road_lanes[roads[0]].get(lane as usize) else {
            return Err(SimError::Spec(format!("road {from} has no lane {lane}")));
        };
        let (lanes, dead_end) = self.net.best_lane_path(start, &roads, 0.0);
        Ok(self.add_lane_route(lanes, roads, dead_end))
    }

    /// The route of `lanes` over `roads` (shared with every vehicle that drives the same).
    pub(super) fn add_lane_route(
        &mut self,
        lanes: Vec<LaneIdx>,
        roads: Vec<usize>,
        dead_end: bool,
    ) -> u32 {
        if let Some(&i) = self.route_index.get(&(lanes.clone(), roads.clone())) {
            return i;
        }
        let mut start_m = Vec::with_capacity(lanes.len());
        let mut road_k = Vec::with_capacity(lanes.len());
        let mut acc = 0.0;
        let mut k = 0u32;
        for (i, &l) in lanes.iter().enumerate() {
            if i > 0 && self.net.road_of(l).is_some() {
                k += 1;
            }
            start_m.push(acc);
            road_k.push(k);
            acc += self.lane_at(l as usize).length;
        }
        let idx = self.routes.len() as u32;
        self.route_index.insert((lanes.clone(), roads.clone()), idx);
        let next_seq = self.road_seqs.len() as u32;
        let roads_id = *self.road_seqs.entry(roads.clone()).or_insert(next_seq);
        let whole_lanes = if dead_end {
            // a network with no way on is refused when its routes are made; the lanes as they are otherwise
            self.net
                .past_dead_ends(&roads, lanes.clone(), true)
                .unwrap_or_else(|_| lanes.clone())
        } else {
            Vec::new()
        };
        self.routes.push(Route {
            lanes: Table(lanes),
            start_m: Table(start_m),
            roads_id,
            roads,
            road_k,
            dead_end,
            whole_lanes,
        });
        idx
    }
}
