//! `mapc import`: read an OSM or SUMO map, write its lane graph and print a summary.

use anyhow::Context;
use mapc_import::{DEFAULT_HIGHWAYS, ImportOptions, MajorRoad, Summary};
use std::path::PathBuf;

#[derive(clap::Args)]
pub struct Args {
    /// The map: OSM XML (.osm), OSM PBF (.osm.pbf) or SUMO network (.net.xml).
    pub file: PathBuf,
    /// Where to write the graph [default: <stem>.graph.json in the current directory].
    #[arg(short, long)]
    pub output: Option<PathBuf>,
    /// OSM highway classes to keep, comma-separated [default: motorway,motorway_link,trunk,trunk_link,primary].
    #[arg(long, value_delimiter = ',')]
    pub highways: Option<Vec<String>>,
    /// Override the right of way: at JUNCTION the road ROAD is major, e.g. `osm:61862553=osm-way:124433709`
    /// (repeatable; junctions as `J4`, `osm:NODE` or a SUMO id; roads as `R7`, `osm-way:WAY` or a SUMO edge id).
    #[arg(long = "major", value_name = "JUNCTION=ROAD")]
    pub major: Vec<MajorRoad>,
    /// Print the summary as JSON.
    #[arg(long)]
    pub json: bool,
}

pub fn run(args: Args) -> anyhow::Result<()> {
    let mut options = ImportOptions::default();
    if let Some(h) = args.highways {
        let h: Vec<String> = h
            .into_iter()
            .map(|s| s.trim().to_string())
            .filter(|s| !s.is_empty())
            .collect();
        anyhow::ensure!(
            !h.is_empty(),
            "--highways: name at least one class (default: {})",
            DEFAULT_HIGHWAYS.join(",")
        );
        options.highways = h;
    }
    options.major_roads = args.major;
    let graph = mapc_import::import_path(&args.file, &options)?;
    let output = args.output.unwrap_or_else(|| {
        PathBuf::from(format!(
            "{}.graph.json",
            super::common::map_stem(&args.file)
        ))
    });
    graph
        .save(&output)
        .with_context(|| format!("writing the graph to {}", output.display()))?;
    let summary = Summary::of(&graph);
    if args.json {
        let mut value = serde_json::to_value(&summary)?;
        value["output"] = serde_json::Value::String(output.display().to_string());
        println!("{}", serde_json::to_string_pretty(&value)?);
    } else {
        println!("{} -> {}", args.file.display(), output.display());
        println!(
            "  {} junctions ({} merges, {} diverges), {} roads, {} lanes, {} connections",
            summary.junctions,
            summary.merges,
            summary.diverges,
            summary.roads,
            summary.lanes,
            summary.connections
        );
        println!(
            "  total length {:.3} km of road, {:.3} km of lane",
            summary.total_length_m / 1000.0,
            summary.total_lane_length_m / 1000.0
        );
        if summary.warnings.is_empty() {
            println!("  no warnings");
        } else {
            println!("  warnings:");
            for (kind, n) in &summary.warnings {
                let example = graph
                    .warnings
                    .examples
                    .get(kind)
                    .and_then(|e| e.first())
                    .map_or("", String::as_str);
                println!("    {kind}: {n} (e.g. {example})");
            }
        }
    }
    Ok(())
}
