//! Training curves from run directories' `progress.csv` (one row per PPO iteration): return, outflow, speed, entropy,
//! losses and KL, several runs overlaid. Columns are found by name; a missing one leaves its panel empty. A run
//! whose directory holds the trainer's `best.json` gets a marker on the log row that chose it.

use crate::VizError;
use crate::canvas::{DrawErr, Figure, draw_to_file};
use crate::colors::run_color;
use crate::csvin::CsvInput;
use plotters::coord::Shift;
use plotters::prelude::*;
use serde::Serialize;
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

/// The log's columns as the trainer writes them.
pub const LOG_COLUMNS: [&str; 11] = [
    "iteration",
    "env_steps",
    "wall_s",
    "mean_return",
    "mean_outflow",
    "mean_speed",
    "policy_loss",
    "value_loss",
    "kl",
    "entropy",
    "kl_coeff",
];

/// One run's log: every numeric column found, by name (empty fields are `None`).
#[derive(Clone, Debug)]
pub struct TrainingLog {
    pub path: PathBuf,
    /// What the run is called on the plot: its directory's name.
    pub label: String,
    pub columns: BTreeMap<String, Vec<Option<f64>>>,
    pub rows: usize,
    /// The `iteration` of the row whose rollouts chose the run's `best.json` (`selected.row_iteration`), if the
    /// run directory has one.
    pub best_iteration: Option<u64>,
}

impl TrainingLog {
    /// `(x, y)` pairs where both are finite numbers.
    pub fn series(&self, x: &str, y: &str) -> Vec<(f64, f64)> {
        let (Some(xs), Some(ys)) = (self.x_values(x), self.columns.get(y)) else {
            return Vec::new();
        };
        xs.iter()
            .zip(ys)
            .filter_map(|(a, b)| match (a, b) {
                (Some(a), Some(b)) if a.is_finite() && b.is_finite() => Some((*a, *b)),
                _ => None,
            })
            .collect()
    }

    /// The x column, or the row number when the log lacks it.
    fn x_values(&self, x: &str) -> Option<Vec<Option<f64>>> {
        match self.columns.get(x) {
            Some(v) => Some(v.clone()),
            None => Some((0..self.rows).map(|i| Some(i as f64)).collect()),
        }
    }
}

/// Read `RUN_DIR/progress.csv`, or a CSV file given directly. Unknown columns are ignored; known ones must hold numbers.
pub fn read_log(run: &Path) -> Result<TrainingLog, VizError> {
    let path = if run.is_dir() {
        run.join("progress.csv")
    } else {
        run.to_path_buf()
    };
    let label = if run.is_dir() {
        run
    } else {
        run.parent().unwrap_or(run)
    }
    .file_name()
    .map(|n| n.to_string_lossy().into_owned())
    .unwrap_or_else(|| run.display().to_string());
    let mut input = CsvInput::open(&path)?;
    let found: Vec<(usize, &str)> = LOG_COLUMNS
        .iter()
        .filter_map(|c| input.column(c).map(|i| (i, *c)))
        .collect();
    if found
        .iter()
        .all(|(_, c)| ["iteration", "env_steps", "wall_s"].contains(c))
    {
        return Err(VizError::Input {
            path,
            message: format!(
                "line 1: none of the training log's value columns (header is `{}`, expected some of `{}`)",
                input.headers.join(","),
                LOG_COLUMNS.join(",")
            ),
        });
    }
    let fields = input.fields();
    let mut columns: BTreeMap<String, Vec<Option<f64>>> = found
        .iter()
        .map(|(_, c)| (c.to_string(), Vec::new()))
        .collect();
    let mut rows = 0;
    input.for_each_row(|rec, line| {
        for (i, name) in &found {
            let v = fields.number(rec, *i, name, line)?;
            columns.get_mut(*name).expect("made above").push(v);
        }
        rows += 1;
        Ok(())
    })?;
    let best_iteration = if run.is_dir() {
        read_best_iteration(&run.join("best.json"))?
    } else {
        None
    };
    Ok(TrainingLog {
        path,
        label,
        columns,
        rows,
        best_iteration,
    })
}

