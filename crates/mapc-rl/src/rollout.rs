//! Rollout collection: the `Env` trait, one episode per seed, episodes run in parallel on the rayon pool and
//! returned in seed order (so the batch is the same bit for bit whatever the thread count).

use rayon::prelude::*;

use mapc_sim::VehicleId;

use crate::env::distributed::DistributedEnv;
use crate::env::{Env, EpisodeMetrics};
use crate::error::RlError;
use crate::ppo::gae::EpisodeEnd;
use crate::ppo::tensor::{Model, PolicyOutput, Scratch, gaussian_log_prob};
use crate::rng::Rng;

/// Builds one environment per worker.
pub type EnvFactory<'a> = dyn Fn() -> Box<dyn Env> + Sync + 'a;

/// One episode, flattened row-major.
#[derive(Clone, Debug, Default)]
pub struct Episode {
    pub obs: Vec<f32>,
    pub actions: Vec<f32>,
    pub rewards: Vec<f32>,
    pub values: Vec<f32>,
    pub log_probs: Vec<f32>,
    pub means: Vec<f32>,
    pub log_stds: Vec<f32>,
    pub end: Option<EpisodeEnd>,
    pub metrics: EpisodeMetrics,
}

impl Episode {
    pub fn len(&self) -> usize {
        self.rewards.len()
    }
    pub fn is_empty(&self) -> bool {
        self.rewards.is_empty()
    }
    pub fn total_reward(&self) -> f64 {
        self.rewards.iter().map(|&r| r as f64).sum()
    }

    /// Keeps what training needs of one step: the observation, the action and the policy's output for it.
    fn record_step(&mut self, obs: &[f32], action: &[f32], out: &PolicyOutput) {
        self.record_action(obs, action, &out.mean, &out.log_std);
        self.values.push(out.value);
    }

    /// One step without its value estimate (added for the whole episode at its end).
    fn record_action(&mut self, obs: &[f32], action: &[f32], mean: &[f32], log_std: &[f32]) {
        self.log_probs
            .push(gaussian_log_prob(action, mean, log_std));
        self.obs.extend_from_slice(obs);
        self.actions.extend_from_slice(action);
        self.means.extend_from_slice(mean);
        self.log_stds.extend_from_slice(log_std);
    }
}

/// How actions are chosen.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ActionMode {
    /// Sample from the Gaussian (training, `--sample`).
    Sample,
    /// The Gaussian's mean (evaluation).
    Mean,
}

/// The action for a policy output: its mean, or a sample of the Gaussian.
pub(crate) fn action_of(
    mean: &[f32],
    log_std: &[f32],
    mode: ActionMode,
    rng: &mut Rng,
) -> Vec<f32> {
    match mode {
        ActionMode::Mean => mean.to_vec(),
        ActionMode::Sample => mean
            .iter()
            .zip(log_std)
            .map(|(&m, &ls)| m + ls.exp() * rng.normal() as f32)
            .collect(),
    }
}

/// What one episode runs with: the environment's seed, the action-noise seed, the step limit, how actions are
/// chosen, and whether the per-step training data are kept.
#[derive(Clone, Copy, Debug)]
pub struct EpisodeSettings {
    pub env_seed: u64,
    pub noise_seed: u64,
    pub horizon: usize,
    pub mode: ActionMode,
    pub record: bool,
}

/// Runs one episode of at most `horizon` steps. `record` keeps the per-step data needed for training.
pub fn run_episode(
    env: &mut dyn Env,
    model: &Model,
    scratch: &mut Scratch,
    settings: EpisodeSettings,
) -> Result<Episode, RlError> {
    run_episode_observed(env, model, scratch, settings, &mut |_| Ok(()))
}

