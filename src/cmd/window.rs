//! `mapc window`: cut a window around a merge of a corridor (or several, `--junction` repeated or `--all`),
//! matched to a source scenario's lengths, and write the scenario (the whole corridor, each window a controlled
//! region, the source's demand on every entry).

mod fit;

use super::common::{RouteArgs, map_stem};
use anyhow::Context;
use fit::WindowLengths;
use mapc_graph::LaneGraph;
use mapc_scenario::compile::{WindowsOptions, WrittenWindows, corridor_of, prepare_windows};
use mapc_scenario::window::{CutRegion, DemandOverride, Fit, Lengths, WindowRequest};
use std::path::PathBuf;

#[derive(clap::Args)]
pub struct Args {
    /// A corridor graph from `mapc simplify`, or a map (.osm, .osm.pbf, .net.xml) simplified first.
    pub map: PathBuf,
    /// The merge junction: `J12`, `osm:NODE` or a SUMO junction id; repeat it for several windows, one
    /// controlled region each (two that overlap are refused, unless --join).
    #[arg(long, value_name = "J", required_unless_present = "all")]
    pub junction: Vec<String>,
    /// A window at every merge of the corridor whose window fits; of two that overlap the first along the
    /// corridor is kept (merges given by --junction are kept with their --upstream-m).
    #[arg(long)]
    pub all: bool,
    /// Join overlapping windows into one controlled region (one FIFO) instead of refusing them.
    #[arg(long)]
    pub join: bool,
    /// Cut a window shorter than the source's where the map has less (a ramp of 194 m, 513 m before the merge),
    /// each length down to --fit-floor of the source's; with --all, every merge that fits above the floor gets a
    /// window. The report says which lengths were fitted and what that does to a policy's observation.
    #[arg(long)]
    pub fit: bool,
    /// With --fit: the shortest a fitted length may be, as a fraction of the source's (default 0.5).
    #[arg(long, value_name = "FRACTION", requires = "fit", value_parser = super::flags::within::<f64>(super::flags::FIT_FLOOR))]
    pub fit_floor: Option<f64>,
    /// Main road before merge J in its window, if not the source's (`J=METRES`, repeatable): windows cut
    /// shorter upstream to fit between close merges.
    #[arg(long = "upstream-m", value_name = "J=M", value_parser = parse_pair)]
    pub upstream_m: Vec<(String, f64)>,
    /// Demand of one merging road, named by any of its roads (`ROAD=VPH`, repeatable; 0: no flow there).
    #[arg(long = "ramp-vph", value_name = "ROAD=VPH", value_parser = parse_pair)]
    pub ramp_vph: Vec<(String, f64)>,
    /// With one window: a flow on every merging road of the corridor, not only the window's (several windows
    /// always have one).
    #[arg(long)]
    pub every_ramp: bool,
    /// The source scenario whose lengths and demand the window takes: a built-in name or a scenario file.
    #[arg(
        long = "match",
        value_name = "SCENARIO",
        default_value = "simple_merge"
    )]
    pub match_: String,
    /// Where to write the scenario; the cut corridor graph goes beside it as `<name>.graph.json`.
    /// Default: `<map name>_window.toml` in the current directory.
    #[arg(short, long, value_name = "SCENARIO")]
    pub output: Option<PathBuf>,
    /// Draw the corridor with the window highlighted (.png or .svg).
    #[arg(long, value_name = "PNG")]
    pub render: Option<PathBuf>,
    /// Total main-road demand in veh/h (split among vehicle types as in the source); default the source's.
    #[arg(long, value_name = "VPH", value_parser = super::flags::within::<f64>(super::flags::DEMAND_VPH))]
    pub main_vph: Option<f64>,
    /// Total merging-road demand in veh/h; default the source's.
    #[arg(long, value_name = "VPH", value_parser = super::flags::within::<f64>(super::flags::DEMAND_VPH))]
    pub merge_vph: Option<f64>,
    /// Controlled AVs at once; default the source's.
    #[arg(long, value_name = "N", value_parser = super::flags::count::<u32>(super::flags::WINDOW_N_AV))]
    pub n_av: Option<u32>,
    /// How a raw map is simplified first (ignored for a corridor graph). Without --via the main road is the
    /// longest route through the junction.
    #[command(flatten)]
    pub route: RouteArgs,
    /// Print the window as JSON.
    #[arg(long)]
    pub json: bool,
}