/// `selected.row_iteration` of a trainer's `best.json` (only that field is read); `None` without the file.
fn read_best_iteration(path: &Path) -> Result<Option<u64>, VizError> {
    #[derive(serde::Deserialize)]
    struct Best {
        selected: Selected,
    }
    #[derive(serde::Deserialize)]
    struct Selected {
        row_iteration: u64,
    }
    let text = match mapc_graph::input::read_to_string(path) {
        Ok(t) => t,
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => return Ok(None),
        Err(e) => {
            return Err(VizError::Input {
                path: path.to_path_buf(),
                message: e.to_string(),
            });
        }
    };
    let best: Best = serde_json::from_str(&text).map_err(|e| VizError::Input {
        path: path.to_path_buf(),
        message: format!(
            "line {} column {}: {e} (expected the trainer's best.json, with `selected.row_iteration`)",
            e.line(),
            e.column()
        ),
    })?;
    Ok(Some(best.selected.row_iteration))
}

impl TrainingLog {
    /// The best row's point in `(x, y)`, when the run has a `best.json` and the row has both values.
    fn best_point(&self, x: &str, y: &str) -> Option<(f64, f64)> {
        let it = self.best_iteration? as f64;
        let row = self
            .columns
            .get("iteration")?
            .iter()
            .position(|v| *v == Some(it))?;
        let xv = self.x_values(x)?.get(row).copied().flatten()?;
        let yv = self.columns.get(y)?.get(row).copied().flatten()?;
        (xv.is_finite() && yv.is_finite()).then_some((xv, yv))
    }
}

/// What goes across the panels.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum XAxis {
    Iteration,
    EnvSteps,
    WallS,
}

impl XAxis {
    fn column(self) -> &'static str {
        match self {
            XAxis::Iteration => "iteration",
            XAxis::EnvSteps => "env_steps",
            XAxis::WallS => "wall_s",
        }
    }
    fn label(self) -> &'static str {
        match self {
            XAxis::Iteration => "iteration",
            XAxis::EnvSteps => "environment steps",
            XAxis::WallS => "wall time (s)",
        }
    }
}

impl std::str::FromStr for XAxis {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, String> {
        match s.trim() {
            "iteration" => Ok(XAxis::Iteration),
            "env_steps" | "env-steps" => Ok(XAxis::EnvSteps),
            "wall_s" | "wall-s" | "wall" => Ok(XAxis::WallS),
            other => Err(format!(
                "`{other}`: expected iteration, env_steps or wall_s"
            )),
        }
    }
}

#[derive(Clone, Debug)]
pub struct TrainingPlotOptions {
    /// A horizontal line on the outflow panel: the all-human baseline, veh/h.
    pub baseline_outflow: Option<f64>,
    pub x: XAxis,
    pub width_px: u32,
    pub height_px: u32,
    pub title: Option<String>,
}

impl Default for TrainingPlotOptions {
    fn default() -> Self {
        TrainingPlotOptions {
            baseline_outflow: None,
            x: XAxis::Iteration,
            width_px: 1800,
            height_px: 900,
            title: None,
        }
    }
}

/// What a plot drew, for `--json` and tests.
#[derive(Clone, Debug, Serialize)]
pub struct TrainingPlotSummary {
    pub path: PathBuf,
    pub runs: Vec<RunSummary>,
    /// Panels whose column no run had.
    pub empty_panels: Vec<String>,
}

#[derive(Clone, Debug, Serialize)]
pub struct RunSummary {
    pub log: PathBuf,
    pub label: String,
    pub rows: usize,
    pub missing_columns: Vec<String>,
    /// Last finite value of each plotted column.
    pub last: BTreeMap<String, f64>,
    /// The row marked as the one that chose `best.json`, if any.
    pub best_iteration: Option<u64>,
}

/// The panels: column and title with units.
const PANELS: [(&str, &str); 8] = [
    ("mean_return", "mean return"),
    ("mean_outflow", "mean outflow (veh/h)"),
    ("mean_speed", "mean speed (m/s)"),
    ("entropy", "policy entropy"),
    ("policy_loss", "policy loss"),
    ("value_loss", "value loss"),
    ("kl", "KL divergence"),
    ("kl_coeff", "KL coefficient"),
];

