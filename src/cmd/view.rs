//! `mapc view`: a replay in the browser. Writes one self-contained HTML page (or serves it on 127.0.0.1) that
//! draws the network and plays a seed of the scenario on it: humans, a policy, or both side by side.

use anyhow::Context;
use mapc_rl::Checkpoint;
use mapc_rl::eval::PolicyDriver;
use mapc_rl::rollout::ActionMode;
use mapc_scenario::ResolvedScenario;
use mapc_sim::{SimSpec, TRACE_HEADER, spec_from_scenario};
use mapc_viz::view::{self, Clock, Replay, RunTotals, ViewPage, WindowMark};
use std::io::Write;
use std::path::PathBuf;

#[derive(clap::Args)]
pub struct Args {
    /// A scenario (file or built-in name: simple_merge) to play, or a map (a saved graph, .osm, .osm.pbf,
    /// .net.xml) to show with its merges and diverges labelled.
    pub target: String,
    /// Drive the AVs with this policy (a checkpoint file or a run directory), as `mapc eval` does.
    #[arg(long)]
    pub policy: Option<PathBuf>,
    /// Two panes on the same seed, in sync: the humans and the policy.
    #[arg(long, requires = "policy")]
    pub compare: bool,
    /// Play this trace (`mapc sim --trace`, `mapc eval --trace`) of the scenario instead of running one; given
    /// twice, the two side by side in sync (a policy's run beside ALINEA's, say).
    #[arg(long, conflicts_with_all = ["policy", "compare"], num_args = 1, action = clap::ArgAction::Append)]
    pub trace: Vec<PathBuf>,
    /// The seed to play.
    #[arg(long, default_value_t = 0)]
    pub seed: u64,
    /// The page to write (script, styles and data inline; it opens from disk with no server or network).
    #[arg(short = 'o', long = "output", default_value = "replay.html")]
    pub output: PathBuf,
    /// Serve the page on 127.0.0.1 instead of writing it (for runs too large to inline); Ctrl-C stops.
    #[arg(long)]
    pub serve: bool,
    /// Port for --serve (0: any free port; the address is printed).
    #[arg(long, default_value_t = 0, requires = "serve")]
    pub port: u16,
    /// Stop serving after this many requests (for scripts and tests).
    #[arg(long, requires = "serve", hide = true, value_parser = super::flags::count::<usize>(1..=u64::MAX))]
    pub max_requests: Option<usize>,
    /// Vehicle-steps a page holds before only every k-th step is kept (default: 1 200 000 in a file, about
    /// 13 MB; 6 000 000 served).
    #[arg(long, value_name = "ROWS", value_parser = super::flags::count::<usize>(1..=u64::MAX))]
    pub max_rows: Option<usize>,
    /// Print what the page holds as JSON.
    #[arg(long)]
    pub json: bool,
}

pub fn run(args: Args) -> anyhow::Result<()> {
    let mut page = if super::common::names_scenario(&args.target) {
        scenario_page(&args)?
    } else {
        let graph = super::common::load_map(&args.target)?;
        anyhow::ensure!(
            args.policy.is_none() && args.trace.is_empty(),
            "{} is a map, not a scenario: --policy and --trace need a scenario (make one with `mapc window`)",
            args.target
        );
        let mut page = ViewPage::new(&format!("{} (mapc view)", args.target), &graph, &[]);
        page.subtitle = format!(
            "{:?} input; merges filled black, diverges white; hover a road or junction for its ids",
            graph.source.format
        );
        page
    };
    if args.serve {
        page.fit_rows(args.max_rows.unwrap_or(view::SERVED_ROW_LIMIT));
        return serve(&page, &args);
    }
    page.fit_rows(args.max_rows.unwrap_or(view::INLINE_ROW_LIMIT));
    let bytes = page.write(&args.output)?;
    let summary = page.summary(bytes);
    if args.json {
        println!("{}", serde_json::to_string_pretty(&summary)?);
        return Ok(());
    }
    println!(
        "wrote {} ({:.2} MB): {} roads, {} junctions, {} window{}",
        args.output.display(),
        bytes as f64 / 1e6,
        summary.roads,
        summary.junctions,
        summary.windows,
        if summary.windows == 1 { "" } else { "s" }
    );
    for p in &summary.panes {
        println!(
            "  {}: {} frames, {} vehicles, {} vehicle-steps{}; outflow {:.1} veh/h, inflow {:.1} veh/h, speed {:.2} m/s",
            p.label,
            p.frames,
            p.vehicles,
            p.vehicle_steps,
            if p.decimation > 1 {
                format!(" ({})", view::kept_steps(p.decimation))
            } else {
                String::new()
            },
            p.outflow_veh_h,
            p.inflow_veh_h,
            p.avg_speed_mps
        );
    }
    Ok(())
}

