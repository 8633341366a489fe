//! The lane-change pass (SUMO's `MSLaneChanger` with LC2013, changes done in one step): after the moves, road by
//! road, the vehicles on a road's lanes are visited front to back across its lanes; each gets its
//! [`Surroundings`], LC2013 decides, messages are delivered at once, and a change moves the vehicle to the
//! neighbour lane at the same position. Runs only on networks with a road of several lanes.

use super::active_lanes::ChangerEdge;
use super::*;
use crate::models::lc::{
    BlockedAhead, Ego, LaneChangeModel, LaneQ, Lc2013, Message, NeighbourLane, Side, Surroundings,
};
use crate::network::best_lanes::BestLane;
use rustc_hash::FxHashMap as HashMap;

/// A vehicle's lane-change record between steps.
#[derive(Clone, Debug, Default)]
pub(in crate::sim) struct LcVeh {
    pub(in crate::sim) mem: <LcModel as LaneChangeModel>::Memory,
    /// Its speed at the latest pass (this one, once the pass has started).
    pass_speed: f64,
    /// Its speed at the pass before that: the others read its acceleration over the last step from it and its
    /// speed now (`Other::speed_before`).
    pub(in crate::sim) speed_before: f64,
    /// Its lane's best-lane offset at the last pass (read when its speed is patched).
    pub(in crate::sim) best_lane_offset: i32,
    /// The best lanes it used last: (its route's road sequence, road index in it, index in
    /// `BestLanesCache::store`), the cache's own key but for the type; the cache is asked again only when it
    /// enters a new road (a lane change keeps the road sequence).
    best_memo: Option<(u32, u32, u32)>,
}

/// Buffers of the lane-change pass, kept between steps so that the pass allocates nothing.
#[derive(Clone, Debug, Default)]
pub(in crate::sim) struct LcScratch {
    lanes: Vec<LaneIdx>,
    cands: Vec<VehicleId>,
    dens: Vec<f64>,
    /// Per lane index: the vehicles visited so far in the pass that are on it now (at a vehicle's turn, mostly its
    /// index in its lane's queue: the pass goes front to back).
    visited: Vec<usize>,
    blocked: Vec<(Option<VehicleId>, Option<VehicleId>)>,
    best_lanes: LanesView,
    next_occupation: NextOccupation,
}

/// The lanes as LC2013 sees them (`Surroundings::best_lanes`), kept between the vehicles of a road.
#[derive(Clone, Debug, Default)]
struct LanesView {
    lanes: Vec<LaneQ>,
    /// The entry of `BestLanesCache::store` that `lanes` was built from, with the occupations as they are now;
    /// `None` on a new road (its densities start again) or when `NextOccupation` was recomputed. Between two
    /// vehicles that share it only one lane's density changes, and only that lane is rewritten.
    of: Option<u32>,
}

/// The summed occupation of each lane's best continuation (SUMO's `nextOccupation`) for one entry of
/// `BestLanesCache::store`: the lanes' occupations change only at the pass's start and when a vehicle changes
/// lanes, so the vehicles visited one after another on a road and route share the sums in between.
#[derive(Clone, Debug, Default)]
struct NextOccupation {
    /// The entry the sums are for; `None` once an occupation changed.
    of: Option<u32>,
    sums: Vec<f64>,
}

/// Best lanes by (road sequence, index of the current road in it, vehicle type): they depend on nothing else, so
/// each is computed once per run, when the first vehicle of its type enters that road on that route.
#[derive(Clone, Debug, Default)]
pub(in crate::sim) struct BestLanesCache {
    index: HashMap<(u32, u32, u16), u32>,
    /// The entries of `store` by (road sequence, road index): types whose best lanes there are the same share
    /// one entry, so that the pass's views and occupation sums, kept by entry, carry over between their vehicles.
    by_place: HashMap<(u32, u32), Vec<u32>>,
    pub(in crate::sim) store: Vec<Vec<BestLane>>,
    /// The route after a lane change, by (route, lane of it changed from, lane changed to, vehicle type).
    after_change: HashMap<(u32, u32, LaneIdx, u16), u32>,
}

