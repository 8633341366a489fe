//! Map renders: roads coloured by class, merges labelled with their ids, a scale bar, north up, equal aspect.
//!
//! The drawing maps the graph's local metric frame (metres east, north) to pixels with one scale for both axes, so
//! angles and lengths look as they are; a UTM frame's grid north is drawn up.

use crate::VizError;
use crate::canvas::{DrawErr, Figure, draw_to_file};
use crate::colors::{class_colors, class_rank};
use mapc_graph::{JunctionId, JunctionKind, LaneGraph, Projection, RoadId};
use plotters::coord::Shift;
use plotters::prelude::*;
use plotters::style::text_anchor::{HPos, Pos, VPos};
use serde::Serialize;
use std::collections::BTreeSet;
use std::path::{Path, PathBuf};

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

const TITLE_H: u32 = 70;
const MARGIN: u32 = 16;
const LEGEND_W: u32 = 260;
const LABEL_FONT: f64 = 15.0;
const HALO: RGBColor = RGBColor(0, 170, 255);

/// Pixel layout: the plot box and the metric window it shows, with one scale for both axes.
#[derive(Clone, Debug)]
struct Layout {
    width: u32,
    height: u32,
    /// Plot box in pixels.
    left: i32,
    top: i32,
    plot_w: i32,
    plot_h: i32,
    /// Metric window shown.
    x0: f64,
    y0: f64,
    x1: f64,
    y1: f64,
    /// Pixels per metre.
    scale: f64,
    scale_bar_m: f64,
}

impl Layout {
    fn new(bounds: [f64; 4], width: u32, min_plot_h: u32) -> Layout {
        let [mut x0, mut y0, mut x1, mut y1] = bounds;
        // A little room around the roads, and never a zero-size window.
        let span = (x1 - x0).max(y1 - y0).max(50.0);
        let pad = 0.04 * span;
        x0 -= pad;
        y0 -= pad;
        x1 += pad;
        y1 += pad;
        let plot_w = width.saturating_sub(2 * MARGIN + LEGEND_W).max(200);
        let aspect = (y1 - y0) / (x1 - x0);
        let max_plot_h = (1.5 * width as f64) as u32;
        let plot_h =
            ((plot_w as f64 * aspect).round() as u32).clamp(min_plot_h.min(max_plot_h), max_plot_h);
        // Equal aspect: widen whichever extent is short of the box's shape, about the centre.
        let scale = (plot_w as f64 / (x1 - x0)).min(plot_h as f64 / (y1 - y0));
        let (cx, cy) = ((x0 + x1) / 2.0, (y0 + y1) / 2.0);
        let (hw, hh) = (plot_w as f64 / scale / 2.0, plot_h as f64 / scale / 2.0);
        let plot_w_m = 2.0 * hw;
        Layout {
            width,
            height: TITLE_H + plot_h + 2 * MARGIN,
            left: MARGIN as i32,
            top: (TITLE_H + MARGIN) as i32,
            plot_w: plot_w as i32,
            plot_h: plot_h as i32,
            x0: cx - hw,
            y0: cy - hh,
            x1: cx + hw,
            y1: cy + hh,
            scale,
            scale_bar_m: nice_length(plot_w_m / 5.0),
        }
    }

    fn px(&self, p: [f64; 2]) -> (i32, i32) {
        (
            self.left + ((p[0] - self.x0) * self.scale).round() as i32,
            self.top + ((self.y1 - p[1]) * self.scale).round() as i32,
        )
    }

    fn inside(&self, p: [f64; 2]) -> bool {
        p[0] >= self.x0 && p[0] <= self.x1 && p[1] >= self.y0 && p[1] <= self.y1
    }

    /// The polyline's pieces within the window, in pixels (segments cut at the window's edge).
    fn clipped_pixels(&self, line: &[[f64; 2]]) -> Vec<Vec<(i32, i32)>> {
        let mut pieces: Vec<Vec<(i32, i32)>> = Vec::new();
        let mut current: Vec<(i32, i32)> = Vec::new();
        for w in line.windows(2) {
            match clip_segment(w[0], w[1], [self.x0, self.y0, self.x1, self.y1]) {
                Some((a, b)) => {
                    let (pa, pb) = (self.px(a), self.px(b));
                    if current.last() != Some(&pa) {
                        if current.len() > 1 {
                            pieces.push(std::mem::take(&mut current));
                        }
                        current.clear();
                        current.push(pa);
                    }
                    current.push(pb);
                }
                None => {
                    if current.len() > 1 {
                        pieces.push(std::mem::take(&mut current));
                    }
                    current.clear();
                }
            }
        }
        if current.len() > 1 {
            pieces.push(current);
        }
        pieces
    }
}

