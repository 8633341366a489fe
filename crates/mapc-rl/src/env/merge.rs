//! The merge-control environment on `mapc-sim`: the centralized observation of the first `N_AV` AVs in the
//! control region, their accelerations as the action, and one of three rewards.

use std::str::FromStr;

use std::borrow::Cow;
use std::sync::Arc;

use mapc_scenario::distribution::LoadedDistribution;
use mapc_sim::{SimSpec, Simulation, VehicleId};
use serde::{Deserialize, Serialize};

use super::obs::{
    AvView, ControlQueue, ObsNorm, RegionExits, centralized_obs, flow_reward, speed_reward,
};
use crate::env::{Env, EpisodeMetrics, Transition};
use crate::error::RlError;

/// Training reward.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum RewardKind {
    /// Vehicles that left the network this step; in a scenario with a control region (a window cut from a
    /// corridor), those that left the region (the paper's window runs: [`RegionExits`]).
    Outflow,
    /// Flow's desired-velocity reward with the AV time-gap penalty.
    Flow,
    /// Mean speed of all vehicles / V.
    Speed,
}

impl RewardKind {
    pub fn name(self) -> &'static str {
        match self {
            RewardKind::Outflow => "outflow",
            RewardKind::Flow => "flow",
            RewardKind::Speed => "speed",
        }
    }
}

impl FromStr for RewardKind {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, String> {
        match s {
            "outflow" => Ok(RewardKind::Outflow),
            "flow" => Ok(RewardKind::Flow),
            "speed" | "average_speed" | "avg_speed" => Ok(RewardKind::Speed),
            _ => Err(format!("unknown reward `{s}` (outflow, flow, speed)")),
        }
    }
}

/// The paper's normalisation: V = 30 m/s, L = 947.68 m (Simple Merge's total lane length). A transferred policy
/// keeps the constants it was trained with.
pub const SIMPLE_MERGE_NORM: ObsNorm = ObsNorm {
    max_speed: 30.0,
    length: 947.68,
};
/// Action bounds (m/s^2): the human driver's comfortable deceleration and maximum acceleration.
pub const ACCEL_MIN: f64 = -4.5;
pub const ACCEL_MAX: f64 = 2.6;
/// Flow's desired velocity v*.
pub const DESIRED_SPEED: f64 = 30.0;

#[derive(Clone, Debug, PartialEq)]
pub struct MergeEnvConfig {
    pub reward: RewardKind,
    pub n_av: usize,
    pub norm: ObsNorm,
    pub accel_min: f64,
    pub accel_max: f64,
    /// Observe the adjacent lanes' leaders and followers too (`mapc train --features lanes`).
    pub lanes: bool,
}

impl MergeEnvConfig {
    /// The paper's environment for `n_av` controlled AVs: the Simple Merge's normalisation and the human
    /// driver's acceleration bounds (what a new centralized training run uses).
    pub fn paper(reward: RewardKind, n_av: usize) -> MergeEnvConfig {
        MergeEnvConfig {
            reward,
            n_av,
            norm: SIMPLE_MERGE_NORM,
            accel_min: ACCEL_MIN,
            accel_max: ACCEL_MAX,
            lanes: false,
        }
    }

    pub fn obs_dim(&self) -> usize {
        super::obs::per_av(self.lanes) * self.n_av
    }
}

/// Where an episode's simulation comes from.
#[derive(Clone, Debug)]
pub enum SpecSource {
    /// One scenario for every episode.
    Fixed(Box<SimSpec>),
    /// A merge drawn from the episode's seed, simulated for `horizon_steps`.
    Drawn {
        distribution: Arc<LoadedDistribution>,
        horizon_steps: u64,
    },
}