/// Read each run's log and draw the curves, overlaid, into `out` (`.png` or `.svg`).
pub fn plot_training(
    runs: &[PathBuf],
    out: &Path,
    options: &TrainingPlotOptions,
) -> Result<TrainingPlotSummary, VizError> {
    crate::canvas::picture_kind(out)?;
    if runs.is_empty() {
        return Err(VizError::Input {
            path: out.to_path_buf(),
            message: "no run directory given".into(),
        });
    }
    let logs: Vec<TrainingLog> = runs.iter().map(|r| read_log(r)).collect::<Result<_, _>>()?;
    if logs.iter().all(|l| l.rows == 0) {
        return Err(VizError::Input {
            path: logs[0].path.clone(),
            message: "the log has no rows yet".into(),
        });
    }
    let fig = TrainingFigure {
        logs: &logs,
        options,
    };
    draw_to_file(
        out,
        (
            options.width_px.clamp(600, 10_000),
            options.height_px.clamp(400, 10_000),
        ),
        &fig,
    )?;
    let empty_panels = PANELS
        .iter()
        .filter(|(c, _)| {
            logs.iter()
                .all(|l| l.series(options.x.column(), c).is_empty())
        })
        .map(|(c, _)| c.to_string())
        .collect();
    let runs = logs
        .iter()
        .map(|l| RunSummary {
            log: l.path.clone(),
            label: l.label.clone(),
            rows: l.rows,
            missing_columns: LOG_COLUMNS
                .iter()
                .filter(|c| !l.columns.contains_key(**c))
                .map(|c| c.to_string())
                .collect(),
            last: PANELS
                .iter()
                .filter_map(|(c, _)| {
                    l.series(options.x.column(), c)
                        .last()
                        .map(|(_, y)| (c.to_string(), *y))
                })
                .collect(),
            best_iteration: l.best_iteration,
        })
        .collect();
    Ok(TrainingPlotSummary {
        path: out.to_path_buf(),
        runs,
        empty_panels,
    })
}

struct TrainingFigure<'a> {
    logs: &'a [TrainingLog],
    options: &'a TrainingPlotOptions,
}

/// A range around `values` with a little room; a flat series gets a band around its value.
fn padded_range(values: impl Iterator<Item = f64>) -> Option<(f64, f64)> {
    let (mut lo, mut hi) = (f64::INFINITY, f64::NEG_INFINITY);
    for v in values.filter(|v| v.is_finite()) {
        lo = lo.min(v);
        hi = hi.max(v);
    }
    if !lo.is_finite() {
        return None;
    }
    let span = hi - lo;
    let pad = if span > 1e-12 * hi.abs().max(1.0) {
        0.06 * span
    } else {
        0.1 * hi.abs().max(1e-3)
    };
    Some((lo - pad, hi + pad))
}

