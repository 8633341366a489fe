//! SUMO net.xml (being written).
use crate::error::ParseError;
use mapc_graph::{LaneGraph, Source};
pub(crate) fn read<R: std::io::BufRead>(_input: R, _source: Source) -> Result<LaneGraph, ParseError> {
    Err(ParseError::new(0, None, "SUMO not yet"))
}
