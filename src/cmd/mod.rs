//! One module per subcommand: its clap arguments and a `run` that returns an error for bad input.

pub mod bench;
pub mod common;
pub mod eval;
pub mod export;
pub mod flags;
pub mod import;
pub mod junctions;
pub mod pipeline;
pub mod plot;
pub mod render;
pub mod scenario;
pub mod sim;
pub mod simplify;
pub mod train;
pub mod training;
pub mod view;
pub mod window;