fn scenario_page(args: &Args) -> anyhow::Result<ViewPage> {
    let resolved = super::common::load_scenario(&args.target)?;
    let spec =
        spec_from_scenario(&resolved).with_context(|| format!("scenario `{}`", resolved.origin))?;
    let mut page = ViewPage::new(
        &format!("{} (mapc view)", resolved.scenario.name),
        &resolved.graph,
        &windows(&resolved),
    );
    page.av_types = resolved
        .scenario
        .vehicle_types
        .iter()
        .filter(|(_, t)| t.controlled)
        .map(|(name, _)| name.clone())
        .collect();
    page.type_lengths = resolved
        .scenario
        .vehicle_types
        .iter()
        .map(|(name, t)| (name.clone(), t.length))
        .collect();
    if !page.network.lights.is_empty() {
        page.network.light_clock_start_s = Some(spec.start_time_s);
    }
    page.speed_max_mps = resolved
        .graph
        .roads
        .iter()
        .map(|r| r.speed_mps())
        .fold(0.0, f64::max)
        .max(1.0);
    let clock = Clock {
        start_s: spec.start_time_s,
        step_s: spec.step_s,
        warmup_steps: spec.warmup_steps,
        horizon_steps: spec.horizon_steps,
    };
    let seed = args.seed;
    if !args.trace.is_empty() {
        anyhow::ensure!(
            args.trace.len() <= 2,
            "--trace given {} times: a page plays one trace, or two side by side",
            args.trace.len()
        );
        let mut labels = Vec::new();
        for path in &args.trace {
            let file = mapc_graph::input::open(path)
                .with_context(|| format!("reading the trace {}", path.display()))?;
            let label = format!("trace {}", path.display());
            page.replays.push(Replay::read(
                path,
                Box::new(std::io::BufReader::new(file)),
                clock,
                &label,
            )?);
            labels.push(label);
        }
        page.subtitle = format!("{}; {}", resolved.origin, labels.join(" beside "));
        return Ok(page);
    }
    match &args.policy {
        None => {
            page.replays.push(simulated_replay(
                &spec,
                seed,
                clock,
                &format!("simulation, seed {seed}"),
            )?);
            page.subtitle = format!(
                "{}; every vehicle drives as its type says (no policy)",
                resolved.origin
            );
        }
        Some(policy) => {
            let file = mapc_rl::checkpoint::policy_file(policy);
            let ck = Checkpoint::load(&file)?;
            let n_av = resolved.scenario.control.as_ref().map(|c| c.n_av as usize);
            let driver =
                PolicyDriver::for_scenario(&ck, &file, &args.target, Some(n_av.unwrap_or(5)))?;
            // worked out once: the `measured` rule runs its calibration for it
            let deployment = mapc_rl::eval::deployed_spec(&ck, &driver, &spec)?;
            let label = format!("policy {}, seed {seed}", file.display());
            if deployment.spec.is_none() {
                // the rule leaves every AV to the humans: the policy's run is theirs, run once for both panes
                let humans = human_replay(&spec, seed, clock)?;
                if args.compare {
                    page.replays.push(humans.clone());
                }
                page.replays.push(Replay { label, ..humans });
            } else {
                // the humans' run of --compare beside the policy's
                let (humans, policy_run) = rayon::join(
                    || args.compare.then(|| human_replay(&spec, seed, clock)),
                    || {
                        let mut measured = None;
                        trace(|w| {
                            measured = Some(driver.trace_deployed(
                                &ck,
                                &spec,
                                &deployment,
                                seed,
                                ActionMode::Mean,
                                w,
                            )?);
                            Ok(())
                        })
                        .map(|rows| (rows, measured))
                    },
                );
                if let Some(humans) = humans {
                    page.replays.push(humans?);
                }
                let (rows, measured) = policy_run
                    .with_context(|| format!("running {} on seed {seed}", file.display()))?;
                let mut replay = read(rows, clock, &label)?;
                if let Some(m) = measured {
                    replay.totals = RunTotals {
                        outflow_veh_h: m.outflow,
                        inflow_veh_h: m.inflow,
                        avg_speed_mps: m.speed,
                    };
                }
                page.replays.push(replay);
            }
            // where the policy's deployment rule leaves the AVs to drive as humans, the page says so
            let withheld: Vec<String> = deployment
                .withheld
                .iter()
                .map(|w| format!("{} left to the humans ({})", w.window, w.reason))
                .collect();
            page.subtitle = format!(
                "{}; AVs driven by {} (mean actions){}{}",
                resolved.origin,
                file.display(),
                if args.compare {
                    "; above, the same seed with humans only"
                } else {
                    ""
                },
                withheld
                    .iter()
                    .map(|w| format!("; {w}"))
                    .collect::<String>()
            );
        }
    }
    Ok(page)
}

