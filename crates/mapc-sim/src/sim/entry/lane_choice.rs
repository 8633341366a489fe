//! Depart lanes chosen at insertion (`depart_lane` `random` and `free`), as SUMO 1.8's `MSEdge::getDepartLane`
//! chooses them: the vehicles of such flows wait at their entry road, not at one lane, and each insertion attempt
//! picks the lane anew.
//!
//! - `random`: a lane of the entry road drawn uniformly (SUMO draws among the lanes the vehicle class may use:
//!   every lane in mapc, which has no lane permissions).
//! - `free`: the lane with the least brutto occupancy (`MSLane::getBruttoOccupancy`: lengths plus min gaps of the
//!   vehicles on it, plus the tail of one that has just left it, less what sticks out behind its start, over the
//!   lane's length), the rightmost on a tie. SUMO 1.8's `getFreeLane` also prefers the lane whose last vehicle is
//!   furthest from the depart position, but with the default depart position (`base`, mapc's only one) that
//!   bound is the road's length, so no lane's gap is positive and the occupancy decides alone (checked in SUMO
//!   1.8.0: docs/sumo_check.md).
//!
//! As in SUMO (`MSEdge::insertVehicle`'s failed-insertion memory), once an insertion on a lane failed in a step,
//! no later vehicle is tried on that lane in that step.

use super::*;
use crate::demand::waiting::EntryQueue;
use crate::spec::DepartLane;

/// The vehicles waiting at one entry road for a lane chosen at insertion (one per road and mode).
#[derive(Clone, Debug)]
pub(in crate::sim) struct RoadEntry {
    /// `Random`, `Free` or `Best`.
    pub(in crate::sim) mode: DepartLane,
    /// The road's lanes, rightmost first.
    pub(in crate::sim) lanes: Vec<LaneIdx>,
    /// The lanes (indices into `lanes`) a vehicle may depart on: all, or for `Best` those that go furthest.
    pub(in crate::sim) candidates: Vec<usize>,
    pub(in crate::sim) queue: EntryQueue,
}

/// A flow whose lane is chosen at insertion: where its vehicles wait, and its route from each lane of the road.
#[derive(Clone, Debug)]
pub(in crate::sim) struct FlowLanes {
    /// Index into the simulation's road entries.
    pub(in crate::sim) entry: u32,
    /// Per lane of the entry road (rightmost first), the flow's route starting on it.
    pub(in crate::sim) routes: Vec<u32>,
}

/// SUMO 1.8's `free` choice among lanes with these brutto occupancies: the first (rightmost) of the least.
pub(in crate::sim) fn least_occupied(occupancy: impl IntoIterator<Item = f64>) -> Option<usize> {
    let mut best: Option<(usize, f64)> = None;
    for (i, o) in occupancy.into_iter().enumerate() {
        if best.is_none_or(|(_, b)| o < b) {
            best = Some((i, o));
        }
    }
    best.map(|(i, _)| i)
}

impl Simulation {
    /// The share of `lane` taken by vehicles with their min gaps (SUMO's `MSLane::getBruttoOccupancy`), at most 1.
    pub(in crate::sim) fn brutto_occupancy(&self, lane: LaneIdx) -> f64 {
        let len = self.lane_at(lane as usize).length;
        let on_lane = &self.lane_veh[lane as usize];
        let mut sum = 0.0;
        for &id in on_lane.iter() {
            sum += self.brutto_length(id);
        }
        // the tail of a vehicle that has just left the lane onto a connection (SUMO counts one partial occupier)
        let mut fraction: f64 = 0.0;
        for &lk in &self.lane_at(lane as usize).out_links {
            let via = self.link_at(lk as usize).via_lane;
            if let Some(&o) = self.lane_veh[via as usize].last() {
                let ov = &self.veh[o as usize];
                fraction = fraction.max((ov.length - ov.pos).min(len));
            }
        }
        // the last vehicle's part behind the lane's start is not on it
        if let Some(&last) = on_lane.last() {
            let v = &self.veh[last as usize];
            if v.pos < v.length {
                fraction -= v.length - v.pos;
            }
        }
        ((sum + fraction) / len).min(1.0)
    }

    /// The lane (index on the road, 0 = rightmost) the next vehicle at road entry `re` tries.
    pub(in crate::sim) fn choose_lane(&mut self, re: usize) -> usize {
        let e = &self.road_entries[re];
        match e.mode {
            DepartLane::Random => {
                let n = e.lanes.len();
                self.rng.random_range(0..n)
            }
            _ => {
                let k = least_occupied(
                    e.candidates
                        .iter()
                        .map(|&k| self.brutto_occupancy(e.lanes[k])),
                )
                .expect("an entry road has a lane");
                e.candidates[k]
            }
        }
    }

    /// Try to insert the vehicles waiting at road entry `re`, with the lanes already refused in this step.
    pub(in crate::sim) fn insert_at_road(&mut self, re: usize, refused: &mut Vec<LaneIdx>) {
        let mut i = 0;
        while let Some(id) = self.road_entry_next(re, i, refused) {
            if !self.road_entry_try(re, id, &mut i, refused) {
                break;
            }
        }
    }

