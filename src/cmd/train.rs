//! `mapc train`: PPO on a scenario, with a progress bar, a CSV log and atomic checkpoints (the training itself:
//! `training.rs`), and its report.

use mapc_rl::IterationStats;
use mapc_rl::run::{TrainRun, log_path};

pub use super::training::Args;
use super::training::train;

pub fn run(args: Args) -> anyhow::Result<()> {
    let json = args.json;
    let (run, last) = train(args)?;
    report(&run, json, last)
}

/// What `mapc train` prints at the end: where the run's files are, its last row and its best policy.
fn report(run: &TrainRun, json: bool, last: Option<IterationStats>) -> anyhow::Result<()> {
    let ck = mapc_rl::checkpoint::checkpoint_path(&run.dir);
    let best_file = mapc_rl::checkpoint::best_path(&run.dir);
    let best = run.best();
    if json {
        let v = serde_json::json!({
            "run_dir": run.dir,
            "checkpoint": ck,
            "log": log_path(&run.dir),
            "last": last,
            "best": best.map(|b| serde_json::json!({
                "file": best_file,
                "by": b.by.name(),
                "score": b.score,
                "policy_iteration": b.row_iteration - 1,
                "row_iteration": b.row_iteration,
            })),
        });
        println!("{}", serde_json::to_string_pretty(&v)?);
    } else {
        if let Some(s) = &last {
            println!(
                "iteration {}: mean return {:.3}, outflow {:.1} veh/h, speed {:.2} m/s, {:.0} s wall in total",
                s.iteration, s.mean_return, s.mean_outflow, s.mean_speed, s.wall_s
            );
        }
        println!(
            "checkpoint: {}\nlog: {}",
            ck.display(),
            log_path(&run.dir).display()
        );
        if let Some(b) = best {
            println!(
                "best: {} (the policy after {} iterations; its training rollouts, row {} of the log, reached \
                 {} {:.2})",
                best_file.display(),
                b.row_iteration - 1,
                b.row_iteration,
                b.by.name(),
                b.score
            );
        }
    }
    Ok(())
}
