//! Who leads whom: the vehicles ahead on the route, across connections, and on merging connections up to the
//! merge point (SUMO's leader search, including the junction's foe leaders).

use super::*;
use crate::network::signals::SignalState;

impl Simulation {
    /// Calls `f(leader, gap)` for every vehicle the ego must follow within `max_dist` (gap: bumper to bumper).
    pub(in crate::sim) fn for_each_leader(
        &self,
        id: VehicleId,
        max_dist: f64,
        f: impl FnMut(VehicleId, f64),
    ) {
        let v = &self.veh[id as usize];
        let idx = self.lane_veh[v.lane as usize]
            .iter()
            .position(|&o| o == id)
            .unwrap_or(0);
        self.for_each_leader_at(id, idx, max_dist, None, f)
    }

    /// As [`Self::for_each_leader`] for the vehicle at index `idx` of its lane. `moving`: the distance the ego
    /// travels in this step when the call guards a move (`None` for a query of the state).
    pub(in crate::sim) fn for_each_leader_at(
        &self,
        id: VehicleId,
        idx: usize,
        max_dist: f64,
        moving: Option<f64>,
        mut f: impl FnMut(VehicleId, f64),
    ) {
        let v = &self.veh[id as usize];
        let q = &self.lane_veh[v.lane as usize];
        if idx > 0 {
            let l = q[idx - 1];
            let lv = &self.veh[l as usize];
            f(l, lv.pos - lv.length - v.pos);
            return;
        }
        self.leaders_beyond(id, max_dist, moving, &mut f);
    }

    /// Leaders beyond the ego's own lane: on the lanes ahead on its route, tails of vehicles that just entered a
    /// connection, and vehicles on merging connections that are closer to the merge point.
    pub(in crate::sim) fn leaders_beyond(
        &self,
        id: VehicleId,
        max_dist: f64,
        moving: Option<f64>,
        f: &mut impl FnMut(VehicleId, f64),
    ) {
        let guard = moving.is_some();
        let v = &self.veh[id as usize];
        let r = &self.routes[v.route as usize];
        let cur = self.lane_at(v.lane as usize);
        let mut seen = cur.length - v.pos;
        let on_via = matches!(cur.kind, LaneKind::Via(_));
        if on_via {
            self.junction_foe_leaders(id, v.lane, seen, guard, f);
        } else {
            // tails of vehicles on any connection out of this road still reach back onto it
            for &k in &cur.out_links {
                let via = self.link_at(k as usize).via_lane;
                if let Some(&o) = self.lane_veh[via as usize].last() {
                    let ov = &self.veh[o as usize];
                    if ov.pos < ov.length && r.lanes.get(v.route_pos as usize + 1) != Some(&via) {
                        f(o, seen + ov.pos - ov.length);
                    }
                }
            }
        }
        let mut k = v.route_pos as usize + 1;
        while k < r.lanes.len() && seen <= max_dist {
            let lane = r.lanes[k];
            let l = self.lane_at(lane as usize);
            // a moving vehicle that stays before its stop line this step cannot meet vehicles on merging
            // connections (they meet only inside the junction)
            let may_enter = moving.is_none_or(|travel| seen < travel);
            if let LaneKind::Via(link) = l.kind
                && may_enter
                && !self.link_at(link as usize).foes.is_empty()
            {
                self.junction_foe_leaders(id, lane, seen + l.length, guard, f);
            }
            if let Some(&o) = self.lane_veh[lane as usize].last() {
                let ov = &self.veh[o as usize];
                f(o, seen + ov.pos - ov.length);
                return;
            }
            seen += l.length;
            k += 1;
        }
    }

    /// Vehicles on connections merging with `via` (or about to enter them) whose front is closer to the merge
    /// point than ego's front at `dist_to_merge`.
    pub(in crate::sim) fn junction_foe_leaders(
        &self,
        id: VehicleId,
        via: LaneIdx,
        dist_to_merge: f64,
        guard: bool,
        f: &mut impl FnMut(VehicleId, f64),
    ) {
        let LaneKind::Via(link) = self.lane_at(via as usize).kind else {
            return;
        };
        let ego_in_junction = self.veh[id as usize].lane == via;
        // only a moving check or an ego inside the junction looks at foes still before their stop line
        let check_from = guard || ego_in_junction;
        let own = self.link_at(link as usize);
        let ego_has_priority_inside = ego_in_junction && own.major;
        for &foe in &own.foes {
            let fl = self.link_at(foe as usize);
            let flen = self.lane_at(fl.via_lane as usize).length;
            // a minor-road vehicle beside ego and short of the conflict point yields to ego
            // (`yield_inside_junction`): it does not lead, or both would wait for each other
            let beside_yields = ego_has_priority_inside && !fl.major;
            for &o in self.lane_veh[fl.via_lane as usize].iter() {
                let ov = &self.veh[o as usize];
                let d = flen - ov.pos;
                if d >= dist_to_merge {
                    continue;
                }
                let gap = dist_to_merge - d - ov.length;
                if beside_yields
                    && gap < 0.0
                    && d > CONFLICT_POINT_SHARE * self.lane_at(via as usize).length.fmin(flen)
                {
                    continue;
                }
                f(o, gap);
            }
            // a minor-road vehicle at its stop line enters only when its link opens: an ego with right of way
            // does not brake for it
            if !check_from || beside_yields {
                continue;
            }
            // a foe held by its light (red), or yielding under it (`g`, or `s` after its stop) to the vehicles
            // inside the junction on links it must let pass, as ego is, does not enter ahead of ego: braking for it,
            // ego would hold the junction for the foe that waits for ego (a deadlock of a city grid's left turns)
            if !guard
                && matches!(
                    self.signal_of(fl, self.time_s - self.spec.start_time_s),
                    Some(SignalState::Red | SignalState::GreenYield | SignalState::Stop)
                )
            {
                continue;
            }
            if let Some(&o) = self.lane_veh[fl.from_lane as usize].first() {
                let ov = &self.veh[o as usize];
                let from_len = self.lane_at(fl.from_lane as usize).length;
                let d = flen + from_len - ov.pos;
                // planning: a foe at its stop line may enter this very step ahead of ego (already inside);
                // moving: a foe that entered in this step (moved past its road's end) leads ego
                let relevant = if guard {
                    ov.pos > from_len
                } else {
                    ego_in_junction && d - flen < ov.speed * self.spec.step_s + 1.0
                };
                if d < dist_to_merge && relevant {
                    f(o, dist_to_merge - d - ov.length);
                }
            }
        }
    }