impl Figure for TrainingFigure<'_> {
    fn draw<DB: DrawingBackend>(&self, root: &DrawingArea<DB, Shift>) -> Result<(), String> {
        root.fill(&WHITE).d()?;
        let title = self.options.title.clone().unwrap_or_else(|| {
            let names: Vec<&str> = self.logs.iter().map(|l| l.label.as_str()).collect();
            format!("Training curves: {}", names.join(", "))
        });
        let root = root.titled(&title, ("sans-serif", 24)).d()?;
        let xcol = self.options.x.column();
        let areas = root.split_evenly((2, 4));
        for (area, (col, panel_title)) in areas.iter().zip(PANELS) {
            let series: Vec<(usize, Vec<(f64, f64)>)> = self
                .logs
                .iter()
                .enumerate()
                .map(|(i, l)| (i, l.series(xcol, col)))
                .filter(|(_, s)| !s.is_empty())
                .collect();
            let baseline = if col == "mean_outflow" {
                self.options.baseline_outflow
            } else {
                None
            };
            let xr = padded_range(series.iter().flat_map(|(_, s)| s.iter().map(|p| p.0)));
            let yr = padded_range(
                series
                    .iter()
                    .flat_map(|(_, s)| s.iter().map(|p| p.1))
                    .chain(baseline),
            );
            let (Some((x0, x1)), Some((y0, y1))) = (xr, yr) else {
                let a = area.margin(10, 10, 10, 10);
                a.draw(&Rectangle::new(
                    [
                        (0, 0),
                        (a.dim_in_pixel().0 as i32 - 1, a.dim_in_pixel().1 as i32 - 1),
                    ],
                    RGBColor(200, 200, 200),
                ))
                .d()?;
                a.draw(&Text::new(
                    format!("{panel_title}: no `{col}` column"),
                    (12, 12),
                    ("sans-serif", 15)
                        .into_font()
                        .color(&RGBColor(110, 110, 110)),
                ))
                .d()?;
                continue;
            };
            let x0 = if self.options.x == XAxis::Iteration {
                x0.max(0.0).min(x1 - 1e-9)
            } else {
                x0
            };
            let mut chart = ChartBuilder::on(area)
                .caption(panel_title, ("sans-serif", 18))
                .margin(8)
                .x_label_area_size(40)
                .y_label_area_size(70)
                .build_cartesian_2d(x0..x1, y0..y1)
                .d()?;
            chart
                .configure_mesh()
                .light_line_style(RGBColor(240, 240, 240))
                .max_light_lines(1)
                .x_desc(self.options.x.label())
                .x_labels(6)
                .y_labels(6)
                .label_style(("sans-serif", 13))
                .axis_desc_style(("sans-serif", 14))
                .x_label_formatter(&|v| short_number(*v))
                .y_label_formatter(&|v| short_number(*v))
                .draw()
                .d()?;
            let many = self.logs.len() > 1;
            for (i, s) in &series {
                let color = run_color(*i);
                let drawn = chart
                    .draw_series(LineSeries::new(s.iter().copied(), color.stroke_width(2)))
                    .d()?;
                if many || baseline.is_some() {
                    drawn
                        .label(self.logs[*i].label.clone())
                        .legend(move |(x, y)| {
                            PathElement::new(vec![(x, y), (x + 20, y)], color.stroke_width(2))
                        });
                }
                if s.len() == 1 {
                    chart
                        .draw_series(s.iter().map(|p| Circle::new(*p, 4, color.filled())))
                        .d()?;
                }
            }
            // the rows that chose each run's best.json: a ring in the run's colour around a black dot (named once
            // in the legend)
            let mut named = false;
            for (i, _) in &series {
                if let Some(p) = self.logs[*i].best_point(xcol, col) {
                    let color = run_color(*i);
                    let drawn = chart
                        .draw_series([
                            Circle::new(p, 7, color.stroke_width(3)),
                            Circle::new(p, 3, BLACK.filled()),
                        ])
                        .d()?;
                    if !named {
                        named = true;
                        drawn.label("row that chose best.json").legend(|(x, y)| {
                            EmptyElement::at((x + 10, y))
                                + Circle::new((0, 0), 6, BLACK.stroke_width(2))
                                + Circle::new((0, 0), 2, BLACK.filled())
                        });
                    }
                }
            }
            if let Some(b) = baseline {
                let grey = RGBColor(60, 60, 60);
                chart
                    .draw_series(DashedLineSeries::new(
                        vec![(x0, b), (x1, b)],
                        8,
                        5,
                        grey.stroke_width(2),
                    ))
                    .d()?
                    .label(format!("human baseline {b:.0} veh/h"))
                    .legend(move |(x, y)| {
                        PathElement::new(vec![(x, y), (x + 20, y)], grey.stroke_width(2))
                    });
            }
            let show_legend = baseline.is_some() || (many && col == "mean_return");
            if show_legend {
                chart
                    .configure_series_labels()
                    .background_style(WHITE.mix(0.85))
                    .border_style(RGBColor(150, 150, 150))
                    .label_font(("sans-serif", 13))
                    .position(SeriesLabelPosition::LowerRight)
                    .draw()
                    .d()?;
            }
        }
        Ok(())
    }
}

/// Axis numbers kept short: 12k, 3.5M, 0.012.
fn short_number(v: f64) -> String {
    let a = v.abs();
    if a >= 1e6 {
        format!("{}M", trim(v / 1e6))
    } else if a >= 1e4 {
        format!("{}k", trim(v / 1e3))
    } else if a >= 100.0 || a == 0.0 {
        format!("{v:.0}")
    } else if a >= 1.0 {
        trim(v)
    } else if a >= 1e-3 {
        format!("{}", (v * 1e4).round() / 1e4)
    } else {
        format!("{v:.1e}")
    }
}

fn trim(v: f64) -> String {
    let s = format!("{v:.2}");
    s.trim_end_matches('0').trim_end_matches('.').to_string()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn short_numbers() {
        assert_eq!(short_number(12_000.0), "12k");
        assert_eq!(short_number(3_500_000.0), "3.5M");
        assert_eq!(short_number(250.0), "250");
        assert_eq!(short_number(2.5), "2.5");
        assert_eq!(short_number(0.0123), "0.0123");
        assert_eq!(short_number(0.0), "0");
    }

    #[test]
    fn ranges_pad_and_handle_flat_series() {
        let (lo, hi) = padded_range([1.0, 2.0].into_iter()).unwrap();
        assert!(lo < 1.0 && hi > 2.0);
        let (lo, hi) = padded_range([5.0, 5.0].into_iter()).unwrap();
        assert!(lo < 5.0 && hi > 5.0);
        assert!(padded_range([f64::NAN].into_iter()).is_none());
    }
}
