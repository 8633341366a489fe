//! The environments and the policy as Python classes. Arrays cross as little-endian `float32` bytes.

use crate::{load_scenario, mapc_error};
use mapc_rl::Checkpoint;
use mapc_rl::RlError;
use mapc_rl::env::Env as _;
use mapc_rl::env::distributed::{AgentReward, DistributedConfig, DistributedEnv, Features};
use mapc_rl::env::merge::{MergeEnv, MergeEnvConfig, RewardKind};
use mapc_rl::ppo::tensor::Scratch;
use pyo3::prelude::*;
use pyo3::types::PyBytes;
use rayon::prelude::*;
use std::path::PathBuf;

fn to_bytes<'py>(py: Python<'py>, xs: &[f32]) -> Bound<'py, PyBytes> {
    let mut out = Vec::with_capacity(std::mem::size_of_val(xs));
    for x in xs {
        out.extend_from_slice(&x.to_le_bytes());
    }
    PyBytes::new(py, &out)
}

fn from_bytes(bytes: &[u8], want: usize, what: &str) -> PyResult<Vec<f32>> {
    if bytes.len() != 4 * want {
        return Err(mapc_error(format!(
            "{what}: {} bytes where {want} float32 values ({} bytes) were expected",
            bytes.len(),
            4 * want
        )));
    }
    Ok(bytes
        .chunks_exact(4)
        .map(|c| f32::from_le_bytes([c[0], c[1], c[2], c[3]]))
        .collect())
}

/// A sub-environment's step: observation, reward, truncated, and for an episode that ended its seed, metrics
/// and last observation.
type Stepped = (
    Vec<f32>,
    f32,
    bool,
    Option<(u64, (f64, f64, f64), Vec<f32>)>,
);

/// One episode's state in an environment: the mapc environment and its step count.
struct Episode {
    env: MergeEnv,
    steps: usize,
    started: bool,
}

impl Episode {
    fn new(scenario: &str, reward: &str, n_av: Option<usize>) -> PyResult<(Episode, String)> {
        let (resolved, spec) = load_scenario(scenario)?;
        let reward: RewardKind = reward.parse().map_err(mapc_error)?;
        let n_av = n_av
            .or(resolved.scenario.control.as_ref().map(|c| c.n_av as usize))
            .unwrap_or(5);
        let env = MergeEnv::new(spec, MergeEnvConfig::paper(reward, n_av)).map_err(mapc_error)?;
        Ok((
            Episode {
                env,
                steps: 0,
                started: false,
            },
            resolved.origin,
        ))
    }

    fn reset(&mut self, seed: u64) -> PyResult<Vec<f32>> {
        let obs = self.env.reset(seed).map_err(mapc_error)?;
        self.steps = 0;
        self.started = true;
        Ok(obs)
    }

    /// One step; `truncated` once the episode (the scenario's warm-up and horizon) is over (it has no other end).
    /// An error is a message (the vector env says which sub-environment it came from).
    fn step(&mut self, action: &[f32]) -> Result<(Vec<f32>, f32, bool), String> {
        if !self.started {
            return Err("step before reset: call reset(seed) first".into());
        }
        if self.steps >= self.env.horizon() {
            return Err("step after the episode's end: call reset(seed) for a new episode".into());
        }
        let tr = self.env.try_step(action).map_err(|e| e.to_string())?;
        self.steps += 1;
        Ok((tr.obs, tr.reward, self.steps >= self.env.horizon()))
    }

    fn metrics(&self) -> (f64, f64, f64) {
        if !self.started {
            return (0.0, 0.0, 0.0);
        }
        let m = self.env.metrics();
        (m.outflow, m.inflow, m.speed)
    }
}

/// The centralized merge-control environment (docs/reference.md sec. 5) on one scenario.
#[pyclass(module = "mapc._mapc")]
pub struct Env {
    episode: Episode,
    #[pyo3(get)]
    scenario: String,
}

