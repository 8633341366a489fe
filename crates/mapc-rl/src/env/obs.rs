//! The centralized observation, the controlled-AV queue and the three rewards, on plain numbers (the simulator
//! adapter in `env::merge` feeds them).

use serde::{Deserialize, Serialize};

/// Values per controlled AV in the centralized observation.
pub const PER_AV: usize = 5;

/// What the observation needs to know about one controlled AV.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct AvView {
    /// Own speed (m/s).
    pub speed: f64,
    /// Leader's speed and bumper-to-bumper gap (m), if any.
    pub leader: Option<(f64, f64)>,
    /// Follower's speed and gap (m), if any (the follower may be on the merging road).
    pub follower: Option<(f64, f64)>,
}

/// `V` and `L` of the observation.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct ObsNorm {
    pub max_speed: f64,
    pub length: f64,
}

/// `[v/V, (v_lead - v)/V, h_lead/L, (v - v_follow)/V, h_follow/L]` per AV, clipped to [-1, 1]; no leader counts
/// as speed V at gap L, no follower as speed 0 at gap L; zero-padded to `5 * n_av`.
pub fn centralized_obs(avs: &[AvView], n_av: usize, norm: ObsNorm, out: &mut Vec<f32>) {
    out.clear();
    out.resize(PER_AV * n_av, 0.0);
    let (vmax, len) = (norm.max_speed, norm.length);
    for (k, av) in avs.iter().take(n_av).enumerate() {
        let (lead_v, lead_gap) = av.leader.unwrap_or((vmax, len));
        let (fol_v, fol_gap) = av.follower.unwrap_or((0.0, len));
        let vals = [
            av.speed / vmax,
            (lead_v - av.speed) / vmax,
            lead_gap / len,
            (av.speed - fol_v) / vmax,
            fol_gap / len,
        ];
        for (j, x) in vals.iter().enumerate() {
            out[k * PER_AV + j] = x.clamp(-1.0, 1.0) as f32;
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
            },
            AvView {
                speed: 6.0,
                leader: None,
                follower: None,
            },
        ];
        let mut o = Vec::new();
        centralized_obs(&avs, 3, NORM, &mut o);
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
        }; 3];
        let mut o = Vec::new();
        centralized_obs(&avs, 2, NORM, &mut o);
        assert_eq!(o.len(), 10);
        assert_eq!(&o[..4], &[1.0, -1.0, 1.0, -1.0]);
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
