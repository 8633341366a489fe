//! The range every number of a policy file and of a training run's hyperparameters must lie in, checked when a
//! policy is loaded (`Checkpoint::load`, in `checkpoint.rs`) and before a run starts ([`check_config`]); `mapc train`'s flags take
//! the same ranges. Like the scenario's ranges (`mapc_scenario::ranges`) they are wide: they catch a typo, a NaN,
//! an infinity or bounds the wrong way round, which would otherwise panic in a clamp or quietly change every
//! figure, not an unusual choice.

use std::ops::RangeInclusive;

pub use mapc_scenario::ranges::Range;
use mapc_scenario::ranges::{N_AV as SCENARIO_N_AV, show};

use crate::PpoConfig;

pub(crate) const fn closed(lo: f64, hi: f64, unit: &'static str) -> Range {
    Range { lo, hi, unit }
}

/// Adam learning rate (also every point of `lr_schedule`).
pub const LR: Range = closed(1e-9, 1.0, "");
pub const GAMMA: Range = closed(0.0, 1.0, "");
pub const LAMBDA: Range = closed(0.0, 1.0, "");
pub const CLIP: Range = closed(1e-3, 10.0, "");
/// The distributed presets turn the value clip off with 1e8.
pub const VF_CLIP: Range = closed(1e-3, 1e10, "");
pub const VF_COEFF: Range = closed(0.0, 1e3, "");
pub const ENTROPY_COEFF: Range = closed(0.0, 1e3, "");
/// The initial KL penalty coefficient.
pub const KL_COEFF: Range = closed(0.0, 1e6, "");
pub const KL_TARGET: Range = closed(1e-9, 10.0, "");
/// Environment steps per iteration (25 times the paper's 40 000).
pub const TRAIN_BATCH_SIZE: RangeInclusive<u64> = 1..=1_000_000;
pub const MINIBATCH: RangeInclusive<u64> = 1..=1_000_000;
pub const EPOCHS: RangeInclusive<u64> = 1..=1000;
pub const ITERATIONS: RangeInclusive<u64> = 0..=1_000_000;
/// Steps per episode.
pub const HORIZON: RangeInclusive<u64> = 1..=1_000_000;
pub const GRAD_SLICES: RangeInclusive<u64> = 1..=1024;
/// Hidden layers, and units in each.
pub const HIDDEN_LAYERS: RangeInclusive<u64> = 1..=16;
pub const HIDDEN_UNITS: RangeInclusive<u64> = 1..=10_000;
/// Controlled AVs of a centralized policy (a scenario's `control.n_av` allows 0; a policy drives at least one).
pub const N_AV: RangeInclusive<u64> = 1..=SCENARIO_N_AV.hi as u64;
/// Either acceleration bound of a policy's actions.
pub const ACCEL_BOUND_MPS2: Range = closed(-50.0, 50.0, "m/s²");
/// The distributed reward's weights (`--eta1`, `--eta2`) and exit bonus.
pub const REWARD_WEIGHT: Range = closed(0.0, 1e3, "");
pub const EXIT_BONUS: Range = closed(0.0, 1e6, "");
/// Share of the mean agent reward every agent gets.
pub const REWARD_SHARE: Range = closed(0.0, 1.0, "");
/// Any finite number (a figure, a weight, an optimiser's moment).
pub(crate) const FINITE: Range = closed(f64::MIN, f64::MAX, "");
pub(crate) const NON_NEGATIVE: Range = closed(0.0, f64::MAX, "");

/// `key = value` within `range`, else a message naming both.
pub fn number(key: &str, value: f64, range: Range) -> Result<(), String> {
    mapc_scenario::ranges::check(key, value, range).map_err(|r| format!("{}: {}", r.key, r.message))
}

/// A count within `range`, else a message naming the key.
pub fn count(key: &str, value: u64, range: RangeInclusive<u64>) -> Result<(), String> {
    if range.contains(&value) {
        return Ok(());
    }
    Err(format!(
        "{key}: {value} is outside the allowed range [{}, {}]",
        range.start(),
        range.end()
    ))
}

/// Every value of `values` finite, else the first that is not, by its index.
pub(crate) fn all_finite(key: &str, values: &[f32]) -> Result<(), String> {
    match values.iter().position(|v| !v.is_finite()) {
        None => Ok(()),
        Some(i) => Err(format!(
            "{key}[{i}]: {} is not a finite number",
            show(values[i] as f64)
        )),
    }
}

/// Every hyperparameter within its range; keys are prefixed with `prefix` (`state.config.` in a policy file).
pub fn check_config(c: &PpoConfig, prefix: &str) -> Result<(), String> {
    let key = |k: &str| format!("{prefix}{k}");
    for (k, v, range) in [
        ("lr", c.lr, LR),
        ("gamma", c.gamma, GAMMA),
        ("lambda", c.lambda, LAMBDA),
        ("clip", c.clip, CLIP),
        ("vf_clip", c.vf_clip, VF_CLIP),
        ("vf_coeff", c.vf_coeff, VF_COEFF),
        ("entropy_coeff", c.entropy_coeff, ENTROPY_COEFF),
        ("kl_coeff", c.kl_coeff, KL_COEFF),
        ("kl_target", c.kl_target, KL_TARGET),
    ] {
        number(&key(k), v as f64, range)?;
    }
    for (k, v, range) in [
        (
            "train_batch_size",
            c.train_batch_size as u64,
            TRAIN_BATCH_SIZE,
        ),
        ("minibatch", c.minibatch as u64, MINIBATCH),
        ("epochs", c.epochs as u64, EPOCHS),
        ("iterations", c.iterations, ITERATIONS),
        ("horizon", c.horizon as u64, HORIZON),
        ("grad_slices", c.grad_slices as u64, GRAD_SLICES),
        ("hidden (layers)", c.hidden.len() as u64, HIDDEN_LAYERS),
    ] {
        count(&key(k), v, range)?;
    }
    for (i, &units) in c.hidden.iter().enumerate() {
        count(&key(&format!("hidden[{i}]")), units as u64, HIDDEN_UNITS)?;
    }
    for (i, &(steps, lr)) in c.lr_schedule.iter().enumerate() {
        number(&key(&format!("lr_schedule[{i}]")), lr as f64, LR)?;
        if i > 0 && steps <= c.lr_schedule[i - 1].0 {
            return Err(format!(
                "{}: steps must increase, got {steps} after {}",
                key(&format!("lr_schedule[{i}]")),
                c.lr_schedule[i - 1].0
            ));
        }
    }
    Ok(())
}
