//! The centralized observation, the controlled-AV queue and the three rewards, on plain numbers (the simulator
//! adapter in `env::merge` feeds them).

use serde::{Deserialize, Serialize};

/// Values per controlled AV in the centralized observation.
pub const PER_AV: usize = 5;

/// Values the adjacent-lanes observation adds per AV: for the lane to the left, then the one to the right,
/// whether it exists, and its leader's and follower's speed differences and gaps as in the paper's five.
pub const ADJACENT_PER_AV: usize = 10;

/// Values per AV of the centralized observation, with the adjacent lanes or without.
pub fn per_av(lanes: bool) -> usize {
    PER_AV + if lanes { ADJACENT_PER_AV } else { 0 }
}

/// What the observation needs to know about one controlled AV.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct AvView {
    /// Own speed (m/s).
    pub speed: f64,
    /// Leader's speed and bumper-to-bumper gap (m), if any, in the AV's own lane.
    pub leader: Option<(f64, f64)>,
    /// Follower's speed and gap (m), if any, in the AV's own lane (it may be on the merging road, or on the
    /// acceleration lane an AV from the ramp is on).
    pub follower: Option<(f64, f64)>,
    /// The lanes to the left and right of the AV's lane; `None` where its road has none (read only by the
    /// adjacent-lanes observation).
    pub left: Option<SideView>,
    pub right: Option<SideView>,
}

/// Leader and follower (speed, gap in m) on an adjacent lane, if any; gaps are negative while side by side.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct SideView {
    pub leader: Option<(f64, f64)>,
    pub follower: Option<(f64, f64)>,
}

/// The paper's five values of one AV, not clipped: `[v/V, (v_lead - v)/V, h_lead/L, (v - v_follow)/V,
/// h_follow/L]`; no leader counts as speed V at gap L, no follower as speed 0 at gap L.
pub fn own_lane_values(av: &AvView, norm: ObsNorm) -> [f64; PER_AV] {
    let (vmax, len) = (norm.max_speed, norm.length);
    let (lead_v, lead_gap) = av.leader.unwrap_or((vmax, len));
    let (fol_v, fol_gap) = av.follower.unwrap_or((0.0, len));
    [
        av.speed / vmax,
        (lead_v - av.speed) / vmax,
        lead_gap / len,
        (av.speed - fol_v) / vmax,
        fol_gap / len,
    ]
}

/// The adjacent-lanes values of one AV, not clipped: for the left lane then the right one, `[1, (v_lead -
/// v)/V, h_lead/L, (v - v_follow)/V, h_follow/L]` with the own lane's defaults for a missing leader or
/// follower. A lane that does not exist reads as an empty one with its first value 0: no vehicle can cut in
/// from it, as from an empty lane, and the flag tells the two apart.
pub fn adjacent_lane_values(av: &AvView, norm: ObsNorm) -> [f64; ADJACENT_PER_AV] {
    let mut out = [0.0; ADJACENT_PER_AV];
    for (k, side) in [av.left, av.right].into_iter().enumerate() {
        let present = side.is_some();
        let side = side.unwrap_or_default();
        let as_own = AvView {
            speed: av.speed,
            leader: side.leader,
            follower: side.follower,
            left: None,
            right: None,
        };
        let v = own_lane_values(&as_own, norm);
        out[k * PER_AV] = if present { 1.0 } else { 0.0 };
        out[k * PER_AV + 1..(k + 1) * PER_AV].copy_from_slice(&v[1..]);
    }
    out
}

/// `V` and `L` of the observation.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct ObsNorm {
    pub max_speed: f64,
    pub length: f64,
}

/// `[v/V, (v_lead - v)/V, h_lead/L, (v - v_follow)/V, h_follow/L]` per AV ([`own_lane_values`]), followed with
/// `lanes` by its adjacent lanes' ten values ([`adjacent_lane_values`]), clipped to [-1, 1]; zero-padded to
/// `per_av(lanes) * n_av`.
pub fn centralized_obs(
    avs: &[AvView],
    n_av: usize,
    norm: ObsNorm,
    lanes: bool,
    out: &mut Vec<f32>,
) {
    let per = per_av(lanes);
    out.clear();
    out.resize(per * n_av, 0.0);
    for (k, av) in avs.iter().take(n_av).enumerate() {
        let own = own_lane_values(av, norm);
        let side = if lanes {
            adjacent_lane_values(av, norm)
        } else {
            [0.0; ADJACENT_PER_AV]
        };
        let vals = own.iter().chain(&side[..per - PER_AV]);
        for (j, x) in vals.enumerate() {
            out[k * per + j] = x.clamp(-1.0, 1.0) as f32;
        }
    }
}

