//! `mapc eval`: a trained policy on a scenario over fixed seeds, against the human baseline.

use std::path::PathBuf;

use anyhow::Context;
use clap::Args as ClapArgs;
use mapc_rl::Checkpoint;
use mapc_rl::checkpoint::policy_file;
use mapc_rl::eval::{EvalRequest, FigureSet, evaluate, evaluate_traced};
use mapc_rl::rollout::ActionMode;

mod alinea;

/// A controller evaluated in place of a policy.
#[derive(clap::ValueEnum, Clone, Copy, Debug)]
pub enum Controller {
    /// ALINEA ramp metering on a traffic light, from downstream detectors' occupancy.
    Alinea,
}

/// Evaluate a policy: mean and 95% CI of outflow, inflow and speed, and a Welch t-test against the humans.
#[derive(ClapArgs, Debug)]
pub struct Args {
    /// Policy: a checkpoint file (policies/*.json) or a run directory of `mapc train`.
    #[arg(
        long,
        required_unless_present = "controller",
        conflicts_with = "controller"
    )]
    pub policy: Option<PathBuf>,
    /// A controller instead of a policy: `alinea` (ramp metering of a scenario's traffic light).
    #[arg(long, value_enum)]
    pub controller: Option<Controller>,
    #[command(flatten)]
    pub alinea: alinea::AlineaArgs,
    #[command(flatten)]
    pub avs: super::common::AvArgs,
    /// Scenario: `simple_merge` or a scenario file (a window from `mapc window` for zero-shot transfer).
    #[arg(long, default_value = "simple_merge")]
    pub scenario: String,
    #[command(flatten)]
    pub runs: super::common::SeedArgs,
    /// Sample actions from the Gaussian instead of taking its mean.
    #[arg(long)]
    pub sample: bool,
    /// Skip the human baseline.
    #[arg(long)]
    pub no_baseline: bool,
    /// Print the report as JSON.
    #[arg(long)]
    pub json: bool,
    /// Write the first seed's trajectories under the policy (or the controller) as CSV (the columns of `mapc sim --trace`; draw
    /// them with `mapc plot timespace`); with `--human-trace`, of the seed that file is of.
    #[arg(long)]
    pub trace: Option<PathBuf>,
    /// Write the humans' run of the first seed as CSV too (the columns of `mapc sim --trace`): the baseline's own
    /// run, so it costs no run of its own; with `--trace`, a policy whose rule leaves every window to the humans
    /// drives that same run, and its trace is a copy (then, in `mapc pipeline`, the first seed that no earlier step
    /// ran: the report names it).
    #[arg(long, value_name = "PATH")]
    pub human_trace: Option<PathBuf>,
    /// Where the policy drives, overriding its own rule: `everywhere`, or `main-road-yields` (only windows whose
    /// merge makes the main road yield, the Simple Merge's regime, or for a distributed policy only AVs whose next
    /// merge is one; the others are left to the humans), or `main-road-yields-congested` (of those, only merges
    /// that the regime report's human runs find congested: a merge that flows or is only dense is left to the
    /// humans, and the report says why), or `simple-merge-regime` (of those, only merges with one lane on every
    /// road in and out), or `measured` (everywhere, but only if the policy first beats the humans on 20
    /// calibration seeds of its own: the rule that never loses, whatever the policy). Default: the policy file's
    /// rule, else everywhere.
    #[arg(long)]
    pub deploy: Option<mapc_rl::deploy::Deploy>,
}