/// The windows to highlight: the control region with the window it was cut as.
fn windows(resolved: &ResolvedScenario) -> Vec<WindowMark> {
    let Some(control) = &resolved.scenario.control else {
        return Vec::new();
    };
    if resolved.region_roads.is_empty() {
        return Vec::new();
    }
    if !control.windows.is_empty() {
        // Several windows: one mark each, with the roads the scenario resolved for it.
        return control
            .windows
            .iter()
            .zip(&resolved.windows)
            .map(|(w, r)| {
                let merges: Vec<String> = w.merges().cloned().collect();
                WindowMark {
                    roads: r.roads.clone(),
                    junction: Some(w.junction.clone()),
                    label: format!(
                        "window at {} ({:.0} m up, {:.0} m of merging road, {:.0} m down; {} AVs)",
                        merges.join(" + "),
                        w.upstream_m,
                        w.merge_m,
                        w.downstream_m,
                        control.n_av
                    ),
                }
            })
            .collect();
    }
    let (junction, label) = match &control.window {
        Some(w) => (
            Some(w.junction.clone()),
            format!(
                "window at {} ({:.0} m up, {:.0} m of merging road, {:.0} m down; {} AVs)",
                w.junction, w.upstream_m, w.merge_m, w.downstream_m, control.n_av
            ),
        ),
        None => (None, format!("control region ({} AVs)", control.n_av)),
    };
    vec![WindowMark {
        roads: resolved.region_roads.clone(),
        junction,
        label,
    }]
}

fn human_replay(spec: &SimSpec, seed: u64, clock: Clock) -> anyhow::Result<Replay> {
    simulated_replay(
        &spec.all_human(),
        seed,
        clock,
        &format!("humans only, seed {seed}"),
    )
}

/// A run of `spec` on `seed`, with the simulator's metrics (not the frames', which a decimated page thins).
fn simulated_replay(
    spec: &SimSpec,
    seed: u64,
    clock: Clock,
    label: &str,
) -> anyhow::Result<Replay> {
    let mut measured = None;
    let rows = trace(|w| {
        measured = Some(mapc_sim::trace_run(spec, seed, w)?.metrics);
        Ok(())
    })?;
    let mut replay = read(rows, clock, label)?;
    if let Some(m) = measured {
        replay.totals = RunTotals {
            outflow_veh_h: m.outflow_veh_h,
            inflow_veh_h: m.inflow_veh_h,
            avg_speed_mps: m.avg_speed_mps,
        };
    }
    Ok(replay)
}

/// A trace written in memory, header first.
fn trace(body: impl FnOnce(&mut Vec<u8>) -> anyhow::Result<()>) -> anyhow::Result<Vec<u8>> {
    let mut rows = Vec::new();
    writeln!(rows, "{TRACE_HEADER}")?;
    body(&mut rows)?;
    Ok(rows)
}

fn read(rows: Vec<u8>, clock: Clock, label: &str) -> anyhow::Result<Replay> {
    let name = PathBuf::from(format!("<{label}>"));
    Ok(Replay::read(
        &name,
        Box::new(std::io::Cursor::new(rows)),
        clock,
        label,
    )?)
}

fn serve(page: &ViewPage, args: &Args) -> anyhow::Result<()> {
    let listener = std::net::TcpListener::bind(("127.0.0.1", args.port))
        .with_context(|| format!("--serve: cannot listen on 127.0.0.1:{}", args.port))?;
    let addr = listener.local_addr()?;
    let data = page.data_json()?;
    let html = view::page_without_data(&page.title);
    println!(
        "serving {} at http://{addr}/ ({:.2} MB of data); Ctrl-C stops",
        page.title,
        data.len() as f64 / 1e6
    );
    std::io::stdout().flush()?;
    view::serve(&listener, &html, &data, args.max_requests)?;
    Ok(())
}