/// Controlled AVs in FIFO order of entry into the control region. An AV is controlled while it is among the
/// first `n_av` present; once it has left the region it is never controlled again.
#[derive(Clone, Debug, Default)]
pub struct ControlQueue {
    /// AVs seen in the region, in order of entry (ids of the simulator).
    order: Vec<u64>,
    /// AVs that have left the region.
    left: std::collections::HashSet<u64>,
}

impl ControlQueue {
    pub fn clear(&mut self) {
        self.order.clear();
        self.left.clear();
    }

    /// Updates with the AVs in the region now (`present` in the simulator's order: new entries of the same step
    /// are queued in that order). Returns the controlled ones, at most `n_av`, in FIFO order.
    pub fn update(&mut self, present: &[u64], n_av: usize) -> Vec<u64> {
        let now: std::collections::HashSet<u64> = present.iter().copied().collect();
        let mut kept = Vec::with_capacity(self.order.len());
        for &id in &self.order {
            if now.contains(&id) {
                kept.push(id);
            } else {
                self.left.insert(id);
            }
        }
        self.order = kept;
        for &id in present {
            if !self.left.contains(&id) && !self.order.contains(&id) {
                self.order.push(id);
            }
        }
        self.order.iter().take(n_av).copied().collect()
    }
}

/// Vehicles that left the control region, each counted once: the outflow reward of a scenario with a region. The
/// paper's runs in a window count the vehicles that leave the window, its "observed area" (a vehicle that was in
/// the window and is now on a road outside it), not those that reach the network's end, which on I-696 lies 5 km
/// and about 200 s further on.
#[derive(Clone, Debug, Default)]
pub struct RegionExits {
    /// Vehicles in the region at the last update, sorted.
    inside: Vec<u64>,
    /// Vehicles that have left it.
    left: std::collections::HashSet<u64>,
}

impl RegionExits {
    pub fn clear(&mut self) {
        self.inside.clear();
        self.left.clear();
    }

    /// Updates with the vehicles in the region now (any order); returns how many of those in it at the last
    /// update have left it since, counting a vehicle only the first time it leaves.
    pub fn update(&mut self, present: &[u64]) -> usize {
        let mut now = present.to_vec();
        now.sort_unstable();
        let mut exits = 0;
        for &id in &self.inside {
            if now.binary_search(&id).is_err() && self.left.insert(id) {
                exits += 1;
            }
        }
        self.inside = now;
        exits
    }
}

/// Flow's desired-velocity reward: `max(||v*·1|| - ||v - v*||, 0) / ||v*·1||` over all vehicles, plus
/// `0.1 * sum over controlled AVs with a leader and positive speed of min(gap/v - 1, 0)`, floored at 0.
pub fn flow_reward(speeds: &[f64], desired: f64, controlled_headways: &[(f64, f64)]) -> f64 {
    if speeds.is_empty() {
        return 0.0;
    }
    let max_cost = (desired * desired * speeds.len() as f64).sqrt();
    let cost = speeds
        .iter()
        .map(|v| (v - desired).powi(2))
        .sum::<f64>()
        .sqrt();
    let r1 = (max_cost - cost).max(0.0) / (max_cost + 1e-3);
    let t_min = 1.0;
    let r2: f64 = controlled_headways
        .iter()
        .filter(|(_, v)| *v > 0.0)
        .map(|&(gap, v)| ((gap / v).max(0.0) - t_min).min(0.0) / t_min)
        .sum();
    (r1 + 0.1 * r2).max(0.0)
}

