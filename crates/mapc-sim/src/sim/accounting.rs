//! The run's figures as the steps accumulate them (after the warm-up), and the invariant that no two vehicles
//! overlap.

use super::*;

#[derive(Clone, Debug, Default)]
pub(super) struct MetricsAcc {
    pub(super) arrived: u64,
    pub(super) departed: u64,
    pub(super) speed_sum: f64,
    pub(super) speed_steps: u64,
    pub(super) steps: u64,
    pub(super) veh_steps: u64,
    pub(super) travel_time_sum: f64,
    pub(super) delay_sum: f64,
    /// Lane changes done, and metres driven (for lane changes per vehicle-km).
    pub(super) lane_changes: u64,
    pub(super) lane_change_reasons: crate::measure::metrics::LaneChangeReasons,
    pub(super) distance_m: f64,
    /// Vehicles taken off a jammed lane ([`super::teleport`]).
    pub(super) teleports: u64,
}

impl Simulation {
    pub fn metrics(&self) -> RunMetrics {
        let m = &self.metrics;
        let secs = (m.steps as f64 * self.spec.step_s).fmax(f64::MIN_POSITIVE);
        RunMetrics {
            outflow_veh_h: 3600.0 * m.arrived as f64 / secs,
            inflow_veh_h: 3600.0 * m.departed as f64 / secs,
            avg_speed_mps: if m.speed_steps > 0 {
                m.speed_sum / m.speed_steps as f64
            } else {
                0.0
            },
            mean_travel_time_s: if m.arrived > 0 {
                m.travel_time_sum / m.arrived as f64
            } else {
                f64::NAN
            },
            mean_delay_s: if m.arrived > 0 {
                m.delay_sum / m.arrived as f64
            } else {
                f64::NAN
            },
            arrived: m.arrived,
            departed: m.departed,
            steps: m.steps,
            vehicle_steps: m.veh_steps,
            lane_changes: m.lane_changes,
            lane_changes_by_reason: m.lane_change_reasons,
            lane_changes_per_veh_km: if m.distance_m > 0.0 {
                m.lane_changes as f64 / (m.distance_m / 1000.0)
            } else {
                0.0
            },
            end_flow_veh_h: 3600.0 * self.measure.end_count as f64 / secs,
            merge_flows_veh_h: self
                .measure
                .counts
                .iter()
                .map(|&c| 3600.0 * c as f64 / secs)
                .collect(),
            entries: self.entry_counts(),
            teleports: m.teleports,
            stuck: self
                .lane_veh
                .iter()
                .flat_map(|q| q.iter())
                .filter(|&&id| {
                    self.veh[id as usize].waiting_s > mapc_scenario::SUMO_TIME_TO_TELEPORT_S
                })
                .count() as u64,
            detector_flows_veh_h: self
                .detectors
                .totals(self.time_s - self.spec.start_time_s)
                .map(|(passed, _)| 3600.0 * passed as f64 / secs)
                .collect(),
            detector_occupancy_pct: self
                .detectors
                .totals(self.time_s - self.spec.start_time_s)
                .map(|(_, occupied)| 100.0 * occupied / secs)
                .collect(),
        }
    }

    /// The lane a vehicle drove before its current one on its route (`None` at its route's first lane).
    fn previous_lane(&self, id: VehicleId) -> Option<LaneIdx> {
        let v = &self.veh[id as usize];
        let k = (v.route_pos as usize).checked_sub(1)?;
        Some(self.routes[v.route as usize].lanes[k])
    }

    /// Every pair of consecutive vehicles keeps a non-negative gap, on lanes, from connections into roads, and
    /// between vehicles on merging connections ordered by their distance to the merge point once the follower has
    /// reached the conflict point (before it the connections run side by side).
    pub fn check_no_overlap(&self) -> Result<(), SimError> {
        const EPS: f64 = 1e-6;
        let err = |a: VehicleId, b: VehicleId, gap: f64| SimError::Collision {
            time_s: self.time_s,
            leader: a,
            follower: b,
            gap_m: gap,
            place: format!(
                "leader on {} at {:.2} m, {:.2} m/s; follower on {} at {:.2} m, {:.2} m/s",
                self.net.lane_names[self.veh[a as usize].lane as usize],
                self.veh[a as usize].pos,
                self.veh[a as usize].speed,
                self.net.lane_names[self.veh[b as usize].lane as usize],
                self.veh[b as usize].pos,
                self.veh[b as usize].speed
            ),
        };
        for (li, q) in self.lane_veh.iter().enumerate() {
            for w in q.iter().collect::<Vec<_>>().windows(2) {
                let (a, b) = (&self.veh[*w[0] as usize], &self.veh[*w[1] as usize]);
                let gap = a.pos - a.length - b.pos;
                if gap < -EPS {
                    return Err(err(*w[0], *w[1], gap));
                }
            }
            // a road's last vehicle versus the front vehicle of each connection into it
            if let LaneKind::Road(_) = self.lane_at(li).kind
                && let Some(&last) = q.last()
            {
                let lv = &self.veh[last as usize];
                let came_via = self.previous_lane(last);
                for l in self.net.links.iter().filter(|l| l.to_lane as usize == li) {
                    if let Some(&f) = self.lane_veh[l.via_lane as usize].first() {
                        let fv = &self.veh[f as usize];
                        let via_len = self.lane_at(l.via_lane as usize).length;
                        let gap = lv.pos - lv.length + (via_len - fv.pos);
                        // a leader whose tail still lies on a merging connection runs beside a follower on
                        // this one until the follower reaches the conflict point
                        let beside = came_via.is_some_and(|c| {
                            c != l.via_lane
                                && l.foes.iter().any(|&foe| {
                                    let fl = self.link_at(foe as usize);
                                    fl.via_lane == c
                                        && via_len - fv.pos
                                            > CONFLICT_POINT_SHARE
                                                * via_len.fmin(self.lane_at(c as usize).length)
                                })
                        });
                        if gap < -EPS && !beside {
                            return Err(err(last, f, gap));
                        }
                    }
                }
            }
        }
        // merging connections: order by distance to the merge point
        for (i, lk) in self.net.links.iter().enumerate() {
            for &foe in &lk.foes {
                if (foe as usize) < i {
                    continue;
                }
                let a_len = self.lane_at(lk.via_lane as usize).length;
                let b_len = self
                    .lane_at(self.link_at(foe as usize).via_lane as usize)
                    .length;
                for &a in &self.lane_veh[lk.via_lane as usize] {
                    for &b in &self.lane_veh[self.link_at(foe as usize).via_lane as usize] {
                        let (av, bv) = (&self.veh[a as usize], &self.veh[b as usize]);
                        let (da, db) = (a_len - av.pos, b_len - bv.pos);
                        let (lead, fol, gap) = if da <= db {
                            (a, b, db - da - av.length)
                        } else {
                            (b, a, da - db - bv.length)
                        };
                        // the connections run side by side up to the conflict point
                        let beside = da.fmax(db) > CONFLICT_POINT_SHARE * a_len.fmin(b_len);
                        if gap < -EPS && !beside {
                            return Err(err(lead, fol, gap));
                        }
                    }
                }
            }
        }
        Ok(())
    }
}
