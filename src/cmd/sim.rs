//! `mapc sim`: the all-human baseline of a scenario over many seeds (in parallel), with mean and 95% confidence
//! interval per metric, and optionally a trajectory trace of the first seed.

use super::common::{DEFAULT_SCENARIO, REGIME_SEEDS, print_regime_lines, write_trace_file};
use anyhow::Context;
use indicatif::{ProgressBar, ProgressStyle};
use mapc_sim::{BaselineReport, MeanCi, RunMetrics, Simulation, spec_from_scenario};
use rayon::prelude::*;
use std::path::PathBuf;

#[derive(clap::Args)]
pub struct Args {
    /// Scenario file, a SUMO configuration (`.sumocfg`), or a built-in scenario name (simple_merge).
    #[arg(long, default_value = DEFAULT_SCENARIO)]
    pub scenario: String,
    /// The scenario as the first argument (`mapc sim X.sumocfg`), instead of --scenario.
    #[arg(value_name = "SCENARIO", conflicts_with = "scenario")]
    pub input: Option<String>,
    #[command(flatten)]
    pub sumo: super::common::SumoInputArgs,
    #[command(flatten)]
    pub runs: super::common::SeedArgs,
    #[command(flatten)]
    pub avs: super::common::AvArgs,
    /// Write the first seed's trajectories as CSV (time_s, vehicle_id, vehicle_type, road, pos_on_road_m,
    /// corridor_x_m, speed_mps, controlled).
    #[arg(long)]
    pub trace: Option<PathBuf>,
    /// Print JSON: {"outflow": {"mean", "ci95", ...}, "inflow": ..., "speed": ..., "seeds": N, ...}.
    #[arg(long)]
    pub json: bool,
    /// Write SUMO's trip-info file of the first seed's run (`--tripinfo-output` of SUMO 1.8).
    #[arg(long, value_name = "FILE")]
    pub tripinfo_output: Option<PathBuf>,
    /// Write SUMO's summary file of the first seed's run (`--summary-output` of SUMO 1.8).
    #[arg(long, value_name = "FILE")]
    pub summary_output: Option<PathBuf>,
    /// Write SUMO's floating-car data of the first seed's run (`--fcd-output` of SUMO 1.8: each vehicle's position,
    /// angle, speed and lane after every step).
    #[arg(long, value_name = "FILE")]
    pub fcd_output: Option<PathBuf>,
    /// Write every output the SUMO configuration names (its trip-info, summary and floating-car data files, its
    /// induction loops' files) into DIR, each under its own file name, from the first seed's run, as `sumo -c`
    /// writes them beside the configuration; a flag above names its file instead.
    #[arg(long, value_name = "DIR")]
    pub sumo_outputs: Option<PathBuf>,
    /// Write the induction loops' files of the first seed's run into DIR, each under the name of the file its
    /// `inductionLoop` names (what SUMO 1.8 writes there).
    #[arg(long, value_name = "DIR")]
    pub detector_output: Option<PathBuf>,
}