impl Simulation {
    /// The best lanes of road `k` of the route `route` for a vehicle of type `vtype` (an index into
    /// `best_cache.store`).
    pub(in crate::sim) fn best_lanes_at(&mut self, route: u32, k: usize, vtype: u16) -> u32 {
        let r = &self.routes[route as usize];
        let key = (r.roads_id, k as u32, vtype);
        if let Some(&i) = self.best_cache.index.get(&key) {
            return i;
        }
        let brake = self.type_consts[vtype as usize].max_brake_dist;
        let best = self.net.best_lanes(&r.roads[k..], brake);
        let cache = &mut self.best_cache;
        let same_place = cache.by_place.entry((key.0, key.1)).or_default();
        let i = match same_place
            .iter()
            .find(|&&i| same_best_lanes(&cache.store[i as usize], &best))
        {
            Some(&i) => i,
            None => {
                let i = cache.store.len() as u32;
                cache.store.push(best);
                same_place.push(i);
                i
            }
        };
        cache.index.insert(key, i);
        i
    }

    /// LC2013's `patch_speed` for a vehicle's next speed between `min` and `max` (`wanted`: the car-following
    /// speed). A lane with no neighbour (a one-lane road, or a junction connection: the SUMO export writes each as
    /// an internal edge of one lane) has no lane changer in SUMO, whose `patchSpeed` then clears the memory as
    /// after a change: the speed-gain and keep-right wishes do not survive a junction. In a SUMO user's network
    /// the connections that run side by side between two roads form one internal edge of several lanes, which has
    /// a lane changer: under SUMO's rules there the memory survives.
    #[allow(clippy::too_many_arguments)]
    pub(in crate::sim) fn patch_lc_speed(
        &mut self,
        id: VehicleId,
        speed: f64,
        vtype: usize,
        lane: LaneIdx,
        desired: f64,
        min: f64,
        wanted: f64,
        max: f64,
    ) -> f64 {
        let l = self.lane_at(lane as usize);
        let has_lane_changer = l.left.is_some()
            || l.right.is_some()
            || (l.beside_another && self.spec.sumo_junction_lane_changes);
        let Some(rec) = self.veh[id as usize].lc.as_mut() else {
            return wanted;
        };
        self.lc_models[vtype].patch_speed(
            &mut rec.mem,
            speed,
            &self.types[vtype],
            desired,
            has_lane_changer,
            rec.best_lane_offset,
            min,
            wanted,
            max,
        )
    }

    /// The lane-change pass of a step (after the moves).
    // out of line: inlined into the step, its code changed the one-lane plans' register use (one-lane runs
    // executed up to 1 % more instructions as the pass changed)
    #[inline(never)]
    pub(in crate::sim) fn change_lanes(&mut self) {
        // each lane's vehicles' lengths with min gaps (SUMO's brutto occupancy), kept up to date by the changes;
        // and, after the moves, before any message of this pass: forget the last step's advices and marks
        // (advices sent in this pass are read in the next move)
        let mut brutto = std::mem::take(&mut self.lane_brutto);
        brutto.clear();
        brutto.resize(self.net.lanes.len(), 0.0);
        for (l, q) in self.lane_veh.iter().enumerate() {
            let mut sum = 0.0;
            for &id in q.iter() {
                sum += self.brutto_length(id);
                let v = &mut self.veh[id as usize];
                let speed = v.speed;
                let rec = v.lc.get_or_insert_with(|| LcVeh {
                    pass_speed: speed,
                    ..LcVeh::default()
                });
                rec.speed_before = rec.pass_speed;
                rec.pass_speed = speed;
                // (the memory's step, the same for every type's model)
                self.lc_models[0].prepare_step(&mut rec.mem);
            }
            brutto[l] = sum;
        }
        self.lane_brutto = brutto;
        let mut scratch = std::mem::take(&mut self.lc_scratch);
        scratch.next_occupation.of = None;
        if self.spec.sumo_junction_lane_changes {
            // SUMO's order: the roads and connections side by side as their lanes stand in the active list
            let mut edges = std::mem::take(&mut self.active_lanes.edges);
            self.changer_edges_in_order(&mut edges);
            for &e in &edges {
                let lanes = self.changer_edge_lanes(e);
                let width = match e {
                    ChangerEdge::Road(_) => lanes.len(),
                    ChangerEdge::Group(_) => {
                        let to = self.lane_at(lanes[0] as usize).via_target;
                        match to.and_then(|t| self.net.road_of(t)) {
                            Some(r) => self.net.road_lanes[r].len(),
                            None => continue,
                        }
                    }
                };
                scratch.lanes.clear();
                scratch.lanes.extend_from_slice(self.changer_edge_lanes(e));
                self.change_on_lanes(&mut scratch, width);
            }
            self.activate_changed_onto(&edges);
            self.active_lanes.edges = edges;
            self.lc_scratch = scratch;
            return;
        }
        for r in 0..self.net.road_lanes.len() {
            let n = self.net.road_lanes[r].len();
            if n < 2 {
                continue;
            }
            scratch.lanes.clear();
            scratch.lanes.extend_from_slice(&self.net.road_lanes[r]);
            self.change_on_lanes(&mut scratch, n);
        }
        self.lc_scratch = scratch;
    }

