//! The distributed (decentralised) merge-control setting of the paper's section 4.3: every AV in the control
//! region is an agent that sees only what its own sensors give (its leader and follower, optionally the distance
//! to the next merge, the congestion ahead of it and the nearest vehicle about to merge) and runs the same
//! shared policy; each agent gets its own reward, a mix of a selfish time penalty and the collaborative average
//! speed (0.1 (-eta1 + eta2 * mean speed / V) per step), and a bonus in the step it leaves (optionally mixed with
//! the step's mean over the agents, [`AgentReward::share`]).

use serde::{Deserialize, Serialize};

use mapc_sim::{SimSpec, Simulation, VehicleId};

use super::obs::{ADJACENT_PER_AV, AvView, ObsNorm, PER_AV};
use crate::error::RlError;
use crate::rollout::EpisodeMetrics;

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
/// the step terms at the scale its code used (`eta1 * -0.1 + eta2 * 0.1 * mean speed / V`, REFERENCE.md sec. 5),
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
mod tests {
    use super::*;

    const NORM: ObsNorm = crate::env::merge::SIMPLE_MERGE_NORM;

    #[test]
    fn observation_by_hand() {
        let view = AgentView {
            av: AvView {
                speed: 15.0,
                leader: Some((45.0, 2000.0)),
                follower: None,
                ..AvView::default()
            },
            junction_dist: Some(150.0),
            congestion_speed: Some(6.0),
            merge_foe: Some((50.0, 9.0)),
        };
        let mut o = Vec::new();
        agent_obs(&view, Features::FULL, NORM, SIMPLE_MERGE_DIST_NORM, &mut o);
        // not clipped: the leader 2000 m ahead gives 2.11, its speed difference 1.0
        let want = [0.5, 1.0, 2000.0 / 947.68, 0.5, 1.0, 0.25, 0.2, 0.25, 0.3];
        assert_eq!(o.len(), Features::FULL.obs_dim());
        for (a, b) in o.iter().zip(want) {
            assert!((a - b as f32).abs() < 1e-6, "{o:?}");
        }
        // without augmentations: the five values only; defaults when nothing is ahead
        let none = Features::parse("none").unwrap();
        agent_obs(&view, none, NORM, SIMPLE_MERGE_DIST_NORM, &mut o);
        assert_eq!(o.len(), 5);
        let bare = AgentView {
            junction_dist: None,
            congestion_speed: None,
            merge_foe: None,
            ..view
        };
        agent_obs(&bare, Features::FULL, NORM, SIMPLE_MERGE_DIST_NORM, &mut o);
        assert_eq!(&o[5..], &[1.0, 1.0, 1.0, 0.0]);
        // on a corridor the next merge may lie kilometres ahead: it reads as the training network's entry
        let far = AgentView {
            junction_dist: Some(2500.0),
            ..view
        };
        agent_obs(&far, Features::FULL, NORM, SIMPLE_MERGE_DIST_NORM, &mut o);
        assert_eq!(o[5], 1.0);
    }

    #[test]
    fn features_parse_and_name() {
        assert_eq!(Features::parse("full").unwrap(), Features::FULL);
        let f = Features::parse("dist, merge").unwrap();
        assert!(f.dist && f.merge_info && !f.congestion);
        assert_eq!(f.obs_dim(), 8);
        assert_eq!(f.name(), "dist,merge");
        assert_eq!(Features::parse("none").unwrap().name(), "none");
        assert!(Features::parse("speed").is_err());
        // the adjacent lanes, alone or with the paper's three
        let l = Features::parse("lanes").unwrap();
        assert!(l.lanes && !l.dist && l.obs_dim() == 15);
        assert_eq!(l.name(), "lanes");
        let fl = Features::parse("full,lanes").unwrap();
        assert_eq!((fl.obs_dim(), fl.name()), (19, "full,lanes".to_string()));
        assert_eq!(Features::parse(&fl.name()).unwrap(), fl);
        assert_eq!(
            Features::parse("merge,lanes").unwrap().name(),
            "merge,lanes"
        );
        // a policy file without the field reads as the paper's observation
        let old: Features =
            serde_json::from_str(r#"{"dist":true,"congestion":true,"merge_info":true}"#).unwrap();
        assert_eq!(old, Features::FULL);
        assert!(
            !serde_json::to_string(&Features::FULL)
                .unwrap()
                .contains("lanes")
        );
    }

    #[test]
    fn reward_by_hand() {
        let r = AgentReward::PAPER;
        assert!((r.of(false, 0.5) - (-0.09 + 0.005)).abs() < 1e-12);
        assert_eq!(r.of(true, 0.5), 20.0);
    }
}

#[cfg(test)]
mod episode_tests {
    use super::*;
    use crate::ppo::tensor::{Architecture, Model, Scratch};
    use crate::rollout::{ActionMode, EpisodeSettings, run_agents_episode};

