//! `mapc bench`: the simulator's speed — vehicle-steps per second on one core, beside SUMO 1.8's command line on
//! the same scenario exported (when SUMO is found; [`sumo`]), and the wall time of a many-seed
//! baseline on a given number of threads. Wall time and CPU time are both reported: on a shared machine CPU time
//! is the steadier measure, and mapc and SUMO run back to back in one process so that they share the load. With
//! `--train N`, the trainer's: N iterations of the paper preset's centralized training, their wall and CPU time
//! by phase, and the preset's 500 iterations extrapolated.

mod sumo;

use mapc_sim::{Simulation, spec_from_scenario};
use rayon::prelude::*;
use std::time::Instant;

#[derive(clap::Args)]
pub struct Args {
    /// Scenario file, a SUMO configuration (`.sumocfg`: SUMO then runs it as it is), or a built-in scenario name
    /// (simple_merge).
    #[arg(long, default_value = super::common::DEFAULT_SCENARIO)]
    pub scenario: String,
    /// The scenario as the first argument (`mapc bench X.sumocfg`), instead of --scenario.
    #[arg(value_name = "SCENARIO", conflicts_with = "scenario")]
    pub input: Option<String>,
    #[command(flatten)]
    pub sumo_input: super::common::SumoInputArgs,
    /// Seeds run one after another on one core for the vehicle-steps figure (1 to 100 000).
    #[arg(long, default_value_t = 20, value_parser = super::flags::seeds())]
    pub single_core_seeds: u64,
    /// Seeds of the parallel baseline (1 to 100 000).
    #[arg(long, default_value_t = 100, value_parser = super::flags::seeds())]
    pub seeds: u64,
    /// Threads of the parallel baseline (1 to 1024).
    #[arg(long, default_value_t = 2, value_parser = super::flags::threads())]
    pub threads: usize,
    /// SUMO binary to compare with (default: SUMO 1.8 where tools/sumo_check installs it, `$MAPC_SUMO_VENV` or
    /// `~/.cache/mapc/sumo-1.8.0`, else `sumo` on the PATH).
    #[arg(long, value_name = "PATH", conflicts_with = "no_sumo")]
    pub sumo: Option<std::path::PathBuf>,
    /// Seeds SUMO runs one after another (it is some 20 times slower than mapc; 1 to 100 000).
    #[arg(long, default_value_t = 5, value_parser = super::flags::seeds())]
    pub sumo_seeds: u64,
    /// Measure mapc only.
    #[arg(long)]
    pub no_sumo: bool,
    /// Print JSON.
    #[arg(long)]
    pub json: bool,
    /// Benchmark training instead: this many iterations of `mapc train --preset paper --reward outflow` on the
    /// scenario (a fresh run in a temporary directory, on `--threads` threads).
    #[arg(long, value_parser = super::flags::count::<u64>(1..=*mapc_rl::limits::ITERATIONS.end()))]
    pub train: Option<u64>,
}

impl Args {
    fn scenario(&self) -> &str {
        self.input.as_deref().unwrap_or(&self.scenario)
    }
}