pub fn run(args: Args) -> anyhow::Result<()> {
    super::common::set_global_threads(args.runs.threads);
    super::common::check_outputs([args.trace.as_deref(), args.human_trace.as_deref()])?;
    if let Some(Controller::Alinea) = args.controller {
        let sc = super::common::load_run_scenario_with(&args.scenario, &args.avs)?;
        return alinea::run(
            &args.scenario,
            &sc.spec,
            &args.runs.seeds(),
            &args.alinea,
            !args.no_baseline,
            args.json,
            args.trace.as_deref(),
        );
    }
    let policy = args
        .policy
        .clone()
        .expect("clap requires --policy without --controller");
    let file = policy_file(&policy);
    let mut ck = Checkpoint::load(&file)?;
    if let Some(rule) = args.deploy {
        ck.spec.deploy = Some(rule);
    }
    let sc = super::common::load_run_scenario_with(&args.scenario, &args.avs)?;
    if let Some(w) = &sc.horizon_warning {
        eprintln!("warning: {}: {w}", args.scenario);
    }
    let seeds = args.runs.seeds();
    let mode = if args.sample {
        ActionMode::Sample
    } else {
        ActionMode::Mean
    };
    let req = EvalRequest {
        ck: &ck,
        policy_file: &file,
        scenario: &args.scenario,
        spec: &sc.spec,
        scenario_n_av: sc.n_av,
        seeds: &seeds,
        mode,
        baseline: !args.no_baseline,
    };
    let context = || format!("evaluating {}", file.display());
    let (report, driver, deployment, traced_seed) = match &args.human_trace {
        Some(path) => {
            let mut evaluated = None;
            super::common::write_trace_file(path, |w| {
                evaluated = Some(evaluate_traced(&req, Some(w)).with_context(context)?);
                Ok(())
            })?;
            evaluated.expect("written only once evaluated")
        }
        None => {
            let (report, driver, deployment) = evaluate(&req).with_context(context)?;
            (report, driver, deployment, seeds[0])
        }
    };
    let policy_is_humans = deployment.spec.is_none();
    match (&args.trace, &args.human_trace) {
        // the rule leaves every window to the humans: the policy's run of the traced seed is theirs
        (Some(path), Some(humans)) if policy_is_humans => copy_trace(humans, path)?,
        (Some(path), _) => {
            // one seed under the policy, every step's vehicles, written atomically
            super::common::write_trace_file(path, |w| {
                driver.trace_deployed(&ck, &sc.spec, &deployment, traced_seed, mode, w)?;
                Ok(())
            })?;
        }
        (None, _) => {}
    }
    let figs = FigureSet {
        outflow: report.outflow,
        inflow: report.inflow,
        speed: report.speed,
        travel_time: report.travel_time,
        seeds: report.seeds,
    };
    if args.json {
        println!("{}", serde_json::to_string_pretty(&report)?);
        return Ok(());
    }
    println!(
        "policy {} on {} ({} seeds, {} actions)",
        report.policy, report.scenario, report.seeds, report.actions
    );
    let row = |name: &str, f: &FigureSet| {
        // one seed has a mean but no interval: say so rather than print "± 0.00"
        let pm = |mean: f64, ci: f64, width: usize, digits: usize| {
            if f.has_ci() {
                format!("{mean:w$.d$} ± {ci:5.d$}", w = width, d = digits)
            } else {
                format!("{mean:w$.d$} (n = 1, no CI)", w = width, d = digits)
            }
        };
        println!(
            "  {name:<8} outflow {} veh/h   inflow {} veh/h   speed {} m/s   trip {} s",
            pm(f.outflow.mean, f.outflow.ci95, 8, 2),
            pm(f.inflow.mean, f.inflow.ci95, 8, 2),
            pm(f.speed.mean, f.speed.ci95, 6, 2),
            pm(f.travel_time.mean, f.travel_time.ci95, 7, 2)
        )
    };
    row("policy", &figs);
    if let Some(rule) = report.deploy {
        println!("  deployed: {rule}");
    }
    for w in &report.withheld {
        println!(
            "  {} left to the humans (its AVs drive as humans): {}",
            w.window, w.reason
        );
    }
    if let (Some(b), Some(c)) = (&report.baseline, &report.comparison) {
        row("human", b);
        let p = |t: &Option<mapc_rl::stats::WelchTest>| {
            t.map_or("n/a".to_string(), |t| {
                format!("t = {:.2}, p = {:.2e}", t.t, t.p_value)
            })
        };
        let direction = if c.outflow_change_pct >= 0.0 {
            "higher"
        } else {
            "lower"
        };
        if figs.has_ci() && b.has_ci() {
            println!(
                "  outflow {:+.1}% vs human ({direction}; 95% CIs {}); Welch outflow {}, speed {}",
                c.outflow_change_pct,
                if c.outflow_ci_disjoint {
                    "disjoint"
                } else {
                    "overlap"
                },
                p(&c.outflow),
                p(&c.speed)
            );
        } else {
            println!(
                "  outflow {:+.1}% vs human ({direction}; n = 1, no CI and no Welch test: give --seeds 2 or more)",
                c.outflow_change_pct
            );
        }
    }
    if let Some(p) = &args.human_trace {
        println!(
            "  trace of seed {} of the humans written to {}",
            traced_seed,
            p.display()
        );
    }
    if let Some(p) = &args.trace {
        println!(
            "  trace of seed {} under the policy written to {}{}",
            traced_seed,
            p.display(),
            if policy_is_humans {
                " (the humans' run: the policy drives no AV)"
            } else {
                ""
            }
        );
    }
    // one seed: means only, no interval and no test
    let one_seed = report.seeds < 2;
    let flow = |mean: f64, ci: f64| {
        if one_seed {
            format!("{mean:8.2} (n = 1, no CI)")
        } else {
            format!("{mean:8.2} ± {ci:5.2}")
        }
    };
    let compared = |f: &mapc_rl::eval::FlowComparison| {
        let human = f
            .baseline
            .map(|b| format!("   human {} veh/h", flow(b.mean, b.ci95)))
            .unwrap_or_default();
        let welch = f
            .welch
            .filter(|_| !one_seed)
            .map(|w| format!("   Welch t = {:.2}", w.t))
            .unwrap_or_default();
        format!(
            "policy {} veh/h{human}{welch}",
            flow(f.flow.mean, f.flow.ci95)
        )
    };
    // per-merge flows where the scenario measures merges, with the corridor's end beside them
    for m in report.merges.iter().flatten() {
        let window = m
            .window
            .as_ref()
            .map(|w| format!(" (window {w})"))
            .unwrap_or_default();
        println!(
            "  past merge {:>4}{window}: {}",
            m.merge,
            compared(&m.figures)
        );
    }
    if let (Some(_), Some(end)) = (&report.merges, &report.end_flow) {
        println!("  past the corridor's end: {}", compared(end));
    }
    println!("  {:.1} s wall", report.wall_s);
    // a run directory means its last checkpoint; its best policy is a file beside it (a hint: a best.json that
    // cannot be read is named, and the evaluation above stands)
    let best = mapc_rl::checkpoint::best_path(&policy);
    if policy.is_dir() && best.exists() {
        match Checkpoint::load(&best) {
            Ok(Checkpoint {
                selected: Some(sel),
                state,
                ..
            }) => println!(
                "  (this is the run's last policy, after {} iterations; its best by training {}, after {}, is {})",
                ck.state.iteration,
                sel.by.name(),
                state.iteration,
                best.display()
            ),
            Ok(_) => println!("  ({} holds no `selected` field)", best.display()),
            Err(e) => println!("  (the run's best policy could not be read: {e})"),
        }
    }
    Ok(())
}

/// A trace file copied to `to`, atomically.
fn copy_trace(from: &std::path::Path, to: &std::path::Path) -> anyhow::Result<()> {
    let mut source = std::fs::File::open(from)
        .with_context(|| format!("reading the trace {}", from.display()))?;
    mapc_graph::write_atomically_with(to, |w| std::io::copy(&mut source, w).map(|_| ()))
        .with_context(|| format!("writing the trace {}", to.display()))
}