    /// The pass over the lanes in `scratch.lanes` (a road's, or a group of side-by-side junction connections),
    /// whose lane-change indices lie below `width` ([`Self::lc_lane`]).
    fn change_on_lanes(&mut self, scratch: &mut LcScratch, width: usize) {
        let LcScratch {
            lanes,
            cands,
            dens,
            visited,
            blocked,
            best_lanes,
            next_occupation,
        } = scratch;
        // SUMO's findCandidate: the largest position first; the right lane first on a tie
        cands.clear();
        if !self.merge_lanes(lanes, cands) {
            cands.extend(
                lanes
                    .iter()
                    .flat_map(|&l| self.lane_veh[l as usize].iter().copied()),
            );
            cands.sort_by(|&a, &b| self.candidate_order(a, b));
        }
        dens.clear();
        dens.resize(width, 0.0);
        visited.clear();
        visited.resize(width, 0);
        blocked.clear();
        blocked.resize(width, (None, None));
        best_lanes.of = None;
        for &id in cands.iter() {
            let final_index =
                self.change_one(id, dens, visited, blocked, best_lanes, next_occupation);
            visited[final_index] += 1;
            dens[final_index] += self.brutto_length(id);
            if best_lanes.of.is_some() {
                best_lanes.lanes[final_index].occupation =
                    dens[final_index] + next_occupation.sums[final_index];
            }
        }
    }

    /// A lane's index and its right and left lanes as the lane-change pass sees them: a road lane's own; for a
    /// via lane of a side-by-side group ([`crate::network::Network::via_groups`]), the index of the lane it leads
    /// to and the group's lanes beside it.
    #[inline]
    pub(in crate::sim) fn lc_lane(
        &self,
        lane: LaneIdx,
    ) -> (usize, Option<LaneIdx>, Option<LaneIdx>) {
        let l = self.lane_at(lane as usize);
        // (a road lane, most of the pass's, is answered without the table of via lanes)
        if let LaneKind::Via(_) = l.kind
            && let Some(b) = self.net.via_beside[lane as usize]
        {
            return (b.index as usize, b.right, b.left);
        }
        (l.index as usize, l.right, l.left)
    }