/// `KEY=NUMBER`.
fn parse_pair(s: &str) -> Result<(String, f64), String> {
    let (k, v) = s
        .split_once('=')
        .ok_or_else(|| format!("`{s}`: expected KEY=NUMBER"))?;
    let v: f64 = v
        .trim()
        .parse()
        .map_err(|_| format!("`{s}`: `{v}` is not a number"))?;
    Ok((k.trim().to_string(), v))
}

pub fn run(args: Args) -> anyhow::Result<()> {
    let fit = if args.fit {
        Some(Fit::new(args.fit_floor.unwrap_or(Fit::DEFAULT_FLOOR))?)
    } else {
        None
    };
    let corridor = corridor_of(
        &args.map,
        args.junction.first().map(String::as_str),
        &args.route.options(),
    )?;
    let output = args
        .output
        .clone()
        .unwrap_or_else(|| PathBuf::from(format!("{}_window.toml", map_stem(&args.map))));
    let demand = DemandOverride {
        main_vph: args.main_vph,
        merge_vph: args.merge_vph,
        n_av: args.n_av,
        ramp_vph: args.ramp_vph.clone(),
        every_ramp: args.every_ramp,
    };
    let mut requests: Vec<WindowRequest> =
        args.junction.iter().map(|j| WindowRequest::at(j)).collect();
    for (j, m) in &args.upstream_m {
        let want = corridor
            .find_junction(j)
            .with_context(|| format!("--upstream-m {j}={m}"))?;
        let Some(r) = requests
            .iter_mut()
            .find(|r| corridor.find_junction(&r.junction).ok() == Some(want))
        else {
            anyhow::bail!("--upstream-m {j}={m}: {j} is not one of the --junction merges");
        };
        r.upstream_m = Some(*m);
    }
    // One `--junction` alone (and no `--all` or `--join`, which compile checks) keeps the one-window format: its
    // scenario, report and render as they always were.
    let one_window = args.junction.len() == 1 && args.upstream_m.is_empty();
    let (written, files) = prepare_windows(
        &corridor,
        &args.map,
        &requests,
        WindowsOptions {
            all: args.all,
            join: args.join,
            fit,
            one_window,
        },
        &args.match_,
        &output,
        &demand,
    )?;
    // a short human run of what is written: which regime each merge is in under this demand; run before writing,
    // so that a scenario the simulator refuses is not left behind
    let regime = regime_of(&files.resolved)?;
    files.write()?;
    let render = match &args.render {
        Some(png) => Some(render(&written, &args, png)?),
        None => None,
    };
    let g = &written.cut.graph;
    let lengths_of = |r| region_lengths(g, r);
    if args.json {
        let mut report = written.report(&args.match_, render.as_ref().map(|r| r.path.as_path()));
        let mut observations = written
            .cut
            .regions
            .iter()
            .map(|r| fit::observation(&written.shape, &lengths_of(r)));
        if written.one_window {
            report["observation"] = observations.next().expect("one window");
        } else {
            for (w, o) in report["windows"]
                .as_array_mut()
                .expect("a list of windows")
                .iter_mut()
                .zip(observations)
            {
                w["observation"] = o;
            }
        }
        report["regime"] = serde_json::to_value(&regime)?;
        println!("{}", serde_json::to_string_pretty(&report)?);
        return Ok(());
    }
    for r in &written.cut.regions {
        let merges: Vec<String> = r.merges.iter().map(|j| describe(g, *j)).collect();
        let along = if written.one_window {
            String::new()
        } else {
            format!(
                " ({:.1} m to {:.1} m along the main road)",
                r.start_m(),
                r.end_m()
            )
        };
        println!(
            "window at {} matched to {}: {:.2} m before the merge, {:.2} m of merging road, {:.2} m after{along}",
            merges.join(" + "),
            args.match_,
            r.upstream_m,
            r.merge_m[0],
            r.downstream_m,
        );
        if r.merges.len() == 1 {
            for line in fit::lines(&written.shape, &args.match_, &lengths_of(r)) {
                println!("  {line}");
            }
        }
    }
    for n in &written.cut.notes {
        println!("  {n}");
    }
    for s in &written.cut.skipped {
        println!("skipped {s}");
    }
    if let Some(t) = &written.timing {
        println!("  {}", t.note);
    }
    for d in &written.demand_notes {
        println!("  {d}");
    }
    // the lanes: before the files written, or after them for one window (as that report always had them)
    let print_lanes = || {
        if g.roads.iter().any(|r| r.lanes.len() > 1) {
            let roads: Vec<_> = written.cut.regions.iter().flat_map(|r| r.roads()).collect();
            super::common::print_lanes(g, &roads);
        }
    };
    if !written.one_window {
        print_lanes();
    }
    println!(
        "wrote {} and {}",
        written.scenario.display(),
        written.graph.display()
    );
    if let Some(r) = render {
        println!("drew {}", r.path.display());
    }
    if written.one_window {
        print_lanes();
    }
    super::common::print_regime(&regime);
    Ok(())
}

