//! Drawing a map render: roads by class, highlighted roads and junctions, labels placed without overlaps, the
//! legend, the scale bar and the north arrow.

use super::Highlight;
use super::layout::*;
use crate::canvas::{DrawErr, Figure};
use crate::colors::{class_colors, class_rank};
use mapc_graph::{JunctionId, JunctionKind, LaneGraph, Projection};
use plotters::coord::Shift;
use plotters::prelude::*;
use plotters::style::text_anchor::{HPos, Pos, VPos};
use std::path::Path;

pub(super) struct MapFigure<'a> {
    pub(super) graph: &'a LaneGraph,
    pub(super) highlight: &'a Highlight,
    pub(super) layout: Layout,
    pub(super) classes: Vec<(String, RGBColor)>,
    /// Labels drawn and skipped, filled in while drawing.
    pub(super) placed: std::cell::RefCell<(usize, usize)>,
}

impl<'a> MapFigure<'a> {
    pub(super) fn new(graph: &'a LaneGraph, highlight: &'a Highlight, width: u32) -> Self {
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

    pub(super) fn class_color(&self, class: &str) -> RGBColor {
        self.classes
            .iter()
            .find(|(c, _)| c == class)
            .map(|(_, col)| *col)
            .unwrap_or(RGBColor(128, 128, 128))
    }

    pub(super) fn frame_note(&self) -> String {
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

pub(super) fn overlaps(a: &[i32; 4], b: &[i32; 4], gap: i32) -> bool {
    a[0] - gap < b[2] && b[0] - gap < a[2] && a[1] - gap < b[3] && b[1] - gap < a[3]
}