#[pymethods]
impl Env {
    #[new]
    #[pyo3(signature = (scenario = "simple_merge", reward = "outflow", n_av = None))]
    fn new(scenario: &str, reward: &str, n_av: Option<usize>) -> PyResult<Self> {
        let (episode, origin) = Episode::new(scenario, reward, n_av)?;
        Ok(Env {
            episode,
            scenario: origin,
        })
    }
    #[getter]
    fn obs_dim(&self) -> usize {
        self.episode.env.obs_dim()
    }
    #[getter]
    fn act_dim(&self) -> usize {
        self.episode.env.act_dim()
    }
    #[getter]
    fn horizon(&self) -> usize {
        self.episode.env.horizon()
    }
    /// (lowest, highest) acceleration, m/s²: actions are clipped to them.
    #[getter]
    fn action_bounds(&self) -> (f64, f64) {
        let c = self.episode.env.config();
        (c.accel_min, c.accel_max)
    }
    /// Start the episode of `seed`; returns the observation.
    fn reset<'py>(&mut self, py: Python<'py>, seed: u64) -> PyResult<Bound<'py, PyBytes>> {
        let obs = self.episode.reset(seed)?;
        Ok(to_bytes(py, &obs))
    }
    /// Apply one acceleration per controlled AV; returns (observation, reward, truncated).
    fn step<'py>(
        &mut self,
        py: Python<'py>,
        action: &[u8],
    ) -> PyResult<(Bound<'py, PyBytes>, f32, bool)> {
        let action = from_bytes(action, self.episode.env.act_dim(), "action")?;
        let (obs, reward, truncated) = self.episode.step(&action).map_err(mapc_error)?;
        Ok((to_bytes(py, &obs), reward, truncated))
    }
    /// (outflow veh/h, inflow veh/h, mean speed m/s) of the episode so far, as `mapc sim` defines them.
    fn metrics(&self) -> (f64, f64, f64) {
        self.episode.metrics()
    }
}

/// K centralized environments stepped together in Rust threads. A sub-environment whose episode ended resets in
/// the next step (the action given to it then is ignored, its reward is 0), or with `same_step` in the step that
/// ended it (its observation is then the new episode's first, the last one is returned beside it).
#[pyclass(module = "mapc._mapc")]
pub struct VecEnv {
    episodes: Vec<Episode>,
    /// Seed of each sub-environment's current episode; the next one is this plus the number of environments.
    seeds: Vec<u64>,
    needs_reset: Vec<bool>,
    same_step: bool,
    #[pyo3(get)]
    scenario: String,
}

#[pymethods]
impl VecEnv {
    #[new]
    #[pyo3(signature = (scenario = "simple_merge", num_envs = 4, reward = "outflow", n_av = None, same_step = false))]
    fn new(
        scenario: &str,
        num_envs: usize,
        reward: &str,
        n_av: Option<usize>,
        same_step: bool,
    ) -> PyResult<Self> {
        if num_envs == 0 {
            return Err(mapc_error("num_envs must be at least 1"));
        }
        let (first, origin) = Episode::new(scenario, reward, n_av)?;
        let mut episodes = vec![first];
        for _ in 1..num_envs {
            episodes.push(Episode::new(scenario, reward, n_av)?.0);
        }
        Ok(VecEnv {
            episodes,
            seeds: vec![0; num_envs],
            needs_reset: vec![false; num_envs],
            same_step,
            scenario: origin,
        })
    }
    #[getter]
    fn num_envs(&self) -> usize {
        self.episodes.len()
    }
    #[getter]
    fn obs_dim(&self) -> usize {
        self.episodes[0].env.obs_dim()
    }
    #[getter]
    fn act_dim(&self) -> usize {
        self.episodes[0].env.act_dim()
    }
    #[getter]
    fn horizon(&self) -> usize {
        self.episodes[0].env.horizon()
    }
    /// Reset every sub-environment: the k-th runs the episode of `seed + k`. Returns the K observations.
    fn reset<'py>(&mut self, py: Python<'py>, seed: u64) -> PyResult<Bound<'py, PyBytes>> {
        let n = self.episodes.len() as u64;
        self.seeds = (seed..seed + n).collect();
        self.needs_reset.iter_mut().for_each(|r| *r = false);
        let obs: Vec<Vec<f32>> = py
            .detach(|| {
                self.episodes
                    .par_iter_mut()
                    .zip(&self.seeds)
                    .map(|(e, &s)| e.reset(s).map_err(|e| e.to_string()))
                    .collect::<Result<_, String>>()
            })
            .map_err(mapc_error)?;
        Ok(to_bytes(py, &obs.concat()))
    }
    /// One step of every sub-environment (K x act_dim actions). Returns (observations, rewards, truncated,
    /// finished) where `finished` lists (index, seed, outflow, inflow, speed, last observation) of the episodes
    /// that ended now.
    #[allow(clippy::type_complexity)]
    fn step<'py>(
        &mut self,
        py: Python<'py>,
        actions: &[u8],
    ) -> PyResult<(
        Bound<'py, PyBytes>,
        Bound<'py, PyBytes>,
        Vec<bool>,
        Vec<(usize, u64, f64, f64, f64, Bound<'py, PyBytes>)>,
    )> {
        let k = self.episodes.len();
        let act_dim = self.act_dim();
        let actions = from_bytes(actions, k * act_dim, "actions")?;
        if self.episodes.iter().any(|e| !e.started) {
            return Err(mapc_error("step before reset: call reset(seed) first"));
        }
        let n = k as u64;
        let same_step = self.same_step;
        let results: Vec<Stepped> = py.detach(|| {
            self.episodes
                .par_iter_mut()
                .zip(self.seeds.par_iter_mut())
                .zip(self.needs_reset.par_iter())
                .enumerate()
                .map(|(i, ((e, seed), &reset))| {
                    if reset {
                        *seed += n;
                        return e.reset(*seed).map(|obs| (obs, 0.0, false, None));
                    }
                    let (obs, reward, truncated) = e
                        .step(&actions[i * act_dim..(i + 1) * act_dim])
                        .map_err(|msg| mapc_error(format!("sub-environment {i}: {msg}")))?;
                    if !truncated {
                        return Ok((obs, reward, false, None));
                    }
                    let ended = (*seed, e.metrics());
                    if !same_step {
                        return Ok((obs.clone(), reward, true, Some((ended.0, ended.1, obs))));
                    }
                    *seed += n;
                    let first = e.reset(*seed)?;
                    Ok((first, reward, true, Some((ended.0, ended.1, obs))))
                })
                .collect::<PyResult<Vec<_>>>()
        })?;
        let mut obs = Vec::with_capacity(k * self.obs_dim());
        let mut rewards = Vec::with_capacity(k);
        let mut truncated = Vec::with_capacity(k);
        let mut finished = Vec::new();
        for (i, (o, r, t, ended)) in results.into_iter().enumerate() {
            obs.extend_from_slice(&o);
            rewards.push(r);
            truncated.push(t);
            self.needs_reset[i] = t && !same_step;
            if let Some((seed, (outflow, inflow, speed), last)) = ended {
                finished.push((i, seed, outflow, inflow, speed, to_bytes(py, &last)));
            }
        }
        Ok((
            to_bytes(py, &obs),
            to_bytes(py, &rewards),
            truncated,
            finished,
        ))
    }
}

