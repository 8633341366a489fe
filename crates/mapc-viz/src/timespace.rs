//! Time-space diagrams from a simulator trace: time across, position along the corridor up, each vehicle's
//! trajectory coloured by its speed (red slow, green fast). A stop-and-go wave shows as a red band sloping down
//! (it travels upstream); controlled vehicles (AVs) are outlined in black.

use crate::VizError;
use crate::canvas::{DrawErr, Figure, draw_to_file};
use crate::colors::speed_color;
use crate::csvin::CsvInput;
use plotters::coord::Shift;
use plotters::prelude::*;
use serde::Serialize;
use std::collections::HashMap;
use std::path::{Path, PathBuf};

/// The trace columns, in the simulator's order.
pub const TRACE_COLUMNS: [&str; 8] = [
    "time_s",
    "vehicle_id",
    "vehicle_type",
    "road",
    "pos_on_road_m",
    "corridor_x_m",
    "speed_mps",
    "controlled",
];

/// Which samples to draw, and so what the vertical axis means.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum RoadFilter {
    /// Samples on the corridor's main line (`corridor_x_m` set); up is the corridor position.
    Main,
    /// Samples on these roads (trace `road` labels such as `R3`); up is the position on the road.
    Roads(Vec<String>),
}

impl std::str::FromStr for RoadFilter {
    type Err = String;
    /// `main`, or road labels separated by commas.
    fn from_str(s: &str) -> Result<Self, String> {
        let s = s.trim();
        if s.eq_ignore_ascii_case("main") {
            return Ok(RoadFilter::Main);
        }
        let roads: Vec<String> = s
            .split(',')
            .map(|r| r.trim().to_string())
            .filter(|r| !r.is_empty())
            .collect();
        if roads.is_empty() {
            return Err("expected `main` or road names separated by commas".to_string());
        }
        Ok(RoadFilter::Roads(roads))
    }
}

/// One trace row kept for drawing.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Sample {
    pub time_s: f64,
    /// Index into [`Trace::vehicles`].
    pub vehicle: u32,
    /// Vertical position: corridor position or position on the road, metres.
    pub y_m: f64,
    pub speed_mps: f64,
    pub controlled: bool,
}

/// The samples of a trace that pass a filter, in file order.
#[derive(Clone, Debug)]
pub struct Trace {
    pub path: PathBuf,
    pub samples: Vec<Sample>,
    /// Vehicle ids as written in the trace, indexed by [`Sample::vehicle`].
    pub vehicles: Vec<String>,
    /// Rows read, kept or not.
    pub rows: usize,
}

/// Read a trace CSV, keeping the samples `filter` selects. The columns are found by name.
pub fn read_trace(path: &Path, filter: &RoadFilter) -> Result<Trace, VizError> {
    read_trace_lane(path, filter, None)
}

