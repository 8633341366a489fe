use std::path::PathBuf;

/// Errors of the trainer and evaluator.
#[derive(Debug, thiserror::Error)]
pub enum RlError {
    #[error("{path}: {source}")]
    Io {
        path: PathBuf,
        source: std::io::Error,
    },
    #[error("{path}: {msg}")]
    Format { path: PathBuf, msg: String },
    #[error(
        "policy {policy} expects {expected} observation values (N_AV = {policy_n_av}) but scenario `{scenario}` gives {got} (N_AV = {scenario_n_av})"
    )]
    ObsMismatch {
        policy: PathBuf,
        expected: usize,
        policy_n_av: usize,
        scenario: String,
        got: usize,
        scenario_n_av: usize,
    },
    #[error("scenario `{scenario}`: {msg}")]
    Scenario { scenario: String, msg: String },
    #[error("{0}")]
    Config(String),
    /// An action that is not a finite acceleration; `index` is its position in the step's actions.
    #[error("{place} is {value}: an action must be a finite acceleration in m/s²")]
    Action {
        index: usize,
        place: String,
        value: f32,
    },
}