impl SpecSource {
    /// The scenario of the episode with seed `seed`.
    pub fn spec_for(&self, seed: u64) -> Result<Cow<'_, SimSpec>, RlError> {
        match self {
            SpecSource::Fixed(spec) => Ok(Cow::Borrowed(spec.as_ref())),
            SpecSource::Drawn {
                distribution,
                horizon_steps,
            } => {
                let scenario_error = |e: String| RlError::Scenario {
                    scenario: distribution.origin.clone(),
                    msg: e,
                };
                let resolved = distribution
                    .resolve(seed)
                    .map_err(|e| scenario_error(e.to_string()))?;
                let mut spec = mapc_sim::spec_from_scenario(&resolved)
                    .map_err(|e| scenario_error(format!("draw {seed}: {e}")))?;
                spec.horizon_steps = *horizon_steps;
                // every draw is a new network and demand: checked as a fixed scenario is at construction
                super::validate_spec(&spec)?;
                Ok(Cow::Owned(spec))
            }
        }
    }

    /// Steps of one episode: a fixed scenario's warm-up and measured horizon (the whole simulation); for drawn
    /// merges, the horizon each draw is simulated for.
    pub fn episode_steps(&self) -> u64 {
        match self {
            SpecSource::Fixed(spec) => spec.warmup_steps + spec.horizon_steps,
            SpecSource::Drawn { horizon_steps, .. } => *horizon_steps,
        }
    }
}

pub struct MergeEnv {
    source: SpecSource,
    cfg: MergeEnvConfig,
    sim: Option<Simulation>,
    queue: ControlQueue,
    controlled: Vec<VehicleId>,
    obs_buf: Vec<f32>,
    /// The outflow reward's count in a scenario with a control region.
    region_exits: RegionExits,
    /// Vehicles that left the control region in the last step.
    region_exits_last: usize,
}

impl MergeEnv {
    /// An environment over `spec` (the control region, if any, is the spec's).
    pub fn new(spec: SimSpec, cfg: MergeEnvConfig) -> Result<Self, RlError> {
        super::validate_spec(&spec)?;
        Self::with_source(SpecSource::Fixed(Box::new(spec)), cfg)
    }

    /// An environment whose episodes draw their scenario from `source` (each draw checked when it is built).
    pub fn with_source(source: SpecSource, cfg: MergeEnvConfig) -> Result<Self, RlError> {
        if let SpecSource::Drawn { .. } = &source {
            // a distribution whose draws cannot be simulated fails here, not in the first iteration
            source.spec_for(0)?;
        }
        if cfg.n_av == 0 {
            return Err(RlError::Config("N_AV must be at least 1".into()));
        }
        Ok(Self {
            source,
            cfg,
            sim: None,
            queue: ControlQueue::default(),
            controlled: vec![],
            obs_buf: vec![],
            region_exits: RegionExits::default(),
            region_exits_last: 0,
        })
    }

    pub fn config(&self) -> &MergeEnvConfig {
        &self.cfg
    }

    /// Steps of one episode ([`SpecSource::episode_steps`]).
    pub fn horizon(&self) -> usize {
        self.source.episode_steps() as usize
    }

    fn sim(&self) -> &Simulation {
        self.sim.as_ref().expect("reset before step")
    }

    /// Picks the controlled AVs and builds the observation.
    fn observe(&mut self) -> Vec<f32> {
        let sim = self.sim.as_ref().expect("reset before observe");
        let mut present: Vec<(u64, VehicleId)> = sim
            .active_ids()
            .filter_map(|id| {
                let v = sim.vehicle(id)?;
                (v.controlled && sim.in_control_region(id)).then_some((v.entry_order, id))
            })
            .collect();
        present.sort_unstable();
        let ids: Vec<u64> = present.iter().map(|&(_, id)| id as u64).collect();
        self.controlled = self
            .queue
            .update(&ids, self.cfg.n_av)
            .into_iter()
            .map(|id| id as VehicleId)
            .collect();
        let len = self.cfg.norm.length;
        let views: Vec<AvView> = self
            .controlled
            .iter()
            .map(|&id| super::av_view(sim, id, len, self.cfg.lanes))
            .collect();
        centralized_obs(
            &views,
            self.cfg.n_av,
            self.cfg.norm,
            self.cfg.lanes,
            &mut self.obs_buf,
        );
        self.obs_buf.clone()
    }

