//! The several-window environment on the shipped I-696 scenarios.

use super::*;
use crate::checkpoint::Checkpoint;
use crate::env::merge::{MergeEnv, RewardKind};
use crate::rollout::{ActionMode, Env};
use std::collections::{HashMap, HashSet};
use std::path::Path;

fn root() -> std::path::PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../..")
}

fn spec_of(scenario: mapc_scenario::ResolvedScenario) -> SimSpec {
    mapc_sim::spec_from_scenario(&scenario).unwrap()
}

fn load(file: &str) -> mapc_scenario::ResolvedScenario {
    mapc_scenario::ResolvedScenario::load(root().join(file).to_str().unwrap()).unwrap()
}

/// Every step: no AV in two windows' FIFOs, each controlled AV on a road of its window, none controlled again
/// by a window it has left; AVs pass from one window's control to the next.
#[test]
fn each_av_has_one_controller_and_none_after_leaving() {
    let spec = spec_of(load("scenarios/i696_3merge.toml"));
    assert_eq!(spec.control_windows.len(), 3);
    let mut env = WindowsEnv::new(spec, MergeEnvConfig::paper(RewardKind::Outflow, 5)).unwrap();
    env.reset(3).unwrap();
    let mut controlled_by: HashMap<VehicleId, HashSet<usize>> = HashMap::new();
    let mut left: HashSet<(usize, VehicleId)> = HashSet::new();
    let mut before: Vec<Vec<VehicleId>> = vec![Vec::new(); 3];
    for step in 0..1200 {
        let sim = env.simulation().unwrap();
        let mut owner: HashMap<VehicleId, usize> = HashMap::new();
        for (k, w) in env.windows.iter().enumerate() {
            assert!(w.controlled.len() <= 5);
            for &id in &w.controlled {
                assert!(
                    owner.insert(id, k).is_none(),
                    "step {step}: AV {id} in two windows"
                );
                assert!(
                    !left.contains(&(k, id)),
                    "step {step}: AV {id} back under window {k}"
                );
                let v = sim.vehicle(id).unwrap();
                assert!(
                    w.contains(v.road, v.in_junction),
                    "step {step}: AV {id} outside window {k}"
                );
                controlled_by.entry(id).or_default().insert(k);
            }
            // An AV that dropped out of the FIFO without being on the window's roads has left it.
            for &id in &before[k] {
                let inside = sim.vehicle(id).is_some_and(|v| {
                    v.status == mapc_sim::VehicleStatus::Active && w.contains(v.road, v.in_junction)
                });
                if !inside {
                    left.insert((k, id));
                }
            }
            before[k] = w.controlled.clone();
        }
        let actions: Vec<Option<Vec<f32>>> = (0..3).map(|_| Some(vec![0.5; 5])).collect();
        env.step(&actions).unwrap();
    }
    let per_window: Vec<usize> = (0..3)
        .map(|k| controlled_by.values().filter(|s| s.contains(&k)).count())
        .collect();
    assert!(per_window.iter().all(|&n| n > 0), "{per_window:?}");
    assert!(
        controlled_by.values().any(|s| s.len() > 1),
        "no AV was handed from one window to the next"
    );
    assert!(!left.is_empty());
}

/// A one-window scenario in the `[[control.windows]]` form drives exactly as the single-window environment:
/// the same FIFO and observation, hence the same episode.
#[test]
fn one_window_in_the_windows_form_is_the_single_window_env() {
    let single = load("scenarios/i696_window.toml");
    let mut scenario = single.scenario.clone();
    let control = scenario.control.as_mut().unwrap();
    let window = control.window.take().unwrap();
    control.windows = vec![mapc_scenario::ControlWindow {
        junction: window.junction,
        joined: vec![],
        matched_to: window.matched_to,
        upstream_m: window.upstream_m,
        merge_m: window.merge_m,
        downstream_m: window.downstream_m,
        region: std::mem::take(&mut control.region),
    }];
    let as_windows =
        mapc_scenario::ResolvedScenario::resolve(scenario, &root().join("scenarios"), "w.toml")
            .unwrap();
    assert_eq!(as_windows.region_roads, single.region_roads);
    let ck = Checkpoint::load(&root().join("policies/simple_merge_outflow.json")).unwrap();
    let cfg = crate::eval::env_config_for(&ck, Path::new("p"), "s", Some(5)).unwrap();
    let horizon = 700;
    for seed in [1, 2] {
        let mut merge = MergeEnv::new(spec_of(single.clone()), cfg.clone()).unwrap();
        let mut scratch = crate::ppo::tensor::Scratch::default();
        let settings = crate::rollout::EpisodeSettings {
            env_seed: seed,
            noise_seed: 9,
            horizon,
            mode: ActionMode::Mean,
            record: false,
        };
        let a = crate::rollout::run_episode(&mut merge, &ck.state.model, &mut scratch, settings)
            .unwrap();
        let mut windows = WindowsEnv::new(spec_of(as_windows.clone()), cfg.clone()).unwrap();
        let b = crate::eval_windows::run_windows_episode(
            &mut windows,
            &ck.state.model,
            &mut scratch,
            settings,
            &mut |_| Ok(()),
        )
        .unwrap();
        assert_eq!(a.metrics, b.metrics, "seed {seed}");
        assert_eq!(merge.metrics(), b.metrics);
    }
}

/// The humans' figures with the merge counter are the simulator's baseline; the flow past the paper's merge is
/// at most the corridor's inflow.
#[test]
fn human_windows_episode_is_the_baseline() {
    let spec = crate::eval::human_spec(&spec_of(load("scenarios/i696_3merge.toml")));
    let base = mapc_sim::run_baseline_spec(&spec, &[4]).unwrap();
    let with_flows = human_windows_episode(&spec, 4).unwrap();
    assert_eq!(with_flows.metrics, EpisodeMetrics::from(&base[0]));
    assert_eq!(with_flows.merge_flows.len(), 3);
    for f in &with_flows.merge_flows {
        assert!(
            *f > 500.0 && *f <= with_flows.metrics.inflow,
            "{with_flows:?}"
        );
    }
}

/// On a scenario with a warm-up, an episode of `horizon()` steps runs the warm-up and the whole measured horizon:
/// with no action its AVs drive as humans, so the flows past the merges are the humans' (within a quarter; the
/// AVs' FIFOs are the only difference). (Stopping after
/// `horizon_steps` measured only what was left of the horizon after the warm-up, and the flows past the merges,
/// divided by the whole horizon, came out ten times too low on a window with a 900 s warm-up.)
#[test]
fn an_episode_runs_the_warm_up_and_the_whole_horizon() {
    let mut spec = spec_of(load("scenarios/i696_3merge.toml"));
    spec.warmup_steps = 400;
    spec.horizon_steps = 600;
    let humans = human_windows_episode(&crate::eval::human_spec(&spec), 2).unwrap();
    let mut env = WindowsEnv::new(spec, MergeEnvConfig::paper(RewardKind::Outflow, 5)).unwrap();
    assert_eq!(env.horizon(), 1000);
    env.reset(2).unwrap();
    let none = vec![None; env.window_count()];
    for _ in 0..env.horizon() {
        env.step(&none).unwrap();
    }
    assert!(env.simulation().unwrap().is_done());
    let ran = env.metrics();
    assert_eq!(ran.merge_flows.len(), humans.merge_flows.len());
    for (f, h) in ran.merge_flows.iter().zip(&humans.merge_flows) {
        assert!(
            *h > 0.0 && (f - h).abs() <= 0.25 * h,
            "{ran:?} against {humans:?}"
        );
    }
}