pub fn run(mut args: Args) -> anyhow::Result<()> {
    if let Some(dir) = args.sumo_outputs.clone() {
        outputs_into(&mut args, &dir)?;
    }
    super::common::check_outputs([
        args.trace.as_deref(),
        args.tripinfo_output.as_deref(),
        args.summary_output.as_deref(),
        args.fcd_output.as_deref(),
    ])?;
    // the loops' folder too (made when its files are written)
    if let Some(dir) = &args.detector_output {
        mapc_graph::check_folder_creatable(dir)
            .with_context(|| format!("creating {}", dir.display()))?;
    }
    // (with --sumo-outputs, the configuration's outputs are written: no word that they are not)
    let writes_named = args.sumo_outputs.is_some();
    let rs = args.avs.apply(super::common::load_scenario_or_sumo_saying(
        args.input.as_deref().unwrap_or(&args.scenario),
        &args.sumo,
        |note| !(writes_named && note.contains(mapc_scenario::sumo::config::OUTPUT_NOT_WRITTEN)),
    )?)?;
    let spec = spec_from_scenario(&rs).with_context(|| format!("scenario `{}`", rs.origin))?;
    let fit = mapc_scenario::timing::HorizonFit::of_resolved(&rs);
    // (a SUMO user's run has no warm-up key to set, and its figures are SUMO's, not the corridor's outflow: the
    // fit stays in the JSON)
    if let Some(w) = fit.warning().filter(|_| !rs.scenario.sumo_clock) {
        eprintln!("warning: {}: {w}", rs.origin);
    }
    let seeds = args.runs.seeds();
    let pool = super::common::thread_pool(args.runs.threads)?;
    // the merges' regime from a few of the same seeds, first: an observed pass of the humans, whose runs are
    // kept, and are the baseline's own where no vehicle type is an AV (then the two specs are one)
    mapc_sim::keep_runs();
    // the seeds run below without the trace or SUMO's outputs: the regime's runs may start some of them
    let sumo_outputs = args.tripinfo_output.is_some()
        || args.summary_output.is_some()
        || args.fcd_output.is_some()
        || args.detector_output.is_some();
    let first_writes = args.trace.is_some() || sumo_outputs;
    // (the regime's runs are the humans': the seeds' own runs where no type is an AV)
    if spec.vehicle_types.iter().all(|t| !t.controlled) {
        mapc_sim::will_run(&seeds[usize::from(first_writes)..]);
    }
    let regime_seeds = &seeds[..seeds.len().min(REGIME_SEEDS)];
    let regime = pool
        .install(|| mapc_sim::merge_regimes(&spec, regime_seeds))
        .with_context(|| format!("scenario `{}`: the merges' regime", rs.origin))?;
    let progress = progress_bar(seeds.len() as u64, args.json);
    let start = std::time::Instant::now();
    let kept = mapc_sim::KeptRuns::of(&spec);
    let run_seed = |seed: u64| -> anyhow::Result<RunMetrics> {
        // (only the regime's runs are kept, its seeds and the few it ran beside them: a long run keeps no figures)
        let m = kept.run(seed)?;
        progress.inc(1);
        Ok(m)
    };
    // the first seed's run writes the trace or SUMO's outputs (one run, not a second one for them), beside the
    // others
    let detector_files: Vec<Option<String>> = rs.detectors.iter().map(|d| d.file.clone()).collect();
    let (first, rest) = pool.install(|| {
        rayon::join(
            || {
                if !first_writes {
                    return run_seed(seeds[0]);
                }
                let m = write_first_run(&spec, seeds[0], &args, &detector_files)?;
                progress.inc(1);
                Ok(m)
            },
            || {
                seeds[1..]
                    .par_iter()
                    .map(|&seed| run_seed(seed))
                    .collect::<anyhow::Result<Vec<_>>>()
            },
        )
    });
    let mut runs: Vec<RunMetrics> = vec![first?];
    runs.extend(rest?);
    progress.finish_and_clear();
    let wall_s = start.elapsed().as_secs_f64();
    let s = BaselineReport::of(&rs.origin, args.runs.first_seed, runs, wall_s, &spec);
    if args.json {
        let mut json = serde_json::to_value(&s)?;
        json["horizon_fit"] = serde_json::to_value(&fit)?;
        json["horizon_warning"] = serde_json::to_value(fit.warning())?;
        json["regime"] = serde_json::to_value(&regime)?;
        println!("{}", serde_json::to_string_pretty(&json)?);
    } else {
        println!(
            "{} — all-human baseline, {} seeds ({:.2} s)",
            rs.origin, s.seeds, wall_s
        );
        // first, as every figure below is of the vehicles that got in
        for line in mapc_sim::EntrySummary::blocked_lines(&s.entries, s.seeds) {
            println!("  {line}");
        }
        for line in mapc_sim::standstill_lines(&s.runs) {
            println!("  {line}");
        }
        let row = |name: &str, m: &MeanCi, unit: &str| {
            // one seed has a mean but neither an interval nor a spread
            if m.n < 2 {
                println!("  {name:<12} {:>10.2} {unit}  (n = 1, no CI)", m.mean);
            } else {
                println!(
                    "  {name:<12} {:>10.2} ± {:<7.2} {unit}  (sd {:.2})",
                    m.mean, m.ci95, m.std
                );
            }
        };
        row("outflow", &s.outflow, "veh/h");
        row("inflow", &s.inflow, "veh/h");
        row("avg speed", &s.speed, "m/s");
        row("travel time", &s.travel_time, "s");
        row("delay", &s.delay, "s");
        if s.runs.iter().any(|r| r.lane_changes > 0) {
            row("lane changes", &s.lane_changes, "per run");
            row("  per veh-km", &s.lane_changes_per_veh_km, "");
            let by = |count: fn(&mapc_sim::LaneChangeReasons) -> u64| {
                let xs: Vec<f64> = s
                    .runs
                    .iter()
                    .map(|r| count(&r.lane_changes_by_reason) as f64)
                    .collect();
                MeanCi::of(&xs)
            };
            row("  strategic", &by(|r| r.strategic), "per run");
            row("  cooperative", &by(|r| r.cooperative), "per run");
            row("  speed gain", &by(|r| r.speed_gain), "per run");
            row("  keep right", &by(|r| r.keep_right), "per run");
        }
        println!(
            "  per hour of the {:.0} s measured (after a {:.0} s warm-up):",
            fit.horizon_s, fit.warmup_s
        );
        row("past end", &s.end_flow, "veh/h");
        for m in &s.merges {
            row(&format!("past {}", m.name), &m.flow, "veh/h");
        }
        for d in &s.detectors {
            row(&format!("detector {}", d.id), &d.flow, "veh/h");
            row("  occupancy", &d.occupancy, "%");
        }
        // the blocked entries are said above, from every seed
        print_regime_lines(regime.seeds, &regime.merge_lines());
        if let Some(p) = &args.trace {
            println!("  trace of seed {} written to {}", seeds[0], p.display());
        }
    }
    Ok(())
}

