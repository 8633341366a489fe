//! The induction loops' view of a step ([`crate::measure::detectors`]): after the moves and before the lane
//! changes (SUMO's loops see the moves while they are made), each detector is shown the vehicles on its lane and
//! the ones it was tracking, wherever they went.

use super::*;
use crate::measure::detectors::{Seen, may_enter};

impl Simulation {
    pub(in crate::sim) fn observe_detectors(&mut self) {
        let t = self.time_s - self.spec.start_time_s;
        let dt = self.spec.step_s;
        let (mut on_lane, mut tracked) = std::mem::take(&mut self.detector_seen);
        for d in 0..self.detectors.len() {
            let types = &self.spec.detectors[d].vehicle_types;
            let seen = |id: VehicleId| {
                let v = &self.veh[id as usize];
                Seen {
                    id,
                    lane: v.lane,
                    road: self.net.road_of(v.lane),
                    pos: v.pos,
                    speed: v.speed,
                    length: v.length,
                    odometer: v.distance_m,
                    active: v.status == VehicleStatus::Active,
                }
            };
            // only the vehicles that may enter the loop: the others on its lane are far before or past it
            let p = self.detectors.pos(d);
            on_lane.clear();
            for &id in self.lane_veh[self.detectors.lane(d) as usize].iter() {
                let v = &self.veh[id as usize];
                if may_enter(p, v.pos, v.speed, v.length, dt)
                    && (types.is_empty() || types.contains(&(v.vtype as usize)))
                {
                    on_lane.push(seen(id));
                }
            }
            tracked.clear();
            tracked.extend(self.detectors.tracked(d).map(seen));
            self.detectors.observe(d, t, dt, &on_lane, &tracked);
        }
        self.detector_seen = (on_lane, tracked);
        if self.step + 1 == self.spec.warmup_steps + self.spec.horizon_steps {
            self.detectors.close(t + dt);
        }
    }
}