    /// The candidates' order, by merging the lanes' queues (each front first) into `cands`: the stable sort's
    /// order when each queue is ordered as the sort orders it (the largest position first; on a tie the lane of the
    /// lower index, then the lane listed first). Returns false, leaving `cands` empty, when a queue is out of that
    /// order or the lanes are more than a road has (then the caller sorts).
    fn merge_lanes(&self, lanes: &[LaneIdx], cands: &mut Vec<VehicleId>) -> bool {
        const MAX_LANES: usize = 8;
        let n = lanes.len();
        if n > MAX_LANES {
            return false;
        }
        let pos = |o: VehicleId| self.veh[o as usize].pos;
        let ordered = |q: &[VehicleId]| {
            q.windows(2)
                .all(|w| pos(w[0]).total_cmp(&pos(w[1])).is_ge())
        };
        let mut queues: [&[VehicleId]; MAX_LANES] = [&[]; MAX_LANES];
        let (mut total, mut occupied, mut last_occupied) = (0, 0, 0);
        for (k, &l) in lanes.iter().enumerate() {
            let q: &[VehicleId] = &self.lane_veh[l as usize];
            queues[k] = q;
            total += q.len();
            if !q.is_empty() {
                occupied += 1;
                last_occupied = k;
            }
        }
        if occupied <= 1 {
            // (most passes: the vehicles of one lane, in its order)
            let q = queues[last_occupied];
            if !ordered(q) {
                return false;
            }
            cands.extend_from_slice(q);
            return true;
        }
        // each queue's front position (minus infinity once empty) and lane index
        let mut head = [f64::NEG_INFINITY; MAX_LANES];
        let mut index = [0usize; MAX_LANES];
        for k in 0..n {
            if !ordered(queues[k]) {
                return false;
            }
            if let Some(&o) = queues[k].first() {
                head[k] = pos(o);
            }
            index[k] = self.lc_lane(lanes[k]).0;
        }
        for _ in 0..total {
            // (an empty queue's minus infinity is below every position: one is left while vehicles are)
            let mut best = 0;
            for k in 1..n {
                let order = head[k].total_cmp(&head[best]);
                if order.is_gt() || (order.is_eq() && index[k] < index[best]) {
                    best = k;
                }
            }
            let q = queues[best];
            cands.push(q[0]);
            queues[best] = &q[1..];
            head[best] = queues[best].first().map_or(f64::NEG_INFINITY, |&o| pos(o));
        }
        debug_assert!({
            let mut sorted: Vec<VehicleId> = lanes
                .iter()
                .flat_map(|&l| self.lane_veh[l as usize].iter().copied())
                .collect();
            sorted.sort_by(|&x, &y| self.candidate_order(x, y));
            sorted == *cands
        });
        true
    }

    /// SUMO's findCandidate order: the largest position first; the right lane first on a tie.
    fn candidate_order(&self, a: VehicleId, b: VehicleId) -> std::cmp::Ordering {
        let (va, vb) = (&self.veh[a as usize], &self.veh[b as usize]);
        vb.pos
            .total_cmp(&va.pos)
            .then(self.lc_lane(va.lane).0.cmp(&self.lc_lane(vb.lane).0))
    }