fn progress_bar(n: u64, quiet: bool) -> ProgressBar {
    if quiet || n < 8 {
        return ProgressBar::hidden();
    }
    let pb = ProgressBar::new(n);
    pb.set_style(
        ProgressStyle::with_template("{bar:40} {pos}/{len} seeds {elapsed}")
            .expect("valid template"),
    );
    pb
}

/// `--sumo-outputs DIR`: the outputs the SUMO configuration names, each into DIR under its file name (the folders
/// of the name dropped: a name read from an input never leads outside the output folder), where no flag names it.
fn outputs_into(args: &mut Args, dir: &std::path::Path) -> anyhow::Result<()> {
    let input = args.input.as_deref().unwrap_or(&args.scenario);
    let cfg = std::path::Path::new(input);
    if args.sumo.net.is_some() || !cfg.is_file() || !mapc_scenario::sumo::is_sumo_config(cfg) {
        anyhow::bail!(
            "--sumo-outputs {}: writes the outputs a SUMO configuration names; `{input}` is not one \
             (name its files with --tripinfo-output, --summary-output, --fcd-output, --detector-output)",
            dir.display()
        );
    }
    let conf = mapc_scenario::sumo::config::read(cfg).map_err(|e| anyhow::anyhow!("{e}"))?;
    let mut taken: Vec<(&str, &std::ffi::OsStr)> = Vec::new();
    for (option, name) in &conf.named_outputs {
        let Some(file) = std::path::Path::new(name).file_name() else {
            eprintln!(
                "warning: {}: `{option}` names `{name}`, no file: not written",
                cfg.display()
            );
            continue;
        };
        // (two outputs of one name would write over each other in DIR)
        if let Some((other, _)) = taken.iter().find(|(_, f)| *f == file) {
            anyhow::bail!(
                "--sumo-outputs {}: {}: `{option}` and `{other}` both name `{}`",
                dir.display(),
                cfg.display(),
                file.to_string_lossy()
            );
        }
        taken.push((option, file));
        let slot = match option.as_str() {
            "tripinfo-output" => &mut args.tripinfo_output,
            "summary-output" => &mut args.summary_output,
            "fcd-output" => &mut args.fcd_output,
            _ => continue,
        };
        slot.get_or_insert_with(|| dir.join(file));
    }
    // (the folder is made when its first file is written: a run refused before leaves nothing)
    args.detector_output
        .get_or_insert_with(|| dir.to_path_buf());
    Ok(())
}