/// A trained policy (a checkpoint file or run directory): its mean action for an observation.
#[pyclass(module = "mapc._mapc")]
pub struct Policy {
    ck: Checkpoint,
    scratch: Scratch,
    #[pyo3(get)]
    path: String,
}

#[pymethods]
impl Policy {
    #[new]
    fn new(path: PathBuf) -> PyResult<Self> {
        let file = mapc_rl::checkpoint::policy_file(&path);
        let ck = Checkpoint::load(&file).map_err(mapc_error)?;
        Ok(Policy {
            ck,
            scratch: Scratch::default(),
            path: file.display().to_string(),
        })
    }
    #[getter]
    fn obs_dim(&self) -> usize {
        self.ck.spec.obs_dim
    }
    #[getter]
    fn act_dim(&self) -> usize {
        self.ck.spec.act_dim
    }
    /// For a distributed policy, the features its agents see (`full`, `dist,congestion`, ...); None for a
    /// centralized one.
    #[getter]
    fn features(&self) -> Option<String> {
        self.ck.spec.distributed.map(|d| d.features.name())
    }
    /// The policy's mean action (what `mapc eval` applies) for one observation: one acceleration per controlled
    /// AV (centralized) or the agent's own (distributed).
    fn act<'py>(&mut self, py: Python<'py>, obs: &[u8]) -> PyResult<Bound<'py, PyBytes>> {
        let obs = from_bytes(obs, self.ck.spec.obs_dim, "observation")?;
        let dist = self.ck.state.model.action_dist(&obs, &mut self.scratch);
        Ok(to_bytes(py, &dist.mean))
    }
}

/// The distributed setting (the paper's section 4.3): every AV in the control region is an agent with its own
/// observation and one acceleration; agents appear as their AVs enter the region and are done when they leave.
#[pyclass(module = "mapc._mapc")]
pub struct DistEnv {
    env: DistributedEnv,
    steps: usize,
    started: bool,
    #[pyo3(get)]
    scenario: String,
    /// The most AVs an episode can hold: the initial AVs and every departure of the AV flows over the horizon.
    #[pyo3(get)]
    max_agents: usize,
}

