//! OSM PBF (being written).
use crate::ImportError;
use crate::error::ParseError;
use crate::osm::{NodePos, OsmWay};
use std::collections::HashMap;
use std::path::Path;

pub(crate) fn read_file(path: &Path, _classes: &[String]) -> Result<(Vec<OsmWay>, HashMap<i64, NodePos>), ImportError> {
    Err(ImportError::unsupported(path, "PBF not yet"))
}
pub(crate) fn read<R: std::io::Read>(
    _open: impl FnMut() -> Result<R, ParseError>,
    path: &Path,
    _classes: &[String],
) -> Result<(Vec<OsmWay>, HashMap<i64, NodePos>), ImportError> {
    Err(ImportError::unsupported(path, "PBF not yet"))
}