/// [`run_episode`], calling `observe` with the environment after the reset and after every step (traces).
pub fn run_episode_observed<E: Env + ?Sized>(
    env: &mut E,
    model: &Model,
    scratch: &mut Scratch,
    settings: EpisodeSettings,
    observe: &mut dyn FnMut(&E) -> Result<(), RlError>,
) -> Result<Episode, RlError> {
    let EpisodeSettings {
        env_seed,
        noise_seed,
        horizon,
        mode,
        record,
    } = settings;
    let mut rng = Rng::new(noise_seed);
    let mut ep = Episode::default();
    let mut obs = env.reset(env_seed)?;
    observe(env)?;
    let mut terminal = false;
    for _ in 0..horizon {
        let dist = model.action_dist(&obs, scratch);
        let action = action_of(&dist.mean, &dist.log_std, mode, &mut rng);
        let tr = env.step(&action)?;
        observe(env)?;
        if record {
            ep.record_action(&obs, &action, &dist.mean, &dist.log_std);
        }
        ep.rewards.push(tr.reward);
        obs = tr.obs;
        if tr.terminal {
            terminal = true;
            break;
        }
    }
    if record {
        // the value estimates in one batched pass (the episode's actions never depend on them)
        ep.values = model.values(&ep.obs);
    }
    ep.end = Some(if terminal {
        EpisodeEnd::Terminal
    } else {
        EpisodeEnd::Truncated {
            bootstrap_value: if record {
                model.value(&obs, scratch)
            } else {
                0.0
            },
        }
    });
    ep.metrics = env.metrics();
    Ok(ep)
}

/// Runs one episode per `(env_seed, noise_seed)` pair in parallel, returned in input order.
pub fn collect(
    factory: &EnvFactory,
    model: &Model,
    seeds: &[(u64, u64)],
    horizon: usize,
    mode: ActionMode,
    record: bool,
) -> Result<Vec<Episode>, RlError> {
    over_seeds(
        factory,
        seeds,
        horizon,
        mode,
        record,
        |env, scratch, settings| run_episode(env.as_mut(), model, scratch, settings),
    )
}

/// `run(env, scratch, settings)` for every seed pair on the rayon pool (one environment and scratch per worker),
/// results in input order.
pub(crate) fn over_seeds<E, T: Send>(
    make_env: &(dyn Fn() -> E + Sync),
    seeds: &[(u64, u64)],
    horizon: usize,
    mode: ActionMode,
    record: bool,
    run: impl Fn(&mut E, &mut Scratch, EpisodeSettings) -> Result<T, RlError> + Sync,
) -> Result<Vec<T>, RlError> {
    seeds
        .par_iter()
        .map_init(
            || (make_env(), Scratch::default()),
            |(env, scratch), &(env_seed, noise_seed)| {
                let settings = EpisodeSettings {
                    env_seed,
                    noise_seed,
                    horizon,
                    mode,
                    record,
                };
                run(env, scratch, settings)
            },
        )
        .collect()
}

/// A distributed episode: one training trajectory per agent (in the order the agents first acted), the
/// simulation's figures and the sum of every agent's rewards.
#[derive(Clone, Debug, Default)]
pub struct AgentsEpisode {
    /// Per-agent trajectories (kept only when recording).
    pub trajectories: Vec<Episode>,
    /// The agent of each trajectory (kept only when recording).
    pub agents: Vec<VehicleId>,
    pub metrics: EpisodeMetrics,
    pub total_reward: f64,
    /// Agent-steps (actions taken).
    pub agent_steps: u64,
}

