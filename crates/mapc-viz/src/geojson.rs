//! GeoJSON export (RFC 7946): a LineString per road, a Point per junction.
//!
//! Coordinates are WGS84 `[longitude, latitude]` when the graph has a geographic frame. A graph without one (a
//! generated network, an abstract SUMO net) is written in its local metres, which RFC 7946 does not allow; the
//! collection then carries the foreign member `"mapc_coordinates": "local_metres"` and a `"mapc_note"` saying so,
//! so that a reader is not misled into placing it on the globe.

use crate::VizError;
use mapc_graph::{LaneGraph, Projection};
use serde::Serialize;
use serde_json::{Value, json};
use std::path::{Path, PathBuf};

/// What an export wrote, for `--json` and tests.
#[derive(Clone, Debug, Serialize)]
pub struct GeoJsonSummary {
    pub path: PathBuf,
    pub roads: usize,
    pub junctions: usize,
    /// `wgs84` or `local_metres`.
    pub coordinates: &'static str,
    /// `[west, south, east, north]` (degrees) or `[min_x, min_y, max_x, max_y]` (metres).
    pub bbox: [f64; 4],
}

/// Coordinates are written to this many decimals: 1e-7 degrees is about 1 cm.
const DEGREE_DECIMALS: f64 = 1e7;
const METRE_DECIMALS: f64 = 1e3;

/// The graph as a GeoJSON FeatureCollection, with its bounding box.
pub fn to_geojson(graph: &LaneGraph) -> (Value, [f64; 4]) {
    let geographic = graph.projection.is_geographic();
    let point = |p: [f64; 2]| -> [f64; 2] {
        match graph.projection.to_lonlat(p) {
            Some([lon, lat]) if geographic => [
                (lon * DEGREE_DECIMALS).round() / DEGREE_DECIMALS,
                (lat * DEGREE_DECIMALS).round() / DEGREE_DECIMALS,
            ],
            _ => [
                (p[0] * METRE_DECIMALS).round() / METRE_DECIMALS,
                (p[1] * METRE_DECIMALS).round() / METRE_DECIMALS,
            ],
        }
    };
    let mut bbox = [
        f64::INFINITY,
        f64::INFINITY,
        f64::NEG_INFINITY,
        f64::NEG_INFINITY,
    ];
    let mut grow = |c: [f64; 2]| {
        bbox = [
            bbox[0].min(c[0]),
            bbox[1].min(c[1]),
            bbox[2].max(c[0]),
            bbox[3].max(c[1]),
        ];
    };
    let mut features = Vec::with_capacity(graph.roads.len() + graph.junctions.len());
    for r in &graph.roads {
        let coords: Vec<[f64; 2]> = r.geometry.iter().map(|p| point(*p)).collect();
        coords.iter().for_each(|c| grow(*c));
        features.push(json!({
            "type": "Feature",
            "id": r.id.to_string(),
            "geometry": { "type": "LineString", "coordinates": coords },
            "properties": {
                "id": r.id.to_string(),
                "feature": "road",
                "class": r.class,
                "name": r.name,
                "ref": r.ref_,
                "lanes": r.lane_count(),
                "speed_mps": r.speed_mps(),
                "length_m": (r.length_m * 1000.0).round() / 1000.0,
                "from": r.from.to_string(),
                "to": r.to.to_string(),
                "priority": r.priority,
                "osm_ways": r.provenance.osm_ways,
                "sumo_ids": r.provenance.sumo_ids,
            }
        }));
    }
    for j in &graph.junctions {
        let c = point(j.pos);
        grow(c);
        features.push(json!({
            "type": "Feature",
            "id": j.id.to_string(),
            "geometry": { "type": "Point", "coordinates": c },
            "properties": {
                "id": j.id.to_string(),
                "feature": "junction",
                "kind": j.kind,
                "osm_node": j.provenance.osm_nodes.first(),
                "osm_nodes": j.provenance.osm_nodes,
                "sumo_id": j.provenance.sumo_ids.first(),
                "sumo_ids": j.provenance.sumo_ids,
                "incoming": j.incoming.iter().map(|r| r.to_string()).collect::<Vec<_>>(),
                "outgoing": j.outgoing.iter().map(|r| r.to_string()).collect::<Vec<_>>(),
            }
        }));
    }
    if !bbox[0].is_finite() {
        bbox = [0.0; 4];
    }
    let mut collection = json!({
        "type": "FeatureCollection",
        "bbox": bbox,
        "features": features,
        "mapc_source": { "file": graph.source.file, "format": graph.source.format },
    });
    match graph.projection {
        Projection::Utm { zone, north, .. } => {
            collection["mapc_coordinates"] = json!("wgs84");
            collection["mapc_note"] = json!(format!(
                "WGS84 longitude/latitude, from the graph's UTM zone {zone}{} frame",
                if north { "N" } else { "S" }
            ));
        }
        Projection::Plane { .. } => {
            collection["mapc_coordinates"] = json!("local_metres");
            collection["mapc_note"] = json!(
                "this graph has no geographic frame: coordinates are local metres (east, north), not longitude/latitude"
            );
        }
    }
    (collection, bbox)
}

/// Write the graph's GeoJSON to `out`, atomically.
pub fn write_geojson(graph: &LaneGraph, out: &Path) -> Result<GeoJsonSummary, VizError> {
    let (value, bbox) = to_geojson(graph);
    let text = serde_json::to_string(&value).map_err(|e| VizError::Input {
        path: out.to_path_buf(),
        message: e.to_string(),
    })?;
    mapc_graph::write_atomically(out, text.as_bytes()).map_err(|source| VizError::Io {
        path: out.to_path_buf(),
        source,
    })?;
    Ok(GeoJsonSummary {
        path: out.to_path_buf(),
        roads: graph.roads.len(),
        junctions: graph.junctions.len(),
        coordinates: if graph.projection.is_geographic() {
            "wgs84"
        } else {
            "local_metres"
        },
        bbox,
    })
}
