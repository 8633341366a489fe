//! The range every number of a policy file and of a training run's hyperparameters must lie in, checked when a
//! policy is loaded ([`check_checkpoint`]) and before a run starts ([`check_config`]); `mapc train`'s flags take
//! the same ranges. Like the scenario's ranges (`mapc_scenario::ranges`) they are wide: they catch a typo, a NaN,
//! an infinity or bounds the wrong way round, which would otherwise panic in a clamp or quietly change every
//! figure, not an unusual choice.

use std::ops::RangeInclusive;

pub use mapc_scenario::ranges::Range;
use mapc_scenario::ranges::{DRIVING_SPEED_MPS, N_AV as SCENARIO_N_AV, ROAD_LENGTH_M, show};

use crate::PpoConfig;
use crate::checkpoint::{Checkpoint, PolicySpec};
use crate::env::merge::RewardKind;

const fn closed(lo: f64, hi: f64, unit: &'static str) -> Range {
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
const FINITE: Range = closed(f64::MIN, f64::MAX, "");
const NON_NEGATIVE: Range = closed(0.0, f64::MAX, "");

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
fn all_finite(key: &str, values: &[f32]) -> Result<(), String> {
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

/// The policy's layout and normalisation: sizes consistent with its AVs or features, bounds the right way round.
fn check_spec(s: &PolicySpec) -> Result<(), String> {
    number("spec.max_speed", s.max_speed, DRIVING_SPEED_MPS)?;
    number("spec.norm_length", s.norm_length, ROAD_LENGTH_M)?;
    number("spec.accel_min", s.accel_min, ACCEL_BOUND_MPS2)?;
    number("spec.accel_max", s.accel_max, ACCEL_BOUND_MPS2)?;
    if s.accel_min >= s.accel_max {
        return Err(format!(
            "spec.accel_min: {} is not below spec.accel_max ({})",
            show(s.accel_min),
            show(s.accel_max)
        ));
    }
    let Some(d) = &s.distributed else {
        s.reward
            .parse::<RewardKind>()
            .map_err(|e| format!("spec.reward: {e}"))?;
        count("spec.n_av", s.n_av as u64, N_AV)?;
        let per_av = crate::env::obs::per_av(s.lanes);
        if s.obs_dim != per_av * s.n_av || s.act_dim != s.n_av {
            return Err(format!(
                "spec.obs_dim, spec.act_dim: a centralized policy for {} AVs reads {} values and sets {} \
                 accelerations, but its spec says {} and {}",
                s.n_av,
                per_av * s.n_av,
                s.n_av,
                s.obs_dim,
                s.act_dim
            ));
        }
        return Ok(());
    };
    // a distributed policy drives every AV it finds: its n_av is only the training scenario's
    count("spec.n_av", s.n_av as u64, 0..=*N_AV.end())?;
    if d.features.obs_dim() != s.obs_dim || s.act_dim != 1 {
        return Err(format!(
            "spec.obs_dim, spec.act_dim: a distributed policy with features `{}` reads {} values and sets 1 \
             acceleration, but its spec says {} and {}",
            d.features.name(),
            d.features.obs_dim(),
            s.obs_dim,
            s.act_dim
        ));
    }
    let key = |k: &str| format!("spec.distributed.{k}");
    number(&key("reward.eta1"), d.reward.eta1, REWARD_WEIGHT)?;
    number(&key("reward.eta2"), d.reward.eta2, REWARD_WEIGHT)?;
    number(&key("reward.exit_bonus"), d.reward.exit_bonus, EXIT_BONUS)?;
    number(&key("reward.share"), d.reward.share, REWARD_SHARE)?;
    number(
        &key("dist_norm.junction"),
        d.dist_norm.junction,
        ROAD_LENGTH_M,
    )?;
    number(&key("dist_norm.merge"), d.dist_norm.merge, ROAD_LENGTH_M)
}

/// Every field of a policy file within its range and consistent with the others, the network's parameters and
/// the optimiser's moments finite.
pub fn check_checkpoint(ck: &Checkpoint) -> Result<(), String> {
    check_spec(&ck.spec)?;
    let state = &ck.state;
    check_config(&state.config, "state.config.")?;
    let arch = &state.model.arch;
    if arch.obs_dim != ck.spec.obs_dim
        || arch.act_dim != ck.spec.act_dim
        || arch.hidden != state.config.hidden
        || arch.shared_value != state.config.shared_value
    {
        return Err(format!(
            "state.model.arch: {} values in, {} out, hidden {:?}{}, but the spec and state.config say {}, {}, \
             {:?}{}",
            arch.obs_dim,
            arch.act_dim,
            arch.hidden,
            if arch.shared_value { " shared" } else { "" },
            ck.spec.obs_dim,
            ck.spec.act_dim,
            state.config.hidden,
            if state.config.shared_value {
                " shared"
            } else {
                ""
            },
        ));
    }
    let params = state.model.params.len();
    for (key, len) in [
        ("state.model.params", params),
        ("state.adam.m", state.adam.m.len()),
        ("state.adam.v", state.adam.v.len()),
    ] {
        if len != arch.param_len() {
            return Err(format!(
                "{key}: {len} values, but the network's sizes need {} (parameter count does not match the \
                 network sizes)",
                arch.param_len()
            ));
        }
    }
    all_finite("state.model.params", &state.model.params)?;
    all_finite("state.adam.m", &state.adam.m)?;
    all_finite("state.adam.v", &state.adam.v)?;
    if let Some(i) = state.adam.v.iter().position(|&v| v < 0.0) {
        return Err(format!(
            "state.adam.v[{i}]: {} is negative (a mean of squares)",
            show(state.adam.v[i] as f64)
        ));
    }
    number(
        "state.adam.beta1",
        state.adam.beta1 as f64,
        closed(0.0, 0.999_999, ""),
    )?;
    number(
        "state.adam.beta2",
        state.adam.beta2 as f64,
        closed(0.0, 0.999_999, ""),
    )?;
    number(
        "state.adam.eps",
        state.adam.eps as f64,
        closed(1e-30, 1.0, ""),
    )?;
    // adapted every iteration, so wider than the initial coefficient's range
    number("state.kl_coeff", state.kl_coeff as f64, NON_NEGATIVE)?;
    number("state.wall_s", state.wall_s, NON_NEGATIVE)?;
    if let Some(sel) = &ck.selected {
        number("selected.score", sel.score, FINITE)?;
        if state.iteration.checked_add(1) != Some(sel.row_iteration) {
            return Err(format!(
                "selected.row_iteration: {} is not the row of this policy's rollouts ({}, its iteration + 1)",
                sel.row_iteration,
                state.iteration.saturating_add(1)
            ));
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn policy(name: &str) -> Checkpoint {
        let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
            .join("../../policies")
            .join(name);
        serde_json::from_str(&std::fs::read_to_string(path).unwrap()).unwrap()
    }

    /// The error `edit` makes `check_checkpoint` find in the shipped centralized (or distributed) policy.
    fn refusal(distributed: bool, edit: impl FnOnce(&mut Checkpoint)) -> String {
        let mut ck = policy(if distributed {
            "simple_merge_distributed.json"
        } else {
            "simple_merge_outflow.json"
        });
        edit(&mut ck);
        check_checkpoint(&ck).expect_err("the edit is refused")
    }

    #[test]
    fn every_shipped_policy_is_within_the_ranges() {
        let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../../policies");
        let mut files = vec![];
        for sub in [dir.clone(), dir.join("table5")] {
            for entry in std::fs::read_dir(sub).unwrap() {
                let path = entry.unwrap().path();
                if path.extension().is_some_and(|e| e == "json") {
                    files.push(path);
                }
            }
        }
        assert!(files.len() > 10, "{files:?}");
        for path in files {
            let ck: Checkpoint =
                serde_json::from_str(&std::fs::read_to_string(&path).unwrap()).unwrap();
            assert_eq!(check_checkpoint(&ck), Ok(()), "{}", path.display());
        }
    }

    #[test]
    fn acceleration_bounds_the_wrong_way_round_are_refused() {
        let e = refusal(false, |ck| ck.spec.accel_min = 3.0);
        assert_eq!(e, "spec.accel_min: 3 is not below spec.accel_max (2.6)");
        let e = refusal(true, |ck| ck.spec.accel_max = f64::NAN);
        assert!(e.starts_with("spec.accel_max: NaN is outside"), "{e}");
    }

    #[test]
    fn normalisation_constants_must_be_positive() {
        for (bad, field) in [
            (-1.0, "max_speed"),
            (0.0, "max_speed"),
            (-1.0, "norm_length"),
        ] {
            let e = refusal(false, |ck| match field {
                "max_speed" => ck.spec.max_speed = bad,
                _ => ck.spec.norm_length = bad,
            });
            assert!(
                e.starts_with(&format!("spec.{field}: {bad} is outside")),
                "{e}"
            );
        }
    }

    #[test]
    fn n_av_must_match_the_observation_and_stay_in_range() {
        let e = refusal(false, |ck| ck.spec.n_av = 0);
        assert!(
            e.starts_with("spec.n_av: 0 is outside the allowed range [1, 1000]"),
            "{e}"
        );
        let e = refusal(false, |ck| ck.spec.n_av = 4_294_967_296);
        assert!(e.starts_with("spec.n_av: 4294967296 is outside"), "{e}");
        let e = refusal(false, |ck| ck.spec.n_av = 4);
        assert!(e.contains("for 4 AVs reads 20 values"), "{e}");
        let e = refusal(true, |ck| ck.spec.n_av = 1_000_000);
        assert!(e.starts_with("spec.n_av: 1000000 is outside"), "{e}");
    }

    #[test]
    fn the_reward_and_the_distributed_constants_are_checked() {
        let e = refusal(false, |ck| ck.spec.reward = "speedy".into());
        assert!(e.starts_with("spec.reward: "), "{e}");
        let e = refusal(true, |ck| {
            ck.spec.distributed.as_mut().unwrap().reward.share = 2.0
        });
        assert!(
            e.starts_with("spec.distributed.reward.share: 2 is outside"),
            "{e}"
        );
        let e = refusal(true, |ck| {
            ck.spec.distributed.as_mut().unwrap().dist_norm.merge = 0.0
        });
        assert!(
            e.starts_with("spec.distributed.dist_norm.merge: 0 is outside"),
            "{e}"
        );
    }

    #[test]
    fn parameters_and_hyperparameters_must_be_finite_numbers_in_range() {
        let e = refusal(false, |ck| ck.state.model.params[7] = f32::INFINITY);
        assert_eq!(e, "state.model.params[7]: inf is not a finite number");
        let e = refusal(false, |ck| ck.state.adam.v[0] = -1.0);
        assert!(e.starts_with("state.adam.v[0]: -1 is negative"), "{e}");
        let e = refusal(false, |ck| ck.state.config.gamma = 2.0);
        assert!(
            e.starts_with("state.config.gamma: 2 is outside the allowed range [0, 1]"),
            "{e}"
        );
        let e = refusal(false, |ck| ck.state.config.hidden[1] = 0);
        assert!(e.starts_with("state.config.hidden[1]: 0 is outside"), "{e}");
        let e = refusal(false, |ck| ck.state.model.arch.hidden = vec![100, 50]);
        assert!(e.starts_with("state.model.arch: "), "{e}");
        let e = refusal(true, |ck| ck.selected.as_mut().unwrap().row_iteration = 0);
        assert!(
            e.starts_with("selected.row_iteration: 0 is not the row"),
            "{e}"
        );
    }
}
