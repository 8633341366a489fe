//! # mapc-py: the native part of mapc's Python package (`mapc._mapc`)
//!
//! Glossary:
//! - **env**: one centralized merge-control episode at a time ([`Env`]): the observation of the first `N_AV` AVs
//!   in the control region, their accelerations as the action, one of the paper's rewards (`mapc_rl`'s
//!   `MergeEnv`, the environment `mapc train` uses).
//! - **vector env**: K such episodes stepped together in Rust threads in one call ([`VecEnv`]), each
//!   sub-environment reset in the step after its episode ended (Gymnasium 1.x's next-step autoreset).
//! - **agent**: in the distributed setting ([`DistEnv`](envs::DistEnv)), an AV in the control region, named by
//!   its vehicle id here and by its order of appearance (`av_0`, `av_1`, ...) in Python's PettingZoo wrapper.
//! - **buffer**: observations, actions and rewards cross into Python as little-endian `float32` bytes, which
//!   `numpy.frombuffer` reads without a copy per value.
//! - **pipeline**: `import_map`, `simplify` and `window` write the stages' files and return the reports of
//!   `mapc import|simplify|window --json`.
//! - **report**: `simulate` and `evaluate` return the JSON that `mapc sim --json` and `mapc eval --json` print
//!   (the same library structs), which the Python side parses into dicts.
//!
//! Every error of mapc becomes `mapc.MapcError` with mapc's message (file and place); nothing here panics on
//! bad input.

mod envs;
mod pipeline;

use mapc_rl::Checkpoint;
use mapc_rl::eval::evaluate as evaluate_policy;
use mapc_rl::rollout::ActionMode;
use mapc_scenario::ResolvedScenario;
use mapc_sim::{BaselineReport, SimSpec, run_baseline_spec, spec_from_scenario};
use pyo3::create_exception;
use pyo3::exceptions::PyException;
use pyo3::prelude::*;
use std::path::PathBuf;

create_exception!(
    _mapc,
    MapcError,
    PyException,
    "An error of mapc: bad input, named with its file and place."
);

/// A mapc error as the Python exception, with the whole chain of causes in its message. Map text in it (ids,
/// names) is written printable, as the binary prints it: a traceback shows it, never obeys it.
pub(crate) fn mapc_error(e: impl std::fmt::Display) -> PyErr {
    MapcError::new_err(mapc_graph::terminal::printable(&e.to_string()).into_owned())
}

/// A scenario file or built-in name, resolved and made into the simulator's spec.
pub(crate) fn load_scenario(scenario: &str) -> PyResult<(ResolvedScenario, SimSpec)> {
    let resolved = ResolvedScenario::load(scenario).map_err(mapc_error)?;
    let spec = spec_from_scenario(&resolved)
        .map_err(|e| mapc_error(format!("scenario `{}`: {e}", resolved.origin)))?;
    Ok((resolved, spec))
}

/// Write `scenario` with `share` of its flows' vehicles (those of `flows`; all when empty) as AVs to `output`, a
/// scenario file every function takes (`mapc_scenario::av_share`; `--av-share` of the binary).
#[pyfunction]
#[pyo3(signature = (scenario, share, output, flows = Vec::new()))]
fn with_avs(scenario: &str, share: f64, output: &str, flows: Vec<String>) -> PyResult<String> {
    let rs = ResolvedScenario::load(scenario).map_err(mapc_error)?;
    let rs = rs.with_av_share(share, &flows).map_err(mapc_error)?;
    rs.scenario_with_absolute_paths()
        .save(std::path::Path::new(output))
        .map_err(mapc_error)?;
    Ok(output.to_string())
}

fn seed_list(seeds: u64, first_seed: u64) -> PyResult<Vec<u64>> {
    if seeds == 0 {
        return Err(mapc_error("seeds must be at least 1"));
    }
    Ok((first_seed..first_seed + seeds).collect())
}

/// The all-human baseline of `scenario` over `seeds` seeds from `first_seed`, as JSON (`mapc sim --json`).
#[pyfunction]
#[pyo3(signature = (scenario, seeds = 100, first_seed = 0))]
fn simulate(py: Python<'_>, scenario: &str, seeds: u64, first_seed: u64) -> PyResult<String> {
    let (resolved, spec) = load_scenario(scenario)?;
    let list = seed_list(seeds, first_seed)?;
    let start = std::time::Instant::now();
    let runs = py
        .detach(|| run_baseline_spec(&spec, &list))
        .map_err(|e| mapc_error(format!("scenario `{}`: {e}", resolved.origin)))?;
    let report = BaselineReport::of(
        &resolved.origin,
        first_seed,
        runs,
        start.elapsed().as_secs_f64(),
        &spec,
    );
    serde_json::to_string(&report).map_err(mapc_error)
}

