//! The distributed (decentralised) merge-control setting of the paper's section 4.3: every AV in the control
//! region is an agent that sees only what its own sensors give (its leader and follower, optionally the distance
//! to the next merge, the congestion ahead of it and the nearest vehicle about to merge) and runs the same
//! shared policy; each agent gets its own reward, a mix of a selfish time penalty and the collaborative average
//! speed (0.1 (-eta1 + eta2 * mean speed / V) per step), and a bonus in the step it leaves (optionally mixed with
//! the step's mean over the agents, [`AgentReward::share`]).

use serde::{Deserialize, Serialize};

use mapc_sim::{SimSpec, Simulation, VehicleId};

use super::obs::{ADJACENT_PER_AV, AvView, ObsNorm, PER_AV};
use crate::env::EpisodeMetrics;
use crate::error::RlError;

/// Which of the paper's state augmentations the agents see (its Table 4 ablation).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub struct Features {
    /// Distance to the next merge ("Dist").
    pub dist: bool,
    /// Mean speed of the vehicles between the agent and the next merge ("Congestion").
    pub congestion: bool,
    /// Distance to the junction and speed of the nearest vehicle about to merge from another road
    /// ("MergeInfo").
    pub merge_info: bool,
    /// The leaders and followers on the adjacent lanes (not in the paper: for multi-lane roads, where vehicles
    /// cut in from the side; [`super::obs::adjacent_lane_values`]).
    #[serde(default, skip_serializing_if = "std::ops::Not::not")]
    pub lanes: bool,
}

impl Features {
    /// All three augmentations (the paper's best, "Full Augmentation").
    pub const FULL: Features = Features {
        dist: true,
        congestion: true,
        merge_info: true,
        lanes: false,
    };

    /// The paper's five values only.
    pub const NONE: Features = Features {
        dist: false,
        congestion: false,
        merge_info: false,
        lanes: false,
    };

    /// Observation values per agent.
    pub fn obs_dim(self) -> usize {
        PER_AV
            + self.dist as usize
            + self.congestion as usize
            + 2 * self.merge_info as usize
            + if self.lanes { ADJACENT_PER_AV } else { 0 }
    }

    /// Parses `full`, `none` or a comma-separated list of `dist`, `congestion`, `merge`, `lanes` (and `full`:
    /// `full,lanes` is the paper's three with the adjacent lanes).
    pub fn parse(s: &str) -> Result<Features, String> {
        let mut f = Features::NONE;
        match s.trim() {
            "none" | "" => return Ok(f),
            _ => {}
        }
        for part in s.split(',') {
            match part.trim() {
                "full" | "all" => {
                    f = Features {
                        lanes: f.lanes,
                        ..Features::FULL
                    }
                }
                "dist" => f.dist = true,
                "congestion" => f.congestion = true,
                "merge" | "merge_info" | "mergeinfo" => f.merge_info = true,
                "lanes" => f.lanes = true,
                other => {
                    return Err(format!(
                        "unknown feature `{other}` (full, none, or a list of dist, congestion, merge, lanes)"
                    ));
                }
            }
        }
        Ok(f)
    }

    pub fn name(self) -> String {
        let paper = Features {
            lanes: false,
            ..self
        };
        let names: Vec<&str> = if paper == Features::FULL {
            vec!["full"]
        } else {
            [
                (self.dist, "dist"),
                (self.congestion, "congestion"),
                (self.merge_info, "merge"),
            ]
            .iter()
            .filter(|(on, _)| *on)
            .map(|&(_, n)| n)
            .collect()
        };
        let names: Vec<&str> = names
            .into_iter()
            .chain(self.lanes.then_some("lanes"))
            .collect();
        if names.is_empty() {
            "none".into()
        } else {
            names.join(",")
        }
    }
}

