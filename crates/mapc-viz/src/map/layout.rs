//! The pixel layout of a map render: the metric window shown, one scale for both axes, the plot box, the scale
//! bar's length, and the sizes of what is drawn.

use super::Highlight;
use mapc_graph::LaneGraph;
use plotters::prelude::*;

pub(super) const TITLE_H: u32 = 70;
pub(super) const MARGIN: u32 = 16;
pub(super) const LEGEND_W: u32 = 260;
pub(super) const LABEL_FONT: f64 = 15.0;
pub(super) const HALO: RGBColor = RGBColor(0, 170, 255);

/// Pixel layout: the plot box and the metric window it shows, with one scale for both axes.
#[derive(Clone, Debug)]
pub(super) struct Layout {
    pub(super) width: u32,
    pub(super) height: u32,
    /// Plot box in pixels.
    pub(super) left: i32,
    pub(super) top: i32,
    pub(super) plot_w: i32,
    pub(super) plot_h: i32,
    /// Metric window shown.
    pub(super) x0: f64,
    pub(super) y0: f64,
    pub(super) x1: f64,
    pub(super) y1: f64,
    /// Pixels per metre.
    pub(super) scale: f64,
    pub(super) scale_bar_m: f64,
}

impl Layout {
    pub(super) fn new(bounds: [f64; 4], width: u32, min_plot_h: u32) -> Layout {
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

    pub(super) fn px(&self, p: [f64; 2]) -> (i32, i32) {
        (
            self.left + ((p[0] - self.x0) * self.scale).round() as i32,
            self.top + ((self.y1 - p[1]) * self.scale).round() as i32,
        )
    }

    pub(super) fn inside(&self, p: [f64; 2]) -> bool {
        p[0] >= self.x0 && p[0] <= self.x1 && p[1] >= self.y0 && p[1] <= self.y1
    }

    /// The polyline's pieces within the window, in pixels (segments cut at the window's edge).
    pub(super) fn clipped_pixels(&self, line: &[[f64; 2]]) -> Vec<Vec<(i32, i32)>> {
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
pub(super) fn clip_segment(a: [f64; 2], b: [f64; 2], bx: [f64; 4]) -> Option<([f64; 2], [f64; 2])> {
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

pub(super) fn format_metres(m: f64) -> String {
    if m >= 1000.0 {
        format!("{} km", m / 1000.0)
    } else {
        format!("{m} m")
    }
}

/// The metric box of what is shown: the whole graph, or the highlighted part with surroundings.
pub(super) fn bounds(graph: &LaneGraph, highlight: &Highlight) -> [f64; 4] {
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
pub(super) fn road_width_px(lanes: usize) -> u32 {
    (1 + lanes as u32).clamp(2, 5)
}
