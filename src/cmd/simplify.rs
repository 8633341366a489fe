//! `mapc simplify`: a highway map becomes a single-lane corridor with its merging roads (a `*.graph.json`), or with
//! `--keep-lanes` a corridor that keeps every lane.

use mapc_scenario::compile::{corridor_report, simplify_map};
use mapc_scenario::simplify::{corridor_merges, no_merge_warning};
use mapc_scenario::transform::{Corridor, SimplifyOptions};
use std::path::{Path, PathBuf};

/// Options shared with `mapc window` when it is given a raw map.
#[derive(clap::Args, Clone, Debug)]
pub struct RouteArgs {
    /// A point the main road must pass, in order (repeat): `osm-way:WAY`, `osm:NODE`, a SUMO edge or junction id,
    /// `R3` or `J3`. Default: the longest through route over --classes (and roads of no class as fast as a
    /// ramp) that passes a junction where another road joins.
    #[arg(long = "via", value_name = "ID")]
    pub via: Vec<String>,
    /// Keep merging roads at most this long (metres) instead of back to where they start in the map.
    #[arg(long, value_name = "M", value_parser = super::flags::within::<f64>(mapc_scenario::ranges::ROAD_LENGTH_M))]
    pub feeder_length: Option<f64>,
    /// Keep diverging roads as exits (up to their next junction) instead of dropping them.
    #[arg(long)]
    pub keep_exits: bool,
    /// Road classes the main road may use where --via does not pin it (comma-separated).
    #[arg(
        long,
        value_delimiter = ',',
        default_value = "motorway,motorway_link,trunk,trunk_link"
    )]
    pub classes: Vec<String>,
    /// Keep footways, paths, cycleways and service roads that meet the main road as merging roads (by default
    /// they are dropped, and a junction only they join is no merge).
    #[arg(long)]
    pub minor_roads: bool,
    /// Keep every lane of the main and merging roads, with their lane-level connections, lane drops, gains and
    /// acceleration lanes (by default each road keeps its rightmost lane, as the paper's corridors do).
    #[arg(long)]
    pub keep_lanes: bool,
}

impl RouteArgs {
    pub fn options(&self) -> SimplifyOptions {
        SimplifyOptions {
            via: self.via.clone(),
            classes: self.classes.clone(),
            feeder_length_m: self.feeder_length,
            keep_exits: self.keep_exits,
            minor_roads: self.minor_roads,
            keep_lanes: self.keep_lanes,
        }
    }
}

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

/// `maps/i696.osm` -> `i696`: the file name without the map or graph extensions (any case).
pub fn map_stem(path: &Path) -> String {
    let name = path
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_else(|| "map".into());
    let lower = name.to_ascii_lowercase();
    for ext in [
        ".corridor.graph.json",
        ".graph.json",
        ".osm.pbf",
        ".osm.xml",
        ".net.xml",
        ".osm",
        ".json",
        ".xml",
        ".pbf",
    ] {
        if lower.len() > ext.len() && lower.ends_with(ext) {
            return name[..name.len() - ext.len()].to_string();
        }
    }
    name
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

/// Lanes per road of a corridor or window that keeps several lanes a road, and the lanes that end there.
pub fn print_lanes(g: &mapc_graph::LaneGraph, roads: &[mapc_graph::RoadId]) {
    let mut parts = Vec::new();
    for r in roads.iter().filter_map(|r| g.road(*r)) {
        let ends: Vec<String> = r
            .lanes
            .iter()
            .filter_map(|l| {
                l.end
                    .map(|e| format!("lane {} {}", l.index, lane_end_name(e)))
            })
            .collect();
        parts.push(if ends.is_empty() {
            format!("{} {}", r.id, r.lanes.len())
        } else {
            format!("{} {} ({})", r.id, r.lanes.len(), ends.join(", "))
        });
    }
    println!("  lanes: {}", parts.join(", "));
}

pub fn lane_end_name(e: mapc_graph::LaneEnd) -> &'static str {
    match e {
        mapc_graph::LaneEnd::Drop => "drops",
        mapc_graph::LaneEnd::Acceleration => "ends (acceleration lane)",
    }
}