/// Liang-Barsky: the part of segment a-b inside the box `[x0, y0, x1, y1]`.
fn clip_segment(a: [f64; 2], b: [f64; 2], bx: [f64; 4]) -> Option<([f64; 2], [f64; 2])> {
    let (dx, dy) = (b[0] - a[0], b[1] - a[1]);
    let (mut t0, mut t1) = (0.0f64, 1.0f64);
    for (p, q) in [
        (-dx, a[0] - bx[0]),
        (dx, bx[2] - a[0]),
        (-dy, a[1] - bx[1]),
        (dy, bx[3] - a[1]),
    ] {
        if p == 0.0 {
            if q < 0.0 {
                return None;
            }
        } else {
            let r = q / p;
            if p < 0.0 {
                t0 = t0.max(r);
            } else {
                t1 = t1.min(r);
            }
        }
    }
    (t0 <= t1).then(|| {
        (
            [a[0] + t0 * dx, a[1] + t0 * dy],
            [a[0] + t1 * dx, a[1] + t1 * dy],
        )
    })
}

/// The largest 1, 2 or 5 times a power of ten not above `x` (metres).
pub(crate) fn nice_length(x: f64) -> f64 {
    if !(x.is_finite() && x > 0.0) {
        return 1.0;
    }
    let p = 10f64.powf(x.log10().floor());
    [5.0, 2.0, 1.0]
        .into_iter()
        .map(|m| m * p)
        .find(|v| *v <= x)
        .unwrap_or(p)
}

fn format_metres(m: f64) -> String {
    if m >= 1000.0 {
        format!("{} km", m / 1000.0)
    } else {
        format!("{m} m")
    }
}

struct MapFigure<'a> {
    graph: &'a LaneGraph,
    highlight: &'a Highlight,
    layout: Layout,
    classes: Vec<(String, RGBColor)>,
    /// Labels drawn and skipped, filled in while drawing.
    placed: std::cell::RefCell<(usize, usize)>,
}

impl<'a> MapFigure<'a> {
    fn new(graph: &'a LaneGraph, highlight: &'a Highlight, width: u32) -> Self {
        let classes: Vec<String> = graph.roads.iter().map(|r| r.class.clone()).collect();
        let classes = class_colors(&classes);
        let legend_rows = classes.len() + 6 + usize::from(!highlight.is_empty());
        let min_plot_h = (legend_rows as u32 * 24 + 60).max(360);
        let layout = Layout::new(bounds(graph, highlight), width, min_plot_h);
        MapFigure {
            graph,
            highlight,
            layout,
            classes,
            placed: std::cell::RefCell::new((0, 0)),
        }
    }

    fn class_color(&self, class: &str) -> RGBColor {
        self.classes
            .iter()
            .find(|(c, _)| c == class)
            .map(|(_, col)| *col)
            .unwrap_or(RGBColor(128, 128, 128))
    }

    fn frame_note(&self) -> String {
        match self.graph.projection {
            Projection::Utm { zone, north, .. } => {
                format!(
                    "UTM zone {zone}{} (grid north up)",
                    if north { "N" } else { "S" }
                )
            }
            Projection::Plane { .. } => "local plane, no geographic frame".to_string(),
        }
    }
}

/// The metric box of what is shown: the whole graph, or the highlighted part with surroundings.
fn bounds(graph: &LaneGraph, highlight: &Highlight) -> [f64; 4] {
    let mut b = [
        f64::INFINITY,
        f64::INFINITY,
        f64::NEG_INFINITY,
        f64::NEG_INFINITY,
    ];
    let mut add = |p: &[f64; 2]| {
        if p[0].is_finite() && p[1].is_finite() {
            b = [
                b[0].min(p[0]),
                b[1].min(p[1]),
                b[2].max(p[0]),
                b[3].max(p[1]),
            ];
        }
    };
    if highlight.zoom_to_highlight && !(highlight.is_empty() && highlight.junctions.is_empty()) {
        for r in highlight.roads.iter().filter_map(|id| graph.road(*id)) {
            r.geometry.iter().for_each(&mut add);
        }
        highlight.paths.iter().flatten().for_each(&mut add);
        for j in highlight
            .junctions
            .iter()
            .filter_map(|id| graph.junction(*id))
        {
            add(&j.pos);
        }
        // Surroundings: a quarter of the window's size each side, at least 150 m.
        let grow = (0.25 * (b[2] - b[0]).max(b[3] - b[1])).max(150.0);
        b = [b[0] - grow, b[1] - grow, b[2] + grow, b[3] + grow];
    } else {
        for r in &graph.roads {
            r.geometry.iter().for_each(&mut add);
        }
        for j in &graph.junctions {
            add(&j.pos);
        }
    }
    if !b[0].is_finite() {
        return [0.0, 0.0, 100.0, 100.0];
    }
    b
}