/// A policy (checkpoint file or run directory) against the humans on `scenario`, as JSON (`mapc eval --json`).
#[pyfunction]
#[pyo3(signature = (policy, scenario = "simple_merge", seeds = 100, first_seed = 0, sample = false, baseline = true, deploy = None))]
#[allow(clippy::too_many_arguments)]
fn evaluate(
    py: Python<'_>,
    policy: PathBuf,
    scenario: &str,
    seeds: u64,
    first_seed: u64,
    sample: bool,
    baseline: bool,
    deploy: Option<&str>,
) -> PyResult<String> {
    let file = mapc_rl::checkpoint::policy_file(&policy);
    let mut ck = Checkpoint::load(&file).map_err(mapc_error)?;
    if let Some(rule) = deploy {
        ck.spec.deploy = Some(rule.parse().map_err(mapc_error)?);
    }
    let (resolved, spec) = load_scenario(scenario)?;
    let list = seed_list(seeds, first_seed)?;
    let n_av = resolved.scenario.control.as_ref().map(|c| c.n_av as usize);
    let mode = if sample {
        ActionMode::Sample
    } else {
        ActionMode::Mean
    };
    let (report, ..) = py
        .detach(|| {
            evaluate_policy(&mapc_rl::eval::EvalRequest {
                ck: &ck,
                policy_file: &file,
                scenario,
                spec: &spec,
                scenario_n_av: n_av,
                seeds: &list,
                mode,
                baseline,
            })
        })
        .map_err(|e| mapc_error(format!("evaluating {}: {e}", file.display())))?;
    serde_json::to_string(&report).map_err(mapc_error)
}

/// Write a policy trained elsewhere (RLlib, Stable-Baselines3) as a mapc policy file that `mapc eval` reads.
/// `params` are float32 bytes in mapc's layout (`mapc.export` builds them from torch layers): the policy MLP
/// obs -> hidden... -> means then log-stds (tanh hidden layers), each layer's weights input-major
/// (`w[i * n_out + j]`) then its biases, and then the value MLP obs -> hidden... -> 1. With `features` the policy
/// is distributed (one acceleration per agent, the observation of those features) and its value is one more
/// output of the policy's last layer instead (shared layers). Written atomically.
#[pyfunction]
#[pyo3(signature = (path, params, scenario = "simple_merge", reward = "outflow", n_av = 5,
                    hidden = vec![100, 50, 25], features = None, eta1 = 0.9, eta2 = 0.1, exit_bonus = 20.0))]
#[allow(clippy::too_many_arguments)]
fn save_policy(
    path: PathBuf,
    params: &[u8],
    scenario: &str,
    reward: &str,
    n_av: usize,
    hidden: Vec<usize>,
    features: Option<&str>,
    eta1: f64,
    eta2: f64,
    exit_bonus: f64,
) -> PyResult<()> {
    use mapc_rl::env::distributed::{AgentReward, Features};
    use mapc_rl::env::merge::RewardKind;
    if n_av == 0 || hidden.is_empty() || hidden.contains(&0) {
        return Err(mapc_error("n_av and every hidden size must be at least 1"));
    }
    let (spec, base) = match features {
        None => {
            let reward: RewardKind = reward.parse().map_err(mapc_error)?;
            let spec = mapc_rl::PolicySpec::centralized(scenario, reward.name(), n_av);
            (spec, mapc_rl::PpoConfig::default())
        }
        Some(f) => {
            let features = Features::parse(f).map_err(mapc_error)?;
            let reward = AgentReward {
                eta1,
                eta2,
                exit_bonus,
                ..AgentReward::PAPER
            };
            let spec = mapc_rl::PolicySpec::distributed(scenario, n_av, features, reward);
            (spec, mapc_rl::PpoConfig::distributed())
        }
    };
    let config = mapc_rl::PpoConfig { hidden, ..base };
    let mut state = mapc_rl::TrainerState::new(config, spec.obs_dim, spec.act_dim);
    if params.len() != 4 * state.model.params.len() {
        return Err(mapc_error(format!(
            "{} parameter bytes where this architecture ({} inputs, hidden {:?}, {} actions{}) has {} float32 values",
            params.len(),
            spec.obs_dim,
            state.model.arch.hidden,
            spec.act_dim,
            if state.model.arch.shared_value {
                ", value in the last layer"
            } else {
                ", a value net"
            },
            state.model.params.len()
        )));
    }
    state.model.params = params
        .chunks_exact(4)
        .map(|c| f32::from_le_bytes([c[0], c[1], c[2], c[3]]))
        .collect();
    if let Some(i) = state.model.params.iter().position(|x| !x.is_finite()) {
        return Err(mapc_error(format!("parameter {i} is not a finite number")));
    }
    Checkpoint {
        format_version: mapc_rl::checkpoint::FORMAT_VERSION,
        spec,
        state,
        selected: None,
    }
    .save(&path)
    .map_err(mapc_error)
}

#[pymodule]
fn _mapc(m: &Bound<'_, PyModule>) -> PyResult<()> {
    mapc_sim::numeric::check_cpu().map_err(pyo3::exceptions::PyImportError::new_err)?;
    m.add("MapcError", m.py().get_type::<MapcError>())?;
    m.add("__version__", env!("CARGO_PKG_VERSION"))?;
    m.add_function(wrap_pyfunction!(simulate, m)?)?;
    m.add_function(wrap_pyfunction!(with_avs, m)?)?;
    m.add_function(wrap_pyfunction!(evaluate, m)?)?;
    m.add_function(wrap_pyfunction!(save_policy, m)?)?;
    m.add_function(wrap_pyfunction!(pipeline::import_map, m)?)?;
    m.add_function(wrap_pyfunction!(pipeline::simplify, m)?)?;
    m.add_function(wrap_pyfunction!(pipeline::window, m)?)?;
    m.add_class::<envs::Env>()?;
    m.add_class::<envs::VecEnv>()?;
    m.add_class::<envs::DistEnv>()?;
    m.add_class::<envs::Policy>()?;
    Ok(())
}