/// A short human run of a window scenario: which regime each merge is in under its demand.
fn regime_of(resolved: &mapc_scenario::ResolvedScenario) -> anyhow::Result<mapc_sim::RegimeReport> {
    let spec = mapc_sim::spec_from_scenario(resolved)?;
    let seeds: Vec<u64> = (0..super::common::REGIME_SEEDS as u64).collect();
    Ok(mapc_sim::merge_regimes(&spec, &seeds)?)
}

/// The corridor with every window highlighted.
fn render(
    written: &WrittenWindows,
    args: &Args,
    picture: &std::path::Path,
) -> anyhow::Result<mapc_viz::MapRenderSummary> {
    let cut = &written.cut;
    let roads = cut.regions.iter().flat_map(|r| r.roads());
    let merges = cut.regions.iter().flat_map(|r| r.merges.clone());
    let mut h = mapc_viz::Highlight::window(roads, merges);
    if written.one_window {
        let r = &cut.regions[0];
        h.title = Some(format!(
            "{}: window at {} matched to {} ({:.0} / {:.0} / {:.0} m)",
            map_stem(&args.map),
            args.junction[0],
            args.match_,
            r.upstream_m,
            r.merge_m[0],
            r.downstream_m
        ));
    } else {
        let names: Vec<String> = cut
            .regions
            .iter()
            .map(|r| {
                r.merges
                    .iter()
                    .map(|j| j.to_string())
                    .collect::<Vec<_>>()
                    .join("+")
            })
            .collect();
        h.title = Some(format!(
            "{}: {} windows ({}) matched to {}",
            map_stem(&args.map),
            cut.regions.len(),
            names.join(", "),
            args.match_
        ));
        h.label = Some("transfer windows".to_string());
    }
    Ok(mapc_viz::render_map(&cut.graph, &h, picture)?)
}

/// A region's lengths for the report (a joined region: its merging roads together, the main road between).
fn region_lengths<'a>(g: &LaneGraph, r: &'a CutRegion) -> WindowLengths<'a> {
    WindowLengths {
        lengths: Lengths {
            upstream_m: r.upstream_m,
            merge_m: r.merge_m.iter().sum(),
            downstream_m: r.downstream_m,
        },
        between_m: r
            .between_roads
            .iter()
            .map(|x| g.road(*x).unwrap().length_m)
            .sum(),
        corridor_before_m: r.merge_at_m[0],
        fitted: &r.fitted,
    }
}

fn describe(g: &LaneGraph, j: mapc_graph::JunctionId) -> String {
    mapc_scenario::transform::pick_route::describe_junction(g, j)
}