/// Run `seed` once and write from that one run whatever was asked of it: the trace, SUMO's trip-info, summary and
/// floating-car data files, the loops' files (each atomically; the trace and the floating-car data as the run goes).
fn write_first_run(
    spec: &mapc_sim::SimSpec,
    seed: u64,
    args: &Args,
    detector_files: &[Option<String>],
) -> anyhow::Result<RunMetrics> {
    let mut sim = Simulation::from_spec(spec.clone(), seed)?;
    let Some(path) = &args.fcd_output else {
        return first_run_writing(sim, args, detector_files, None);
    };
    let mut fcd = mapc_sumo::fcd::FcdOutput::new(&mut sim);
    let mut metrics = None;
    super::common::write_streamed(path, "", |w| {
        fcd.start(w)?;
        metrics = Some(first_run_writing(
            sim,
            args,
            detector_files,
            Some((&mut fcd, &mut *w)),
        )?);
        fcd.finish(w)?;
        Ok(())
    })?;
    Ok(metrics.expect("the run ended"))
}

/// [`write_first_run`]'s run, with the floating-car data's writer where one was asked for.
fn first_run_writing(
    mut sim: Simulation,
    args: &Args,
    detector_files: &[Option<String>],
    mut fcd: Option<(&mut mapc_sumo::fcd::FcdOutput, &mut dyn std::io::Write)>,
) -> anyhow::Result<RunMetrics> {
    let mut out = (args.tripinfo_output.is_some() || args.summary_output.is_some()).then(|| {
        mapc_sumo::run_outputs::SumoOutputs::new(
            &mut sim,
            args.tripinfo_output.is_some(),
            args.summary_output.is_some(),
        )
    });
    let mut observe = |s: &Simulation| -> anyhow::Result<()> {
        if let Some(out) = &mut out {
            out.observe(s);
        }
        if let Some((fcd, w)) = &mut fcd {
            fcd.observe(s, w)?;
        }
        Ok(())
    };
    match &args.trace {
        Some(path) => {
            let (mut note, mut failure) = (None, None);
            let traced = write_trace_file(path, |w| {
                note = mapc_sim::trace_sim(&mut sim, w, |s| {
                    // (the floating-car data's own error, kept aside: the trace's writer passes only the simulator's)
                    observe(s).map_err(|e| {
                        let said = mapc_sim::SimError::Spec(e.to_string());
                        failure = Some(e);
                        said
                    })
                })?;
                Ok(())
            });
            if let Some(e) = failure {
                return Err(e);
            }
            traced?;
            if let Some(note) = note {
                eprintln!("note: {}: {note}", path.display());
            }
        }
        None => {
            while !sim.is_done() {
                sim.step()?;
                observe(&sim)?;
            }
        }
    }
    if let Some(out) = &out {
        for (path, text) in [
            (&args.tripinfo_output, out.tripinfo_xml()),
            (&args.summary_output, out.summary_xml()),
        ] {
            if let (Some(path), Some(text)) = (path, text) {
                mapc_graph::write_atomically(path, text.as_bytes())
                    .with_context(|| format!("writing {}", path.display()))?;
            }
        }
    }
    if let Some(dir) = &args.detector_output {
        std::fs::create_dir_all(dir).with_context(|| format!("creating {}", dir.display()))?;
        for (name, text) in mapc_sumo::run_outputs::detector_files(&sim, detector_files) {
            let path = dir.join(&name);
            mapc_graph::write_atomically(&path, text.as_bytes())
                .with_context(|| format!("writing {}", path.display()))?;
        }
    }
    Ok(sim.metrics())
}
