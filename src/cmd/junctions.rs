//! `mapc junctions`: list a map's junctions with the roads in and out of each.

use mapc_graph::{Junction, JunctionKind, LaneGraph, RoadId};
use mapc_import::ImportOptions;
use mapc_scenario::transform::map_merges::{counted_roads, junction_kind};
use serde::Serialize;
use std::path::PathBuf;

#[derive(Clone, Copy, Debug, clap::ValueEnum)]
pub enum KindArg {
    Merge,
    Diverge,
    Through,
    Source,
    Sink,
    Complex,
}

impl From<KindArg> for JunctionKind {
    fn from(k: KindArg) -> JunctionKind {
        match k {
            KindArg::Merge => JunctionKind::Merge,
            KindArg::Diverge => JunctionKind::Diverge,
            KindArg::Through => JunctionKind::Through,
            KindArg::Source => JunctionKind::Source,
            KindArg::Sink => JunctionKind::Sink,
            KindArg::Complex => JunctionKind::Complex,
        }
    }
}

#[derive(clap::Args)]
pub struct Args {
    /// A saved graph (*.graph.json) or a map (.osm, .osm.pbf, .net.xml), imported on the fly.
    pub map: PathBuf,
    /// Only junctions of this kind.
    #[arg(long, value_enum)]
    pub kind: Option<KindArg>,
    /// OSM highway classes to keep when MAP is an OSM file, comma-separated.
    #[arg(long, value_delimiter = ',')]
    pub highways: Option<Vec<String>>,
    /// Print JSON instead of text.
    #[arg(long)]
    pub json: bool,
    /// Count footways, paths, cycleways and service roads too. By default a junction's kind is that among the
    /// other roads (a footway touching a motorway makes no merge), and those roads are not listed.
    #[arg(long)]
    pub minor_roads: bool,
}

#[derive(Serialize)]
struct RoadRow {
    id: String,
    label: String,
    #[serde(skip_serializing_if = "Option::is_none")]
    name: Option<String>,
    #[serde(rename = "ref", skip_serializing_if = "Option::is_none")]
    ref_: Option<String>,
    class: String,
    lanes: usize,
    length_m: f64,
    #[serde(skip_serializing_if = "Vec::is_empty")]
    osm_ways: Vec<i64>,
    #[serde(skip_serializing_if = "Vec::is_empty")]
    sumo_ids: Vec<String>,
}

#[derive(Serialize)]
struct JunctionRow {
    id: String,
    kind: JunctionKind,
    /// `osm:NODE` or the SUMO junction id.
    provenance: String,
    #[serde(skip_serializing_if = "Option::is_none")]
    lat: Option<f64>,
    #[serde(skip_serializing_if = "Option::is_none")]
    lon: Option<f64>,
    incoming: Vec<RoadRow>,
    outgoing: Vec<RoadRow>,
}

fn provenance_text(j: &Junction) -> String {
    let p = &j.provenance;
    let mut parts: Vec<String> = p.osm_nodes.iter().map(|n| format!("osm:{n}")).collect();
    if p.osm_nodes.is_empty() {
        parts.extend(p.sumo_ids.iter().cloned());
    }
    if parts.is_empty() {
        parts.extend(p.made_by.iter().cloned());
    }
    parts.join(" ")
}

fn road_row(g: &LaneGraph, id: RoadId) -> RoadRow {
    let r = g.road(id).expect("junctions list existing roads");
    RoadRow {
        id: id.to_string(),
        label: r.label(),
        name: r.name.clone(),
        ref_: r.ref_.clone(),
        class: r.class.clone(),
        lanes: r.lanes.len(),
        length_m: (r.length_m * 100.0).round() / 100.0,
        osm_ways: r.provenance.osm_ways.clone(),
        sumo_ids: r.provenance.sumo_ids.clone(),
    }
}

pub fn run(args: Args) -> anyhow::Result<()> {
    let mut options = ImportOptions::default();
    if let Some(h) = args.highways {
        options.highways = h;
    }
    let graph = mapc_import::load_any_with(&args.map, &options)?;
    let want: Option<JunctionKind> = args.kind.map(Into::into);
    let counted = |ids: &[RoadId]| counted_roads(&graph, ids, args.minor_roads);
    let rows: Vec<JunctionRow> = graph
        .junctions
        .iter()
        .filter_map(|j| {
            // a junction of footways or service roads only is none of the main roads' junctions
            let kind = junction_kind(&graph, j, args.minor_roads)?;
            let (incoming, outgoing) = (counted(&j.incoming), counted(&j.outgoing));
            want.is_none_or(|k| kind == k)
                .then_some((j, kind, incoming, outgoing))
        })
        .map(|(j, kind, incoming, outgoing)| {
            let lonlat = graph.junction_lonlat(j.id);
            JunctionRow {
                id: j.id.to_string(),
                kind,
                provenance: provenance_text(j),
                lat: lonlat.map(|p| (p[1] * 1e7).round() / 1e7),
                lon: lonlat.map(|p| (p[0] * 1e7).round() / 1e7),
                incoming: incoming.iter().map(|&r| road_row(&graph, r)).collect(),
                outgoing: outgoing.iter().map(|&r| road_row(&graph, r)).collect(),
            }
        })
        .collect();
    if args.json {
        println!("{}", serde_json::to_string_pretty(&rows)?);
        return Ok(());
    }
    println!("{} junctions in {}", rows.len(), args.map.display());
    for j in &rows {
        let at = match (j.lat, j.lon) {
            (Some(lat), Some(lon)) => format!(" at {lat:.7}, {lon:.7}"),
            _ => String::new(),
        };
        println!("{} {:?} ({}){at}", j.id, j.kind, j.provenance);
        for (dir, roads) in [("in ", &j.incoming), ("out", &j.outgoing)] {
            for r in roads {
                let from = if !r.osm_ways.is_empty() {
                    format!(
                        "way {}",
                        r.osm_ways
                            .iter()
                            .map(i64::to_string)
                            .collect::<Vec<_>>()
                            .join(",")
                    )
                } else {
                    format!("edge {}", r.sumo_ids.join(","))
                };
                println!(
                    "    {dir} {:<5} {:<36} {:<20} {:<16} {} lanes {:>9.1} m",
                    r.id, r.label, from, r.class, r.lanes, r.length_m
                );
            }
        }
    }
    Ok(())
}
