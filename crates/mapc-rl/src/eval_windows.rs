//! A policy's episode on a several-window scenario: one centralized policy drives every window's AVs, each
//! window's observation its own. The evaluation (`eval.rs`) runs it per seed and reads the simulation's
//! measurement, as for any other run; [`CentralizedEnv`] lets it run a centralized policy's one region and its
//! several windows with the same code.

use mapc_sim::{SimSpec, Simulation};

use crate::env::EpisodeMetrics;
use crate::env::merge::{MergeEnv, MergeEnvConfig};
use crate::env::windows::WindowsEnv;
use crate::error::RlError;
use crate::ppo::tensor::{Model, Scratch};
use crate::rng::Rng;
use crate::rollout::{EpisodeSettings, action_of, run_episode_observed};

/// Where a centralized policy drives: one control region ([`MergeEnv`]) or several windows ([`WindowsEnv`]).
pub trait CentralizedEnv: Sized {
    fn build(spec: SimSpec, cfg: MergeEnvConfig) -> Result<Self, RlError>;
    /// Policy steps of an episode (the measured horizon after the warm-up).
    fn episode_steps(&self) -> usize;
    /// The simulation of the current episode (none before the first reset).
    fn sim(&self) -> Option<&Simulation>;
    /// One episode of `model`, `observe` seeing the environment after the reset and after every step.
    fn run_policy_episode(
        &mut self,
        model: &Model,
        scratch: &mut Scratch,
        settings: EpisodeSettings,
        observe: &mut dyn FnMut(&Self) -> Result<(), RlError>,
    ) -> Result<EpisodeMetrics, RlError>;
}

impl CentralizedEnv for MergeEnv {
    fn build(spec: SimSpec, cfg: MergeEnvConfig) -> Result<Self, RlError> {
        MergeEnv::new(spec, cfg)
    }
    fn episode_steps(&self) -> usize {
        self.horizon()
    }
    fn sim(&self) -> Option<&Simulation> {
        self.simulation()
    }
    fn run_policy_episode(
        &mut self,
        model: &Model,
        scratch: &mut Scratch,
        settings: EpisodeSettings,
        observe: &mut dyn FnMut(&Self) -> Result<(), RlError>,
    ) -> Result<EpisodeMetrics, RlError> {
        Ok(run_episode_observed(self, model, scratch, settings, observe)?.metrics)
    }
}

impl CentralizedEnv for WindowsEnv {
    fn build(spec: SimSpec, cfg: MergeEnvConfig) -> Result<Self, RlError> {
        WindowsEnv::new(spec, cfg)
    }
    fn episode_steps(&self) -> usize {
        self.horizon()
    }
    fn sim(&self) -> Option<&Simulation> {
        self.simulation()
    }
    fn run_policy_episode(
        &mut self,
        model: &Model,
        scratch: &mut Scratch,
        settings: EpisodeSettings,
        observe: &mut dyn FnMut(&Self) -> Result<(), RlError>,
    ) -> Result<EpisodeMetrics, RlError> {
        run_windows_episode(self, model, scratch, settings, observe)
    }
}

/// One window episode: every step, each window with controlled AVs acts on its own observation (a window
/// without one skips inference: its action would drive nobody). `observe` sees the environment after the reset
/// and after every step (traces).
pub fn run_windows_episode(
    env: &mut WindowsEnv,
    model: &Model,
    scratch: &mut Scratch,
    settings: EpisodeSettings,
    observe: &mut dyn FnMut(&WindowsEnv) -> Result<(), RlError>,
) -> Result<EpisodeMetrics, RlError> {
    let mut rng = Rng::new(settings.noise_seed);
    let mut obs: Vec<Vec<f32>> = env.reset(settings.env_seed)?.to_vec();
    observe(env)?;
    let mut actions: Vec<Option<Vec<f32>>> = vec![None; env.window_count()];
    for _ in 0..settings.horizon {
        for (k, o) in obs.iter().enumerate() {
            actions[k] = (!env.controlled(k).is_empty()).then(|| {
                let dist = model.action_dist(o, scratch);
                action_of(&dist.mean, &dist.log_std, settings.mode, &mut rng)
            });
        }
        let next = env.step(&actions)?;
        obs.iter_mut().zip(next).for_each(|(o, n)| o.clone_from(n));
        observe(env)?;
    }
    Ok(env.metrics())
}