fn agent_list<'py>(py: Python<'py>, obs: &[(u32, Vec<f32>)]) -> Vec<(u32, Bound<'py, PyBytes>)> {
    obs.iter().map(|(id, o)| (*id, to_bytes(py, o))).collect()
}

#[pymethods]
impl DistEnv {
    #[new]
    #[pyo3(signature = (scenario = "simple_merge", features = "full", eta1 = 0.9, eta2 = 0.1, exit_bonus = 20.0,
                        count_waiting = false, reward_share = 0.0))]
    fn new(
        scenario: &str,
        features: &str,
        eta1: f64,
        eta2: f64,
        exit_bonus: f64,
        count_waiting: bool,
        reward_share: f64,
    ) -> PyResult<Self> {
        let (resolved, spec) = load_scenario(scenario)?;
        let features = Features::parse(features).map_err(mapc_error)?;
        for (name, v) in [("eta1", eta1), ("eta2", eta2), ("exit_bonus", exit_bonus)] {
            if !v.is_finite() {
                return Err(mapc_error(format!("{name} must be a number, got {v}")));
            }
        }
        let reward = AgentReward {
            eta1,
            eta2,
            exit_bonus,
            count_waiting,
            share: reward_share,
        };
        let horizon_s = (spec.warmup_steps + spec.horizon_steps) as f64 * spec.step_s;
        let is_av = |t: usize| spec.vehicle_types[t].controlled;
        let max_agents = spec
            .initial
            .iter()
            .filter(|v| is_av(v.vehicle_type))
            .count()
            + spec
                .flows
                .iter()
                .filter(|f| is_av(f.vehicle_type))
                .map(|f| (f.vehs_per_hour * horizon_s / 3600.0).ceil() as usize + 1)
                .sum::<usize>();
        let env = DistributedEnv::new(spec, DistributedConfig::paper(features, reward))
            .map_err(mapc_error)?;
        Ok(DistEnv {
            env,
            steps: 0,
            started: false,
            scenario: resolved.origin,
            max_agents,
        })
    }
    #[getter]
    fn obs_dim(&self) -> usize {
        self.env.config().obs_dim()
    }
    #[getter]
    fn horizon(&self) -> usize {
        self.env.horizon()
    }
    #[getter]
    fn action_bounds(&self) -> (f64, f64) {
        (self.env.config().accel_min, self.env.config().accel_max)
    }
    /// Start the episode of `seed`; returns (vehicle id, observation) of the agents present, in entry order.
    fn reset<'py>(
        &mut self,
        py: Python<'py>,
        seed: u64,
    ) -> PyResult<Vec<(u32, Bound<'py, PyBytes>)>> {
        let obs = self.env.reset(seed).map_err(mapc_error)?;
        self.steps = 0;
        self.started = true;
        Ok(agent_list(py, &obs))
    }
    /// One step with (vehicle id, acceleration) per agent. Returns the acting agents' (vehicle id, reward,
    /// done), the agents present now with their observations, and whether the horizon is reached.
    #[allow(clippy::type_complexity)]
    fn step<'py>(
        &mut self,
        py: Python<'py>,
        actions: Vec<(u32, f32)>,
    ) -> PyResult<(Vec<(u32, f32, bool)>, Vec<(u32, Bound<'py, PyBytes>)>, bool)> {
        if !self.started {
            return Err(mapc_error("step before reset: call reset(seed) first"));
        }
        if self.steps >= self.env.horizon() {
            return Err(mapc_error(
                "step after the episode's end: call reset(seed) for a new episode",
            ));
        }
        let out = self.env.step(&actions).map_err(|e| {
            let index = match e {
                RlError::Action { index, .. } => Some(index),
                _ => None,
            };
            let err = mapc_error(e);
            // which action was refused, for the PettingZoo wrapper to name the agent
            if let Some(index) = index {
                let _ = err.value(py).setattr("action_index", index);
            }
            err
        })?;
        self.steps += 1;
        Ok((
            out.rewards,
            agent_list(py, &out.obs),
            self.steps >= self.env.horizon(),
        ))
    }
    /// (outflow veh/h, inflow veh/h, mean speed m/s) of the episode so far.
    fn metrics(&self) -> (f64, f64, f64) {
        if !self.started {
            return (0.0, 0.0, 0.0);
        }
        let m = self.env.metrics();
        (m.outflow, m.inflow, m.speed)
    }
}
