//! `mapc bench`: the simulator's speed — vehicle-steps per second on one core, and the wall time of a many-seed
//! baseline on a given number of threads.

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
}

pub fn run(args: Args) -> anyhow::Result<()> {
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

/// The process's peak resident memory so far (MiB), as the kernel counts it.
fn peak_rss_mib() -> f64 {
    // SAFETY: getrusage only writes the struct it is given
    let mut usage: libc::rusage = unsafe { std::mem::zeroed() };
    if unsafe { libc::getrusage(libc::RUSAGE_SELF, &mut usage) } != 0 {
        return f64::NAN;
    }
    usage.ru_maxrss as f64 / 1024.0 // KiB on Linux
}
