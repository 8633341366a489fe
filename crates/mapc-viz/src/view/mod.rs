//! Replays in the browser (`mapc view`): one self-contained HTML file that draws a network and plays traces on it.
//!
//! Glossary:
//! - **page**: the HTML file, its script, styles and data inline; it opens from disk with no server and no network.
//! - **pane**: one run on the page: the map with its vehicles, the metrics so far, and the time-space diagram;
//!   `--compare` puts two panes (humans, policy) under one time slider, with one shared pan and zoom.
//! - **frame**: the state after a number of steps (frame 0: the state before the first step), one row per vehicle
//!   on the road; a trace has warm-up + horizon + 1 frames.
//! - **decimation**: only every k-th frame is kept when a run has more rows than a page holds
//!   ([`INLINE_ROW_LIMIT`]); the page says so.
//! - **serve**: the same page over HTTP on 127.0.0.1 ([`serve`]), its data fetched as `data.json`.
//!
//! The data travels as JSON with the rows in little-endian typed arrays (base64): about 11 bytes per
//! vehicle-step. The page's own code is `assets/viewer.js`, plain JavaScript without a build step.

mod network;
mod page;
mod replay;
mod serve;

pub use network::{NetworkView, WindowMark, provenance_text};
pub use page::{Delivery, content_security_policy, embed_json, hash_source};
pub use replay::{Clock, Replay, RunTotals, Track};
pub use serve::serve;

use crate::VizError;
use base64::Engine;
use mapc_graph::LaneGraph;
use serde::Serialize;
use serde_json::{Value, json};
use std::collections::{BTreeMap, BTreeSet, HashMap};
use std::path::Path;

/// Rows (vehicle-steps over all panes) kept in a page written to a file: about 13 MB of data; larger runs are
/// decimated.
pub const INLINE_ROW_LIMIT: usize = 1_200_000;
/// Rows kept when the page is served (the data is fetched, not parsed from the HTML).
pub const SERVED_ROW_LIMIT: usize = 6_000_000;

/// Everything a page shows.
#[derive(Clone, Debug)]
pub struct ViewPage {
    pub title: String,
    pub subtitle: String,
    pub network: NetworkView,
    /// Vehicle types that are AVs (drawn in their own colour).
    pub av_types: BTreeSet<String>,
    /// Length of each vehicle type (m), drawn to scale when zoomed in; a type not listed is 5 m.
    pub type_lengths: BTreeMap<String, f64>,
    pub replays: Vec<Replay>,
    /// Top of the speed scale, m/s.
    pub speed_max_mps: f64,
    /// For a bare map: what the map holds, one line.
    pub summary: String,
}

/// What a page holds, for `--json` and tests.
#[derive(Clone, Debug, Serialize)]
pub struct ViewSummary {
    pub roads: usize,
    pub junctions: usize,
    pub windows: usize,
    pub panes: Vec<PaneSummary>,
    pub bytes: usize,
}

#[derive(Clone, Debug, Serialize)]
pub struct PaneSummary {
    pub label: String,
    pub frames: usize,
    pub vehicles: usize,
    pub vehicle_steps: usize,
    pub decimation: usize,
    /// The run's metrics over its whole measured time ([`Replay::totals`]).
    pub outflow_veh_h: f64,
    pub inflow_veh_h: f64,
    pub avg_speed_mps: f64,
}

impl ViewPage {
    /// A page for `graph` with `windows` highlighted and no run yet.
    pub fn new(title: &str, graph: &LaneGraph, windows: &[WindowMark]) -> ViewPage {
        let network = NetworkView::of(graph, windows);
        let count = |k: &str| network.junctions.iter().filter(|j| j.kind == k).count();
        let summary = format!(
            "{} roads, {} junctions: {} merges, {} diverges",
            network.roads.len(),
            network.junctions.len(),
            count("merge"),
            count("diverge")
        );
        ViewPage {
            title: title.to_string(),
            subtitle: String::new(),
            network,
            av_types: BTreeSet::new(),
            type_lengths: BTreeMap::new(),
            replays: Vec::new(),
            speed_max_mps: 30.0,
            summary,
        }
    }

