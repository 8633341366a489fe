//! Evaluates a checkpoint on a scenario against the human baseline (the library side of `mapc eval`):
//! `cargo run -p mapc-rl --example eval_merge -- POLICY SCENARIO SEEDS`.

use mapc_rl::Checkpoint;
use mapc_rl::eval::{EvalReport, FigureSet, compare, env_config_for, run_human, run_policy};
use mapc_rl::rollout::ActionMode;

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let a: Vec<String> = std::env::args().collect();
    let start = std::time::Instant::now();
    let file = std::path::PathBuf::from(&a[1]);
    let scenario = a.get(2).map_or("simple_merge", |s| s.as_str());
    let n: u64 = a.get(3).map_or(Ok(100), |s| s.parse())?;
    let ck = Checkpoint::load(&file)?;
    let resolved = mapc_scenario::ResolvedScenario::load(scenario)?;
    let spec = mapc_sim::spec_from_scenario(&resolved)?;
    let n_av = resolved
        .scenario
        .control
        .as_ref()
        .map_or(5, |c| c.n_av as usize);
    let cfg = env_config_for(&ck, &file, scenario, Some(n_av))?;
    let seeds: Vec<u64> = (0..n).collect();
    let runs = run_policy(&ck, &spec, &cfg, &seeds, ActionMode::Mean)?;
    let human = run_human(&spec, &seeds)?;
    let f = FigureSet::of(&runs);
    let report = EvalReport {
        outflow: f.outflow,
        inflow: f.inflow,
        speed: f.speed,
        seeds: f.seeds,
        policy: file.display().to_string(),
        scenario: scenario.into(),
        actions: "mean".into(),
        baseline: Some(FigureSet::of(&human)),
        comparison: Some(compare(&runs, &human)),
        wall_s: start.elapsed().as_secs_f64(),
    };
    println!("{}", serde_json::to_string_pretty(&report)?);
    Ok(())
}
