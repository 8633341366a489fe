//! `mapc export`: write a map as GeoJSON (RFC 7946) for QGIS, geojson.io and the like, or a map or scenario as
//! SUMO 1.8 inputs (`mapc_sumo`).

use anyhow::bail;
use std::path::{Path, PathBuf};

#[derive(clap::Args)]
#[command(group(clap::ArgGroup::new("output").required(true).args(["geojson", "sumo"])))]
#[command(
    after_help = "--sumo targets SUMO 1.8.0 (the release mapc's simulator is calibrated to); the files load in \
                  `sumo -c DIR/NAME.sumocfg`. The paper's runs drive every vehicle with speed mode 9 through \
                  TraCI, which tools/sumo_check does."
)]
pub struct Args {
    /// The map: a saved graph (.graph.json), an OSM (.osm, .osm.pbf) or SUMO (.net.xml) map, a scenario file
    /// (.toml) or a built-in scenario name (simple_merge).
    pub map: String,
    /// Output GeoJSON file: a LineString per road, a Point per junction, WGS84 longitude/latitude (local metres,
    /// said so in `mapc_note`, for maps without a geographic frame).
    #[arg(
        long,
        value_name = "FILE",
        required_unless_present = "sumo",
        conflicts_with = "sumo"
    )]
    pub geojson: Option<PathBuf>,
    /// Output directory for SUMO 1.8: NAME.net.xml (mapc's lane lengths and right of way), and for a scenario
    /// NAME.rou.xml (vehicle types with their models, type mixes, flows, initial vehicles), NAME.sumocfg (step
    /// and the paper's options) and NAME.mapc.json (horizon, controlled region, N_AV). The directory is replaced as a whole.
    #[arg(long, value_name = "DIR")]
    pub sumo: Option<PathBuf>,
    /// Print what was written as JSON.
    #[arg(long)]
    pub json: bool,
    /// A scenario's AVs (`--sumo` only), as `mapc eval` gives them: the export carries their flows, types and
    /// controlled region for tools/sumo_check's policy runs.
    #[command(flatten)]
    pub avs: super::common::AvArgs,
}

pub fn run(args: Args) -> anyhow::Result<()> {
    match (&args.geojson, &args.sumo) {
        (Some(file), None) => geojson(&args.map, file, args.json),
        (None, Some(dir)) => sumo(&args.map, dir, args.json, &args.avs),
        _ => bail!("give exactly one of --geojson FILE and --sumo DIR"),
    }
}

fn sumo(map: &str, dir: &Path, json: bool, avs: &super::common::AvArgs) -> anyhow::Result<()> {
    let summary = if super::common::names_scenario(map) {
        let resolved = avs.apply(mapc_scenario::ResolvedScenario::load(map)?)?;
        mapc_sumo::export_scenario(&resolved, dir)?
    } else {
        if avs.av_share.is_some() {
            bail!("--av-share needs a scenario; {map} is a map");
        }
        let graph = mapc_import::load_any(Path::new(map))?;
        let name = Path::new(map)
            .file_name()
            .map(|n| n.to_string_lossy().into_owned())
            .unwrap_or_default();
        let name = name.split('.').next().unwrap_or("map").to_string();
        mapc_sumo::export_network(&graph, &name, dir)?
    };
    if json {
        println!("{}", serde_json::to_string_pretty(&summary)?);
    } else {
        println!(
            "wrote {} for SUMO {}: {} ({} edges, {} lanes, {} junctions, {} connections, {} flows, {} initial vehicles)",
            summary.dir.display(),
            summary.sumo_version,
            summary.files.join(", "),
            summary.edges,
            summary.lanes,
            summary.junctions,
            summary.connections,
            summary.flows,
            summary.initial_vehicles
        );
    }
    Ok(())
}

fn geojson(map: &str, file: &Path, json: bool) -> anyhow::Result<()> {
    let graph = super::common::load_map(map)?;
    let summary = mapc_viz::geojson::write_geojson(&graph, file)?;
    if json {
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