    /// One vehicle's turn; returns the index of the lane it ends on.
    fn change_one(
        &mut self,
        id: VehicleId,
        dens: &[f64],
        visited: &[usize],
        blocked: &mut [(Option<VehicleId>, Option<VehicleId>)],
        best_lanes: &mut LanesView,
        next_occupation: &mut NextOccupation,
    ) -> usize {
        let (route, route_pos, vtype) = {
            let v = &self.veh[id as usize];
            (v.route, v.route_pos, v.vtype)
        };
        let r = &self.routes[route as usize];
        let lane = self.veh[id as usize].lane;
        // on a junction connection, the best lanes of the road it leads to (SUMO's LC2013 on an internal lane)
        let on_via = matches!(self.lane_at(lane as usize).kind, LaneKind::Via(_));
        let (k, roads_id) = (r.road_k[route_pos as usize] + on_via as u32, r.roads_id);
        let best_i = match self.lc_rec(id).best_memo {
            Some((seq, rk, i)) if seq == roads_id && rk == k => i,
            _ => {
                let i = self.best_lanes_at(route, k as usize, vtype);
                self.lc_rec(id).best_memo = Some((roads_id, k, i));
                i
            }
        };
        let (index, l_right, l_left) = self.lc_lane(lane);
        let best_lane_offset = self.best_cache.store[best_i as usize][index].best_lane_offset;
        self.lc_rec(id).best_lane_offset = best_lane_offset;
        let best: &[BestLane] = &self.best_cache.store[best_i as usize];
        let v = &self.veh[id as usize];
        // SUMO's occupation: this pass's density on the lane plus the vehicles on its continuation
        if next_occupation.of != Some(best_i) {
            next_occupation.sums.clear();
            next_occupation.sums.extend(best.iter().map(|q| {
                q.continuation
                    .iter()
                    .map(|&c| self.lane_brutto[c as usize])
                    .sum::<f64>()
            }));
            next_occupation.of = Some(best_i);
            best_lanes.of = None;
        }
        debug_assert!(best.iter().zip(&next_occupation.sums).all(|(q, &next)| {
            let fresh: f64 = q
                .continuation
                .iter()
                .map(|&c| self.lane_brutto[c as usize])
                .sum();
            fresh.to_bits() == next.to_bits()
        }));
        let lane_q = |((q, &d), &next): ((&BestLane, &f64), &f64)| LaneQ {
            length: q.length,
            occupation: d + next,
            best_lane_offset: q.best_lane_offset,
            leads_elsewhere: q.leads_elsewhere,
        };
        if best_lanes.of != Some(best_i) {
            best_lanes.lanes.clear();
            best_lanes
                .lanes
                .extend(best.iter().zip(dens).zip(&next_occupation.sums).map(lane_q));
            best_lanes.of = Some(best_i);
        }
        debug_assert!(
            best.iter()
                .zip(dens)
                .zip(&next_occupation.sums)
                .map(lane_q)
                .zip(best_lanes.lanes.iter())
                .all(|(a, b)| a.occupation.to_bits() == b.occupation.to_bits()
                    && a.length.to_bits() == b.length.to_bits()
                    && a.best_lane_offset == b.best_lane_offset
                    && a.leads_elsewhere == b.leads_elsewhere)
                && best_lanes.lanes.len() == best.len()
        );
        let l = self.lane_at(lane as usize);
        // SUMO lets a vehicle whose back is still in the junction behind change lanes; mapc's own scenarios were
        // measured with it staying on its lane until its back has left
        let may_change = self.spec.sumo_junction_lane_changes || v.pos >= v.length;
        let side_lane = |n: Option<LaneIdx>| n.filter(|_| may_change);
        let (last, first) = blocked[index];
        // built in place, each neighbour written where the model reads it: moved between locals, the copies of
        // the neighbours cost as much as the model's gap checks
        let mut s = Surroundings {
            ego: Ego {
                speed: v.speed,
                params: &self.types[v.vtype as usize],
                length: v.length,
                pos: v.pos,
                lane_index: index,
                lane_length: l.length,
                lane_speed_limit: l.speed_limit,
                max_speed: self.desired_speed(v, lane),
            },
            leader: None,
            right: None,
            left: None,
            best_lanes: &best_lanes.lanes,
            blocked_ahead: BlockedAhead::default(),
            road_has_lane_changer: true,
        };
        let types = &self.types;
        s.leader = self.own_leader(types, id, visited[index]);
        // the vehicles visited so far on a side lane are, mostly, those ahead of the split there
        if let Some(n) = side_lane(l_right) {
            let guess = index.checked_sub(1).map_or(usize::MAX, |i| visited[i]);
            self.neighbours(
                types,
                id,
                n,
                best,
                guess,
                true,
                s.right.insert(NeighbourLane::default()),
            );
        }
        if let Some(n) = side_lane(l_left) {
            let guess = visited.get(index + 1).copied().unwrap_or(usize::MAX);
            self.neighbours(
                types,
                id,
                n,
                best,
                guess,
                false,
                s.left.insert(NeighbourLane::default()),
            );
        }
        if let Some(o) = last {
            s.blocked_ahead.last = Some(self.other(types, o, self.gap_ahead_same_road(id, o)));
        }
        if let Some(o) = first.filter(|&f| Some(f) != last) {
            s.blocked_ahead.first = Some(self.other(types, o, self.gap_ahead_same_road(id, o)));
        }
        let vtype = self.veh[id as usize].vtype as usize;
        let mem = &mut self.veh[id as usize]
            .lc
            .as_mut()
            .expect("recorded at the pass's start")
            .mem;
        let d = self.lc_models[vtype].decide(mem, &s);
        for m in &d.messages {
            let (Message::SpeedAdvice { to, .. } | Message::KeepRoom { to, .. }) = *m;
            let v = &mut self.veh[to as VehicleId as usize];
            let own = v.speed;
            let to_type = v.vtype as usize;
            let mem = &mut v.lc.get_or_insert_default().mem;
            self.lc_models[to_type].receive(mem, m, own);
        }
        for side in &d.urgent_blocked {
            let t = (index as i32 + side.offset()) as usize;
            if let Some(b) = blocked.get_mut(t) {
                b.0 = Some(id);
                b.1.get_or_insert(id);
            }
        }
        let Some(side) = d.change else {
            return index;
        };
        let target = match side {
            Side::Right => l_right,
            Side::Left => l_left,
        }
        .expect("the model changes only to an existing lane");
        self.move_to_lane(id, target);
        next_occupation.of = None;
        best_lanes.of = None;
        let target_index = self.lc_lane(target).0;
        let offset = self.best_cache.store[best_i as usize][target_index].best_lane_offset;
        if let Some(rec) = self.veh[id as usize].lc.as_mut() {
            rec.best_lane_offset = offset;
        }
        self.metrics.lane_changes += 1;
        self.metrics.lane_change_reasons.count(d.reason);
        target_index
    }

