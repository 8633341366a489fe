//! Trains on a scenario with the `fast` preset, writing a run directory (as `mapc train` does, without the
//! progress bar): `cargo run -p mapc-rl --example train_merge -- SCENARIO REWARD ITERS OUT_DIR [SEED]`.

use mapc_rl::PpoConfig;
use mapc_rl::checkpoint::PolicySpec;
use mapc_rl::env::merge::{
    ACCEL_MAX, ACCEL_MIN, MergeEnv, MergeEnvConfig, RewardKind, SIMPLE_MERGE_NORM,
};
use mapc_rl::env::obs::PER_AV;
use mapc_rl::rollout::Env;
use mapc_rl::run::TrainRun;

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let a: Vec<String> = std::env::args().collect();
    let scenario = a.get(1).map_or("simple_merge", |s| s.as_str());
    let reward: RewardKind = a.get(2).map_or("outflow", |s| s.as_str()).parse()?;
    let iters: u64 = a.get(3).map_or(Ok(150), |s| s.parse())?;
    let out = std::path::PathBuf::from(
        a.get(4)
            .cloned()
            .unwrap_or_else(|| format!("out/train-{}", reward.name())),
    );
    let seed: u64 = a.get(5).map_or(Ok(0), |s| s.parse())?;
    let resolved = mapc_scenario::ResolvedScenario::load(scenario)?;
    let spec = mapc_sim::spec_from_scenario(&resolved)?;
    let n_av = resolved
        .scenario
        .control
        .as_ref()
        .map_or(5, |c| c.n_av as usize);
    let cfg = MergeEnvConfig {
        reward,
        n_av,
        norm: SIMPLE_MERGE_NORM,
        accel_min: ACCEL_MIN,
        accel_max: ACCEL_MAX,
    };
    let mut run = if mapc_rl::checkpoint::checkpoint_path(&out).exists() {
        let mut r = TrainRun::resume(&out, 5)?;
        r.state.config.iterations = iters;
        r
    } else {
        let pspec = PolicySpec {
            scenario: scenario.into(),
            reward: reward.name().into(),
            n_av,
            obs_dim: PER_AV * n_av,
            act_dim: n_av,
            max_speed: SIMPLE_MERGE_NORM.max_speed,
            norm_length: SIMPLE_MERGE_NORM.length,
            accel_min: ACCEL_MIN,
            accel_max: ACCEL_MAX,
        };
        let config = PpoConfig {
            iterations: iters,
            seed,
            horizon: spec.horizon_steps as usize,
            ..PpoConfig::fast()
        };
        TrainRun::create(&out, pspec, config, 5)?
    };
    let factory = move || -> Box<dyn Env> {
        Box::new(MergeEnv::new(spec.clone(), cfg.clone()).expect("valid spec"))
    };
    while !run.done() {
        let s = run.step(&factory)?;
        println!(
            "it {:4} steps {:8} wall {:7.1}s return {:8.3} outflow {:7.1} speed {:5.2} kl {:.4} ent {:.3} vf {:.3}",
            s.iteration,
            s.env_steps,
            s.wall_s,
            s.mean_return,
            s.mean_outflow,
            s.mean_speed,
            s.kl,
            s.entropy,
            s.value_loss
        );
    }
    run.save()?;
    Ok(())
}