    /// Decimate every replay by the same factor so that the rows fit `limit`.
    pub fn fit_rows(&mut self, limit: usize) {
        let rows: usize = self.replays.iter().map(Replay::rows).sum();
        if rows > limit {
            let k = rows.div_ceil(limit);
            for r in &mut self.replays {
                r.decimate(k);
            }
        }
    }

    pub fn summary(&self, bytes: usize) -> ViewSummary {
        ViewSummary {
            roads: self.network.roads.len(),
            junctions: self.network.junctions.len(),
            windows: self.network.windows.len(),
            panes: self
                .replays
                .iter()
                .map(|r| PaneSummary {
                    label: r.label.clone(),
                    frames: r.on_road.len(),
                    vehicles: r.tracks.len(),
                    vehicle_steps: r.rows(),
                    decimation: r.decimation,
                    outflow_veh_h: r.totals.outflow_veh_h,
                    inflow_veh_h: r.totals.inflow_veh_h,
                    avg_speed_mps: r.totals.avg_speed_mps,
                })
                .collect(),
            bytes,
        }
    }

    /// The page's data as JSON (what `#mapc-data` holds and `data.json` serves).
    pub fn data_json(&self) -> Result<String, VizError> {
        let road_index: HashMap<&str, usize> = self
            .network
            .roads
            .iter()
            .enumerate()
            .map(|(i, r)| (r.id.as_str(), i))
            .collect();
        let replays = self
            .replays
            .iter()
            .map(|r| {
                replay_json(
                    r,
                    &self.network,
                    &road_index,
                    &self.av_types,
                    &self.type_lengths,
                )
            })
            .collect::<Result<Vec<_>, _>>()?;
        let stops: Vec<Value> = crate::colors::SPEED_STOPS
            .iter()
            .map(|(t, c)| json!([t, c[0], c[1], c[2]]))
            .collect();
        let data = json!({
            "format": "mapc-view",
            "version": 1,
            "title": self.title,
            "subtitle": self.subtitle,
            "summary": self.summary,
            "network": self.network,
            "speed_scale": { "max_mps": self.speed_max_mps, "stops": stops },
            "replays": replays,
        });
        Ok(data.to_string())
    }

    /// The page with its data inline (see [`page`] for how map text is kept from running).
    pub fn html(&self) -> Result<String, VizError> {
        Ok(page::page_html(
            &self.title,
            Some(&self.data_json()?),
            Delivery::File,
        ))
    }

    /// Write the page atomically; returns its size in bytes.
    pub fn write(&self, path: &Path) -> Result<usize, VizError> {
        let html = self.html()?;
        mapc_graph::write_atomically_with(path, |w| {
            use std::io::Write;
            w.write_all(html.as_bytes())
        })
        .map_err(|source| VizError::Io {
            path: path.to_path_buf(),
            source,
        })?;
        Ok(html.len())
    }
}

/// The page without data: its script fetches `data.json` from where it was served ([`serve`]).
pub fn page_without_data(title: &str) -> String {
    page::page_html(title, None, Delivery::Served)
}

