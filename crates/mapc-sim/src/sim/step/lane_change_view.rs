//! The lane changer's view of the others (SUMO 1.8's `MSLaneChanger` finding leaders and followers): the leader on
//! the own lane and past its end, the neighbours on a lane beside split at the ego's front, across a lane's end
//! along its best continuation and across its start through the connections into it, and where a vehicle stands
//! in a lane's queue.

use super::*;
use crate::models::lc::{LaneChangeModel, NeighbourLane, Other};
use crate::network::best_lanes::BestLane;

impl Simulation {
    /// `o` as the model sees it, at `gap`.
    /// `types` is `self.types`, passed apart so that the neighbours borrow only it while the pass writes the
    /// vehicle's memory.
    pub(in crate::sim) fn other<'t>(
        &self,
        types: &'t Table<CfModel>,
        o: VehicleId,
        gap: f64,
    ) -> Other<'t> {
        let ov = &self.veh[o as usize];
        let rec = ov.lc.as_ref();
        Other {
            id: o as u64,
            gap,
            speed: ov.speed,
            speed_before: rec.map_or(ov.speed, |r| r.speed_before),
            params: &types[ov.vtype as usize],
            length: ov.length,
            max_speed: self.desired_speed(ov, ov.lane),
            stopped: false,
            lc_state: rec.map_or(0, |r| self.lc_models[ov.vtype as usize].state(&r.mem)),
        }
    }

    /// The gap from `id`'s front to the back of `o`, a vehicle ahead on the same road (minus `id`'s min gap).
    pub(in crate::sim) fn gap_ahead_same_road(&self, id: VehicleId, o: VehicleId) -> f64 {
        let (v, ov) = (&self.veh[id as usize], &self.veh[o as usize]);
        ov.pos - ov.length - v.pos - self.types[v.vtype as usize].min_gap
    }

    /// The leader on the own lane, or across its end along the route; `guess`: where `id` likely is in its lane's
    /// queue (taken when it is there, else searched).
    pub(in crate::sim) fn own_leader<'t>(
        &self,
        types: &'t Table<CfModel>,
        id: VehicleId,
        guess: usize,
    ) -> Option<Other<'t>> {
        let v = &self.veh[id as usize];
        let q = &self.lane_veh[v.lane as usize];
        let qi = if q.get(guess) == Some(&id) {
            guess
        } else {
            self.index_in_lane(id, v.lane)?
        };
        if qi > 0 {
            let o = q[qi - 1];
            return Some(self.other(types, o, self.gap_ahead_same_road(id, o)));
        }
        let r = &self.routes[v.route as usize];
        let lanes = &r.lanes.0[v.route_pos as usize + 1..];
        self.first_ahead(
            types,
            id,
            lanes.iter().copied(),
            self.lane_at(v.lane as usize).length - v.pos,
        )
    }

    /// The lanes ahead along a lane's best continuation (`roads`, its road lanes), from its link `first` on:
    /// each junction connection, then the road lane it leads to.
    pub(in crate::sim) fn continuation_lanes<'a>(
        &'a self,
        first: LinkIdx,
        roads: &'a [LaneIdx],
    ) -> impl Iterator<Item = LaneIdx> + 'a {
        let mut link = Some(first);
        // roads[0] is the lane `first` leads to
        let mut next = 1;
        std::iter::from_fn(move || {
            let lk = self.link_at(link.take()? as usize);
            link = roads.get(next).and_then(|&to| {
                self.lane_at(lk.to_lane as usize)
                    .out_links
                    .iter()
                    .copied()
                    .find(|&k| self.link_at(k as usize).to_lane == to)
            });
            next += 1;
            Some([lk.via_lane, lk.to_lane])
        })
        .flatten()
    }

    /// The last vehicle on the first occupied lane of `lanes` (which start `seen` m ahead of `id`'s front), looked
    /// for as SUMO's lane changer does past the end of a lane (`getRealLeader`, `getLeaderOnConsecutive`): only
    /// when the end lies within the ego's braking distance plus min gap, and on the lanes that start within it
    /// (and the road lane after a junction connection); a vehicle farther ahead is no leader for lane changing.
    pub(in crate::sim) fn first_ahead<'t>(
        &self,
        types: &'t Table<CfModel>,
        id: VehicleId,
        lanes: impl IntoIterator<Item = LaneIdx>,
        mut seen: f64,
    ) -> Option<Other<'t>> {
        let v = &self.veh[id as usize];
        let p = &self.types[v.vtype as usize];
        // far from the lane's end (most vehicles) the bound decides without the exact braking distance
        let tc = &self.type_consts[v.vtype as usize];
        if seen > tc.brake_gap_above(v.speed, p.tau) + p.min_gap {
            debug_assert!(seen > p.brake_gap(v.speed, p.decel, p.tau) + p.min_gap);
            return None;
        }
        let mut dist = p.brake_gap(v.speed, p.decel, p.tau) + p.min_gap;
        if seen > dist {
            return None;
        }
        for l in lanes {
            if let Some(&o) = self.lane_veh[l as usize].last() {
                let ov = &self.veh[o as usize];
                return Some(self.other(types, o, seen + ov.pos - ov.length - p.min_gap));
            }
            let lane_max = self.desired_speed(v, l);
            if lane_max < v.speed {
                dist = p.brake_gap(lane_max, p.decel, p.tau);
            }
            seen += self.lane_at(l as usize).length;
            if seen > dist && !matches!(self.lane_at(l as usize).kind, LaneKind::Via(_)) {
                break;
            }
        }
        None
    }

    /// Leader and follower of `id` on neighbour lane `n` of its road, as SUMO's lane changer finds them, written
    /// into `out`: the leader is the nearest vehicle already visited in this pass (front ahead of `id`'s front),
    /// the follower the next one, even when it drives alongside (then its gap is negative); across the lane's end
    /// along its best continuation, and across its start through the connections into it. `guess`: the likely
    /// index of the split in `n`'s queue (taken when right, else searched); `n_is_right`: `n` lies to the right of
    /// the ego's lane (the caller knows the side).
    // inlined: its two neighbours are then written where the model reads them, not copied there
    #[inline(always)]
    #[allow(clippy::too_many_arguments)]
    pub(in crate::sim) fn neighbours<'t>(
        &self,
        types: &'t Table<CfModel>,
        id: VehicleId,
        n: LaneIdx,
        best: &[BestLane],
        guess: usize,
        n_is_right: bool,
        out: &mut NeighbourLane<'t>,
    ) {
        let v = &self.veh[id as usize];
        let back = v.pos - v.length;
        let q = &self.lane_veh[n as usize];
        // front first; at the ego's very position, a vehicle on the lane to the right was visited first (the pass
        // takes the rightmost lane on a tie) and leads, one on the lane to the left follows
        debug_assert_eq!(n_is_right, self.lc_lane(n).0 < self.lc_lane(v.lane).0);
        let split = if n_is_right {
            self.queue_index_behind_near(n, v.pos, guess, |o, p| o < p)
        } else {
            self.queue_index_behind_near(n, v.pos, guess, |o, p| o <= p)
        };
        if split > 0 {
            let o = q[split - 1];
            out.leader = Some(self.other(types, o, self.gap_ahead_same_road(id, o)));
        } else {
            let nl = self.lane_at(n as usize);
            out.leader = match (nl.kind, nl.via_target) {
                // a junction connection beside the ego's (SUMO's junction rules): the lane it leads to, then on
                (LaneKind::Via(_), Some(to)) => {
                    let nq = &best[self.lc_lane(n).0];
                    let beyond = nq
                        .next_link
                        .into_iter()
                        .flat_map(|link| self.continuation_lanes(link, &nq.continuation));
                    self.first_ahead(
                        types,
                        id,
                        std::iter::once(to).chain(beyond),
                        nl.length - v.pos,
                    )
                }
                _ => {
                    let nq = &best[nl.index as usize];
                    nq.next_link.and_then(|link| {
                        let lanes = self.continuation_lanes(link, &nq.continuation);
                        self.first_ahead(types, id, lanes, nl.length - v.pos)
                    })
                }
            };
        }
        if let Some(&o) = q.get(split) {
            let ov = &self.veh[o as usize];
            out.follower = Some(self.other(
                types,
                o,
                back - ov.pos - self.types[ov.vtype as usize].min_gap,
            ));
        } else {
            // behind the lane's start: the first vehicle on a connection into it, or on that connection's lane
            let mut found: Option<Other> = None;
            for &link in &self.lane_at(n as usize).in_links {
                let lk = self.link_at(link as usize);
                let via_len = self.lane_at(lk.via_lane as usize).length;
                let from_len = self.lane_at(lk.from_lane as usize).length;
                let cand = if let Some(&o) = self.lane_veh[lk.via_lane as usize].first() {
                    Some((o, back + via_len - self.veh[o as usize].pos))
                } else {
                    self.lane_veh[lk.from_lane as usize]
                        .first()
                        .map(|&o| (o, back + via_len + from_len - self.veh[o as usize].pos))
                };
                if let Some((o, dist)) = cand {
                    let gap = dist - self.types[self.veh[o as usize].vtype as usize].min_gap;
                    if found.is_none_or(|f| gap < f.gap) {
                        found = Some(self.other(types, o, gap));
                    }
                }
            }
            // a junction connection beside the ego's: the first vehicle on the lane it leaves
            if let LaneKind::Via(link) = self.lane_at(n as usize).kind {
                let from = self.link_at(link as usize).from_lane;
                let from_len = self.lane_at(from as usize).length;
                found = self.lane_veh[from as usize].first().map(|&o| {
                    let ov = &self.veh[o as usize];
                    let gap = back + from_len - ov.pos - self.types[ov.vtype as usize].min_gap;
                    self.other(types, o, gap)
                });
            }
            out.follower = found;
        }
    }

    /// The index in lane `l`'s queue (front first, positions falling) of its first vehicle whose position `p`
    /// satisfies `behind(p, pos)` (the queue's length if none), by bisection: the pass asks this of every
    /// vehicle, and a linear scan made it quadratic in the vehicles per lane.
    pub(in crate::sim) fn queue_index_behind(
        &self,
        l: LaneIdx,
        pos: f64,
        behind: impl Fn(f64, f64) -> bool,
    ) -> usize {
        let q = &self.lane_veh[l as usize];
        let i = q.partition_point(|&o| !behind(self.veh[o as usize].pos, pos));
        debug_assert_eq!(
            Some(i),
            q.iter()
                .position(|&o| behind(self.veh[o as usize].pos, pos))
                .or(Some(q.len())),
            "lane {l} is not ordered front first"
        );
        i
    }

    /// [`Self::queue_index_behind`], checked first at `guess`: the index there when the vehicle before it (if any)
    /// is not behind and the one at it (if any) is, the one index that satisfies both in an ordered queue.
    #[inline(always)]
    pub(in crate::sim) fn queue_index_behind_near(
        &self,
        l: LaneIdx,
        pos: f64,
        guess: usize,
        behind: impl Fn(f64, f64) -> bool,
    ) -> usize {
        let q = &self.lane_veh[l as usize];
        let is_behind = |i: usize| behind(self.veh[q[i] as usize].pos, pos);
        if guess <= q.len()
            && (guess == 0 || !is_behind(guess - 1))
            && (guess == q.len() || is_behind(guess))
        {
            debug_assert_eq!(guess, self.queue_index_behind(l, pos, &behind));
            return guess;
        }
        self.queue_index_behind(l, pos, behind)
    }

    /// Where `id` is in lane `l`'s queue.
    pub(in crate::sim) fn index_in_lane(&self, id: VehicleId, l: LaneIdx) -> Option<usize> {
        let q = &self.lane_veh[l as usize];
        let pos = self.veh[id as usize].pos;
        let from = self.queue_index_behind(l, pos, |o, p| o <= p);
        let i = q
            .iter()
            .skip(from)
            .take_while(|&&o| self.veh[o as usize].pos == pos)
            .position(|&o| o == id)
            .map(|i| from + i);
        debug_assert_eq!(i, q.iter().position(|&o| o == id), "lane {l}");
        i
    }
}
