//! `mapc window`: cut a window around a merge of a corridor, matched to a source scenario's lengths, and write
//! the scenario (the whole corridor, the window as the controlled region, the source's demand).

use super::simplify::{RouteArgs, load_map, map_stem};
use anyhow::Context;
use mapc_graph::LaneGraph;
use mapc_scenario::ResolvedScenario;
use mapc_scenario::simplify::simplify;
use mapc_scenario::transform::CorridorRoles;
use mapc_scenario::window::{DemandOverride, SourceShape, cut_window, window_scenario};
use serde_json::json;
use std::path::{Path, PathBuf};

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

/// The corridor: the graph itself when it is one, else the map simplified.
fn corridor_of(map: &Path, junction: &str, route: &RouteArgs) -> anyhow::Result<LaneGraph> {
    let g = load_map(map)?;
    if CorridorRoles::of(&g).is_ok() {
        return Ok(g);
    }
    let mut opts = route.options();
    if opts.via.is_empty() {
        opts.via = vec![junction.to_string()];
    }
    Ok(simplify(&g, &opts)
        .map_err(|e| anyhow::anyhow!("{}: {e}", map.display()))?
        .graph)
}

pub fn run(args: Args) -> anyhow::Result<()> {
    for (name, v) in [
        ("--main-vph", args.main_vph),
        ("--merge-vph", args.merge_vph),
    ] {
        if let Some(v) = v {
            anyhow::ensure!(
                v.is_finite() && v >= 0.0,
                "{name} must be zero or a positive rate, not {v}"
            );
        }
    }
    let corridor = corridor_of(&args.map, &args.junction, &args.route)?;
    let source =
        ResolvedScenario::load(&args.match_).with_context(|| format!("--match {}", args.match_))?;
    let shape = SourceShape::of(&source)?;
    let cut = cut_window(&corridor, &args.junction, &shape)
        .map_err(|e| anyhow::anyhow!("{}: {e}", args.map.display()))?;
    let output = args
        .output
        .clone()
        .unwrap_or_else(|| PathBuf::from(format!("{}_window.toml", map_stem(&args.map))));
    let name = output
        .file_name()
        .and_then(|n| n.to_str())
        .map(|n| n.trim_end_matches(".toml").to_string());
    let name = name
        .filter(|n| !n.is_empty())
        .unwrap_or_else(|| "window".into());
    let graph_file = format!("{name}.graph.json");
    let graph_path = output.parent().unwrap_or(Path::new("")).join(&graph_file);
    let demand = DemandOverride {
        main_vph: args.main_vph,
        merge_vph: args.merge_vph,
        n_av: args.n_av,
    };
    let scenario = window_scenario(&cut, &source, &shape, &name, &graph_file, &demand)?;
    cut.graph.save(&graph_path)?;
    scenario.save(&output)?;
    // What was written must read back as a sound scenario.
    ResolvedScenario::load(&output.display().to_string()).with_context(|| {
        format!(
            "the written scenario {} does not load back",
            output.display()
        )
    })?;
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
    let junction = cut.graph.junction(cut.junction).unwrap();
    if args.json {
        let report = json!({
            "junction": cut.junction.to_string(),
            "osm_node": junction.provenance.osm_nodes.first(),
            "sumo_id": junction.provenance.sumo_ids.first(),
            "matched_to": args.match_,
            "source": { "upstream_m": shape.upstream_m, "merge_m": shape.merge_m, "downstream_m": shape.downstream_m },
            "upstream_m": cut.upstream_m,
            "merge_m": cut.merge_m,
            "downstream_m": cut.downstream_m,
            "region": cut.region().iter().map(|r| r.to_string()).collect::<Vec<_>>(),
            "main_entry": cut.main_entry.to_string(),
            "merge_entry": cut.merge_entry.to_string(),
            "cuts": cut.notes,
            "scenario": output.display().to_string(),
            "graph": graph_path.display().to_string(),
            "render": render.as_ref().map(|r| r.path.display().to_string()),
        });
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
    println!("wrote {} and {}", output.display(), graph_path.display());
    if let Some(r) = render {
        println!("drew {}", r.path.display());
    }
    Ok(())
}

fn describe(g: &LaneGraph, j: mapc_graph::JunctionId) -> String {
    mapc_scenario::transform::pick_route::describe_junction(g, j)
}