/// [`read_trace`], keeping only the samples on lane `lane` of their road (trace column `lane`; a trace without it
/// has every vehicle on lane 0).
pub fn read_trace_lane(
    path: &Path,
    filter: &RoadFilter,
    lane: Option<u8>,
) -> Result<Trace, VizError> {
    let mut input = CsvInput::open(path)?;
    let idx = input.require(&TRACE_COLUMNS)?;
    let i_lane = input.column("lane");
    let [i_time, i_vid, _i_type, i_road, i_pos, i_x, i_speed, i_ctrl] = idx[..] else {
        unreachable!("require returns one index per name")
    };
    let parser = input.fields();
    let mut samples = Vec::new();
    let mut vehicles: Vec<String> = Vec::new();
    let mut vehicle_index: HashMap<String, u32> = HashMap::new();
    let mut rows = 0usize;
    input.for_each_row(|rec, line| {
        rows += 1;
        if let Some(want) = lane {
            let on = match i_lane {
                Some(i) => parser.number(rec, i, "lane", line)?.unwrap_or(0.0),
                None => 0.0,
            };
            if on != f64::from(want) {
                return Ok(());
            }
        }
        let y = match filter {
            RoadFilter::Main => match parser.number(rec, i_x, "corridor_x_m", line)? {
                Some(x) if x.is_finite() => x,
                Some(x) => {
                    return Err(parser.error(
                        line,
                        "corridor_x_m",
                        format!("`{x}` is not a finite number"),
                    ));
                }
                None => return Ok(()),
            },
            RoadFilter::Roads(roads) => {
                let road = rec.get(i_road).unwrap_or("").trim();
                if !roads.iter().any(|r| r == road) {
                    return Ok(());
                }
                parser.required(rec, i_pos, "pos_on_road_m", line)?
            }
        };
        let time_s = parser.required(rec, i_time, "time_s", line)?;
        let speed_mps = parser.required(rec, i_speed, "speed_mps", line)?;
        let controlled = parser.boolean(rec, i_ctrl, "controlled", line)?;
        let vid = rec.get(i_vid).unwrap_or("").trim();
        if vid.is_empty() {
            return Err(parser.error(line, "vehicle_id", "empty field".to_string()));
        }
        let vehicle = match vehicle_index.get(vid) {
            Some(v) => *v,
            None => {
                let v = vehicles.len() as u32;
                vehicles.push(vid.to_string());
                vehicle_index.insert(vid.to_string(), v);
                v
            }
        };
        samples.push(Sample {
            time_s,
            vehicle,
            y_m: y,
            speed_mps,
            controlled,
        });
        Ok(())
    })?;
    Ok(Trace {
        path: path.to_path_buf(),
        samples,
        vehicles,
        rows,
    })
}

/// How to draw a time-space diagram.
#[derive(Clone, Debug)]
pub struct TimeSpaceOptions {
    pub filter: RoadFilter,
    pub width_px: u32,
    pub height_px: u32,
    /// Top of the speed scale, m/s; default: the fastest sample, rounded up.
    pub speed_max_mps: Option<f64>,
    /// Only samples at or after this time (to skip a warm-up).
    pub start_s: Option<f64>,
    /// Only samples on this lane of their road (0 rightmost); all lanes when `None`.
    pub lane: Option<u8>,
    pub title: Option<String>,
}

impl Default for TimeSpaceOptions {
    fn default() -> Self {
        TimeSpaceOptions {
            filter: RoadFilter::Main,
            width_px: 1400,
            height_px: 800,
            speed_max_mps: None,
            start_s: None,
            lane: None,
            title: None,
        }
    }
}

/// What a diagram drew, for `--json` and tests.
#[derive(Clone, Debug, Serialize)]
pub struct TimeSpaceSummary {
    pub path: PathBuf,
    pub rows_read: usize,
    pub samples_drawn: usize,
    pub vehicles: usize,
    pub controlled_vehicles: usize,
    pub time_range_s: [f64; 2],
    pub position_range_m: [f64; 2],
    pub speed_max_mps: f64,
    /// Polylines drawn (trajectory pieces of one speed colour).
    pub polylines: usize,
}

/// Read `trace` and draw its time-space diagram into `out` (`.png` or `.svg`).
pub fn plot_timespace(
    trace: &Path,
    out: &Path,
    options: &TimeSpaceOptions,
) -> Result<TimeSpaceSummary, VizError> {
    crate::canvas::picture_kind(out)?;
    let mut t = read_trace_lane(trace, &options.filter, options.lane)?;
    if let Some(start) = options.start_s {
        t.samples.retain(|s| s.time_s >= start);
    }
    if t.samples.is_empty() {
        let what = match &options.filter {
            RoadFilter::Main => {
                "no samples on the main line (corridor_x_m is empty in every row; try --road-filter ROAD)".to_string()
            }
            RoadFilter::Roads(r) => format!("no samples on road(s) {}", r.join(",")),
        };
        let what = match options.lane {
            Some(k) => format!("{what} in lane {k}"),
            None => what,
        };
        return Err(VizError::Input {
            path: trace.to_path_buf(),
            message: format!("{what}; {} rows read", t.rows),
        });
    }
    let figure = TimeSpaceFigure::new(&t, options);
    draw_to_file(
        out,
        (
            options.width_px.clamp(400, 10_000),
            options.height_px.clamp(300, 10_000),
        ),
        &figure,
    )?;
    let controlled = {
        let mut v: Vec<u32> = t
            .samples
            .iter()
            .filter(|s| s.controlled)
            .map(|s| s.vehicle)
            .collect();
        v.sort_unstable();
        v.dedup();
        v.len()
    };
    Ok(TimeSpaceSummary {
        path: out.to_path_buf(),
        rows_read: t.rows,
        samples_drawn: t.samples.len(),
        vehicles: t.vehicles.len(),
        controlled_vehicles: controlled,
        time_range_s: [figure.t0, figure.t1],
        position_range_m: [figure.y0, figure.y1],
        speed_max_mps: figure.vmax,
        polylines: figure.lines.len(),
    })
}