    /// Whether the outflow reward counts vehicles leaving the control region rather than the network.
    fn counts_region_exits(&self) -> bool {
        self.cfg.reward == RewardKind::Outflow && self.sim().spec().control_region.is_some()
    }

    /// Updates the count of vehicles that left the control region (see [`RewardKind::Outflow`]).
    fn update_region_exits(&mut self) {
        if !self.counts_region_exits() {
            return;
        }
        let sim = self.sim.as_ref().expect("reset before step");
        let inside: Vec<u64> = sim
            .active_ids()
            .filter(|&id| sim.in_control_region(id))
            .map(|id| id as u64)
            .collect();
        self.region_exits_last = self.region_exits.update(&inside);
    }

    fn reward(&self) -> f64 {
        let sim = self.sim();
        match self.cfg.reward {
            RewardKind::Outflow if self.counts_region_exits() => self.region_exits_last as f64,
            RewardKind::Outflow => sim.arrived_last_step().len() as f64,
            RewardKind::Speed | RewardKind::Flow => {
                let speeds: Vec<f64> = sim
                    .active_ids()
                    .filter_map(|id| sim.vehicle(id).map(|v| v.speed))
                    .collect();
                if self.cfg.reward == RewardKind::Speed {
                    speed_reward(&speeds, self.cfg.norm.max_speed)
                } else {
                    let headways: Vec<(f64, f64)> = self
                        .controlled
                        .iter()
                        .filter_map(|&id| {
                            let v = sim.vehicle(id)?;
                            sim.leader(id, f64::INFINITY).map(|l| (l.gap_m, v.speed))
                        })
                        .collect();
                    flow_reward(&speeds, DESIRED_SPEED, &headways)
                }
            }
        }
    }

    /// Steps with the given accelerations; errors of the simulator are passed on.
    pub fn try_step(&mut self, action: &[f32]) -> Result<Transition, RlError> {
        let (lo, hi) = (self.cfg.accel_min, self.cfg.accel_max);
        super::check_actions(action.iter().copied(), |k| format!("action[{k}]"))?;
        let sim = self.sim.as_mut().expect("reset before step");
        for (k, &id) in self.controlled.iter().enumerate() {
            if let Some(&a) = action.get(k) {
                super::apply_action(sim, id, a, (lo, hi))?;
            }
        }
        if !sim.is_done() {
            sim.step().map_err(super::sim_error)?;
        }
        self.update_region_exits();
        // The reward sees the controlled set that acted in this step.
        let reward = self.reward() as f32;
        let obs = self.observe();
        Ok(Transition {
            obs,
            reward,
            terminal: false,
        })
    }

    /// The controlled AVs of the current observation, in slot order.
    pub fn controlled(&self) -> &[VehicleId] {
        &self.controlled
    }

    /// The simulation of the current episode (after `reset`).
    pub fn simulation(&self) -> Option<&Simulation> {
        self.sim.as_ref()
    }
}

impl Env for MergeEnv {
    fn obs_dim(&self) -> usize {
        self.cfg.obs_dim()
    }
    fn act_dim(&self) -> usize {
        self.cfg.n_av
    }
    fn reset(&mut self, seed: u64) -> Result<Vec<f32>, RlError> {
        let spec = self.source.spec_for(seed)?;
        self.sim = Some(super::episode_simulation(&spec, seed)?);
        self.queue.clear();
        self.region_exits.clear();
        self.update_region_exits();
        Ok(self.observe())
    }
    fn step(&mut self, action: &[f32]) -> Result<Transition, RlError> {
        self.try_step(action)
    }
    fn metrics(&self) -> EpisodeMetrics {
        (&self.sim().metrics()).into()
    }
}
