//! `mapc window`: cut a window around a merge of a corridor, matched to a source scenario's lengths, and write
//! the scenario (the whole corridor, the window as the controlled region, the source's demand).

use super::simplify::{RouteArgs, map_stem};
use mapc_graph::LaneGraph;
use mapc_scenario::compile::{corridor_of, write_window};
use mapc_scenario::window::DemandOverride;
use std::path::PathBuf;

#[derive(clap::Args)]
pub struct Args {
    /// A corridor graph from `mapc simplify`, or a map (.osm, .osm.pbf, .net.xml) simplified first.
    pub map: PathBuf,
    /// The merge junction: `J12`, `osm:NODE` or a SUMO junction id.
    #[arg(long, value_name = "J")]
    pub junction: String,
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
    #[arg(long, value_name = "VPH")]
    pub main_vph: Option<f64>,
    /// Total merging-road demand in veh/h; default the source's.
    #[arg(long, value_name = "VPH")]
    pub merge_vph: Option<f64>,
    /// Controlled AVs at once; default the source's.
    #[arg(long, value_name = "N")]
    pub n_av: Option<u32>,
    /// How a raw map is simplified first (ignored for a corridor graph). Without --via the main road is the
    /// longest route through the junction.
    #[command(flatten)]
    pub route: RouteArgs,
    /// Print the window as JSON.
    #[arg(long)]
    pub json: bool,
}

pub fn run(args: Args) -> anyhow::Result<()> {
    let corridor = corridor_of(&args.map, &args.junction, &args.route.options())?;
    let output = args
        .output
        .clone()
        .unwrap_or_else(|| PathBuf::from(format!("{}_window.toml", map_stem(&args.map))));
    let demand = DemandOverride {
        main_vph: args.main_vph,
        merge_vph: args.merge_vph,
        n_av: args.n_av,
    };
    let written = write_window(
        &corridor,
        &args.map,
        &args.junction,
        &args.match_,
        &output,
        &demand,
    )?;
    let cut = &written.cut;
    let render = match &args.render {
        Some(png) => {
            let mut h = mapc_viz::Highlight::window(cut.region(), [cut.junction]);
            h.title = Some(format!(
                "{}: window at {} matched to {} ({:.0} / {:.0} / {:.0} m)",
                map_stem(&args.map),
                args.junction,
                args.match_,
                cut.upstream_m,
                cut.merge_m,
                cut.downstream_m
            ));
            Some(mapc_viz::render_map(&cut.graph, &h, png)?)
        }
        None => None,
    };
    // a short human run of what was written: which regime each merge is in under this demand
    let resolved = mapc_scenario::ResolvedScenario::load(&written.scenario.display().to_string())?;
    let spec = mapc_sim::spec_from_scenario(&resolved)?;
    let seeds: Vec<u64> = (0..super::sim::REGIME_SEEDS as u64).collect();
    let regime = mapc_sim::merge_regimes(&spec, &seeds)?;
    if args.json {
        let mut report = written.report(&args.match_, render.as_ref().map(|r| r.path.as_path()));
        report["regime"] = serde_json::to_value(&regime)?;
        println!("{}", serde_json::to_string_pretty(&report)?);
        return Ok(());
    }
    println!(
        "window at {} matched to {}: {:.2} m before the merge, {:.2} m of merging road, {:.2} m after",
        super::super::cmd::window::describe(&cut.graph, cut.junction),
        args.match_,
        cut.upstream_m,
        cut.merge_m,
        cut.downstream_m
    );
    for n in &cut.notes {
        println!("  {n}");
    }
    if let Some(t) = &written.timing {
        println!("  {}", t.note);
    }
    println!(
        "wrote {} and {}",
        written.scenario.display(),
        written.graph.display()
    );
    if let Some(r) = render {
        println!("drew {}", r.path.display());
    }
    super::sim::print_regime(&regime);
    Ok(())
}

fn describe(g: &LaneGraph, j: mapc_graph::JunctionId) -> String {
    mapc_scenario::transform::pick_route::describe_junction(g, j)
}