/// Speed colours are quantised so that a run of similar speeds becomes one polyline (a much smaller SVG).
const SPEED_BINS: usize = 48;

/// A trajectory piece of one speed colour.
#[derive(Clone, Debug)]
struct Polyline {
    bin: usize,
    controlled: bool,
    points: Vec<(f64, f64)>,
}

struct TimeSpaceFigure {
    title: String,
    y_label: String,
    t0: f64,
    t1: f64,
    y0: f64,
    y1: f64,
    vmax: f64,
    lines: Vec<Polyline>,
}

impl TimeSpaceFigure {
    fn new(t: &Trace, options: &TimeSpaceOptions) -> Self {
        let (mut t0, mut t1, mut y0, mut y1, mut vfast) =
            (f64::MAX, f64::MIN, f64::MAX, f64::MIN, 0.0f64);
        for s in &t.samples {
            t0 = t0.min(s.time_s);
            t1 = t1.max(s.time_s);
            y0 = y0.min(s.y_m);
            y1 = y1.max(s.y_m);
            vfast = vfast.max(s.speed_mps);
        }
        if t1 <= t0 {
            t1 = t0 + 1.0;
        }
        if y1 <= y0 {
            y1 = y0 + 1.0;
        }
        let vmax = options
            .speed_max_mps
            .filter(|v| v.is_finite() && *v > 0.0)
            .unwrap_or_else(|| (vfast.max(1.0) / 5.0).ceil() * 5.0);
        let step = sample_step(&t.samples);
        let lines = trajectories(&t.samples, t.vehicles.len(), step, vmax);
        let file = t
            .path
            .file_name()
            .map(|f| f.to_string_lossy().into_owned())
            .unwrap_or_default();
        let (y_label, what) = match &options.filter {
            RoadFilter::Main => (
                "position along the corridor (m)".to_string(),
                "main line".to_string(),
            ),
            RoadFilter::Roads(r) => (
                format!("position on {} (m)", r.join(", ")),
                format!("road {}", r.join(", ")),
            ),
        };
        let what = match options.lane {
            Some(k) => format!("{what}, lane {k}"),
            None => what,
        };
        let n_veh = {
            let mut v: Vec<u32> = t.samples.iter().map(|s| s.vehicle).collect();
            v.sort_unstable();
            v.dedup();
            v.len()
        };
        let title = options
            .title
            .clone()
            .unwrap_or_else(|| format!("Time-space diagram: {file}, {what}, {n_veh} vehicles"));
        TimeSpaceFigure {
            title,
            y_label,
            t0,
            t1,
            y0,
            y1,
            vmax,
            lines,
        }
    }
}

/// The trace's time step: the smallest positive gap between successive distinct times.
fn sample_step(samples: &[Sample]) -> f64 {
    let mut times: Vec<f64> = samples.iter().map(|s| s.time_s).collect();
    times.sort_by(f64::total_cmp);
    times.dedup();
    times
        .windows(2)
        .map(|w| w[1] - w[0])
        .filter(|d| *d > 1e-9)
        .fold(f64::INFINITY, f64::min)
        .min(1e6)
}

