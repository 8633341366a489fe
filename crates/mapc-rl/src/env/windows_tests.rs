//! The several-window environment on the shipped I-696 scenarios.

use super::*;
use crate::checkpoint::Checkpoint;
use crate::env::Env;
use crate::env::merge::{MergeEnv, RewardKind};
use crate::rollout::ActionMode;
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
        assert_eq!(a.metrics, b, "seed {seed}");
        assert_eq!(merge.metrics(), b);
    }
}

/// Per vehicle, with merge_robust driving J43's window and a warm-up: every passage of a measured merge the test
/// sees (a vehicle seen on the road after the merge, having been seen on another road before) is one the
/// simulation counted, after the warm-up exactly when the test saw it then; so a vehicle counted at the
/// corridor's end was counted at every merge it passed in the measured time. The episode is the whole
/// simulation, and its flows are those passages.
#[test]
fn every_vehicle_counted_at_the_end_was_counted_at_the_merges_it_passed() {
    let mut spec = spec_of(load("scenarios/i696_all_windows.toml"));
    spec.warmup_steps = 400;
    spec.horizon_steps = 1200;
    let ck = Checkpoint::load(&root().join("policies/merge_robust.json")).unwrap();
    let cfg = crate::eval::env_config_for(&ck, Path::new("p"), "s", Some(5)).unwrap();
    let mut env = WindowsEnv::new(spec.clone(), cfg).unwrap();
    let mut scratch = crate::ppo::tensor::Scratch::default();
    let mut obs = env.reset(0).unwrap().to_vec();
    env.sim.as_mut().unwrap().record_passages();
    let point_of: HashMap<RoadId, usize> = spec
        .measure_points
        .iter()
        .enumerate()
        .flat_map(|(k, p)| p.roads.iter().map(move |&r| (r, k)))
        .collect();
    let mut last_road: HashMap<VehicleId, RoadId> = HashMap::new();
    // (vehicle, point) -> passed after the warm-up
    let mut seen: HashMap<(VehicleId, usize), bool> = HashMap::new();
    for _ in 0..env.horizon() {
        let measuring = !env.simulation().unwrap().in_warmup();
        let actions: Vec<Option<Vec<f32>>> = obs
            .iter()
            .enumerate()
            .map(|(k, o)| {
                (!env.controlled(k).is_empty()).then(|| ck.state.model.infer(o, &mut scratch).mean)
            })
            .collect();
        obs = env.step(&actions).unwrap().to_vec();
        let sim = env.simulation().unwrap();
        for id in sim.active_ids() {
            let v = sim.vehicle(id).unwrap();
            if v.in_junction {
                continue;
            }
            if let Some(before) = last_road.insert(id, v.road)
                && before != v.road
                && let Some(&k) = point_of.get(&v.road)
            {
                seen.insert((id, k), measuring);
            }
        }
    }
    let sim = env.simulation().unwrap();
    assert!(sim.is_done());
    let m = sim.metrics();
    assert_eq!(m.steps, spec.horizon_steps);
    let passages = sim.passages();
    let secs = spec.horizon_steps as f64 * spec.step_s;
    for k in 0..spec.measure_points.len() {
        let n = passages
            .iter()
            .filter(|p| p.counted && p.point == Some(k))
            .count();
        assert_eq!(
            m.merge_flows_veh_h[k],
            3600.0 * n as f64 / secs,
            "point {k}"
        );
    }
    let at_end: HashSet<VehicleId> = passages
        .iter()
        .filter(|p| p.counted && p.point.is_none())
        .map(|p| p.vehicle)
        .collect();
    assert_eq!(m.end_flow_veh_h, 3600.0 * at_end.len() as f64 / secs);
    let kept: HashSet<(VehicleId, usize, bool)> = passages
        .iter()
        .filter_map(|p| Some((p.vehicle, p.point?, p.counted)))
        .collect();
    assert_eq!(kept.len(), seen.len());
    for (&(id, k), &measuring) in &seen {
        assert!(
            kept.contains(&(id, k, measuring)),
            "vehicle {id} (counted at the end: {}) passed point {k} (after the warm-up: {measuring})",
            at_end.contains(&id)
        );
    }
    // nearly everything leaving at the end came through the last window's merge (R72 joins after it)
    let j60 = spec
        .measure_points
        .iter()
        .position(|p| p.name.starts_with("merge J60 "))
        .unwrap();
    let through = at_end
        .iter()
        .filter(|&&id| seen.contains_key(&(id, j60)))
        .count();
    assert!(
        4 * through > 3 * at_end.len(),
        "{through} of {}",
        at_end.len()
    );
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
    let humans = mapc_sim::Simulation::from_spec(spec.all_human(), 2)
        .unwrap()
        .run()
        .unwrap();
    let mut env = WindowsEnv::new(spec, MergeEnvConfig::paper(RewardKind::Outflow, 5)).unwrap();
    assert_eq!(env.horizon(), 1000);
    env.reset(2).unwrap();
    let none = vec![None; env.window_count()];
    for _ in 0..env.horizon() {
        env.step(&none).unwrap();
    }
    assert!(env.simulation().unwrap().is_done());
    let ran = env.simulation().unwrap().metrics();
    assert_eq!(ran.merge_flows_veh_h.len(), humans.merge_flows_veh_h.len());
    for (f, h) in ran.merge_flows_veh_h.iter().zip(&humans.merge_flows_veh_h) {
        assert!(
            *h > 0.0 && (f - h).abs() <= 0.25 * h,
            "{ran:?} against {humans:?}"
        );
    }
}