pub fn run(args: Args) -> anyhow::Result<()> {
    if let Some(iters) = args.train {
        return bench_training(&args, iters);
    }
    let scenario = args.scenario();
    let rs = super::common::load_scenario_or_sumo(scenario, &args.sumo_input)?;
    let spec = spec_from_scenario(&rs)?;

    let sumo_bin = if args.no_sumo {
        None
    } else {
        sumo::find_sumo(args.sumo.as_deref())?
    };

    // One core: seeds in sequence on this thread.
    let cpu_start = thread_cpu_s();
    let start = Instant::now();
    let mut vehicle_steps = 0u64;
    let mut all_vehicle_steps = 0u64;
    let mut steps = 0u64;
    for seed in 0..args.single_core_seeds {
        let mut sim = Simulation::from_spec(spec.clone(), seed)?;
        sim.set_invariant_checks(false);
        // the warm-up's vehicle-steps too, as SUMO counts them
        while !sim.is_done() {
            all_vehicle_steps += sim.active_count() as u64;
            sim.step()?;
        }
        let m = sim.metrics();
        vehicle_steps += m.vehicle_steps;
        steps += m.steps;
    }
    let single_s = start.elapsed().as_secs_f64();
    let single_cpu_s = thread_cpu_s() - cpu_start;
    let vs_per_s = vehicle_steps as f64 / single_s;
    let mapc_rss_mib = peak_rss_mib();

    // SUMO right after, on the same load
    let sumo = match &sumo_bin {
        Some(bin) => {
            let dir = std::env::temp_dir().join(format!("mapc-bench-sumo-{}", std::process::id()));
            let input = match &args.sumo_input.net {
                Some(net) => sumo::SumoInput::Files {
                    net,
                    routes: &args.sumo_input.routes,
                    additional: &args.sumo_input.additional,
                },
                None if std::path::Path::new(scenario).is_file()
                    && mapc_scenario::sumo::is_sumo_config(std::path::Path::new(scenario)) =>
                {
                    sumo::SumoInput::Config(std::path::Path::new(scenario))
                }
                None => sumo::SumoInput::Export(&rs),
            };
            let runs = sumo::run_sumo(bin, input, &dir, args.sumo_seeds);
            std::fs::remove_dir_all(&dir).ok();
            Some(runs?)
        }
        None => None,
    };
    // per CPU second, over every step of the run (SUMO's count includes the warm-up)
    let mapc_cpu_rate = all_vehicle_steps as f64 / single_cpu_s;
    let against_sumo = sumo.as_ref().map(|s| {
        let sumo_cpu_rate = s.vehicle_steps / s.cpu_s;
        let sumo_wall_rate = s.vehicle_steps / s.wall_s;
        (
            sumo_cpu_rate,
            sumo_wall_rate,
            mapc_cpu_rate / sumo_cpu_rate,
            (all_vehicle_steps as f64 / single_s) / sumo_wall_rate,
            // CPU time of one run of the scenario, SUMO's over mapc's
            (s.cpu_s / s.seeds as f64) / (single_cpu_s / args.single_core_seeds as f64),
        )
    });

    // The parallel baseline, as `mapc sim` runs it.
    let pool = super::common::thread_pool(Some(args.threads))?;
    let baseline_cpu_start = cpu_seconds();
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
    let baseline_cpu_s = cpu_seconds() - baseline_cpu_start;
    let peak_mib = peak_rss_mib();
    let mean_vehicles = vehicle_steps as f64 / steps as f64;
    let sumo_absent = if args.no_sumo {
        "not run (--no-sumo)".to_string()
    } else {
        "not found (give --sumo PATH, or install SUMO 1.8 with tools/sumo_check/sumo_check)"
            .to_string()
    };
    if args.json {
        let sumo_json = match (&sumo, against_sumo) {
            (Some(s), Some((cpu_rate, wall_rate, x_cpu, x_wall, x_run))) => serde_json::json!({
                "binary": s.binary, "version": s.version, "input": s.command, "seeds": s.seeds, "wall_s": s.wall_s,
                "cpu_s": s.cpu_s, "vehicle_steps": s.vehicle_steps, "vehicle_steps_per_cpu_s": cpu_rate,
                "vehicle_steps_per_s": wall_rate, "peak_rss_mib": s.peak_rss_mib,
                "mapc_speedup_per_cpu_s": x_cpu, "mapc_speedup_per_wall_s": x_wall,
                "mapc_speedup_cpu_per_run": x_run,
            }),
            _ => serde_json::json!({ "absent": sumo_absent }),
        };
        let out = serde_json::json!({
            "scenario": rs.origin,
            "single_core": {"seeds": args.single_core_seeds, "wall_s": single_s, "cpu_s": single_cpu_s,
                            "vehicle_steps": vehicle_steps, "vehicle_steps_per_s": vs_per_s,
                            "vehicle_steps_with_warmup": all_vehicle_steps,
                            "vehicle_steps_with_warmup_per_cpu_s": mapc_cpu_rate,
                            "steps_per_s": steps as f64 / single_s, "mean_vehicles": mean_vehicles,
                            "peak_rss_mib": mapc_rss_mib},
            "sumo": sumo_json,
            "baseline": {"seeds": args.seeds, "threads": args.threads, "wall_s": baseline_s,
                         "cpu_s": baseline_cpu_s, "runs": runs.len()},
            "peak_rss_mib": peak_mib,
        });
        println!("{}", serde_json::to_string_pretty(&out)?);
    } else {
        println!("{}", rs.origin);
        println!(
            "  mapc, one core: {} seeds, {:.3} s wall, {:.3} s CPU, {:.3e} vehicle-steps/s ({:.0} steps/s, {:.1} \
             vehicles on average); with the warm-up {:.3e} vehicle-steps per CPU second; peak memory {:.1} MiB",
            args.single_core_seeds,
            single_s,
            single_cpu_s,
            vs_per_s,
            steps as f64 / single_s,
            mean_vehicles,
            mapc_cpu_rate,
            mapc_rss_mib
        );
        match (&sumo, against_sumo) {
            (Some(s), Some((cpu_rate, wall_rate, x_cpu, x_wall, x_run))) => {
                println!(
                    "  {} ({} {}), one core: {} seeds, {:.3} s wall, {:.3} s CPU, {:.3e} vehicle-steps per CPU \
                     second ({:.3e} per wall second); peak memory of a run {:.1} MiB",
                    s.version,
                    s.binary.display(),
                    s.command,
                    s.seeds,
                    s.wall_s,
                    s.cpu_s,
                    cpu_rate,
                    wall_rate,
                    s.peak_rss_mib
                );
                println!(
                    "  mapc against SUMO: {x_cpu:.1}x the vehicle-steps per CPU second ({x_wall:.1}x per wall \
                     second); one run takes {x_run:.1}x less CPU time"
                );
            }
            _ => println!("  SUMO: {sumo_absent}"),
        }
        println!(
            "  baseline: {} seeds on {} threads in {:.3} s wall ({:.3} s CPU); peak memory of the process {:.1} MiB",
            args.seeds, args.threads, baseline_s, baseline_cpu_s, peak_mib
        );
    }
    Ok(())
}

