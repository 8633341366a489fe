//! Evaluation on a several-window scenario: one centralized policy drives every window's AVs (each window's
//! observation its own), and the flow past every window's merge is reported beside the corridor's figures,
//! against the humans on the same seeds.

use rayon::prelude::*;
use serde::{Deserialize, Serialize};

use mapc_sim::{MeanCi, SimSpec};

use crate::env::merge::MergeEnvConfig;
use crate::env::windows::{MergeFlowCounter, WindowsEnv, WindowsMetrics, human_windows_episode};
use crate::error::RlError;
use crate::eval::{Figure, human_spec};
use crate::ppo::tensor::{Model, Scratch};
use crate::rng::Rng;
use crate::rollout::{EpisodeSettings, action_of};
use crate::stats::{WelchTest, welch_t_test};

/// One window episode: every step, each window with controlled AVs acts on its own observation (a window
/// without one skips inference: its action would drive nobody). `observe` sees the environment after the reset
/// and after every step (traces).
pub fn run_windows_episode(
    env: &mut WindowsEnv,
    model: &Model,
    scratch: &mut Scratch,
    settings: EpisodeSettings,
    observe: &mut dyn FnMut(&WindowsEnv) -> Result<(), RlError>,
) -> Result<WindowsMetrics, RlError> {
    let mut rng = Rng::new(settings.noise_seed);
    let mut obs: Vec<Vec<f32>> = env.reset(settings.env_seed)?.to_vec();
    observe(env)?;
    let mut actions: Vec<Option<Vec<f32>>> = vec![None; env.window_count()];
    for _ in 0..settings.horizon {
        for (k, o) in obs.iter().enumerate() {
            actions[k] = (!env.controlled(k).is_empty()).then(|| {
                let out = model.infer(o, scratch);
                action_of(&out.mean, &out.log_std, settings.mode, &mut rng)
            });
        }
        let next = env.step(&actions)?;
        obs.iter_mut().zip(next).for_each(|(o, n)| o.clone_from(n));
        observe(env)?;
    }
    Ok(env.metrics())
}

/// The policy on every window of `spec` for each seed (in parallel, results in seed order).
pub fn run_windows_policy(
    model: &Model,
    spec: &SimSpec,
    cfg: &MergeEnvConfig,
    seeds: &[(u64, u64)],
    mode: crate::rollout::ActionMode,
) -> Result<Vec<WindowsMetrics>, RlError> {
    let probe = WindowsEnv::new(spec.clone(), cfg.clone())?;
    let horizon = probe.horizon();
    seeds
        .par_iter()
        .map_init(
            || {
                (
                    WindowsEnv::new(spec.clone(), cfg.clone()).expect("validated above"),
                    Scratch::default(),
                )
            },
            |(env, scratch), &(env_seed, noise_seed)| {
                let settings = EpisodeSettings {
                    env_seed,
                    noise_seed,
                    horizon,
                    mode,
                    record: false,
                };
                run_windows_episode(env, model, scratch, settings, &mut |_| Ok(()))
            },
        )
        .collect()
}

/// The humans on `spec` (every AV driving as one) for each seed, with the flows past the merges.
pub fn run_human_windows(spec: &SimSpec, seeds: &[u64]) -> Result<Vec<WindowsMetrics>, RlError> {
    let human = human_spec(spec);
    seeds
        .par_iter()
        .map(|&seed| human_windows_episode(&human, seed))
        .collect()
}

/// The flow past one merge of a window: the policy's, the humans', and the Welch test of the difference.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct MergeFlowReport {
    /// The window (its first merge, as the scenario names it).
    pub window: String,
    /// The merge junction.
    pub merge: String,
    /// Vehicles past the merge per hour.
    pub flow: Figure,
    pub baseline: Option<Figure>,
    pub welch: Option<WelchTest>,
}

/// Every merge's flow report, in window order.
pub fn merge_flow_reports(
    spec: &SimSpec,
    policy: &[WindowsMetrics],
    baseline: Option<&[WindowsMetrics]>,
) -> Vec<MergeFlowReport> {
    let merges: Vec<(String, String)> = spec
        .control_windows
        .iter()
        .flat_map(|w| w.merges.iter().map(|j| (w.name.clone(), j.to_string())))
        .collect();
    let column = |runs: &[WindowsMetrics], k: usize| -> Vec<f64> {
        runs.iter().map(|r| r.merge_flows[k]).collect()
    };
    debug_assert_eq!(merges.len(), MergeFlowCounter::merges_of(spec).len());
    merges
        .into_iter()
        .enumerate()
        .map(|(k, (window, merge))| {
            let p = column(policy, k);
            let b = baseline.map(|b| column(b, k));
            MergeFlowReport {
                window,
                merge,
                flow: MeanCi::of(&p).into(),
                baseline: b.as_ref().map(|b| MeanCi::of(b).into()),
                welch: b.as_ref().and_then(|b| welch_t_test(&p, b)),
            }
        })
        .collect()
}
