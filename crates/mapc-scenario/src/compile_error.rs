//! The scenario compiler's one error type, shared by the compiler (`compile.rs`) and the files it checks and
//! writes (`compile_files.rs`).

use crate::ScenarioError;
use crate::transform::TransformError;
use std::path::PathBuf;

/// What can go wrong compiling a scenario from files; every message names the file or the argument at fault.
/// The inner error is part of the message (not a `source`), so that printing the error chain does not repeat it.
#[derive(Debug, thiserror::Error)]
pub enum CompileError {
    #[error("cannot read map {path}: {error}")]
    Map {
        path: PathBuf,
        error: mapc_import::ImportError,
    },
    #[error("{path}: {error}")]
    Transform {
        path: PathBuf,
        error: TransformError,
    },
    #[error("--match {arg}: {error}")]
    Source { arg: String, error: ScenarioError },
    #[error("--match {arg}: {error}")]
    SourceShape { arg: String, error: TransformError },
    #[error(transparent)]
    Scenario(#[from] ScenarioError),
    #[error("{path}: {error}")]
    Graph {
        path: PathBuf,
        error: mapc_graph::GraphFileError,
    },
    #[error("{0}")]
    Demand(String),
    /// The picked timing out of the scenario's bounds (a corridor too slow to fill within the warm-up's limit).
    #[error("{0}")]
    Timing(String),
    #[error("{path}: --junction {junction}: {error}")]
    Junction {
        path: PathBuf,
        junction: String,
        error: mapc_graph::LookupError,
    },
    #[error("the scenario made for {path} would not load (nothing written): {error}")]
    ReadBack { path: PathBuf, error: ScenarioError },
    #[error("{path}: {source} (nothing written)")]
    Write {
        path: PathBuf,
        source: std::io::Error,
    },
}
