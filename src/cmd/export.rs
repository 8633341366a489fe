//! `mapc export`: write a map as GeoJSON (RFC 7946) for QGIS, geojson.io and the like.

use std::path::PathBuf;

#[derive(clap::Args)]
pub struct Args {
    /// The map: a saved graph (.graph.json), an OSM (.osm, .osm.pbf) or SUMO (.net.xml) map, a scenario file
    /// (.toml) or a built-in scenario name (simple_merge).
    pub map: String,
    /// Output GeoJSON file: a LineString per road, a Point per junction, WGS84 longitude/latitude (local metres,
    /// said so in `mapc_note`, for maps without a geographic frame).
    #[arg(long, value_name = "FILE")]
    pub geojson: PathBuf,
    /// Print what was written as JSON.
    #[arg(long)]
    pub json: bool,
}

pub fn run(args: Args) -> anyhow::Result<()> {
    let graph = super::render::load_map(&args.map)?;
    let summary = mapc_viz::geojson::write_geojson(&graph, &args.geojson)?;
    if args.json {
        println!("{}", serde_json::to_string_pretty(&summary)?);
    } else {
        let frame = if summary.coordinates == "wgs84" {
            "WGS84 longitude/latitude"
        } else {
            "local metres: this map has no geographic frame"
        };
        println!(
            "wrote {}: {} roads, {} junctions ({frame})",
            summary.path.display(),
            summary.roads,
            summary.junctions
        );
    }
    Ok(())
}