/// Wider for more lanes, within what stays legible when carriageways lie side by side.
fn road_width_px(lanes: usize) -> u32 {
    (1 + lanes as u32).clamp(2, 5)
}

impl Figure for MapFigure<'_> {
    fn draw<DB: DrawingBackend>(&self, root: &DrawingArea<DB, Shift>) -> Result<(), String> {
        let l = &self.layout;
        root.fill(&WHITE).d()?;

        // Title and subtitle.
        let title = self.highlight.title.clone().unwrap_or_else(|| {
            let file = Path::new(&self.graph.source.file)
                .file_name()
                .map(|f| f.to_string_lossy().into_owned())
                .unwrap_or_else(|| self.graph.source.file.clone());
            format!(
                "{file}: {} roads, {} junctions ({} merges, {} diverges)",
                self.graph.roads.len(),
                self.graph.junctions.len(),
                self.graph.count_kind(JunctionKind::Merge),
                self.graph.count_kind(JunctionKind::Diverge)
            )
        });
        root.draw(&Text::new(
            title,
            (MARGIN as i32, 10),
            ("sans-serif", 26).into_font().color(&BLACK),
        ))
        .d()?;
        let sub = format!(
            "{}; shown {:.2} km x {:.2} km, equal aspect, {:.1} m per pixel",
            self.frame_note(),
            (l.x1 - l.x0) / 1000.0,
            (l.y1 - l.y0) / 1000.0,
            1.0 / l.scale
        );
        root.draw(&Text::new(
            sub,
            (MARGIN as i32, 44),
            ("sans-serif", 16).into_font().color(&RGBColor(80, 80, 80)),
        ))
        .d()?;

        // Plot box.
        let (bx0, by0, bx1, by1) = (l.left, l.top, l.left + l.plot_w, l.top + l.plot_h);
        root.draw(&Rectangle::new(
            [(bx0, by0), (bx1, by1)],
            RGBColor(250, 250, 247).filled(),
        ))
        .d()?;

        // Halos under the roads.
        let halo = HALO.mix(0.35).stroke_width(12);
        let mut halo_lines: Vec<&[[f64; 2]]> = Vec::new();
        for r in self
            .highlight
            .roads
            .iter()
            .filter_map(|id| self.graph.road(*id))
        {
            halo_lines.push(&r.geometry);
        }
        for p in &self.highlight.paths {
            halo_lines.push(p);
        }
        for line in halo_lines {
            for piece in l.clipped_pixels(line) {
                root.draw(&PathElement::new(piece, halo)).d()?;
            }
        }

        // Roads, least important first so motorways end on top.
        let mut order: Vec<usize> = (0..self.graph.roads.len()).collect();
        order.sort_by_key(|&i| std::cmp::Reverse(class_rank(&self.graph.roads[i].class)));
        for i in order {
            let r = &self.graph.roads[i];
            let style = self
                .class_color(&r.class)
                .stroke_width(road_width_px(r.lane_count()));
            for piece in l.clipped_pixels(&r.geometry) {
                root.draw(&PathElement::new(piece, style)).d()?;
            }
        }

        // Junction markers: diverges hollow, merges filled, labelled ones ringed in the halo colour.
        let dark = RGBColor(30, 30, 30);
        for j in &self.graph.junctions {
            if !l.inside(j.pos) {
                continue;
            }
            let p = l.px(j.pos);
            match j.kind {
                JunctionKind::Merge => {
                    root.draw(&Circle::new(p, 4, WHITE.filled())).d()?;
                    root.draw(&Circle::new(p, 3, dark.filled())).d()?;
                }
                JunctionKind::Diverge => {
                    root.draw(&Circle::new(p, 3, dark.stroke_width(1))).d()?;
                }
                _ => {}
            }
            if self.highlight.junctions.contains(&j.id) {
                root.draw(&Circle::new(p, 6, HALO.stroke_width(2))).d()?;
            }
        }

        // Labels: asked-for junctions first, then merges; each tries four places around its marker.
        let mut to_label: Vec<(JunctionId, bool)> = self
            .highlight
            .junctions
            .iter()
            .map(|j| (*j, true))
            .collect();
        if self.highlight.label_merges {
            to_label.extend(
                self.graph
                    .junctions
                    .iter()
                    .filter(|j| {
                        j.kind == JunctionKind::Merge && !self.highlight.junctions.contains(&j.id)
                    })
                    .map(|j| (j.id, false)),
            );
        }
        // Markers count as taken space so that labels do not hide them.
        let mut taken: Vec<[i32; 4]> = self
            .graph
            .junctions
            .iter()
            .filter(|j| {
                matches!(j.kind, JunctionKind::Merge | JunctionKind::Diverge) && l.inside(j.pos)
            })
            .map(|j| {
                let (x, y) = l.px(j.pos);
                [x - 3, y - 3, x + 3, y + 3]
            })
            .collect();
        let (mut drawn, mut skipped) = (0, 0);
        for (id, asked) in to_label {
            let Some(j) = self.graph.junction(id) else {
                continue;
            };
            if !l.inside(j.pos) {
                continue;
            }
            let text = id.to_string();
            let color = if asked { RGBColor(0, 90, 160) } else { dark };
            let font = (
                "sans-serif",
                if asked { LABEL_FONT + 3.0 } else { LABEL_FONT },
            )
                .into_font()
                .color(&color);
            let (tw, th) = root.estimate_text_size(&text, &font).d()?;
            let (tw, th) = (tw as i32 + 4, th as i32 + 2);
            let (x, y) = l.px(j.pos);
            let candidates = [
                (x + 6, y - 6 - th),
                (x + 6, y + 6),
                (x - 6 - tw, y - 6 - th),
                (x - 6 - tw, y + 6),
            ];
            let spot = candidates
                .into_iter()
                .map(|(cx, cy)| [cx, cy, cx + tw, cy + th])
                .find(|bx| {
                    bx[0] >= bx0
                        && bx[1] >= by0
                        && bx[2] <= bx1
                        && bx[3] <= by1
                        && !taken.iter().any(|t| overlaps(t, bx, 1))
                });
            let Some(bx) = spot else {
                skipped += 1;
                continue;
            };
            taken.push(bx);
            drawn += 1;
            root.draw(&Rectangle::new(
                [(bx[0], bx[1]), (bx[2], bx[3])],
                WHITE.mix(0.8).filled(),
            ))
            .d()?;
            root.draw(&Text::new(text, (bx[0] + 2, bx[1] + 1), font))
                .d()?;
        }
        *self.placed.borrow_mut() = (drawn, skipped);

        // North arrow, top left of the plot.
        let (nx, ny) = (bx0 + 28, by0 + 16);
        root.draw(&Polygon::new(
            vec![
                (nx, ny),
                (nx - 9, ny + 24),
                (nx, ny + 18),
                (nx + 9, ny + 24),
            ],
            dark.filled(),
        ))
        .d()?;
        root.draw(&Text::new(
            "N",
            (nx, ny + 28),
            ("sans-serif", 18)
                .into_font()
                .color(&dark)
                .pos(Pos::new(HPos::Center, VPos::Top)),
        ))
        .d()?;

        // Scale bar, bottom left of the plot: two halves, black and white.
        let bar_px = (l.scale_bar_m * l.scale).round() as i32;
        let (sx, sy) = (bx0 + 20, by1 - 30);
        root.draw(&Rectangle::new(
            [(sx - 8, sy - 22), (sx + bar_px + 40, sy + 16)],
            WHITE.mix(0.85).filled(),
        ))
        .d()?;
        root.draw(&Rectangle::new(
            [(sx, sy), (sx + bar_px / 2, sy + 6)],
            dark.filled(),
        ))
        .d()?;
        root.draw(&Rectangle::new(
            [(sx + bar_px / 2, sy), (sx + bar_px, sy + 6)],
            WHITE.filled(),
        ))
        .d()?;
        root.draw(&Rectangle::new(
            [(sx, sy), (sx + bar_px, sy + 6)],
            dark.stroke_width(1),
        ))
        .d()?;
        let small = ("sans-serif", 15)
            .into_font()
            .color(&dark)
            .pos(Pos::new(HPos::Center, VPos::Bottom));
        root.draw(&Text::new("0", (sx, sy - 3), small.clone()))
            .d()?;
        root.draw(&Text::new(
            format_metres(l.scale_bar_m),
            (sx + bar_px, sy - 3),
            small,
        ))
        .d()?;

        root.draw(&Rectangle::new(
            [(bx0, by0), (bx1, by1)],
            RGBColor(120, 120, 120).stroke_width(1),
        ))
        .d()?;

        // Legend, right of the plot.
        let lx = bx1 + 18;
        let mut ly = by0 + 4;
        let head = ("sans-serif", 19).into_font().color(&BLACK);
        let item = ("sans-serif", 16).into_font().color(&RGBColor(40, 40, 40));
        root.draw(&Text::new("Road class", (lx, ly), head.clone()))
            .d()?;
        ly += 26;
        for (class, color) in &self.classes {
            let n = self
                .graph
                .roads
                .iter()
                .filter(|r| &r.class == class)
                .count();
            root.draw(&PathElement::new(
                vec![(lx, ly + 8), (lx + 30, ly + 8)],
                color.stroke_width(4),
            ))
            .d()?;
            root.draw(&Text::new(
                format!("{class} ({n})"),
                (lx + 40, ly),
                item.clone(),
            ))
            .d()?;
            ly += 22;
        }
        if !self.highlight.is_empty() {
            root.draw(&PathElement::new(
                vec![(lx, ly + 8), (lx + 30, ly + 8)],
                HALO.mix(0.35).stroke_width(12),
            ))
            .d()?;
            let label = self
                .highlight
                .label
                .clone()
                .unwrap_or_else(|| "highlighted roads".to_string());
            root.draw(&Text::new(label, (lx + 40, ly), item.clone()))
                .d()?;
            ly += 22;
        }
        ly += 12;
        root.draw(&Text::new("Junctions", (lx, ly), head)).d()?;
        ly += 26;
        root.draw(&Circle::new((lx + 15, ly + 8), 3, dark.filled()))
            .d()?;
        root.draw(&Text::new(
            "merge (labelled Jn)",
            (lx + 40, ly),
            item.clone(),
        ))
        .d()?;
        ly += 22;
        root.draw(&Circle::new((lx + 15, ly + 8), 3, dark.stroke_width(1)))
            .d()?;
        root.draw(&Text::new("diverge", (lx + 40, ly), item.clone()))
            .d()?;
        ly += 22;
        if !self.highlight.junctions.is_empty() {
            root.draw(&Circle::new((lx + 15, ly + 8), 6, HALO.stroke_width(2)))
                .d()?;
            root.draw(&Text::new("named junction", (lx + 40, ly), item.clone()))
                .d()?;
            ly += 22;
        }
        if skipped > 0 {
            ly += 8;
            let note = ("sans-serif", 14).into_font().color(&RGBColor(90, 90, 90));
            root.draw(&Text::new(
                format!("{skipped} merge labels left out"),
                (lx, ly),
                note.clone(),
            ))
            .d()?;
            root.draw(&Text::new(
                "where they would overlap;",
                (lx, ly + 16),
                note.clone(),
            ))
            .d()?;
            root.draw(&Text::new(
                "`mapc junctions` lists all",
                (lx, ly + 32),
                note,
            ))
            .d()?;
        }
        Ok(())
    }
}

