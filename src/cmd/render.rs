//! `mapc render`: draw a map as PNG or SVG, roads coloured by class, merges labelled, optionally a transfer window
//! highlighted.

use super::common::load_map;
use anyhow::Context;
use mapc_graph::{JunctionId, LaneGraph, RoadId};
use mapc_viz::{Highlight, RenderOptions};
use std::collections::BTreeSet;
use std::path::PathBuf;

#[derive(clap::Args)]
pub struct Args {
    /// The map: a saved graph (.graph.json), an OSM (.osm, .osm.pbf) or SUMO (.net.xml) map, a scenario file
    /// (.toml, its network is drawn) or a built-in scenario name (simple_merge).
    pub map: String,
    /// Output picture; the name's extension picks the kind: .png or .svg.
    #[arg(short = 'o', long = "output", value_name = "FILE")]
    pub output: PathBuf,
    /// Highlight a window scenario's control region on the map (a scenario file or built-in name).
    #[arg(long, value_name = "SCENARIO")]
    pub window: Option<String>,
    /// Picture width in pixels; the height follows from the map's shape.
    #[arg(long, default_value_t = 1600, value_name = "PX", value_parser = super::flags::pixels())]
    pub width: u32,
    /// Junctions to label and ring, whatever their kind (mapc, OSM `osm:NODE` or SUMO ids), comma separated.
    #[arg(long, value_delimiter = ',', value_name = "JUNCTIONS")]
    pub label: Vec<String>,
    /// Roads to highlight (mapc `R12`, `osm-way:WAY` or SUMO ids), comma separated.
    #[arg(long, value_delimiter = ',', value_name = "ROADS")]
    pub highlight: Vec<String>,
    /// Do not label merge junctions.
    #[arg(long)]
    pub no_merge_labels: bool,
    /// Show only the highlighted part (window, roads, labelled junctions) and its surroundings.
    #[arg(long)]
    pub zoom: bool,
    /// Title (default: the map's file name and counts).
    #[arg(long)]
    pub title: Option<String>,
    /// Print what was drawn as JSON.
    #[arg(long)]
    pub json: bool,
}

pub fn run(args: Args) -> anyhow::Result<()> {
    let graph = load_map(&args.map)?;
    let mut highlight = Highlight {
        label_merges: !args.no_merge_labels,
        title: args.title.clone(),
        zoom_to_highlight: args.zoom,
        ..Highlight::default()
    };
    for q in &args.label {
        let id = graph
            .find_junction(q.trim())
            .with_context(|| format!("--label {q}: in map {}", args.map))?;
        highlight.junctions.insert(id);
    }
    for q in &args.highlight {
        let ids = graph
            .find_roads(q.trim())
            .with_context(|| format!("--highlight {q}: in map {}", args.map))?;
        highlight.roads.extend(ids);
    }
    if let Some(window) = &args.window {
        add_window(&graph, window, &mut highlight)?;
    }
    if args.zoom
        && highlight.roads.is_empty()
        && highlight.paths.is_empty()
        && highlight.junctions.is_empty()
    {
        anyhow::bail!("--zoom needs something to zoom onto: --window, --highlight or --label");
    }
    let summary = mapc_viz::render_map_with(
        &graph,
        &highlight,
        &RenderOptions {
            width_px: args.width,
        },
        &args.output,
    )?;
    if args.json {
        println!("{}", serde_json::to_string_pretty(&summary)?);
    } else {
        println!(
            "wrote {} ({}x{} px, {:.1} m/px): {} roads, {} merges, {} labels ({} left out where they overlapped)",
            summary.path.display(),
            summary.width_px,
            summary.height_px,
            summary.metres_per_px,
            summary.roads_drawn,
            summary.merges,
            summary.labels_drawn,
            summary.labels_skipped
        );
    }
    Ok(())
}

/// Put a window scenario's control region on the map. Its roads are found in the map by their provenance (OSM
/// ways, SUMO ids) when they carry some; a window drawn in the map's own frame is also laid over as lines.
fn add_window(graph: &LaneGraph, window: &str, highlight: &mut Highlight) -> anyhow::Result<()> {
    let resolved = mapc_scenario::ResolvedScenario::load(window)?;
    let wg = &resolved.graph;
    let region: Vec<RoadId> = if resolved.region_roads.is_empty() {
        wg.roads.iter().map(|r| r.id).collect()
    } else {
        resolved.region_roads.clone()
    };
    let same_frame = wg.projection == graph.projection && graph.projection.is_geographic();
    let mut found: BTreeSet<RoadId> = BTreeSet::new();
    for rid in &region {
        let Some(r) = wg.road(*rid) else { continue };
        if same_frame {
            highlight.paths.push(r.geometry.clone());
        }
        for m in &graph.roads {
            let shares_way = r
                .provenance
                .osm_ways
                .iter()
                .any(|w| m.provenance.osm_ways.contains(w));
            let shares_sumo = r
                .provenance
                .sumo_ids
                .iter()
                .any(|s| m.provenance.sumo_ids.contains(s));
            if shares_way || shares_sumo {
                found.insert(m.id);
            }
        }
    }
    if !same_frame {
        // In another frame, provenance is all there is to go by; it may take in whole OSM ways, wider than the
        // window itself, so the window's own lines are preferred when the frames agree.
        highlight.roads.extend(found.iter().copied());
    }
    if highlight.paths.is_empty() && found.is_empty() {
        anyhow::bail!(
            "--window {window}: none of its {} region roads could be placed on {} (different frames and no shared OSM or SUMO ids)",
            region.len(),
            graph.source.file
        );
    }
    if let Some(info) = resolved
        .scenario
        .control
        .as_ref()
        .and_then(|c| c.window.as_ref())
    {
        let j: Option<JunctionId> = graph.find_junction(&info.junction).ok();
        highlight.junctions.extend(j);
        highlight.label = Some(format!(
            "window at {} ({:.0} m up, {:.0} m down)",
            info.junction, info.upstream_m, info.downstream_m
        ));
    } else {
        highlight.label = Some(format!("control region of {}", resolved.scenario.name));
    }
    Ok(())
}
