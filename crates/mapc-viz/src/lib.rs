//! # mapc-viz: pictures of maps, traffic and training
//!
//! Glossary:
//! - **render**: a drawing of a lane graph, north up, equal aspect, roads coloured by class, merge junctions
//!   labelled with their ids (`J12`), a scale bar in metres ([`render_map`]).
//! - **highlight**: roads drawn with a halo (a transfer window) and junctions always labelled ([`Highlight`]).
//! - **GeoJSON export**: one LineString per road and one Point per junction, WGS84 longitude/latitude
//!   (RFC 7946) when the graph has a geographic frame ([`geojson`]).
//! - **trace**: the simulator's CSV of vehicle samples
//!   (`time_s,vehicle_id,vehicle_type,road,pos_on_road_m,corridor_x_m,speed_mps,controlled,lane`; `lane` is the
//!   lane's index on its road, 0 rightmost, and traces written without it read as lane 0).
//! - **time-space diagram**: vehicle trajectories with time across and corridor position up, coloured by speed;
//!   stop-and-go waves show as red bands running upstream ([`timespace`]).
//! - **replay page**: `mapc view`'s self-contained HTML file that plays traces on the map in a browser
//!   ([`view`]).
//! - **training log**: a run directory's `progress.csv`, one row per PPO iteration; drawn as curves ([`training`]).
//!
//! The output kind follows the file name: `.png` is drawn on a bitmap, `.svg` as vector graphics. Every file is
//! written atomically (a temporary file beside it, then a rename).

mod canvas;
pub mod colors;
pub mod csvin;
pub mod geojson;
pub mod map;
pub mod pngstats;
pub mod timespace;
pub mod training;
pub mod view;

pub use map::{Highlight, MapRenderSummary, RenderOptions, render_map, render_map_with};

use std::path::PathBuf;

/// Everything that can go wrong making a picture; each message names the file and, for CSV input, the line and
/// column.
#[derive(Debug, thiserror::Error)]
pub enum VizError {
    #[error("{path}: {source}")]
    Io {
        path: PathBuf,
        source: std::io::Error,
    },
    #[error("{path}: line {line}, column `{column}`: {message}")]
    Field {
        path: PathBuf,
        line: u64,
        column: String,
        message: String,
    },
    #[error("{path}: {message}")]
    Input { path: PathBuf, message: String },
    #[error("{path}: unsupported picture type (the name must end in .png or .svg)")]
    PictureType { path: PathBuf },
    #[error("{path}: drawing failed: {message}")]
    Draw { path: PathBuf, message: String },
}

#[cfg(test)]
mod tests;
