//! What a vehicle sees beside it on a multi-lane road: the leader and follower on the lane to its left or right
//! (for policies that observe the adjacent lanes), and which connections join a road from another road (the
//! merges of a multi-lane road, where the merging road may end on an acceleration lane of its own).

use super::*;
use crate::models::lc::Side;

/// The nearest vehicles on one adjacent lane.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct SideNeighbors {
    /// The nearest vehicle whose front is ahead of the ego's front; gap from the ego's front to its back (negative
    /// while the two overlap side by side).
    pub leader: Option<Neighbor>,
    /// The nearest vehicle whose front is at or behind the ego's front; gap from its front to the ego's back
    /// (negative while they overlap).
    pub follower: Option<Neighbor>,
}

impl Simulation {
    /// Leader and follower of `id` on the lane to its `side` on its road, within `max_dist` metres (searched across
    /// the lane's end along the vehicle's route and across its start through the connections into it). `None`
    /// when the road has no lane on that side, and inside a junction.
    pub fn side_neighbors(
        &self,
        id: VehicleId,
        side: Side,
        max_dist: f64,
    ) -> Option<SideNeighbors> {
        let v = self
            .veh
            .get(id as usize)
            .filter(|v| v.status == VehicleStatus::Active)?;
        let own = self.lane_at(v.lane as usize);
        let lane = match side {
            Side::Right => own.right,
            Side::Left => own.left,
        }?;
        let q = &self.lane_veh[lane as usize];
        // front first: the vehicles before `split` are ahead of the ego's front
        let split = q
            .iter()
            .position(|&o| self.veh[o as usize].pos <= v.pos)
            .unwrap_or(q.len());
        let neighbor = |o: VehicleId, gap_m: f64| Neighbor {
            id: o,
            gap_m,
            speed: self.veh[o as usize].speed,
        };
        let leader = if split > 0 {
            let o = q[split - 1];
            let ov = &self.veh[o as usize];
            Some(neighbor(o, ov.pos - ov.length - v.pos))
        } else {
            self.first_ahead_along_route(
                id,
                lane,
                self.lane_at(lane as usize).length - v.pos,
                max_dist,
            )
            .map(|(o, gap)| neighbor(o, gap))
        };
        let leader = leader.filter(|n| n.gap_m <= max_dist);
        let follower = match q.get(split) {
            Some(&o) => Some(neighbor(o, v.pos - v.length - self.veh[o as usize].pos)),
            None => self.first_behind(id, lane, v.pos - v.length, max_dist),
        }
        .filter(|n| n.gap_m <= max_dist);
        Some(SideNeighbors { leader, follower })
    }

    /// The last vehicle on the lanes that continue `lane` (whose end lies `seen` m ahead of `id`'s front) toward
    /// the next roads of `id`'s route, and the gap to its back.
    fn first_ahead_along_route(
        &self,
        id: VehicleId,
        lane: LaneIdx,
        mut seen: f64,
        max_dist: f64,
    ) -> Option<(VehicleId, f64)> {
        let v = &self.veh[id as usize];
        let r = &self.routes[v.route as usize];
        let mut k = r.road_k[v.route_pos as usize] as usize + 1;
        let mut cur = lane;
        while seen <= max_dist {
            let next_road = *r.roads.get(k)?;
            let link = self.lane_at(cur as usize).out_links.iter().find(|&&l| {
                self.net.road_of(self.link_at(l as usize).to_lane) == Some(next_road)
            })?;
            let lk = self.link_at(*link as usize);
            for l in [lk.via_lane, lk.to_lane] {
                if let Some(&o) = self.lane_veh[l as usize].last() {
                    let ov = &self.veh[o as usize];
                    return Some((o, seen + ov.pos - ov.length));
                }
                seen += self.lane_at(l as usize).length;
            }
            cur = lk.to_lane;
            k += 1;
        }
        None
    }

    /// Whether another road joins the road that link `k` leads onto: some connection into any lane of that road
    /// comes from a different road. On one-lane roads this is exactly "the link has foes"; on multi-lane roads
    /// it also finds a merging road that ends on an acceleration lane of its own.
    pub(in crate::sim) fn joins_another_road(&self, k: LinkIdx) -> bool {
        !self.joining_links(k).is_empty()
    }

    /// The connections into the road that link `k` leads onto that come from another road than `k`'s.
    pub(in crate::sim) fn joining_links(&self, k: LinkIdx) -> Vec<LinkIdx> {
        let lk = self.link_at(k as usize);
        let (Some(from_road), Some(to_road)) =
            (self.net.road_of(lk.from_lane), self.net.road_of(lk.to_lane))
        else {
            return Vec::new();
        };
        self.net.road_lanes[to_road]
            .iter()
            .flat_map(|&l| self.lane_at(l as usize).in_links.iter().copied())
            .filter(|&o| self.net.road_of(self.link_at(o as usize).from_lane) != Some(from_road))
            .collect()
    }
}
