//! The training log: one CSV row per iteration.

use std::path::Path;

use crate::checkpoint::write_atomic;
use crate::error::RlError;
use crate::ppo::IterationStats;

pub const CSV_HEADER: &str = "iteration,env_steps,wall_s,mean_return,mean_outflow,mean_speed,policy_loss,value_loss,kl,entropy,kl_coeff";

/// Rows of a training log, rewritten atomically after each iteration (it is small).
#[derive(Default, Debug, Clone)]
pub struct TrainingLog {
    pub rows: Vec<IterationStats>,
}

impl TrainingLog {
    /// Reads an existing log (for `--resume`).
    pub fn read(path: &Path) -> Result<Self, RlError> {
        let mut rdr = csv::Reader::from_path(path).map_err(|e| RlError::Format {
            path: path.into(),
            msg: e.to_string(),
        })?;
        let headers = rdr
            .headers()
            .map_err(|e| RlError::Format {
                path: path.into(),
                msg: e.to_string(),
            })?
            .clone();
        if headers.iter().collect::<Vec<_>>().join(",") != CSV_HEADER {
            return Err(RlError::Format {
                path: path.into(),
                msg: format!("header is not `{CSV_HEADER}`"),
            });
        }
        let mut rows = Vec::new();
        for (i, rec) in rdr.deserialize().enumerate() {
            let row: IterationStats = rec.map_err(|e| RlError::Format {
                path: path.into(),
                msg: format!("row {}: {e}", i + 2),
            })?;
            rows.push(row);
        }
        Ok(Self { rows })
    }

    pub fn to_csv(&self) -> String {
        let mut s = String::from(CSV_HEADER);
        s.push('\n');
        for r in &self.rows {
            s.push_str(&format!(
                "{},{},{:.3},{},{},{},{},{},{},{},{}\n",
                r.iteration,
                r.env_steps,
                r.wall_s,
                r.mean_return,
                r.mean_outflow,
                r.mean_speed,
                r.policy_loss,
                r.value_loss,
                r.kl,
                r.entropy,
                r.kl_coeff
            ));
        }
        s
    }

    pub fn write(&self, path: &Path) -> Result<(), RlError> {
        write_atomic(path, self.to_csv().as_bytes())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn csv_round_trip() {
        let log = TrainingLog {
            rows: vec![IterationStats {
                iteration: 1,
                env_steps: 2000,
                mean_outflow: 1555.5,
                kl: 0.01,
                ..Default::default()
            }],
        };
        let dir = std::env::temp_dir().join(format!("mapc-rl-log-{}", std::process::id()));
        let p = dir.join("train.csv");
        log.write(&p).unwrap();
        let back = TrainingLog::read(&p).unwrap();
        assert_eq!(back.rows, log.rows);
        assert!(log.to_csv().starts_with(CSV_HEADER));
        std::fs::remove_dir_all(dir).ok();
    }
}