/// The distributed reward `(1 - done) 0.1 (-eta1 + eta2 * mean speed / V) + done * bonus`: the paper's eq. 3 with
/// the step terms at the scale its code used (`eta1 * -0.1 + eta2 * 0.1 * mean speed / V`, docs/reference.md sec. 5),
/// so the exit bonus outweighs the time penalty of a normal trip (about -0.09 per step over 100-200 steps).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct AgentReward {
    /// Weight of the selfish time penalty.
    pub eta1: f64,
    /// Weight of the collaborative average speed.
    pub eta2: f64,
    /// Reward in the step the agent leaves.
    pub exit_bonus: f64,
    /// Count the vehicles waiting to enter in the mean speed, as standing (not in the paper: without it, holding
    /// back the entry raises the mean speed of those inside).
    #[serde(default)]
    pub count_waiting: bool,
    /// Share of the step's mean agent reward that each agent gets in place of as much of its own: `(1 - share) *
    /// own + share * mean over the agents that acted`, in [0, 1] (not in the paper, which has 0). Agents are then
    /// credited for what happens to the others.
    #[serde(default, skip_serializing_if = "is_zero")]
    pub share: f64,
}

fn is_zero(x: &f64) -> bool {
    *x == 0.0
}

impl AgentReward {
    /// The paper's best mix: eta1 = 0.9, eta2 = 0.1, bonus 20.
    pub const PAPER: AgentReward = AgentReward {
        eta1: 0.9,
        eta2: 0.1,
        exit_bonus: 20.0,
        count_waiting: false,
        share: 0.0,
    };

    /// One agent's reward for a step after which the network's mean speed over V is `speed_ratio`.
    pub fn of(&self, done: bool, speed_ratio: f64) -> f64 {
        if done {
            self.exit_bonus
        } else {
            self.eta1 * -0.1 + self.eta2 * 0.1 * speed_ratio
        }
    }
}

/// Lengths the distances of the augmentations are divided by (kept from training, like `ObsNorm`).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct DistNorm {
    /// Distance from the network entry to the merge on the main road (m).
    pub junction: f64,
    /// Length of the merging road (m).
    pub merge: f64,
}

/// Simple Merge: 600 m of main road before the merge, a 200 m ramp.
pub const SIMPLE_MERGE_DIST_NORM: DistNorm = DistNorm {
    junction: 600.0,
    merge: 200.0,
};

/// What an agent's augmentations need to know.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct AgentView {
    pub av: AvView,
    /// Distance to the next merge (m); `None` past the last one.
    pub junction_dist: Option<f64>,
    /// Mean speed of the vehicles between the agent and that junction (m/s); `None` when there is none.
    pub congestion_speed: Option<f64>,
    /// The nearest vehicle about to merge: its distance to the merge point (m) and speed (m/s).
    pub merge_foe: Option<(f64, f64)>,
}

/// Merging vehicles count up to this many `DistNorm::merge` from the merge point (1.5: the Simple Merge's 200 m ramp
/// and its 23 m connection fit, so its observations are unchanged).
pub const MERGE_FOE_RANGE: f64 = 1.5;

/// One agent's observation: the centralized observation's five values for the agent (not clipped), then the
/// augmentations in the order dist, congestion, merge distance, merge speed. The distance is to the next merge on
/// the agent's route, at most `DistNorm::junction`; no merge ahead counts as that far, no vehicle ahead of it as speed V, no merging vehicle as one at the merging road's
/// start, standing; with `lanes`, the adjacent lanes' ten values last (not clipped either).
pub fn agent_obs(
    view: &AgentView,
    features: Features,
    norm: ObsNorm,
    dist_norm: DistNorm,
    out: &mut Vec<f32>,
) {
    out.clear();
    let vmax = norm.max_speed;
    let av = &view.av;
    for x in super::obs::own_lane_values(av, norm) {
        out.push(x as f32);
    }
    if features.dist {
        // farther than the training network's entry reads as its entry (on a corridor the next merge may lie
        // kilometres ahead)
        let d = view
            .junction_dist
            .unwrap_or(dist_norm.junction)
            .min(dist_norm.junction);
        out.push((d / dist_norm.junction) as f32);
    }
    if features.congestion {
        out.push((view.congestion_speed.unwrap_or(vmax) / vmax) as f32);
    }
    if features.merge_info {
        let (d, v) = view.merge_foe.unwrap_or((dist_norm.merge, 0.0));
        out.push((d / dist_norm.merge) as f32);
        out.push((v / vmax) as f32);
    }
    if features.lanes {
        for x in super::obs::adjacent_lane_values(av, norm) {
            out.push(x as f32);
        }
    }
}

