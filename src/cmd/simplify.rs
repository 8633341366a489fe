//! `mapc simplify`: a highway map becomes a single-lane corridor with its merging roads (a `*.graph.json`), or with
//! `--keep-lanes` a corridor that keeps every lane.

use super::common::{RouteArgs, map_stem, print_lanes};
use mapc_scenario::compile::{corridor_report, simplify_map};
use mapc_scenario::simplify::{corridor_merges, no_merge_warning};
use mapc_scenario::transform::Corridor;
use std::path::PathBuf;

#[derive(clap::Args)]
pub struct Args {
    /// A map (.osm, .osm.pbf, .net.xml) or a graph file (.graph.json).
    pub map: PathBuf,
    #[command(flatten)]
    pub route: RouteArgs,
    /// Where to write the corridor graph; default `<map name>.corridor.graph.json` in the current directory.
    #[arg(short, long, value_name = "OUT")]
    pub output: Option<PathBuf>,
    /// Print what each transformation step did.
    #[arg(long)]
    pub explain: bool,
    /// Print the result as JSON (the merges with their lengths, the steps).
    #[arg(long)]
    pub json: bool,
}

pub fn run(args: Args) -> anyhow::Result<()> {
    let s = simplify_map(&args.map, &args.route.options())?;
    let output = args
        .output
        .clone()
        .unwrap_or_else(|| PathBuf::from(format!("{}.corridor.graph.json", map_stem(&args.map))));
    s.graph.save(&output)?;
    // on stderr, so that the JSON on stdout stays one document (it carries the warning too)
    if let Some(warning) = no_merge_warning(&s, &args.map) {
        eprintln!("warning: {warning}");
    }
    if args.json {
        println!(
            "{}",
            serde_json::to_string_pretty(&corridor_report(&s, &args.map, &output))?
        );
        return Ok(());
    }
    if args.explain {
        for (i, step) in s.steps.iter().enumerate() {
            println!("{}. {}: {}", i + 1, step.step, step.summary);
        }
    }
    let g = &s.graph;
    println!(
        "{}: corridor of {} roads and {} junctions, main road {:.1} m, written to {}",
        args.map.display(),
        g.roads.len(),
        g.junctions.len(),
        Corridor::chain_length_m(g, &s.roles.main),
        output.display()
    );
    println!(
        "{:<8} {:>12} {:>10} {:>10} {:>10}  merging road",
        "merge", "osm node", "before m", "merge m", "after m"
    );
    for m in corridor_merges(g, &s.roles) {
        println!(
            "{:<8} {:>12} {:>10.1} {:>10.1} {:>10.1}  {} {}{}",
            m.junction,
            m.osm_node
                .map_or_else(|| m.sumo_id.clone().unwrap_or_default(), |n| n.to_string()),
            m.main_before_m,
            m.merge_m,
            m.main_after_m,
            m.merging_roads.join("..."),
            m.merging_label,
            if m.merging_is_major { " (major)" } else { "" }
        );
    }
    if g.roads.iter().any(|r| r.lanes.len() > 1) {
        print_lanes(g, &g.roads.iter().map(|r| r.id).collect::<Vec<_>>());
    }
    Ok(())
}
