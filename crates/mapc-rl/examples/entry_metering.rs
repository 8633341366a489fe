//! What the average-speed metric rewards: hand-made "entry metering" controllers on the Simple Merge.
//!
//! The controlled AVs (FIFO, N_AV = 5, the same control as a policy gets) track a slow target speed until they
//! are `until` metres down the main road, then drive at the speed limit. A slow AV near the entry holds back the
//! vehicles behind it, some of which then cannot be inserted (they wait outside the network and count neither in
//! the inflow nor in the average speed). The sweep shows which (outflow, average speed) pairs are reachable, so a
//! trained policy can be placed against them (docs/results.md).
//!
//!     cargo run --release -p mapc-rl --example entry_metering -- [SEEDS] [SCENARIO]
//!
//! Prints a markdown table: target speed, metering distance, outflow, inflow, average speed (mean ± 95% CI).
use mapc_rl::Env;
use mapc_rl::env::merge::{
    ACCEL_MAX, ACCEL_MIN, MergeEnv, MergeEnvConfig, RewardKind, SIMPLE_MERGE_NORM,
};
use mapc_rl::eval::FigureSet;
use rayon::prelude::*;

/// Metering distances (m from the main road's start) and target speeds (m/s) of the sweep.
const UNTIL_M: [f64; 4] = [30.0, 60.0, 100.0, 200.0];
const TARGET_MPS: [f64; 5] = [3.0, 4.0, 5.0, 6.0, 8.0];

fn run(
    spec: &mapc_sim::SimSpec,
    cfg: &MergeEnvConfig,
    target: f64,
    until_m: f64,
    seed: u64,
) -> Result<mapc_rl::EpisodeMetrics, mapc_rl::RlError> {
    let mut env = MergeEnv::new(spec.clone(), cfg.clone())?;
    env.reset(seed)?;
    let dt = spec.step_s;
    for _ in 0..env.horizon() {
        let sim = env.simulation().expect("reset above");
        let action: Vec<f32> = env
            .controlled()
            .iter()
            .map(|&id| {
                let speed = sim.vehicle(id).map_or(0.0, |v| v.speed);
                // off the main line (none on the Simple Merge's main road) counts as past the metering stretch
                let x = sim.corridor_x(id).unwrap_or(f64::INFINITY);
                let goal = if x < until_m {
                    target
                } else {
                    cfg.norm.max_speed
                };
                ((goal - speed) / dt).clamp(cfg.accel_min, cfg.accel_max) as f32
            })
            .collect();
        env.step(&action)?;
    }
    Ok(env.metrics())
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let args: Vec<String> = std::env::args().collect();
    let seeds: u64 = args.get(1).map_or(Ok(20), |s| s.parse())?;
    let scenario = args
        .get(2)
        .map_or("scenarios/simple_merge.toml", |s| s.as_str());
    let rs = mapc_scenario::ResolvedScenario::load(scenario)?;
    let spec = mapc_sim::spec_from_scenario(&rs)?;
    let n_av = rs.scenario.control.as_ref().map_or(5, |c| c.n_av as usize);
    // the same control a trained policy gets (its normalisation and action bounds)
    let cfg = MergeEnvConfig {
        reward: RewardKind::Speed,
        n_av,
        norm: SIMPLE_MERGE_NORM,
        accel_min: ACCEL_MIN,
        accel_max: ACCEL_MAX,
        lanes: false,
    };
    let fmt = |f: mapc_rl::eval::Figure| format!("{:.1} ± {:.1}", f.mean, f.ci95);
    println!("| target m/s | metering until m | outflow veh/h | inflow veh/h | speed m/s |");
    println!("|---|---|---|---|---|");
    for &until_m in &UNTIL_M {
        for &target in &TARGET_MPS {
            let runs = (0..seeds)
                .into_par_iter()
                .map(|seed| run(&spec, &cfg, target, until_m, seed))
                .collect::<Result<Vec<_>, _>>()?;
            let f = FigureSet::of(&runs);
            println!(
                "| {target} | {until_m} | {} | {} | {:.2} ± {:.2} |",
                fmt(f.outflow),
                fmt(f.inflow),
                f.speed.mean,
                f.speed.ci95
            );
        }
    }
    Ok(())
}