/// Everything the distributed setting is run with.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct DistributedConfig {
    pub features: Features,
    pub reward: AgentReward,
    pub norm: ObsNorm,
    pub dist_norm: DistNorm,
    pub accel_min: f64,
    pub accel_max: f64,
}

impl DistributedConfig {
    /// The paper's distributed setting with `features` and `reward`: the Simple Merge's normalisations and the
    /// human driver's acceleration bounds (what a new `mapc train --distributed` run uses).
    pub fn paper(features: Features, reward: AgentReward) -> DistributedConfig {
        DistributedConfig {
            features,
            reward,
            norm: super::merge::SIMPLE_MERGE_NORM,
            dist_norm: SIMPLE_MERGE_DIST_NORM,
            accel_min: super::merge::ACCEL_MIN,
            accel_max: super::merge::ACCEL_MAX,
        }
    }

    pub fn obs_dim(&self) -> usize {
        self.features.obs_dim()
    }
}

/// What one step gave every agent that acted in it.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct AgentsStep {
    /// `(agent, reward, done)` for every agent that acted, in the order of the actions.
    pub rewards: Vec<(VehicleId, f32, bool)>,
    /// The agents present now, with their observations, in entry order.
    pub obs: Vec<(VehicleId, Vec<f32>)>,
}

/// The multi-agent environment: every controlled AV in the control region is an agent until it leaves the
/// region or the network (after which it is never controlled again).
pub struct DistributedEnv {
    spec: SimSpec,
    cfg: DistributedConfig,
    sim: Option<Simulation>,
    /// Agents that have left the region (never agents again).
    gone: std::collections::HashSet<VehicleId>,
}

impl DistributedEnv {
    pub fn new(spec: SimSpec, cfg: DistributedConfig) -> Result<Self, RlError> {
        super::validate_spec(&spec)?;
        if !(0.0..=1.0).contains(&cfg.reward.share) {
            return Err(RlError::Config(format!(
                "the reward share must lie in [0, 1], got {}",
                cfg.reward.share
            )));
        }
        Ok(Self {
            spec,
            cfg,
            sim: None,
            gone: Default::default(),
        })
    }

    pub fn config(&self) -> &DistributedConfig {
        &self.cfg
    }

    /// Steps of one episode: the scenario's warm-up and measured horizon (the whole simulation).
    pub fn horizon(&self) -> usize {
        (self.spec.warmup_steps + self.spec.horizon_steps) as usize
    }

    /// The simulation of the current episode (after `reset`).
    pub fn simulation(&self) -> Option<&Simulation> {
        self.sim.as_ref()
    }

    /// Starts an episode; returns the first observations.
    pub fn reset(&mut self, seed: u64) -> Result<Vec<(VehicleId, Vec<f32>)>, RlError> {
        self.sim = Some(super::episode_simulation(&self.spec, seed)?);
        self.gone.clear();
        Ok(self.observe())
    }

    /// The agents now: controlled AVs in the region that never left it, in entry order.
    fn agents(&self) -> Vec<VehicleId> {
        let sim = self.sim.as_ref().expect("reset before use");
        let mut present: Vec<(u64, VehicleId)> = sim
            .active_ids()
            .filter(|id| !self.gone.contains(id))
            .filter_map(|id| {
                let v = sim.vehicle(id)?;
                (v.controlled && sim.in_control_region(id)).then_some((v.entry_order, id))
            })
            .collect();
        present.sort_unstable();
        present.into_iter().map(|(_, id)| id).collect()
    }

    fn view(&self, id: VehicleId) -> AgentView {
        let sim = self.sim.as_ref().expect("reset before use");
        let len = self.cfg.norm.length;
        let f = self.cfg.features;
        let junction_dist = if f.dist || f.congestion {
            sim.distance_to_next_merge(id).map(|(d, _)| d)
        } else {
            None
        };
        let congestion_speed = if f.congestion {
            junction_dist.and_then(|d| congestion_ahead(sim, id, d))
        } else {
            None
        };
        let merge_foe = if f.merge_info {
            // a vehicle farther up its road than the training network's merging road (and its connection) is not
            // about to merge: on a corridor the merging road may be kilometres long
            sim.nearest_merge_foe(id, MERGE_FOE_RANGE * self.cfg.dist_norm.merge)
                .map(|f| (f.dist_to_merge_m, f.speed))
        } else {
            None
        };
        AgentView {
            av: super::av_view(sim, id, len, f.lanes),
            junction_dist,
            congestion_speed,
            merge_foe,
        }
    }