fn replay_json(
    r: &Replay,
    network: &NetworkView,
    road_index: &HashMap<&str, usize>,
    av_types: &BTreeSet<String>,
    type_lengths: &BTreeMap<String, f64>,
) -> Result<Value, VizError> {
    let unknown = |name: &str| VizError::Input {
        path: r.source.clone(),
        message: format!("road `{name}` is not in the network of {}", network.source),
    };
    let lanes = r
        .lanes
        .iter()
        .zip(&r.lane_corridor_start)
        .map(|(name, start)| {
            let mut lane = serde_json::Map::new();
            lane.insert("name".into(), json!(name));
            let length = match name.split_once('>') {
                None => {
                    let i = *road_index.get(name.as_str()).ok_or_else(|| unknown(name))?;
                    lane.insert("road".into(), json!(i));
                    network.roads[i].length_m
                }
                Some((from, to)) => {
                    let a = *road_index.get(from).ok_or_else(|| unknown(from))?;
                    let b = *road_index.get(to).ok_or_else(|| unknown(to))?;
                    lane.insert("from".into(), json!(a));
                    lane.insert("to".into(), json!(b));
                    // the simulator lengthens connections shorter than 0.1 m to that
                    network
                        .via_length_m
                        .get(name)
                        .copied()
                        .unwrap_or(0.0)
                        .max(0.1)
                }
            };
            lane.insert("length".into(), json!(length));
            if let Some(s) = start {
                lane.insert("corridor_start".into(), json!((s * 10.0).round() / 10.0));
            }
            Ok(Value::Object(lane))
        })
        .collect::<Result<Vec<_>, VizError>>()?;
    let types: Vec<Value> = r
        .types
        .iter()
        .zip(r.av_type_flags(av_types))
        .map(|(name, av)| match type_lengths.get(name) {
            Some(l) => json!({ "name": name, "av": av, "length_m": l }),
            None => json!({ "name": name, "av": av }),
        })
        .collect();
    let col = |f: fn(&Track) -> u32| -> Vec<u32> { r.tracks.iter().map(f).collect() };
    Ok(json!({
        "label": r.label,
        "start_s": r.clock.start_s,
        "step_s": r.clock.step_s * r.decimation as f64,
        "frames": r.on_road.len(),
        "warmup_frames": (r.clock.warmup_steps as usize).div_ceil(r.decimation),
        "decimation": r.decimation,
        "kept": kept_steps(r.decimation),
        "lanes": lanes,
        "types": types,
        "vehicles": {
            "ids": r.tracks.iter().map(|t| t.id.as_str()).collect::<Vec<_>>(),
            "type": b64(&r.tracks.iter().map(|t| t.vtype).collect::<Vec<u16>>()),
            "first": b64(&col(|t| t.first)),
            "count": b64(&col(|t| t.count)),
            "offset": b64(&col(|t| t.offset)),
        },
        "rows": {
            "lane": b64(&r.row_lane),
            "lane_index": b64(&r.row_lane_index),
            "pos": b64(&r.row_pos),
            "speed": b64(&r.row_speed),
        },
        "metrics": {
            "outflow": b64(&r.outflow_vph),
            "inflow": b64(&r.inflow_vph),
            "speed": b64(&r.avg_speed_mps),
            "on_road": b64(&r.on_road),
        },
    }))
}

/// What a decimated replay keeps, in words (`every 92nd step kept`; empty when every step is kept).
pub fn kept_steps(decimation: usize) -> String {
    if decimation > 1 {
        format!("every {} step kept", ordinal(decimation))
    } else {
        String::new()
    }
}

/// `1st`, `2nd`, `3rd`, `4th`, `11th`, `12th`, `13th`, `21st`, `92nd`, `111th` ...
pub fn ordinal(n: usize) -> String {
    let suffix = match (n % 10, n % 100) {
        (_, 11..=13) => "th",
        (1, _) => "st",
        (2, _) => "nd",
        (3, _) => "rd",
        _ => "th",
    };
    format!("{n}{suffix}")
}

/// Numbers that travel as little-endian bytes.
trait LeBytes: Copy {
    fn put(self, out: &mut Vec<u8>);
}
impl LeBytes for u8 {
    fn put(self, out: &mut Vec<u8>) {
        out.push(self);
    }
}
impl LeBytes for u16 {
    fn put(self, out: &mut Vec<u8>) {
        out.extend_from_slice(&self.to_le_bytes());
    }
}
impl LeBytes for u32 {
    fn put(self, out: &mut Vec<u8>) {
        out.extend_from_slice(&self.to_le_bytes());
    }
}
impl LeBytes for f32 {
    fn put(self, out: &mut Vec<u8>) {
        out.extend_from_slice(&self.to_le_bytes());
    }
}

/// A typed array for the page: its little-endian bytes in base64 (what `atob` and a typed-array view read back).
fn b64<T: LeBytes>(xs: &[T]) -> String {
    let mut bytes = Vec::with_capacity(std::mem::size_of_val(xs));
    for x in xs {
        x.put(&mut bytes);
    }
    base64::engine::general_purpose::STANDARD.encode(bytes)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn ordinals_take_their_english_suffix() {
        let words: Vec<String> = [1, 2, 3, 4, 11, 12, 13, 21, 22, 23, 92, 101, 111, 112]
            .into_iter()
            .map(ordinal)
            .collect();
        assert_eq!(
            words,
            [
                "1st", "2nd", "3rd", "4th", "11th", "12th", "13th", "21st", "22nd", "23rd", "92nd",
                "101st", "111th", "112th"
            ]
        );
        assert_eq!(kept_steps(1), "");
        assert_eq!(kept_steps(92), "every 92nd step kept");
    }
}
