//! `mapc plot`: time-space diagrams of simulator traces and training curves of PPO runs.

use mapc_viz::timespace::{RoadFilter, TimeSpaceOptions};
use mapc_viz::training::{TrainingPlotOptions, XAxis};
use std::path::PathBuf;

#[derive(clap::Subcommand)]
pub enum Command {
    /// Time-space diagram of a trace (`mapc sim --trace`): time across, corridor position up, colour = speed.
    Timespace(TimespaceArgs),
    /// Training curves of one or more runs (RUN_DIR/progress.csv), overlaid.
    Training(TrainingArgs),
}

#[derive(clap::Args)]
pub struct TimespaceArgs {
    /// Trace CSV (header `time_s,vehicle_id,vehicle_type,road,pos_on_road_m,corridor_x_m,speed_mps,controlled,lane`;
    /// traces without `lane` are read as one-lane).
    pub trace: PathBuf,
    /// Output picture: .png or .svg.
    #[arg(short = 'o', long = "output", value_name = "FILE")]
    pub output: PathBuf,
    /// `main`: the corridor's main line (rows with corridor_x_m); or road names from the trace's `road` column,
    /// comma separated (position on the road is drawn up).
    #[arg(long, default_value = "main", value_name = "FILTER")]
    pub road_filter: RoadFilter,
    /// Top of the speed colour scale, m/s (default: the fastest sample, rounded up to 5).
    #[arg(long, value_name = "MPS", value_parser = super::flags::within::<f64>(mapc_scenario::ranges::DRIVING_SPEED_MPS))]
    pub speed_max: Option<f64>,
    /// Leave out samples before this time, s (a warm-up).
    #[arg(long, value_name = "S", value_parser = super::flags::within::<f64>(mapc_scenario::ranges::FLOW_TIME_S))]
    pub start: Option<f64>,
    /// Draw only lane N of each road (0 rightmost; default: all lanes).
    #[arg(long, value_name = "N", value_parser = super::flags::lane())]
    pub lane: Option<u8>,
    #[arg(long, default_value_t = 1400, value_name = "PX", value_parser = super::flags::pixels())]
    pub width: u32,
    #[arg(long, default_value_t = 800, value_name = "PX", value_parser = super::flags::pixels())]
    pub height: u32,
    /// Title (default: the trace's file name and what is shown).
    #[arg(long)]
    pub title: Option<String>,
    /// Print what was drawn as JSON.
    #[arg(long)]
    pub json: bool,
}

#[derive(clap::Args)]
pub struct TrainingArgs {
    /// Run directories (each with a progress.csv) or log files; several are overlaid.
    #[arg(required = true, value_name = "RUN_DIR")]
    pub runs: Vec<PathBuf>,
    /// Output picture: .png or .svg.
    #[arg(short = 'o', long = "output", value_name = "FILE")]
    pub output: PathBuf,
    /// Draw the all-human baseline's outflow, veh/h, as a dashed line on the outflow panel.
    #[arg(long, value_name = "VEH_PER_H", value_parser = super::flags::within::<f64>(super::flags::DEMAND_VPH))]
    pub baseline_outflow: Option<f64>,
    /// What goes across: iteration, env_steps or wall_s.
    #[arg(long, default_value = "iteration")]
    pub x: XAxis,
    #[arg(long, default_value_t = 1800, value_name = "PX", value_parser = super::flags::pixels())]
    pub width: u32,
    #[arg(long, default_value_t = 900, value_name = "PX", value_parser = super::flags::pixels())]
    pub height: u32,
    #[arg(long)]
    pub title: Option<String>,
    /// Print what was drawn as JSON.
    #[arg(long)]
    pub json: bool,
}

pub fn run(c: Command) -> anyhow::Result<()> {
    match c {
        Command::Timespace(a) => timespace(a),
        Command::Training(a) => training(a),
    }
}

fn timespace(a: TimespaceArgs) -> anyhow::Result<()> {
    let options = TimeSpaceOptions {
        filter: a.road_filter,
        width_px: a.width,
        height_px: a.height,
        speed_max_mps: a.speed_max,
        start_s: a.start,
        lane: a.lane,
        title: a.title,
    };
    let s = mapc_viz::timespace::plot_timespace(&a.trace, &a.output, &options)?;
    if a.json {
        println!("{}", serde_json::to_string_pretty(&s)?);
    } else {
        println!(
            "wrote {}: {} samples of {} vehicles ({} controlled), {:.0}-{:.0} s, {:.0}-{:.0} m",
            s.path.display(),
            s.samples_drawn,
            s.vehicles,
            s.controlled_vehicles,
            s.time_range_s[0],
            s.time_range_s[1],
            s.position_range_m[0],
            s.position_range_m[1]
        );
    }
    Ok(())
}

fn training(a: TrainingArgs) -> anyhow::Result<()> {
    let options = TrainingPlotOptions {
        baseline_outflow: a.baseline_outflow,
        x: a.x,
        width_px: a.width,
        height_px: a.height,
        title: a.title,
    };
    let s = mapc_viz::training::plot_training(&a.runs, &a.output, &options)?;
    if a.json {
        println!("{}", serde_json::to_string_pretty(&s)?);
    } else {
        let rows: Vec<String> = s
            .runs
            .iter()
            .map(|r| format!("{} ({} iterations)", r.label, r.rows))
            .collect();
        println!("wrote {}: {}", s.path.display(), rows.join(", "));
        for r in &s.runs {
            if !r.missing_columns.is_empty() {
                println!(
                    "  {}: no column {}",
                    r.log.display(),
                    r.missing_columns.join(", ")
                );
            }
        }
    }
    Ok(())
}
