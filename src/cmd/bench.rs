//! `mapc bench`: the simulator's speed — vehicle-steps per second on one core, and the wall time of a many-seed
//! baseline on a given number of threads; with `--train N`, the trainer's: N iterations of the paper preset's
//! centralized training, their wall and CPU time by phase, and the preset's 500 iterations extrapolated.

use mapc_sim::{Simulation, spec_from_scenario};
use rayon::prelude::*;
use std::time::Instant;

#[derive(clap::Args)]
pub struct Args {
    /// Scenario file, or a built-in scenario name (simple_merge).
    #[arg(long, default_value = super::sim::DEFAULT_SCENARIO)]
    pub scenario: String,
    /// Seeds run one after another on one core for the vehicle-steps figure.
    #[arg(long, default_value_t = 20)]
    pub single_core_seeds: u64,
    /// Seeds of the parallel baseline.
    #[arg(long, default_value_t = 100)]
    pub seeds: u64,
    /// Threads of the parallel baseline.
    #[arg(long, default_value_t = 2)]
    pub threads: usize,
    /// Print JSON.
    #[arg(long)]
    pub json: bool,
    /// Benchmark training instead: this many iterations of `mapc train --preset paper --reward outflow` on the
    /// scenario (a fresh run in a temporary directory, on `--threads` threads).
    #[arg(long)]
    pub train: Option<u64>,
}

pub fn run(args: Args) -> anyhow::Result<()> {
    if let Some(iters) = args.train {
        return bench_training(&args, iters);
    }
    anyhow::ensure!(
        args.single_core_seeds >= 1 && args.seeds >= 1,
        "seed counts must be at least 1"
    );
    let rs = super::sim::load_scenario(&args.scenario)?;
    let spec = spec_from_scenario(&rs)?;

    // One core: seeds in sequence on this thread.
    let start = Instant::now();
    let mut vehicle_steps = 0u64;
    let mut steps = 0u64;
    for seed in 0..args.single_core_seeds {
        let mut sim = Simulation::from_spec(spec.clone(), seed)?;
        sim.set_invariant_checks(false);
        let m = sim.run()?;
        vehicle_steps += m.vehicle_steps;
        steps += m.steps;
    }
    let single_s = start.elapsed().as_secs_f64();
    let vs_per_s = vehicle_steps as f64 / single_s;

    // The parallel baseline, as `mapc sim` runs it.
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(args.threads)
        .build()?;
    let start = Instant::now();
    let runs = pool.install(|| {
        (0..args.seeds)
            .into_par_iter()
            .map(|seed| {
                let mut sim = Simulation::from_spec(spec.clone(), seed)?;
                sim.set_invariant_checks(false);
                sim.run()
            })
            .collect::<Result<Vec<_>, _>>()
    })?;
    let baseline_s = start.elapsed().as_secs_f64();
    let peak_mib = peak_rss_mib();
    let mean_vehicles = vehicle_steps as f64 / steps as f64;
    if args.json {
        let out = serde_json::json!({
            "scenario": rs.origin,
            "single_core": {"seeds": args.single_core_seeds, "wall_s": single_s, "vehicle_steps": vehicle_steps,
                            "vehicle_steps_per_s": vs_per_s, "steps_per_s": steps as f64 / single_s,
                            "mean_vehicles": mean_vehicles},
            "baseline": {"seeds": args.seeds, "threads": args.threads, "wall_s": baseline_s, "runs": runs.len()},
            "peak_rss_mib": peak_mib,
        });
        println!("{}", serde_json::to_string_pretty(&out)?);
    } else {
        println!("{}", rs.origin);
        println!(
            "  one core: {} seeds, {:.3} s, {:.3e} vehicle-steps/s ({:.0} steps/s, {:.1} vehicles on average)",
            args.single_core_seeds,
            single_s,
            vs_per_s,
            steps as f64 / single_s,
            mean_vehicles
        );
        println!(
            "  baseline: {} seeds on {} threads in {:.3} s; peak memory of the process {:.1} MiB",
            args.seeds, args.threads, baseline_s, peak_mib
        );
    }
    Ok(())
}