/// Cut every vehicle's samples into polylines of one speed colour. A trajectory breaks where the vehicle was not
/// sampled for a while or jumped (left the filtered roads and came back, or a teleport).
fn trajectories(samples: &[Sample], n_vehicles: usize, step: f64, vmax: f64) -> Vec<Polyline> {
    let mut by_vehicle: Vec<Vec<&Sample>> = vec![Vec::new(); n_vehicles];
    for s in samples {
        by_vehicle[s.vehicle as usize].push(s);
    }
    let max_gap = if step.is_finite() {
        2.5 * step
    } else {
        f64::INFINITY
    };
    let bin = |v: f64| (((v / vmax) * SPEED_BINS as f64) as usize).min(SPEED_BINS - 1);
    let mut lines = Vec::new();
    for mut vs in by_vehicle {
        vs.sort_by(|a, b| a.time_s.total_cmp(&b.time_s));
        let mut current: Option<Polyline> = None;
        for w in vs.windows(2) {
            let (a, b) = (w[0], w[1]);
            let dt = b.time_s - a.time_s;
            let dy = b.y_m - a.y_m;
            let plausible = dt > 0.0
                && dt <= max_gap
                && dy >= -1.0
                && dy <= (vmax.max(a.speed_mps).max(b.speed_mps) * 2.0) * dt + 5.0;
            if !plausible {
                lines.extend(current.take());
                continue;
            }
            let k = bin(0.5 * (a.speed_mps + b.speed_mps));
            let controlled = a.controlled || b.controlled;
            match current.as_mut() {
                Some(p)
                    if p.bin == k
                        && p.controlled == controlled
                        && p.points.last() == Some(&(a.time_s, a.y_m)) =>
                {
                    p.points.push((b.time_s, b.y_m));
                }
                _ => {
                    lines.extend(current.take());
                    current = Some(Polyline {
                        bin: k,
                        controlled,
                        points: vec![(a.time_s, a.y_m), (b.time_s, b.y_m)],
                    });
                }
            }
        }
        lines.extend(current);
    }
    lines
}