/// `--train N`: N iterations of the paper preset, timed; the preset's full run extrapolated from their mean.
fn bench_training(args: &Args, iters: u64) -> anyhow::Result<()> {
    use clap::Parser;
    let dir = std::env::temp_dir().join(format!("mapc-bench-train-{}", std::process::id()));
    std::fs::remove_dir_all(&dir).ok();
    #[derive(Parser)]
    struct Train {
        #[command(flatten)]
        args: super::training::Args,
    }
    let threads = args.threads.to_string();
    let iters_s = iters.to_string();
    let train = Train::try_parse_from(
        [
            "train",
            "--scenario",
            args.scenario(),
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
    let run = super::training::train(train.args);
    let (wall_s, cpu_s) = (start.elapsed().as_secs_f64(), cpu_seconds() - cpu0);
    std::fs::remove_dir_all(&dir).ok();
    let (run, _) = run?;
    let timing = run.state.timing;
    let full = mapc_rl::PpoConfig::default().iterations as f64;
    let per_iter = wall_s / iters as f64;
    let out = serde_json::json!({
        "scenario": args.scenario(),
        "threads": args.threads,
        "iterations": iters,
        "wall_s": wall_s,
        "cpu_s": cpu_s,
        "per_iteration": {"wall_s": per_iter, "cpu_s": cpu_s / iters as f64,
                          "rollout_s": timing.rollout_s / iters as f64,
                          "update_s": timing.update_s / iters as f64},
        "extrapolated_500_iterations_min": per_iter * full / 60.0,
        "machine": machine(),
    });
    if args.json {
        println!("{}", serde_json::to_string_pretty(&out)?);
    } else {
        println!(
            "training, paper preset, {}: {iters} iterations on {} threads in {wall_s:.2} s wall, {cpu_s:.2} s CPU",
            args.scenario(),
            args.threads
        );
        println!(
            "  per iteration: {per_iter:.3} s wall ({:.3} s rollouts, {:.3} s update), {:.3} s CPU",
            timing.rollout_s / iters as f64,
            timing.update_s / iters as f64,
            cpu_s / iters as f64
        );
        println!(
            "  the preset's {full} iterations at this rate: {:.1} min (a fresh policy's iterations: a trained \
             one's cost up to 30 % more, docs/perf.md)",
            per_iter * full / 60.0
        );
        let m = machine();
        println!(
            "  ran on: {}, {} logical CPUs; x86 features {}; {}",
            m["cpu"].as_str().unwrap_or("?"),
            m["logical_cpus"],
            m["features"].as_str().unwrap_or("?"),
            m["kernels"].as_str().unwrap_or("?")
        );
    }
    Ok(())
}

/// What a benchmark ran on: the CPU's name (Linux), its logical CPUs, the vector features the kernels look for,
/// and the kernels the trainer's hot paths take there.
fn machine() -> serde_json::Value {
    let cpu = std::fs::read_to_string("/proc/cpuinfo")
        .ok()
        .and_then(|t| {
            t.lines()
                .find(|l| l.starts_with("model name"))
                .and_then(|l| l.split_once(':'))
                .map(|(_, v)| v.trim().to_string())
        })
        .unwrap_or_else(|| "unknown CPU".to_string());
    let logical_cpus = std::thread::available_parallelism().map_or(0, |n| n.get());
    #[cfg(target_arch = "x86_64")]
    let (features, kernels) = {
        let has = [
            ("avx2", std::arch::is_x86_feature_detected!("avx2")),
            ("fma", std::arch::is_x86_feature_detected!("fma")),
            ("avx512f", std::arch::is_x86_feature_detected!("avx512f")),
        ];
        let names: Vec<&str> = has.iter().filter(|(_, on)| *on).map(|(n, _)| *n).collect();
        // the matrix kernels and the element-wise loops' wide copies give the plain code's bits (mapc-rl's
        // `ppo::tensor::matmul` and `ppo::tensor::simd`), so only the speed depends on what is found here
        let loops = match (has[2].1, has[0].1) {
            (true, _) => "AVX-512",
            (false, true) => "AVX2",
            (false, false) => "baseline x86-64",
        };
        let kernels = format!(
            "matrix products: mapc's {} kernels (one fused multiply-add per term, the same bits on every \
             machine); element-wise loops: {loops}; update's exp: straight-line (rollouts': glibc's expf); \
             allocator: mimalloc",
            mapc_rl::ppo::tensor::matrix_kernel_name()
        );
        (names.join(" "), kernels)
    };
    #[cfg(not(target_arch = "x86_64"))]
    let (features, kernels) = (
        String::from("(not x86-64)"),
        format!(
            "matrix products: mapc's {} kernels; allocator: mimalloc",
            mapc_rl::ppo::tensor::matrix_kernel_name()
        ),
    );
    serde_json::json!({
        "cpu": cpu,
        "logical_cpus": logical_cpus,
        "features": features,
        "kernels": kernels,
    })
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

/// CPU time (user + system, s) of the calling thread.
fn thread_cpu_s() -> f64 {
    // SAFETY: getrusage only writes the struct it is given
    let mut u: libc::rusage = unsafe { std::mem::zeroed() };
    #[cfg(any(target_os = "linux", target_os = "android"))]
    let who = libc::RUSAGE_THREAD;
    // elsewhere the process's (the one-core loop runs while no other thread of it works)
    #[cfg(not(any(target_os = "linux", target_os = "android")))]
    let who = libc::RUSAGE_SELF;
    if unsafe { libc::getrusage(who, &mut u) } != 0 {
        return f64::NAN;
    }
    sumo::cpu_seconds(&u)
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