    /// The vehicle road entry `re` tries next, at place `i` of its queue (every built vehicle before `i` was
    /// refused in this step: the next counted one is built behind them and tries its own lane); `None` when no
    /// later vehicle can enter in this step.
    pub(in crate::sim) fn road_entry_next(
        &mut self,
        re: usize,
        i: usize,
        refused: &[LaneIdx],
    ) -> Option<VehicleId> {
        let e = &self.road_entries[re];
        if e.candidates.iter().all(|&k| refused.contains(&e.lanes[k])) {
            // no later vehicle can enter (SUMO still draws a lane for each: mapc's numbers differ anyway)
            return None;
        }
        if let Some(id) = self.road_entries[re].queue.built_at(i) {
            return Some(id);
        }
        let f = self.road_entries[re].queue.take_counted()?;
        let id = self.build_flow_vehicle(f);
        self.road_entries[re].queue.push_taken(id);
        Some(id)
    }

    /// Tries vehicle `id`, at place `*i` of road entry `re`'s queue, on the lane the entry chooses for it (the
    /// place moves past it when it stays); returns whether later vehicles of the entry may still try in this step.
    pub(in crate::sim) fn road_entry_try(
        &mut self,
        re: usize,
        id: VehicleId,
        i: &mut usize,
        refused: &mut Vec<LaneIdx>,
    ) -> bool {
        let k = self.choose_lane(re);
        let lane = self.road_entries[re].lanes[k];
        let random = self.road_entries[re].mode == DepartLane::Random;
        if refused.contains(&lane) {
            // a free choice stays the same until a vehicle enters: every later one is refused too
            *i += 1;
            return random;
        }
        // the vehicle's route is one of its flow's lane routes (flows over the same roads share them)
        let current = self.veh[id as usize].route;
        let route = self
            .flow_lanes
            .iter()
            .flatten()
            .find(|fl| fl.routes.contains(&current))
            .expect("a vehicle waiting at a road entry has lane routes")
            .routes[k];
        self.set_route(id, route);
        if self.try_insert(id) {
            self.road_entries[re].queue.remove_built(*i);
            true
        } else {
            refused.push(lane);
            *i += 1;
            random
        }
    }

    /// Every entry's waiting vehicles tried in one list by the time each was due, earliest first (SUMO 1.8 tries
    /// the vehicles refused before, then the newly due ones, each in departure order): an entry whose vehicle is
    /// refused tries no more in this step, as entry by entry.
    pub(in crate::sim) fn insert_in_due_order(&mut self, refused: &mut Vec<LaneIdx>) {
        let (n_fixed, n_road) = (self.entry_lanes.len(), self.road_entries.len());
        if self.pending.iter().all(|q| q.is_empty())
            && self.road_entries.iter().all(|e| e.queue.is_empty())
        {
            return;
        }
        // per queue (fixed entries first, then road entries): whether it may still try, and its place
        let mut open = std::mem::take(&mut self.due_order_open);
        open.clear();
        open.resize(n_fixed + n_road, true);
        let mut place = std::mem::take(&mut self.due_order_place);
        place.clear();
        place.resize(n_road, 0);
        loop {
            let mut next: Option<(f64, VehicleId, usize)> = None;
            for q in 0..n_fixed + n_road {
                if !open[q] {
                    continue;
                }
                let id = if q < n_fixed {
                    self.fixed_entry_next(q)
                } else {
                    self.road_entry_next(q - n_fixed, place[q - n_fixed], refused)
                };
                let Some(id) = id else {
                    open[q] = false;
                    continue;
                };
                let due = self.veh[id as usize].due_s;
                if next.is_none_or(|(d, o, _)| due < d || (due == d && id < o)) {
                    next = Some((due, id, q));
                }
            }
            let Some((_, id, q)) = next else { break };
            if q < n_fixed {
                let lane = self.entry_lanes[q];
                if !refused.contains(&lane) && self.try_insert(id) {
                    self.pending[q].pop_built();
                } else {
                    refused.push(lane);
                    open[q] = false;
                }
            } else if !self.road_entry_try(q - n_fixed, id, &mut place[q - n_fixed], refused) {
                open[q] = false;
            }
        }
        self.due_order_open = open;
        self.due_order_place = place;
    }

    /// The vehicle at the front of fixed entry `ei`'s queue (a counted one is built now).
    fn fixed_entry_next(&mut self, ei: usize) -> Option<VehicleId> {
        if let Some(id) = self.pending[ei].front_built() {
            return Some(id);
        }
        let f = self.pending[ei].take_counted()?;
        let id = self.build_flow_vehicle(f);
        self.pending[ei].push_taken(id);
        Some(id)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn free_takes_the_least_occupied_lane_and_the_rightmost_on_a_tie() {
        assert_eq!(least_occupied([0.3, 0.1, 0.2]), Some(1));
        assert_eq!(least_occupied([0.0, 0.0]), Some(0));
        assert_eq!(least_occupied([0.2, 0.1, 0.1]), Some(1));
        assert_eq!(least_occupied([1.0, 1.0, 0.999]), Some(2));
        assert_eq!(least_occupied([0.0; 0]), None);
    }
}
