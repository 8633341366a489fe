//! Map renders: roads coloured by class, merges labelled with their ids, a scale bar, north up, equal aspect.
//!
//! The drawing maps the graph's local metric frame (metres east, north) to pixels with one scale for both axes, so
//! angles and lengths look as they are; a UTM frame's grid north is drawn up.

use crate::VizError;
use crate::canvas::draw_to_file;
use mapc_graph::{JunctionId, JunctionKind, LaneGraph, RoadId};
use serde::Serialize;
use std::collections::BTreeSet;
use std::path::{Path, PathBuf};

mod draw;
mod layout;
#[cfg(test)]
mod tests;

use draw::MapFigure;

/// What to emphasise on a map render. `Highlight::default()` labels every merge and highlights nothing.
#[derive(Clone, Debug)]
pub struct Highlight {
    /// Roads of the rendered graph drawn with a halo (a transfer window).
    pub roads: BTreeSet<RoadId>,
    /// Polylines in the graph's local frame drawn with the same halo: a window cut from this map, whose roads
    /// carry other ids.
    pub paths: Vec<Vec<[f64; 2]>>,
    /// Junctions always labelled, whatever their kind, before any merge.
    pub junctions: BTreeSet<JunctionId>,
    /// Label merge junctions with their ids (`J12`); labels that would overlap others are left out and counted.
    pub label_merges: bool,
    /// Legend text for the halo; default `highlighted roads`.
    pub label: Option<String>,
    /// Title; default: the map's file name and counts.
    pub title: Option<String>,
    /// Show only the highlighted roads, paths and junctions with some surroundings instead of the whole map.
    pub zoom_to_highlight: bool,
}

impl Default for Highlight {
    fn default() -> Self {
        Highlight {
            roads: BTreeSet::new(),
            paths: Vec::new(),
            junctions: BTreeSet::new(),
            label_merges: true,
            label: None,
            title: None,
            zoom_to_highlight: false,
        }
    }
}

impl Highlight {
    /// Highlight these roads (a transfer window) and label these junctions, on top of the merges.
    pub fn window(
        roads: impl IntoIterator<Item = RoadId>,
        junctions: impl IntoIterator<Item = JunctionId>,
    ) -> Self {
        Highlight {
            roads: roads.into_iter().collect(),
            junctions: junctions.into_iter().collect(),
            label: Some("transfer window".to_string()),
            ..Highlight::default()
        }
    }

    fn is_empty(&self) -> bool {
        self.roads.is_empty() && self.paths.is_empty()
    }
}

/// Size of a render.
#[derive(Clone, Debug)]
pub struct RenderOptions {
    /// Picture width in pixels; the height follows from the map's shape (equal aspect).
    pub width_px: u32,
}

impl Default for RenderOptions {
    fn default() -> Self {
        RenderOptions { width_px: 1600 }
    }
}

/// What a render drew, for `--json` and tests.
#[derive(Clone, Debug, Serialize)]
pub struct MapRenderSummary {
    pub path: PathBuf,
    pub width_px: u32,
    pub height_px: u32,
    pub roads_drawn: usize,
    pub roads_highlighted: usize,
    pub merges: usize,
    pub labels_drawn: usize,
    /// Labels left out because every place for them overlapped another label.
    pub labels_skipped: usize,
    /// Metres per pixel.
    pub metres_per_px: f64,
    /// Area shown, local frame: `[min_x, min_y, max_x, max_y]` in metres.
    pub bounds_m: [f64; 4],
    /// Length of the scale bar in metres.
    pub scale_bar_m: f64,
}

/// Draw `graph` into `out` (`.png` or `.svg`, chosen by the name) at the default size. The scenario tools call this
/// to show a transfer window on its map: put the window's roads in `highlight.roads` and its merge in
/// `highlight.junctions`.
pub fn render_map(
    graph: &LaneGraph,
    highlight: &Highlight,
    out: &Path,
) -> Result<MapRenderSummary, VizError> {
    render_map_with(graph, highlight, &RenderOptions::default(), out)
}

/// [`render_map`] with a chosen size.
pub fn render_map_with(
    graph: &LaneGraph,
    highlight: &Highlight,
    options: &RenderOptions,
    out: &Path,
) -> Result<MapRenderSummary, VizError> {
    crate::canvas::picture_kind(out)?;
    if graph.roads.is_empty() {
        return Err(VizError::Input {
            path: out.to_path_buf(),
            message: "the map has no roads to draw".into(),
        });
    }
    for r in &highlight.roads {
        if graph.road(*r).is_none() {
            return Err(VizError::Input {
                path: out.to_path_buf(),
                message: format!("highlighted road {r} is not in the map"),
            });
        }
    }
    for j in &highlight.junctions {
        if graph.junction(*j).is_none() {
            return Err(VizError::Input {
                path: out.to_path_buf(),
                message: format!("labelled junction {j} is not in the map"),
            });
        }
    }
    let width = options.width_px.clamp(400, 10_000);
    let fig = MapFigure::new(graph, highlight, width);
    draw_to_file(out, (fig.layout.width, fig.layout.height), &fig)?;
    let placed = fig.placed.borrow();
    Ok(MapRenderSummary {
        path: out.to_path_buf(),
        width_px: fig.layout.width,
        height_px: fig.layout.height,
        roads_drawn: graph.roads.len(),
        roads_highlighted: highlight.roads.len(),
        merges: graph.count_kind(JunctionKind::Merge),
        labels_drawn: placed.0,
        labels_skipped: placed.1,
        metres_per_px: 1.0 / fig.layout.scale,
        bounds_m: [fig.layout.x0, fig.layout.y0, fig.layout.x1, fig.layout.y1],
        scale_bar_m: fig.layout.scale_bar_m,
    })
}