/// `--train N`: N iterations of the paper preset, timed; the preset's full run extrapolated from their mean.
fn bench_training(args: &Args, iters: u64) -> anyhow::Result<()> {
    use clap::Parser;
    anyhow::ensure!(iters >= 1, "--train needs at least 1 iteration");
    let dir = std::env::temp_dir().join(format!("mapc-bench-train-{}", std::process::id()));
    std::fs::remove_dir_all(&dir).ok();
    #[derive(Parser)]
    struct Train {
        #[command(flatten)]
        args: super::train::Args,
    }
    let threads = args.threads.to_string();
    let iters_s = iters.to_string();
    let train = Train::try_parse_from(
        [
            "train",
            "--scenario",
            &args.scenario,
            "--reward",
            "outflow",
            "--preset",
            "paper",
            "--iters",
            &iters_s,
            "--threads",
            &threads,
            // (no progress bar)
            "--json",
            "-o",
        ]
        .into_iter()
        .map(std::ffi::OsString::from)
        .chain([dir.clone().into_os_string()]),
    )?;
    let (cpu0, start) = (cpu_seconds(), Instant::now());
    let run = super::train::train(train.args);
    let (wall_s, cpu_s) = (start.elapsed().as_secs_f64(), cpu_seconds() - cpu0);
    std::fs::remove_dir_all(&dir).ok();
    let (run, _) = run?;
    let timing = run.state.timing;
    let full = mapc_rl::PpoConfig::default().iterations as f64;
    let per_iter = wall_s / iters as f64;
    let out = serde_json::json!({
        "scenario": args.scenario,
        "threads": args.threads,
        "iterations": iters,
        "wall_s": wall_s,
        "cpu_s": cpu_s,
        "per_iteration": {"wall_s": per_iter, "cpu_s": cpu_s / iters as f64,
                          "rollout_s": timing.rollout_s / iters as f64,
                          "update_s": timing.update_s / iters as f64},
        "extrapolated_500_iterations_min": per_iter * full / 60.0,
    });
    if args.json {
        println!("{}", serde_json::to_string_pretty(&out)?);
    } else {
        println!(
            "training, paper preset, {}: {iters} iterations on {} threads in {wall_s:.2} s wall, {cpu_s:.2} s CPU",
            args.scenario, args.threads
        );
        println!(
            "  per iteration: {per_iter:.3} s wall ({:.3} s rollouts, {:.3} s update), {:.3} s CPU",
            timing.rollout_s / iters as f64,
            timing.update_s / iters as f64,
            cpu_s / iters as f64
        );
        println!(
            "  the preset's {full} iterations at this rate: {:.1} min",
            per_iter * full / 60.0
        );
    }
    Ok(())
}

/// CPU time (user and system) of the whole process so far, in seconds.
fn cpu_seconds() -> f64 {
    // SAFETY: getrusage only writes the struct it is given
    let mut usage: libc::rusage = unsafe { std::mem::zeroed() };
    if unsafe { libc::getrusage(libc::RUSAGE_SELF, &mut usage) } != 0 {
        return f64::NAN;
    }
    let secs = |t: libc::timeval| t.tv_sec as f64 + t.tv_usec as f64 * 1e-6;
    secs(usage.ru_utime) + secs(usage.ru_stime)
}

/// The process's peak resident memory so far (MiB), as the kernel counts it.
fn peak_rss_mib() -> f64 {
    // SAFETY: getrusage only writes the struct it is given
    let mut usage: libc::rusage = unsafe { std::mem::zeroed() };
    if unsafe { libc::getrusage(libc::RUSAGE_SELF, &mut usage) } != 0 {
        return f64::NAN;
    }
    usage.ru_maxrss as f64 / 1024.0 // KiB on Linux
}