/// Average-speed reward: mean speed over all vehicles divided by V (0 with no vehicle).
pub fn speed_reward(speeds: &[f64], max_speed: f64) -> f64 {
    if speeds.is_empty() {
        0.0
    } else {
        speeds.iter().sum::<f64>() / speeds.len() as f64 / max_speed
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const NORM: ObsNorm = ObsNorm {
        max_speed: 30.0,
        length: 947.68,
    };

    #[test]
    fn observation_by_hand() {
        let avs = [
            AvView {
                speed: 15.0,
                leader: Some((20.0, 47.384)),
                follower: Some((12.0, 94.768)),
                ..AvView::default()
            },
            AvView {
                speed: 6.0,
                leader: None,
                follower: None,
                ..AvView::default()
            },
        ];
        let mut o = Vec::new();
        centralized_obs(&avs, 3, NORM, false, &mut o);
        let want = [
            0.5,
            1.0 / 6.0,
            0.05,
            0.1,
            0.1,
            0.2,
            0.8,
            1.0,
            0.2,
            1.0,
            0.0,
            0.0,
            0.0,
            0.0,
            0.0,
        ];
        assert_eq!(o.len(), 15);
        for (a, b) in o.iter().zip(want) {
            assert!((a - b).abs() < 1e-6, "{o:?}");
        }
    }

    #[test]
    fn observation_clips_and_truncates() {
        // A leader 2 L away clips to 1; a follower much faster gives (v - v_f)/V < -1, clipped to -1.
        let avs = [AvView {
            speed: 40.0,
            leader: Some((0.0, 2000.0)),
            follower: Some((75.0, 1.0)),
            ..AvView::default()
        }; 3];
        let mut o = Vec::new();
        centralized_obs(&avs, 2, NORM, false, &mut o);
        assert_eq!(o.len(), 10);
        assert_eq!(&o[..4], &[1.0, -1.0, 1.0, -1.0]);
    }

    #[test]
    fn adjacent_lanes_by_hand() {
        // a left lane with a leader 47.384 m ahead at 18 m/s and a follower 2 m behind the AV's back (side by side:
        // -2 m) at 21 m/s; no lane on the right
        let av = AvView {
            speed: 15.0,
            leader: Some((20.0, 47.384)),
            follower: None,
            left: Some(SideView {
                leader: Some((18.0, 47.384)),
                follower: Some((21.0, -2.0)),
            }),
            right: None,
        };
        let mut o = Vec::new();
        centralized_obs(&[av], 2, NORM, true, &mut o);
        assert_eq!(o.len(), 30);
        let want = [
            // own lane: the paper's five
            0.5,
            1.0 / 6.0,
            0.05,
            0.5,
            1.0,
            // left: present, leader, follower (clipped)
            1.0,
            0.1,
            0.05,
            -0.2,
            -2.0 / 947.68,
            // right: missing, read as an empty lane
            0.0,
            0.5,
            1.0,
            0.5,
            1.0,
        ];
        for (a, b) in o.iter().zip(want) {
            assert!((a - b as f32).abs() < 1e-6, "{o:?}");
        }
        assert!(o[15..].iter().all(|&x| x == 0.0));
        // without the option, the paper's five values, whatever the sides hold
        centralized_obs(&[av], 2, NORM, false, &mut o);
        assert_eq!(o.len(), 10);
        let bare = AvView { left: None, ..av };
        let mut p = Vec::new();
        centralized_obs(&[bare], 2, NORM, false, &mut p);
        assert_eq!(o, p);
    }

    #[test]
    fn queue_is_fifo_and_never_takes_back() {
        let mut q = ControlQueue::default();
        assert_eq!(q.update(&[7, 3], 2), vec![7, 3]);
        assert_eq!(q.update(&[3, 9, 7], 2), vec![7, 3]);
        // 7 leaves: 9 moves up.
        assert_eq!(q.update(&[3, 9], 2), vec![3, 9]);
        // 7 reappears in the region (e.g. a window re-entered): not controlled again.
        assert_eq!(q.update(&[7, 3, 9, 11], 2), vec![3, 9]);
        assert_eq!(q.update(&[7, 11], 2), vec![11]);
    }

    #[test]
    fn region_exits_count_each_vehicle_once() {
        let mut e = RegionExits::default();
        assert_eq!(e.update(&[4, 2]), 0);
        // 5 enters, nobody leaves.
        assert_eq!(e.update(&[5, 2, 4]), 0);
        // 4 and 2 leave in the same step (2 arrived, 4 drove on: both are gone from the region).
        assert_eq!(e.update(&[5]), 2);
        // 4 comes back and leaves again: not counted twice.
        assert_eq!(e.update(&[5, 4]), 0);
        assert_eq!(e.update(&[]), 1);
        e.clear();
        assert_eq!(e.update(&[]), 0);
    }

    #[test]
    fn rewards_by_hand() {
        // Speeds 30, 30 -> cost 0 -> r1 = max_cost / (max_cost + 1e-3).
        let r = flow_reward(&[30.0, 30.0], 30.0, &[]);
        let mc = (1800.0f64).sqrt();
        assert!((r - mc / (mc + 1e-3)).abs() < 1e-12);
        // Speeds 0, 30: max_cost = sqrt(1800) = 42.43, cost = 30; r1 = 12.43/42.43; an AV at 10 m/s 5 m behind its
        // leader has time gap 0.5 s: penalty 0.1 * (0.5 - 1) = -0.05.
        let r = flow_reward(&[0.0, 30.0], 30.0, &[(5.0, 10.0)]);
        let r1 = (mc - 30.0) / (mc + 1e-3);
        assert!((r - (r1 - 0.05)).abs() < 1e-12, "{r}");
        assert_eq!(flow_reward(&[], 30.0, &[]), 0.0);
        assert!((speed_reward(&[10.0, 20.0], 30.0) - 0.5).abs() < 1e-12);
    }
}
