//! Actions that are not numbers are refused at the environments' boundary, naming where they were, and leave the
//! episode as it was: the same episode continues with good actions exactly as if the bad step had not been tried.

use super::distributed::{AgentReward, DistributedConfig, DistributedEnv, Features};
use super::merge::{MergeEnv, MergeEnvConfig, RewardKind};
use super::windows::WindowsEnv;
use crate::env::Env as _;
use crate::error::RlError;
use mapc_sim::SimSpec;

fn spec(file: &str) -> SimSpec {
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../..")
        .join(file);
    let rs = mapc_scenario::ResolvedScenario::load(path.to_str().unwrap()).unwrap();
    mapc_sim::spec_from_scenario(&rs).unwrap()
}

const BAD: [f32; 3] = [f32::NAN, f32::INFINITY, f32::NEG_INFINITY];

fn refused_at(e: RlError) -> (usize, String) {
    match e {
        RlError::Action {
            index,
            ref place,
            value,
        } => {
            assert!(!value.is_finite(), "{e}");
            let text = e.to_string();
            assert!(
                text.contains(place) && text.contains("finite acceleration"),
                "{text}"
            );
            (index, text)
        }
        other => panic!("not an action error: {other}"),
    }
}

#[test]
fn the_centralized_env_refuses_a_non_finite_action_and_keeps_its_episode() {
    let cfg = MergeEnvConfig::paper(RewardKind::Outflow, 5);
    let (mut tried, mut plain) = (
        MergeEnv::new(spec("scenarios/simple_merge.toml"), cfg.clone()).unwrap(),
        MergeEnv::new(spec("scenarios/simple_merge.toml"), cfg).unwrap(),
    );
    assert_eq!(tried.reset(3).unwrap(), plain.reset(3).unwrap());
    for t in 0..300usize {
        let good = [1.5f32, -2.0, 0.5, 2.6, -4.5];
        if t % 50 == 10 {
            // the bad value in every slot, padding included: the whole action is refused
            for (slot, bad) in (0..5).zip(BAD.iter().cycle()) {
                let mut action = good;
                action[slot] = *bad;
                let (index, text) = refused_at(tried.try_step(&action).unwrap_err());
                assert_eq!(index, slot);
                assert!(text.starts_with(&format!("action[{slot}] is ")), "{text}");
            }
        }
        let (a, b) = (
            tried.try_step(&good).unwrap(),
            plain.try_step(&good).unwrap(),
        );
        assert_eq!(
            (a.obs, a.reward.to_bits()),
            (b.obs, b.reward.to_bits()),
            "step {t}"
        );
    }
    assert!(!tried.controlled().is_empty());
}

#[test]
fn the_distributed_env_names_the_agent_of_a_non_finite_action() {
    let cfg = DistributedConfig::paper(Features::FULL, AgentReward::PAPER);
    let spec = spec("scenarios/simple_merge.toml");
    let (mut tried, mut plain) = (
        DistributedEnv::new(spec.clone(), cfg).unwrap(),
        DistributedEnv::new(spec, cfg).unwrap(),
    );
    let mut obs = tried.reset(4).unwrap();
    assert_eq!(plain.reset(4).unwrap(), obs);
    let mut refusals = 0;
    for t in 0..600 {
        let good: Vec<(u32, f32)> = obs.iter().map(|(id, _)| (*id, 1.0)).collect();
        if good.len() >= 2 && t % 40 == 0 {
            let mut bad = good.clone();
            bad[1].1 = BAD[refusals % 3];
            let (index, text) = refused_at(tried.step(&bad).unwrap_err());
            assert_eq!(index, 1);
            assert!(
                text.contains(&format!("agent vehicle {} (actions[1])", good[1].0)),
                "{text}"
            );
            refusals += 1;
        }
        let (a, b) = (tried.step(&good).unwrap(), plain.step(&good).unwrap());
        assert_eq!(a.obs, b.obs, "step {t}");
        assert_eq!(a.rewards, b.rewards, "step {t}");
        obs = a.obs;
    }
    assert!(refusals >= 3, "{refusals}");
}

#[test]
fn the_windows_env_names_the_window_and_the_slot() {
    let cfg = MergeEnvConfig::paper(RewardKind::Outflow, 5);
    let spec = spec("scenarios/i696_3merge.toml");
    let mut env = WindowsEnv::new(spec, cfg).unwrap();
    env.reset(1).unwrap();
    let good = Some(vec![0.5f32; 5]);
    let mut actions = vec![good.clone(), None, good];
    actions[2].as_mut().unwrap()[4] = f32::NAN;
    let (index, text) = refused_at(env.step(&actions).unwrap_err());
    assert_eq!(index, 4);
    assert!(text.starts_with("window 2 action[4] is NaN"), "{text}");
}