    fn simple_merge(horizon: u64) -> SimSpec {
        let rs = mapc_scenario::ResolvedScenario::load("simple_merge").unwrap();
        let mut spec = mapc_sim::spec_from_scenario(&rs).unwrap();
        spec.horizon_steps = horizon;
        spec
    }

    fn config() -> DistributedConfig {
        DistributedConfig {
            features: Features::FULL,
            reward: AgentReward::PAPER,
            norm: crate::env::merge::SIMPLE_MERGE_NORM,
            dist_norm: SIMPLE_MERGE_DIST_NORM,
            accel_min: crate::env::merge::ACCEL_MIN,
            accel_max: crate::env::merge::ACCEL_MAX,
        }
    }

    fn episode(seed: u64) -> crate::rollout::AgentsEpisode {
        episode_with(seed, config())
    }

    fn episode_with(seed: u64, cfg: DistributedConfig) -> crate::rollout::AgentsEpisode {
        let mut env = DistributedEnv::new(simple_merge(400), cfg).unwrap();
        let arch = Architecture {
            obs_dim: cfg.obs_dim(),
            act_dim: 1,
            hidden: vec![16, 8],
            shared_value: false,
        };
        let model = Model::new(arch, 7);
        let settings = EpisodeSettings {
            env_seed: seed,
            noise_seed: seed + 100,
            horizon: 400,
            mode: ActionMode::Sample,
            record: true,
        };
        run_agents_episode(
            &mut env,
            &|_| &model,
            &mut Scratch::default(),
            settings,
            &mut |_| Ok(()),
        )
        .unwrap()
    }

    #[test]
    fn every_agent_gets_one_trajectory_with_one_reward_per_action() {
        let ep = episode(3);
        // 200 AVs/h for 200 s: a few AVs enter, the first ones leave within the 400 steps
        assert!(ep.trajectories.len() >= 3, "{}", ep.trajectories.len());
        let mut terminal = 0;
        let mut steps = 0;
        for t in &ep.trajectories {
            assert!(!t.is_empty());
            assert_eq!(t.obs.len(), t.len() * Features::FULL.obs_dim());
            assert_eq!(t.actions.len(), t.len());
            assert_eq!(t.values.len(), t.len());
            steps += t.len() as u64;
            match t.end {
                Some(crate::ppo::gae::EpisodeEnd::Terminal) => {
                    // leaving pays the bonus in the last step, and only there
                    terminal += 1;
                    assert_eq!(*t.rewards.last().unwrap(), 20.0);
                    assert!(t.rewards[..t.len() - 1].iter().all(|&r| r < 0.0));
                }
                Some(crate::ppo::gae::EpisodeEnd::Truncated { bootstrap_value }) => {
                    assert!(bootstrap_value.is_finite());
                    assert!(t.rewards.iter().all(|&r| r < 0.0));
                }
                None => panic!("a trajectory without an end"),
            }
        }
        assert!(terminal >= 1, "no agent left the network");
        assert_eq!(steps, ep.agent_steps);
        let sum: f64 = ep
            .trajectories
            .iter()
            .flat_map(|t| &t.rewards)
            .map(|&r| r as f64)
            .sum();
        assert!((sum - ep.total_reward).abs() < 1e-6 * sum.abs().max(1.0));
    }