    /// Moves a vehicle to `target`, a neighbour lane of its road, at the same position, and follows the route
    /// from there (the lanes' occupations change: within the pass, `NextOccupation` must be cleared after it).
    pub(in crate::sim) fn move_to_lane(&mut self, id: VehicleId, target: LaneIdx) {
        let (old, pos, route, rp, vtype, occupancy) = {
            let v = &self.veh[id as usize];
            let occupancy = self.brutto_length(id);
            (
                v.lane,
                v.pos,
                v.route,
                v.route_pos as usize,
                v.vtype,
                occupancy,
            )
        };
        if let Some(b) = self.lane_brutto.get_mut(old as usize) {
            *b -= occupancy;
        }
        if let Some(b) = self.lane_brutto.get_mut(target as usize) {
            *b += occupancy;
        }
        if let Some(i) = self.index_in_lane(id, old) {
            self.lane_veh[old as usize].remove(i);
        }
        // behind every vehicle at its position or ahead
        let at = self.queue_index_behind(target, pos, |o, p| o < p);
        self.lane_veh[target as usize].insert(at, id);
        let key = (route, rp as u32, target, vtype);
        let new_route = match self.best_cache.after_change.get(&key) {
            Some(&r) => r,
            None => {
                let r = self.route_after_change(route, rp, target, vtype);
                self.best_cache.after_change.insert(key, r);
                r
            }
        };
        let v = &mut self.veh[id as usize];
        v.lane = target;
        v.route = new_route;
        v.route_pos = Self::route_pos_after_change(rp);
    }

