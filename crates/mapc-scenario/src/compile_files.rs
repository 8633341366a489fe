//! The two files a window compile writes, a scenario and its graph beside it, made and checked in memory before
//! either is written: the graph read back as the graph loader reads it, the scenario read back and resolved on it
//! as every later command resolves it, and only then both written together ([`mapc_graph::write_all_atomically`]).
//! A compile that fails writes nothing, and a file that would not load is never left behind.

use crate::compile_error::CompileError;
use crate::{ResolvedScenario, Scenario};
use mapc_graph::LaneGraph;
use std::path::{Path, PathBuf};

/// A scenario and its graph, checked and ready to write.
#[derive(Clone, Debug)]
pub struct CheckedFiles {
    pub graph_path: PathBuf,
    graph_json: String,
    pub scenario_path: PathBuf,
    scenario_toml: String,
    /// The scenario as a later command will load it from the written files.
    pub resolved: ResolvedScenario,
}

impl CheckedFiles {
    /// `g` for `graph_path` and `scenario` (which names `graph_path`'s file as its network) for `scenario_path`,
    /// read back from their text and resolved together.
    pub fn check(
        g: &LaneGraph,
        graph_path: &Path,
        scenario: &Scenario,
        scenario_path: &Path,
    ) -> Result<CheckedFiles, CompileError> {
        let graph_json = g.to_json();
        let scenario_toml = scenario.to_toml();
        let read_back = |error| CompileError::ReadBack {
            path: scenario_path.to_path_buf(),
            error,
        };
        let graph_back =
            LaneGraph::from_json(&graph_json, graph_path).map_err(|error| CompileError::Graph {
                path: graph_path.to_path_buf(),
                error,
            })?;
        let scenario_back =
            Scenario::from_toml(&scenario_toml, scenario_path).map_err(read_back)?;
        let resolved = ResolvedScenario::resolve_with(
            scenario_back,
            graph_back,
            &scenario_path.display().to_string(),
        )
        .map_err(read_back)?;
        Ok(CheckedFiles {
            graph_path: graph_path.to_path_buf(),
            graph_json,
            scenario_path: scenario_path.to_path_buf(),
            scenario_toml,
            resolved,
        })
    }

    /// Both files written, or neither.
    pub fn write(&self) -> Result<(), CompileError> {
        mapc_graph::write_all_atomically(&[
            (self.graph_path.as_path(), self.graph_json.as_bytes()),
            (self.scenario_path.as_path(), self.scenario_toml.as_bytes()),
        ])
        .map_err(|(path, source)| CompileError::Write { path, source })
    }
}