    #[test]
    fn distributed_training_is_the_same_for_any_thread_count() {
        let run = |threads: usize| {
            crate::on_threads(threads, || {
                let mut c = crate::ppo::PpoConfig::distributed_fast();
                c.train_batch_size = 600;
                c.horizon = 300;
                c.minibatch = 256;
                c.epochs = 2;
                c.hidden = vec![16, 8];
                let mut st = crate::ppo::TrainerState::new(c, config().obs_dim(), 1);
                let factory = || DistributedEnv::new(simple_merge(300), config()).unwrap();
                let returns: Vec<u64> = (0..2)
                    .map(|_| st.iterate_agents(&factory).unwrap().mean_return.to_bits())
                    .collect();
                (st.model.params.clone(), returns)
            })
        };
        assert_eq!(run(1), run(3));
    }

    #[test]
    fn a_reward_share_moves_reward_between_agents_and_keeps_the_sum() {
        // two environments in lockstep with the same actions (rewards do not move vehicles)
        let mut shared_cfg = config();
        shared_cfg.reward.share = 1.0;
        let mut half_cfg = config();
        half_cfg.reward.share = 0.5;
        let envs = [config(), shared_cfg, half_cfg]
            .map(|c| DistributedEnv::new(simple_merge(600), c).unwrap());
        let [mut own, mut shared, mut half] = envs;
        let mut obs = own.reset(2).unwrap();
        assert_eq!(shared.reset(2).unwrap(), obs);
        assert_eq!(half.reset(2).unwrap(), obs);
        let (mut multi_agent_steps, mut unequal_steps) = (0, 0);
        for t in 0..600 {
            // brake and accelerate in turns, so agents' rewards differ (some leave, with the bonus)
            let a = if (t / 40) % 2 == 0 { -1.0 } else { 1.0 };
            let actions: Vec<(VehicleId, f32)> = obs.iter().map(|(id, _)| (*id, a)).collect();
            let (o, s, h) = (
                own.step(&actions).unwrap(),
                shared.step(&actions).unwrap(),
                half.step(&actions).unwrap(),
            );
            assert_eq!(o.obs, s.obs);
            assert_eq!(o.obs, h.obs);
            let n = o.rewards.len();
            if n > 1 {
                multi_agent_steps += 1;
            }
            if n == 0 {
                obs = o.obs;
                continue;
            }
            let mean = o.rewards.iter().map(|&(_, r, _)| r as f64).sum::<f64>() / n as f64;
            let spread = |rs: &[(VehicleId, f32, bool)]| {
                let max = rs.iter().map(|r| r.1).fold(f32::MIN, f32::max);
                let min = rs.iter().map(|r| r.1).fold(f32::MAX, f32::min);
                (max - min) as f64
            };
            if spread(&o.rewards) > 1.0 {
                unequal_steps += 1;
            }
            for ((x, y), z) in o.rewards.iter().zip(&s.rewards).zip(&h.rewards) {
                // same agents, same done flags; all get the mean, or halfway to it
                assert_eq!((x.0, x.2), (y.0, y.2));
                assert_eq!((x.0, x.2), (z.0, z.2));
                assert!((y.1 as f64 - mean).abs() < 1e-5, "{y:?} {mean}");
                let halfway = 0.5 * x.1 as f64 + 0.5 * mean;
                assert!((z.1 as f64 - halfway).abs() < 1e-5, "{z:?} {halfway}");
            }
            assert!(spread(&s.rewards) < 1e-6);
            obs = o.obs;
        }
        // the check saw steps with several agents whose own rewards differ (an exit bonus among time penalties)
        assert!(
            multi_agent_steps > 100 && unequal_steps > 0,
            "{multi_agent_steps} {unequal_steps}"
        );
    }