    /// A driver still before its minor link, `dist_to_merge` from the end of its connection `via` (of length
    /// `via_length`), under SUMO's rules: the speed behind its link leaders inside the junction, and the speed
    /// that stops it before entering if it must (infinite if not). A leader that overlaps it (a negative gap)
    /// makes it stop before entering, as SUMO's `getSafeFollowSpeed` does for an in-lapping leader; so does a car
    /// on a merging connection farther from the merge point, which entered the junction first (SUMO's
    /// `MSLink::isLeader`). Out of line: the plan of every other driver keeps its registers.
    #[inline(never)]
    pub(in crate::sim) fn minor_entry_leaders(
        &self,
        id: VehicleId,
        via: LaneIdx,
        dist_to_merge: f64,
        via_length: f64,
        speed: f64,
        desired: f64,
    ) -> (f64, f64) {
        let v = &self.veh[id as usize];
        let p = &self.types[v.vtype as usize];
        let stop_before = || {
            p.stop_speed(
                (dist_to_merge - via_length - POSITION_EPS).fmax(0.0),
                speed,
                desired,
            )
        };
        let mut m = f64::INFINITY;
        self.junction_foe_leaders(id, via, dist_to_merge, false, &mut |o, gap| {
            m = m.fmin(if gap - p.min_gap < 0.0 {
                stop_before()
            } else {
                p.follow_speed(gap - p.min_gap, speed, self.veh[o as usize].speed, desired)
            });
        });
        let LaneKind::Via(link) = self.lane_at(via as usize).kind else {
            return (m, f64::INFINITY);
        };
        let behind = self.link_at(link as usize).foes.iter().any(|&foe| {
            let fl = self.link_at(foe as usize);
            let flen = self.lane_at(fl.via_lane as usize).length;
            self.lane_veh[fl.via_lane as usize]
                .iter()
                .any(|&o| flen - self.veh[o as usize].pos >= dist_to_merge)
        });
        (m, if behind { stop_before() } else { f64::INFINITY })
    }

    /// A minor-road vehicle inside the junction that has not reached the conflict point yet keeps yielding to every
    /// major-road vehicle inside the junction beside it, even one a little behind (SUMO's right of way among
    /// junction leaders): with a negative gap it brakes as hard as it can. A major-road vehicle so far behind that
    /// it cannot pass beside (ego lies wholly ahead of its front, measured to the merge point) follows ego
    /// ([`Self::junction_foe_leaders`]), so ego goes first: both waiting would hold them there for good.
    pub(in crate::sim) fn yield_inside_junction(
        &self,
        id: VehicleId,
        link: LinkIdx,
        p: &CfModel,
        des: f64,
    ) -> f64 {
        let lk = self.link_at(link as usize);
        let mut vmax = f64::INFINITY;
        if lk.major || lk.foes.is_empty() {
            return vmax;
        }
        let v = &self.veh[id as usize];
        let own_len = self.lane_at(lk.via_lane as usize).length;
        let d = own_len - v.pos;
        for &foe in &lk.foes {
            let fl = self.link_at(foe as usize);
            if !fl.major {
                continue;
            }
            let flen = self.lane_at(fl.via_lane as usize).length;
            if d <= CONFLICT_POINT_SHARE * own_len.fmin(flen) {
                continue;
            }
            for &o in &self.lane_veh[fl.via_lane as usize] {
                let ov = &self.veh[o as usize];
                let df = flen - ov.pos;
                if df >= d && df - d - v.length < 0.0 {
                    vmax = vmax.fmin(p.follow_speed(
                        d - df - ov.length - p.min_gap,
                        v.speed,
                        ov.speed,
                        des,
                    ));
                }
            }
        }
        vmax
    }
}