/// Runs one episode of a shared policy on every agent of a [`DistributedEnv`] (`policy_of(agent)`: one model for
/// all, or two in a mixed population): each agent acts on its own
/// observation (one acceleration), its trajectory ends when it leaves (terminal, with its exit bonus) or at the
/// horizon (truncated, bootstrapped from its last observation). `observe` sees the environment after the reset
/// and after every step (traces).
pub fn run_agents_episode<'m>(
    env: &mut DistributedEnv,
    policy_of: &dyn Fn(VehicleId) -> &'m Model,
    scratch: &mut Scratch,
    settings: EpisodeSettings,
    observe: &mut dyn FnMut(&DistributedEnv) -> Result<(), RlError>,
) -> Result<AgentsEpisode, RlError> {
    let EpisodeSettings {
        env_seed,
        noise_seed,
        horizon,
        mode,
        record,
    } = settings;
    if horizon > env.horizon() {
        return Err(RlError::Config(format!(
            "episodes of {horizon} steps on a scenario of {} steps",
            env.horizon()
        )));
    }
    let mut rng = Rng::new(noise_seed);
    let mut out = AgentsEpisode::default();
    // trajectory index of each agent with an open (or closed) trajectory
    let mut index: std::collections::HashMap<VehicleId, usize> = Default::default();
    let mut obs = env.reset(env_seed)?;
    observe(env)?;
    let mut actions: Vec<(VehicleId, f32)> = Vec::new();
    for _ in 0..horizon {
        actions.clear();
        for (id, o) in &obs {
            let po = policy_of(*id).infer(o, scratch);
            let action = action_of(&po.mean, &po.log_std, mode, &mut rng);
            if record {
                let k = *index.entry(*id).or_insert_with(|| {
                    out.trajectories.push(Episode::default());
                    out.agents.push(*id);
                    out.trajectories.len() - 1
                });
                out.trajectories[k].record_step(o, &action, &po);
            }
            actions.push((*id, action.first().copied().unwrap_or(0.0)));
        }
        out.agent_steps += actions.len() as u64;
        let st = env.step(&actions)?;
        observe(env)?;
        for &(id, r, done) in &st.rewards {
            out.total_reward += r as f64;
            if let Some(&k) = index.get(&id) {
                let e = &mut out.trajectories[k];
                e.rewards.push(r);
                if done {
                    e.end = Some(EpisodeEnd::Terminal);
                }
            }
        }
        obs = st.obs;
    }
    if record {
        // agents still driving at the horizon: bootstrapped from their last observation
        let last: std::collections::HashMap<VehicleId, &Vec<f32>> =
            obs.iter().map(|(id, o)| (*id, o)).collect();
        let mut open: Vec<(VehicleId, usize)> = index
            .iter()
            .filter(|&(_, &k)| out.trajectories[k].end.is_none())
            .map(|(&id, &k)| (id, k))
            .collect();
        open.sort_unstable_by_key(|&(_, k)| k);
        for (id, k) in open {
            let bootstrap_value = last
                .get(&id)
                .map_or(0.0, |o| policy_of(id).value(o, scratch));
            out.trajectories[k].end = Some(EpisodeEnd::Truncated { bootstrap_value });
        }
    }
    out.metrics = env.metrics();
    Ok(out)
}

/// Builds one distributed environment per worker.
pub type AgentsEnvFactory<'a> = dyn Fn() -> DistributedEnv + Sync + 'a;

/// Runs one distributed episode per `(env_seed, noise_seed)` pair in parallel, returned in input order.
pub fn collect_agents(
    factory: &AgentsEnvFactory,
    model: &Model,
    seeds: &[(u64, u64)],
    horizon: usize,
    mode: ActionMode,
    record: bool,
) -> Result<Vec<AgentsEpisode>, RlError> {
    collect_agents_with(factory, &|_| model, seeds, horizon, mode, record)
}

/// [`collect_agents`] with each agent's model chosen by `policy_of(agent)`.
pub fn collect_agents_with<'m>(
    factory: &AgentsEnvFactory,
    policy_of: &(dyn Fn(VehicleId) -> &'m Model + Sync),
    seeds: &[(u64, u64)],
    horizon: usize,
    mode: ActionMode,
    record: bool,
) -> Result<Vec<AgentsEpisode>, RlError> {
    over_seeds(
        factory,
        seeds,
        horizon,
        mode,
        record,
        |env, scratch, settings| {
            run_agents_episode(env, policy_of, scratch, settings, &mut |_| Ok(()))
        },
    )
}
