//! Teleports (SUMO's `--time-to-teleport`): the front human driver of a lane that has stood still for longer than
//! the scenario's bound leaves the network, travels on along its route off the road, and comes back at the start of
//! the first road where it fits; at its route's end it arrives. Each is counted, so a jam that would stop a
//! merge for the rest of a run shows instead as teleports in the figures.

use super::*;

/// A vehicle between leaving the network and coming back.
#[derive(Clone, Copy, Debug)]
pub(in crate::sim) struct InTransfer {
    pub(in crate::sim) veh: VehicleId,
    /// Index into its route's roads of the road it is virtually on.
    pub(in crate::sim) road_k: usize,
    /// When it moves on to the next road unless it came back before (NaN until its first try failed).
    pub(in crate::sim) proceed_s: f64,
}

/// Least speed of a teleported vehicle's virtual trip along its route (SUMO's teleport minimum speed).
const TELEPORT_MIN_SPEED_MPS: f64 = 1.0;

impl Simulation {
    /// Takes off the network every lane's front vehicle that has waited longer than the time to teleport (SUMO
    /// checks each lane's front vehicle after the moves).
    pub(in crate::sim) fn teleport_stuck(&mut self) {
        let bound = self.spec.time_to_teleport_s;
        // (most steps: nobody has waited that long, as the moves found)
        if !(bound > 0.0) || !(self.longest_wait_s > bound) {
            return;
        }
        for li in 0..self.lane_order.len() {
            let lane = self.lane_order[li];
            let Some(&id) = self.lane_veh[lane as usize].first() else {
                continue;
            };
            let v = &self.veh[id as usize];
            // a controlled vehicle moves as its policy commands: standing is the policy's choice (its reward
            // says what it cost), and taking it off would change the agents of an episode under training
            if !(v.waiting_s > bound) || v.controlled {
                continue;
            }
            self.lane_veh[lane as usize].remove(0);
            self.in_network -= 1;
            self.forget_lc(id);
            self.metrics.teleports += 1;
            let v = &self.veh[id as usize];
            let r = &self.routes[v.route as usize];
            // the next road of its route (past the junction it is in or waits before)
            let road_k = r.road_k[v.route_pos as usize] as usize + 1;
            if road_k >= r.roads.len() {
                // on its last road: it arrives
                self.arrive(id);
                continue;
            }
            // it passes the lanes up to that road as a driven vehicle would (the measure points count it)
            let next_k = (v.route_pos as usize + 1..r.lanes.len()).find(|&k| {
                r.road_k[k] as usize == road_k && self.net.road_of(r.lanes[k]).is_some()
            });
            let passed: Vec<LaneIdx> = match next_k {
                Some(k) => (v.route_pos as usize + 1..=k).map(|i| r.lanes[i]).collect(),
                None => Vec::new(),
            };
            for lane in passed {
                self.measure.entered(lane, id);
            }
            let v = &mut self.veh[id as usize];
            v.status = VehicleStatus::Teleporting;
            v.speed = 0.0;
            v.waiting_s = 0.0;
            self.transfers.push(InTransfer {
                veh: id,
                road_k,
                proceed_s: f64::NAN,
            });
        }
    }

    /// Brings teleported vehicles back where they fit (in order of id, after the step's departures), at the
    /// start of the road they are virtually on, on the first of its lanes that takes them; one that did not fit
    /// moves on to the next road after the road's travel time at its speed limit, and arrives past its route's end.
    pub(in crate::sim) fn reinsert_teleported(&mut self) {
        if self.transfers.is_empty() {
            return;
        }
        let mut transfers = std::mem::take(&mut self.transfers);
        transfers.sort_by_key(|t| t.veh);
        let now = self.time_s;
        let mut kept = Vec::with_capacity(transfers.len());
        for mut t in transfers {
            if self.try_reinsert(t.veh, t.road_k) {
                continue;
            }
            let route = self.veh[t.veh as usize].route as usize;
            let roads_len = self.routes[route].roads.len();
            if t.proceed_s.is_nan() {
                t.proceed_s = now + self.road_travel_time(t.veh, t.road_k);
            } else if t.proceed_s < now {
                if t.road_k + 1 >= roads_len {
                    self.arrive(t.veh);
                    continue;
                }
                t.road_k += 1;
                t.proceed_s = now + self.road_travel_time(t.veh, t.road_k);
            }
            kept.push(t);
        }
        self.transfers = kept;
    }

    /// Seconds to drive the `road_k`-th road of a teleported vehicle's route at its limit (at least 1 m/s).
    fn road_travel_time(&self, id: VehicleId, road_k: usize) -> f64 {
        let r = &self.routes[self.veh[id as usize].route as usize];
        let lane = self.net.road_lanes[r.roads[road_k]][0];
        let l = self.lane_at(lane as usize);
        l.length / l.speed_limit.fmax(TELEPORT_MIN_SPEED_MPS)
    }

    /// Puts a teleported vehicle back at the start of road `road_k` of its route, on the first lane from the
    /// right where the insertion check passes at the lane's speed or, failing that, standing; its departure
    /// time and free-flow time stay its own.
    fn try_reinsert(&mut self, id: VehicleId, road_k: usize) -> bool {
        let v = &self.veh[id as usize];
        let (old_route, depart_s, free_flow_s, depart_speed) =
            (v.route, v.depart_s, v.free_flow_s, v.depart_speed);
        let roads: Vec<usize> = self.routes[old_route as usize].roads[road_k..].to_vec();
        let max_brake = self.type_consts[v.vtype as usize].max_brake_dist;
        for lane in self.net.road_lanes[roads[0]].clone() {
            let (lanes, dead_end) = self.net.best_lane_path(lane, &roads, max_brake);
            let route = self.add_lane_route(lanes, roads.clone(), dead_end);
            let v = &mut self.veh[id as usize];
            v.route = route;
            v.route_pos = 0;
            v.lane = lane;
            let limit = self.desired_speed(&self.veh[id as usize], lane);
            for speed in [limit, 0.0] {
                self.veh[id as usize].depart_speed = speed;
                if self.insertion_allowed(id) {
                    self.place_at_route_start(id, false);
                    let v = &mut self.veh[id as usize];
                    v.depart_s = depart_s;
                    v.free_flow_s = free_flow_s;
                    v.depart_speed = depart_speed;
                    return true;
                }
            }
        }
        let v = &mut self.veh[id as usize];
        v.route = old_route;
        v.depart_speed = depart_speed;
        v.route_pos = 0;
        false
    }
}