    /// The route of a vehicle of type `vtype` on `route` that changes to `target` at lane `rp` of it: the lane
    /// before (the connection it came by, so that the lane it drove before stays known), then the path from
    /// `target`. The lanes before those are left out, so that vehicles changing to one lane share the route
    /// whatever their past: a route that kept every vehicle's past was one per vehicle, and its reads in every
    /// step missed the cache.
    fn route_after_change(&mut self, route: u32, rp: usize, target: LaneIdx, vtype: u16) -> u32 {
        let r = &self.routes[route as usize];
        let k = r.road_k[rp] as usize;
        let from = rp - Self::route_pos_after_change(rp) as usize;
        let roads: Vec<usize> = r.roads[r.road_k[from] as usize..].to_vec();
        let mut lanes: Vec<LaneIdx> = r.lanes.0[from..rp].to_vec();
        let old_roads = r.roads.len();
        // the path on from the new lane: at each road the link a vehicle of this type entering it would take
        let best_at: Vec<u32> = (k..old_roads.saturating_sub(1))
            .map(|j| self.best_lanes_at(route, j, vtype))
            .collect();
        let store = &self.best_cache.store;
        let r = &self.routes[route as usize];
        let (rest, dead_end) = match self.lane_at(target as usize).kind {
            // onto the junction connection beside (SUMO's junction rules): the lane before is the one that
            // connection leaves, the path goes on from the lane it leads to
            LaneKind::Via(link) => {
                let lk = self.link_at(link as usize);
                if let Some(before) = lanes.last_mut() {
                    *before = lk.from_lane;
                }
                let (path, dead_end) = self.net.lane_path(lk.to_lane, &r.roads[k + 1..], |j, i| {
                    store[best_at[j + 1] as usize][i].next_link
                });
                (std::iter::once(target).chain(path).collect(), dead_end)
            }
            LaneKind::Road(_) => self.net.lane_path(target, &r.roads[k..], |j, i| {
                store[best_at[j] as usize][i].next_link
            }),
        };
        lanes.extend(rest);
        self.add_lane_route(lanes, roads, dead_end)
    }

    /// Where a vehicle is on the route [`Self::route_after_change`] gives for a change at lane `rp` of its route:
    /// on its second lane, after the lane before, unless it changes on its route's first lane.
    fn route_pos_after_change(rp: usize) -> u32 {
        rp.min(1) as u32
    }

    /// The lane-change record of a vehicle in the pass (made at its start).
    fn lc_rec(&mut self, id: VehicleId) -> &mut LcVeh {
        self.veh[id as usize]
            .lc
            .as_mut()
            .expect("recorded at the pass's start")
    }

    /// Per-vehicle lane-change records are dropped when a vehicle leaves.
    pub(in crate::sim) fn forget_lc(&mut self, id: VehicleId) {
        self.veh[id as usize].lc = None;
    }
}

/// The same best lanes, bit for bit (the pass's arithmetic reads them).
fn same_best_lanes(a: &[BestLane], b: &[BestLane]) -> bool {
    a.len() == b.len()
        && a.iter().zip(b).all(|(x, y)| {
            x.length.to_bits() == y.length.to_bits()
                && x.best_lane_offset == y.best_lane_offset
                && x.next_link == y.next_link
                && x.leads_elsewhere == y.leads_elsewhere
                && x.continuation == y.continuation
        })
}

/// The model every vehicle uses (SUMO 1.8's LC2013 defaults), for steps of `dt` seconds.
/// The lane-change model every vehicle drives with.
pub(in crate::sim) type LcModel = Lc2013;

/// A type's LC2013 from its `lc*` parameters (SUMO 1.8's defaults where absent), for steps of `dt` seconds.
pub(in crate::sim) fn model_of(p: &mapc_scenario::LaneChangeParams, dt: f64) -> LcModel {
    let d = crate::models::lc::Lc2013Params::default();
    let cooperative = p.cooperative.unwrap_or(d.cooperative);
    Lc2013::new(crate::models::lc::Lc2013Params {
        strategic: p.strategic.unwrap_or(d.strategic),
        cooperative,
        speed_gain: p.speed_gain.unwrap_or(d.speed_gain),
        keep_right: p.keep_right.unwrap_or(d.keep_right),
        lookahead_left: p.lookahead_left.unwrap_or(d.lookahead_left),
        speed_gain_right: p.speed_gain_right.unwrap_or(d.speed_gain_right),
        assertive: p.assertive.unwrap_or(d.assertive),
        // SUMO: lcCooperativeSpeed defaults to lcCooperative
        cooperative_speed: cooperative,
        ..d
    })
    .for_step(dt)
}