    fn observe(&self) -> Vec<(VehicleId, Vec<f32>)> {
        self.agents()
            .into_iter()
            .map(|id| {
                let mut o = Vec::with_capacity(self.cfg.obs_dim());
                agent_obs(
                    &self.view(id),
                    self.cfg.features,
                    self.cfg.norm,
                    self.cfg.dist_norm,
                    &mut o,
                );
                (id, o)
            })
            .collect()
    }

    /// Applies one acceleration per agent (clipped to the bounds; a non-finite one is refused), steps the
    /// simulation, and returns each acting agent's reward and whether it is done (left the region or the
    /// network), then the observations of the agents present now.
    pub fn step(&mut self, actions: &[(VehicleId, f32)]) -> Result<AgentsStep, RlError> {
        let (lo, hi) = (self.cfg.accel_min, self.cfg.accel_max);
        super::check_actions(actions.iter().map(|&(_, a)| a), |k| {
            format!(
                "the action of agent vehicle {} (actions[{k}])",
                actions[k].0
            )
        })?;
        let sim = self.sim.as_mut().expect("reset before step");
        for &(id, a) in actions {
            super::apply_action(sim, id, a, (lo, hi))?;
        }
        if !sim.is_done() {
            sim.step().map_err(super::sim_error)?;
        }
        let sim = self.sim.as_ref().expect("reset before step");
        let mut speeds: Vec<f64> = sim
            .active_ids()
            .filter_map(|id| sim.vehicle(id).map(|v| v.speed))
            .collect();
        if self.cfg.reward.count_waiting {
            // vehicles waiting to enter count as standing
            speeds.resize(speeds.len() + sim.waiting_to_enter(), 0.0);
        }
        let speed_ratio = super::obs::speed_reward(&speeds, self.cfg.norm.max_speed);
        let mut own = Vec::with_capacity(actions.len());
        let mut newly_gone = Vec::new();
        for &(id, _) in actions {
            let done = !sim.in_control_region(id);
            if done {
                newly_gone.push(id);
            }
            own.push((id, self.cfg.reward.of(done, speed_ratio), done));
        }
        let share = self.cfg.reward.share;
        if share != 0.0 && !own.is_empty() {
            let mean = own.iter().map(|&(_, r, _)| r).sum::<f64>() / own.len() as f64;
            for (_, r, _) in &mut own {
                *r = (1.0 - share) * *r + share * mean;
            }
        }
        let rewards = own
            .into_iter()
            .map(|(id, r, done)| (id, r as f32, done))
            .collect();
        self.gone.extend(newly_gone);
        Ok(AgentsStep {
            rewards,
            obs: self.observe(),
        })
    }

    pub fn metrics(&self) -> EpisodeMetrics {
        (&self.sim.as_ref().expect("reset before use").metrics()).into()
    }
}

/// Mean speed of the vehicles ahead of `id` whose backs are within `dist` (the distance to the next merge),
/// following the chain of leaders.
fn congestion_ahead(sim: &Simulation, id: VehicleId, dist: f64) -> Option<f64> {
    let mut covered = 0.0;
    let mut cur = id;
    let (mut sum, mut n) = (0.0, 0usize);
    // a bound on the chain, for safety against a cycle in a malformed network
    for _ in 0..1000 {
        let Some(l) = sim.leader(cur, dist - covered) else {
            break;
        };
        if covered + l.gap_m > dist {
            break;
        }
        sum += l.speed;
        n += 1;
        covered += l.gap_m + sim.vehicle(l.id).map_or(0.0, |v| v.length);
        cur = l.id;
    }
    (n > 0).then(|| sum / n as f64)
}

#[cfg(test)]
#[path = "distributed_tests.rs"]
mod tests;
