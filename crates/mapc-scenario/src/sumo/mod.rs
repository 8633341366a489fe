//! A SUMO user's scenario as mapc runs it: a `.sumocfg` (or a net with route and additional files, as
//! `sumo -n -r -a`) read as SUMO 1.8 reads it and turned into a mapc [`Scenario`] on the SUMO network.
//!
//! Glossary:
//! - **option**: a `.sumocfg` setting (`<end value="3600"/>`), read by [`config`]; those that change the model in
//!   ways mapc does not implement are refused by name.
//! - **vType**: a SUMO vehicle type; its vClass gives the defaults SUMO 1.8 gives ([`vtypes`]).
//! - **demand**: SUMO's `vehicle`, `flow` and `trip` elements, each a mapc flow ([`demand`]): a vehicle or a trip
//!   is a flow of one.
//! - **unsupported**: an element or a value mapc does not simulate; refused with the file, the line and the
//!   element, or with `skip_unsupported` dropped with one warning per kind (SUMO's `--ignore-route-errors`).

// `!(x > 0.0)` and the like reject NaN on purpose.
#![allow(clippy::neg_cmp_op_on_partial_ord)]

pub mod config;
pub mod demand;
pub mod vtypes;

use crate::model::Scenario;
use std::path::{Path, PathBuf};

pub use config::SumoConfig;

/// What went wrong reading a SUMO scenario: the place (file, line, element) and why.
#[derive(Debug, thiserror::Error)]
pub enum SumoError {
    #[error("{0}")]
    Read(#[from] mapc_import::ImportError),
    #[error("{place}: {message}")]
    At { place: String, message: String },
    #[error("{path}: {message}")]
    File { path: PathBuf, message: String },
}

impl SumoError {
    pub fn at(place: &str, message: impl Into<String>) -> SumoError {
        SumoError::At {
            place: place.to_string(),
            message: message.into(),
        }
    }
}

/// How to read a SUMO scenario.
#[derive(Clone, Debug, Default)]
pub struct ReadOptions {
    /// Drop what mapc does not simulate (one warning per kind) instead of refusing it.
    pub skip_unsupported: bool,
}

/// A SUMO scenario turned into a mapc scenario, with what was dropped or approximated.
#[derive(Clone, Debug)]
pub struct FromSumo {
    pub scenario: Scenario,
    /// The SUMO network, imported.
    pub graph: mapc_graph::LaneGraph,
    pub config: SumoConfig,
    /// One line per kind of element or value dropped (`skip_unsupported`) or option ignored.
    pub warnings: Vec<String>,
}

/// Whether `path` is a SUMO configuration: named `.sumocfg`, or XML whose root is `<configuration>` or
/// `<sumoConfiguration>`.
pub fn is_sumo_config(path: &Path) -> bool {
    if path.extension().is_some_and(|e| e == "sumocfg") {
        return true;
    }
    let Ok(mut f) = std::fs::File::open(path) else {
        return false;
    };
    let mut head = vec![0u8; 4096];
    let n = std::io::Read::read(&mut f, &mut head).unwrap_or(0);
    let text = String::from_utf8_lossy(&head[..n]);
    // the first element that is not a declaration or a comment
    let mut rest = text.as_ref();
    while let Some(i) = rest.find('<') {
        rest = &rest[i + 1..];
        if let Some(comment) = rest.strip_prefix("!--") {
            // a comment may quote elements (SUMO writes its options into a network's header)
            match comment.find("-->") {
                Some(end) => rest = &comment[end + 3..],
                None => return false,
            }
            continue;
        }
        if rest.starts_with('?') || rest.starts_with('!') {
            continue;
        }
        return rest.starts_with("configuration") || rest.starts_with("sumoConfiguration");
    }
    false
}

/// Read `cfg`, a `.sumocfg`, and the files it names.
pub fn from_sumocfg(cfg: &Path, options: &ReadOptions) -> Result<FromSumo, SumoError> {
    let config = config::read(cfg)?;
    from_config(config, options)
}

/// A scenario from a net and route/additional files, as `sumo -n NET -r R1,R2 -a A` would run it (SUMO's
/// defaults for every other option).
pub fn from_files(
    net: &Path,
    routes: &[PathBuf],
    additional: &[PathBuf],
    options: &ReadOptions,
) -> Result<FromSumo, SumoError> {
    let config = SumoConfig::for_files(net, routes, additional);
    from_config(config, options)
}

/// The root elements of route and additional files SUMO 1.8 reads (`additionals` in some users' files).
const CONTAINERS: [&str; 4] = ["routes", "additional", "additionals", "add"];

/// A route or additional file's elements as SUMO reads them, wherever they stand: a container inside the root (a
/// `<routes>` inside an `<additionals>`, as some users' files have) holds elements like the root's own, in place.
fn flatten_containers(mut root: mapc_import::SumoElement) -> mapc_import::SumoElement {
    let is_container = |e: &mapc_import::SumoElement| CONTAINERS.contains(&e.name.as_str());
    if root.children.iter().any(is_container) {
        for c in std::mem::take(&mut root.children) {
            if is_container(&c) {
                root.children.extend(flatten_containers(c).children);
            } else {
                root.children.push(c);
            }
        }
    }
    root
}

fn from_config(config: SumoConfig, options: &ReadOptions) -> Result<FromSumo, SumoError> {
    let mut warnings = config.warnings.clone();
    let mut files = Vec::new();
    for p in config.route_files.iter().chain(&config.additional_files) {
        files.push(flatten_containers(mapc_import::read_sumo_xml(
            p,
            &CONTAINERS,
            "a SUMO route or additional file",
        )?));
    }
    let graph = mapc_import::import_path(&config.net_file, &mapc_import::ImportOptions::default())?;
    let scenario = demand::scenario(&config, &files, &graph, options, &mut warnings)?;
    Ok(FromSumo {
        scenario,
        graph,
        config,
        warnings,
    })
}

#[cfg(test)]
mod tests;