fn overlaps(a: &[i32; 4], b: &[i32; 4], gap: i32) -> bool {
    a[0] - gap < b[2] && b[0] - gap < a[2] && a[1] - gap < b[3] && b[1] - gap < a[3]
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn nice_lengths_are_one_two_five() {
        assert_eq!(nice_length(730.0), 500.0);
        assert_eq!(nice_length(2100.0), 2000.0);
        assert_eq!(nice_length(1.0), 1.0);
        assert_eq!(nice_length(0.0), 1.0);
        assert_eq!(format_metres(2000.0), "2 km");
        assert_eq!(format_metres(500.0), "500 m");
    }

    #[test]
    fn clipping_keeps_the_inside_part() {
        let bx = [0.0, 0.0, 10.0, 10.0];
        assert_eq!(
            clip_segment([-5.0, 5.0], [5.0, 5.0], bx),
            Some(([0.0, 5.0], [5.0, 5.0]))
        );
        assert_eq!(clip_segment([-5.0, 20.0], [5.0, 20.0], bx), None);
        assert_eq!(
            clip_segment([1.0, 1.0], [2.0, 2.0], bx),
            Some(([1.0, 1.0], [2.0, 2.0]))
        );
    }

    #[test]
    fn layout_keeps_equal_aspect() {
        // A long thin corridor: 10 km by 500 m.
        let l = Layout::new([0.0, 0.0, 10_000.0, 500.0], 1600, 400);
        let sx = l.plot_w as f64 / (l.x1 - l.x0);
        let sy = l.plot_h as f64 / (l.y1 - l.y0);
        assert!((sx - sy).abs() / sx < 1e-9, "{sx} vs {sy}");
        assert!(l.x0 < 0.0 && l.x1 > 10_000.0 && l.y0 < 0.0 && l.y1 > 500.0);
        assert!(l.plot_h >= 400);
    }
}