impl Figure for TimeSpaceFigure {
    fn draw<DB: DrawingBackend>(&self, root: &DrawingArea<DB, Shift>) -> Result<(), String> {
        root.fill(&WHITE).d()?;
        let (w, _h) = root.dim_in_pixel();
        let (main, bar) = root.split_horizontally(w as i32 - 120);
        let main = main.titled(&self.title, ("sans-serif", 22)).d()?;
        let mut chart = ChartBuilder::on(&main)
            .margin(12)
            .x_label_area_size(48)
            .y_label_area_size(80)
            .build_cartesian_2d(self.t0..self.t1, self.y0..self.y1)
            .d()?;
        chart
            .configure_mesh()
            .disable_mesh()
            .x_desc("time (s)")
            .x_label_formatter(&|v| format!("{v:.0}"))
            .y_label_formatter(&|v| format!("{v:.0}"))
            .y_desc(self.y_label.as_str())
            .axis_desc_style(("sans-serif", 17))
            .label_style(("sans-serif", 14))
            .draw()
            .d()?;
        let bin_speed = |b: usize| (b as f64 + 0.5) / SPEED_BINS as f64;
        // Humans first, then AVs outlined on top so that they stay visible in dense traffic.
        for line in self.lines.iter().filter(|l| !l.controlled) {
            let style = speed_color(bin_speed(line.bin)).stroke_width(2);
            chart
                .draw_series(std::iter::once(PathElement::new(
                    line.points.clone(),
                    style,
                )))
                .d()?;
        }
        let av_lines: Vec<&Polyline> = self.lines.iter().filter(|l| l.controlled).collect();
        for line in &av_lines {
            chart
                .draw_series(std::iter::once(PathElement::new(
                    line.points.clone(),
                    BLACK.stroke_width(5),
                )))
                .d()?;
        }
        for line in &av_lines {
            let style = speed_color(bin_speed(line.bin)).stroke_width(2);
            chart
                .draw_series(std::iter::once(PathElement::new(
                    line.points.clone(),
                    style,
                )))
                .d()?;
        }
        if !av_lines.is_empty() {
            chart
                .draw_series(std::iter::once(PathElement::new(
                    Vec::<(f64, f64)>::new(),
                    BLACK,
                )))
                .d()?
                .label("AV (controlled), outlined")
                .legend(|(x, y)| {
                    EmptyElement::at((x, y))
                        + PathElement::new(vec![(0, 0), (20, 0)], BLACK.stroke_width(5))
                        + PathElement::new(vec![(0, 0), (20, 0)], speed_color(0.8).stroke_width(2))
                });
            chart
                .configure_series_labels()
                .background_style(WHITE.mix(0.85))
                .border_style(BLACK)
                .label_font(("sans-serif", 14))
                .position(SeriesLabelPosition::UpperLeft)
                .draw()
                .d()?;
        }

        // Colour bar: the speed scale, with its own axis.
        let bar = bar.margin(50, 60, 10, 40);
        let mut cb = ChartBuilder::on(&bar)
            .y_label_area_size(0)
            .x_label_area_size(0)
            .right_y_label_area_size(50)
            .build_cartesian_2d(0.0..1.0, 0.0..self.vmax)
            .d()?;
        cb.configure_mesh()
            .disable_mesh()
            .disable_x_axis()
            .y_desc("speed (m/s)")
            .y_label_formatter(&|v| format!("{v:.0}"))
            .axis_desc_style(("sans-serif", 16))
            .label_style(("sans-serif", 14))
            .draw()
            .d()?;
        let n = 120;
        cb.draw_series((0..n).map(|i| {
            let v0 = self.vmax * i as f64 / n as f64;
            let v1 = self.vmax * (i + 1) as f64 / n as f64;
            Rectangle::new(
                [(0.0, v0), (1.0, v1)],
                speed_color((i as f64 + 0.5) / n as f64).filled(),
            )
        }))
        .d()?;
        cb.draw_series(std::iter::once(Rectangle::new(
            [(0.0, 0.0), (1.0, self.vmax)],
            BLACK.stroke_width(1),
        )))
        .d()?;
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn s(t: f64, v: u32, y: f64, speed: f64) -> Sample {
        Sample {
            time_s: t,
            vehicle: v,
            y_m: y,
            speed_mps: speed,
            controlled: false,
        }
    }

    #[test]
    fn trajectories_join_equal_speeds_and_break_at_gaps() {
        let samples = vec![
            s(0.0, 0, 0.0, 10.0),
            s(0.5, 0, 5.0, 10.0),
            s(1.0, 0, 10.0, 10.0),
            // Not sampled for 5 s: a new piece.
            s(6.0, 0, 60.0, 10.0),
            s(6.5, 0, 65.0, 10.0),
            // Backwards jump: broken again.
            s(7.0, 0, 0.0, 10.0),
        ];
        let lines = trajectories(&samples, 1, sample_step(&samples), 30.0);
        assert_eq!(lines.len(), 2, "{lines:?}");
        assert_eq!(lines[0].points.len(), 3);
        assert_eq!(lines[1].points.len(), 2);
    }

    #[test]
    fn speed_changes_start_new_colours() {
        let samples = vec![
            s(0.0, 0, 0.0, 0.0),
            s(0.5, 0, 0.0, 0.0),
            s(1.0, 0, 10.0, 29.0),
            s(1.5, 0, 25.0, 29.0),
        ];
        let lines = trajectories(&samples, 1, 0.5, 30.0);
        assert!(lines.len() >= 2);
        assert_eq!(lines[0].bin, 0);
        assert_eq!(
            lines.last().unwrap().bin,
            (29.0 / 30.0 * SPEED_BINS as f64) as usize
        );
    }

    #[test]
    fn filters_parse() {
        assert_eq!("main".parse::<RoadFilter>().unwrap(), RoadFilter::Main);
        assert_eq!(
            "R1, R2".parse::<RoadFilter>().unwrap(),
            RoadFilter::Roads(vec!["R1".into(), "R2".into()])
        );
        assert!(" , ".parse::<RoadFilter>().is_err());
    }
}