    #[test]
    fn a_reward_share_outside_zero_to_one_is_refused() {
        for share in [-0.1, 1.5, f64::NAN] {
            let mut cfg = config();
            cfg.reward.share = share;
            let err = DistributedEnv::new(simple_merge(10), cfg).err().unwrap();
            assert!(err.to_string().contains("reward share"), "{err}");
        }
    }

    #[test]
    fn waiting_vehicles_lower_the_collaborative_reward() {
        // the same episode (actions do not depend on rewards); counting the vehicles waiting at the entry as
        // standing can only lower the mean speed, and does when some wait
        let mut cfg = config();
        let plain = episode_with(11, cfg);
        cfg.reward.count_waiting = true;
        let counted = episode_with(11, cfg);
        assert_eq!(plain.agent_steps, counted.agent_steps);
        assert!(
            counted.total_reward < plain.total_reward,
            "{} {}",
            counted.total_reward,
            plain.total_reward
        );
    }

    #[test]
    fn the_same_seeds_give_the_same_episode() {
        let (a, b) = (episode(5), episode(5));
        assert_eq!(a.total_reward.to_bits(), b.total_reward.to_bits());
        assert_eq!(a.trajectories.len(), b.trajectories.len());
        for (x, y) in a.trajectories.iter().zip(&b.trajectories) {
            assert_eq!(x.actions, y.actions);
            assert_eq!(x.rewards, y.rewards);
        }
        assert_ne!(a.total_reward, episode(6).total_reward);
    }

    #[test]
    fn a_mixed_population_drives_each_agent_with_its_own_policy() {
        let cfg = config();
        let spec = simple_merge(400);
        let arch = Architecture {
            obs_dim: cfg.obs_dim(),
            act_dim: 1,
            hidden: vec![16, 8],
            shared_value: false,
        };
        let (a, b) = (Model::new(arch.clone(), 7), Model::new(arch, 8));
        let seeds = [3, 4];
        let odd = |id: VehicleId| id % 2 == 1;
        let run = |base: &Model, deviant: &Model, deviates: &(dyn Fn(VehicleId) -> bool + Sync)| {
            crate::eval::run_mixed_population(
                base,
                deviant,
                deviates,
                &spec,
                &cfg,
                &seeds,
                ActionMode::Sample,
            )
            .unwrap()
        };
        let all_a = run(&a, &b, &|_| false);
        let outcomes = |eps: &[crate::eval::MixedEpisode]| -> Vec<_> {
            eps.iter()
                .map(|e| {
                    let agents: Vec<_> = e
                        .agents
                        .iter()
                        .map(|x| (x.id, x.ret, x.left, x.steps))
                        .collect();
                    (e.metrics, agents)
                })
                .collect()
        };
        // the deviant policy is the base one: nothing changes but the labels
        assert_eq!(outcomes(&run(&a, &a, &odd)), outcomes(&all_a));
        // the odd agents on `b` among `a` is the even agents on `a` among `b`, agent for agent
        let mixed = run(&a, &b, &odd);
        let swapped = run(&b, &a, &|id| !odd(id));
        for (m, s) in mixed.iter().zip(&swapped) {
            assert_eq!(m.metrics, s.metrics);
            assert_eq!(m.agents.len(), s.agents.len());
            for (x, y) in m.agents.iter().zip(&s.agents) {
                assert_eq!(
                    (x.id, x.ret, x.left, x.steps),
                    (y.id, y.ret, y.left, y.steps)
                );
            }
        }
        assert_ne!(outcomes(&mixed), outcomes(&all_a));
        for e in &mixed {
            // the episodes hold both kinds of agent
            assert!(e.agents.iter().any(|x| odd(x.id)) && e.agents.iter().any(|x| !odd(x.id)));
            for x in &e.agents {
                // a step's reward lies in [-0.09, -0.08]; the exit bonus only in the step an agent leaves
                let steps_part = x.ret - if x.left { 20.0 } else { 0.0 };
                let n = (x.steps - x.left as usize) as f64;
                assert!(
                    steps_part >= -0.0901 * n - 1e-3 && steps_part <= -0.0799 * n + 1e-3,
                    "{x:?}"
                );
            }
        }
    }
}
