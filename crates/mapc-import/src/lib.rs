//! # mapc-import: OSM XML, OSM PBF and SUMO net.xml into a lane graph
//!
//! Glossary:
//! - **kept way**: an OSM way whose `highway` class is one of [`ImportOptions::highways`]; everything else is
//!   dropped while streaming.
//! - **piece**: the stretch of a kept way between two junction nodes; a way is split at every node another kept way
//!   (or the same way again) passes through. Each piece becomes one road per direction of travel.
//! - **clipped way**: a way naming nodes the file lacks (an extract cut at a bounding box); it is cut there and the
//!   `way_clipped_at_missing_node` warning counted.
//! - **class defaults**: lanes, speed limit and priority assumed for a class when tags are missing
//!   ([`osm::class_defaults`]); every use is a counted warning.
//! - **internal lane**: SUMO's lane inside a junction; folded into the connection that uses it
//!   (`Connection::via_length_m`, `via_speed_mps`), never a road.
//! - **major / minor**: right of way. OSM: the higher class, then more lanes, then the straighter road in is major.
//!   SUMO: the connection's state (`M`/`m`) or, without one, the junction's request table. [`MajorRoad`] overrides.
//! - **duplicate element**: a node or kept way whose id appears twice. The same element again is a counted
//!   warning (`duplicate_node`, `duplicate_way`); another one under the same id is an error naming the id, since
//!   either choice would silently change roads.
//! - **dropped way**: a kept way that cannot be driven as a line (`area=yes`, `oneway=reversible|alternating`);
//!   counted by kind.
//!
//! Entry points: [`import_path`] (chosen by file name, then by content), [`import_bytes`] (in memory) and
//! [`load_any`] (a graph mapc wrote, recognised by its content whatever its name, or any map). Ids are
//! deterministic: junctions by OSM node id or SUMO file order, roads by (way id, piece, forward first) or SUMO file
//! order.

// `!(x > 0.0)` and the like reject NaN on purpose; `partial_cmp` would hide that.
#![allow(clippy::neg_cmp_op_on_partial_ord)]

mod error;
pub mod gz;
pub mod osm;
mod osm_pbf;
mod osm_xml;
mod summary;
mod sumo;
mod sumo_xml;
mod xml;

pub use error::ImportError;
pub use summary::Summary;
pub use sumo_xml::{SumoElement, read_sumo_xml, sumo_bool};

use mapc_graph::{LaneGraph, MapcFile, RightOfWay, Source, SourceFormat, filekind};
use std::io::BufReader;
use std::path::Path;

use error::{Located, ParseError};

/// What to import and how.
#[derive(Clone, Debug)]
pub struct ImportOptions {
    /// OSM `highway` classes kept.
    pub highways: Vec<String>,
    /// Right-of-way overrides applied after import, whatever the format.
    pub major_roads: Vec<MajorRoad>,
}

impl Default for ImportOptions {
    fn default() -> Self {
        ImportOptions {
            highways: DEFAULT_HIGHWAYS.map(String::from).to_vec(),
            major_roads: Vec::new(),
        }
    }
}

/// The OSM classes kept unless `--highways` says otherwise.
pub const DEFAULT_HIGHWAYS: [&str; 5] = [
    "motorway",
    "motorway_link",
    "trunk",
    "trunk_link",
    "primary",
];

/// "At junction `junction`, the roads named by `road` are major and every other road in yields". Both are
/// lookups as `mapc_graph` understands them: `osm:61862553`, `J4`, a SUMO id; `osm-way:124433709`, `R7`, an edge id.
#[derive(Clone, Debug, PartialEq)]
pub struct MajorRoad {
    pub junction: String,
    pub road: String,
}

impl std::str::FromStr for MajorRoad {
    type Err = String;
    /// `JUNCTION=ROAD`, e.g. `osm:61862553=osm-way:124433709`.
    fn from_str(s: &str) -> Result<Self, String> {
        let (j, r) = s.split_once('=').ok_or_else(|| {
            format!("`{s}`: expected JUNCTION=ROAD, e.g. osm:61862553=osm-way:124433709")
        })?;
        if j.trim().is_empty() || r.trim().is_empty() {
            return Err(format!("`{s}`: expected JUNCTION=ROAD"));
        }
        Ok(MajorRoad {
            junction: j.trim().to_string(),
            road: r.trim().to_string(),
        })
    }
}

/// The kinds of map file mapc reads.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum MapFormat {
    OsmXml,
    OsmPbf,
    SumoNet,
}

impl MapFormat {
    /// By file name: `.osm.pbf`/`.pbf`, `.net.xml`, `.osm`/`.osm.xml`. `None` when the name does not tell.
    pub fn from_name(path: &Path) -> Option<MapFormat> {
        let name = path.file_name()?.to_string_lossy().to_ascii_lowercase();
        if name.ends_with(".pbf") {
            Some(MapFormat::OsmPbf)
        } else if name.ends_with(".net.xml") {
            Some(MapFormat::SumoNet)
        } else if name.ends_with(".osm") || name.ends_with(".osm.xml") {
            Some(MapFormat::OsmXml)
        } else {
            None
        }
    }

    /// By the first bytes ([`filekind::sniff_map`]).
    pub fn sniff(head: &[u8]) -> Option<MapFormat> {
        Some(match filekind::sniff_map(head)? {
            filekind::MapKind::OsmXml => MapFormat::OsmXml,
            filekind::MapKind::OsmPbf => MapFormat::OsmPbf,
            filekind::MapKind::SumoNet => MapFormat::SumoNet,
        })
    }

    fn source_format(self) -> SourceFormat {
        match self {
            MapFormat::OsmXml => SourceFormat::OsmXml,
            MapFormat::OsmPbf => SourceFormat::OsmPbf,
            MapFormat::SumoNet => SourceFormat::SumoNet,
        }
    }
}

/// The format of a map file: by its name, else by its first bytes. A file mapc wrote for a later stage (a graph,
/// a scenario, a policy) is recognised by its content and refused with what it is, whatever its name.
pub fn detect_format(path: &Path) -> Result<MapFormat, ImportError> {
    detect(path).map(|(format, _)| format)
}

/// [`detect_format`], and whether the file is gzip-compressed ([`gz`]).
fn detect(path: &Path) -> Result<(MapFormat, bool), ImportError> {
    let meta = std::fs::metadata(path).map_err(|e| ImportError::io(path, e))?;
    if meta.is_dir() {
        return Err(ImportError::unsupported(
            path,
            "is a directory, not a map file",
        ));
    }
    // a device or a FIFO has no length: read it (up to the input cap) to tell what it is
    if meta.is_file() && meta.len() == 0 {
        return Err(ImportError::Empty {
            path: path.to_path_buf(),
        });
    }
    let (head, compressed) = gz::read_head(path).map_err(|e| ImportError::io(path, e))?;
    if let Some(kind) = filekind::sniff(&head) {
        return Err(ImportError::unsupported(
            path,
            format!(
                "is {}, not a map to import{}",
                kind.name(),
                if kind == MapcFile::Graph {
                    " (every command that takes a map reads it as it is)"
                } else {
                    ""
                }
            ),
        ));
    }
    if let Some(f) = MapFormat::from_name(&gz::inner_name(path)) {
        return Ok((f, compressed));
    }
    let format = MapFormat::sniff(&head).ok_or_else(|| {
        ImportError::unsupported(
            path,
            "not a map mapc reads (expected OSM XML, OSM PBF or a SUMO net.xml, or a graph mapc wrote)",
        )
    })?;
    Ok((format, compressed))
}

/// Read any supported map, chosen by its file name (`.osm`, `.osm.pbf`, `.net.xml`) or, failing that, its content.
pub fn import_path(path: &Path, options: &ImportOptions) -> Result<LaneGraph, ImportError> {
    let (format, compressed) = detect(path)?;
    if compressed {
        // a compressed map is read whole, decompressed (its messages' lines are the decompressed text's)
        let bytes = gz::read_input(path).map_err(|e| ImportError::io(path, e))?;
        return import_bytes(&bytes, format, &path.display().to_string(), options);
    }
    let source = Source {
        file: path.display().to_string(),
        format: format.source_format(),
    };
    let located = Located::File(path);
    let open = || -> Result<BufReader<mapc_graph::input::Capped<std::fs::File>>, ParseError> {
        mapc_graph::input::open(path)
            .map(|f| BufReader::with_capacity(1 << 16, f))
            .map_err(|e| ParseError::new(0, None, format!("cannot open: {e}")))
    };
    let graph = match format {
        MapFormat::OsmXml => {
            let data = osm_xml::read(open, &options.highways).map_err(|e| located.error(e))?;
            osm::build_graph(data, source, options)
                .map_err(|m| ImportError::unsupported(path, m))?
        }
        MapFormat::OsmPbf => {
            let bytes = mapc_graph::input::read(path).map_err(|e| ImportError::io(path, e))?;
            let data =
                osm_pbf::read(&bytes, &options.highways).map_err(|e| binary_error(path, e))?;
            osm::build_graph(data, source, options)
                .map_err(|m| ImportError::unsupported(path, m))?
        }
        MapFormat::SumoNet => {
            let input = open().map_err(|e| located.error(e))?;
            sumo::read(input, source).map_err(|e| located.error(e))?
        }
    };
    finish(graph, path, options)
}

/// Import a map held in memory; `name` stands for the file in messages and in the graph's source.
pub fn import_bytes(
    bytes: &[u8],
    format: MapFormat,
    name: &str,
    options: &ImportOptions,
) -> Result<LaneGraph, ImportError> {
    let path = Path::new(name);
    if bytes.is_empty() {
        return Err(ImportError::Empty {
            path: path.to_path_buf(),
        });
    }
    let source = Source {
        file: name.to_string(),
        format: format.source_format(),
    };
    let located = Located::Bytes(path, bytes);
    let graph = match format {
        MapFormat::OsmXml => {
            let data =
                osm_xml::read(|| Ok(bytes), &options.highways).map_err(|e| located.error(e))?;
            osm::build_graph(data, source, options)
                .map_err(|m| ImportError::unsupported(path, m))?
        }
        MapFormat::OsmPbf => {
            let data =
                osm_pbf::read(bytes, &options.highways).map_err(|e| binary_error(path, e))?;
            osm::build_graph(data, source, options)
                .map_err(|m| ImportError::unsupported(path, m))?
        }
        MapFormat::SumoNet => sumo::read(bytes, source).map_err(|e| located.error(e))?,
    };
    finish(graph, path, options)
}

/// An error in a binary file: the place is a byte offset and the blob, not a line.
fn binary_error(path: &Path, e: ParseError) -> ImportError {
    let mut place = format!("byte {}", e.byte);
    if let Some(el) = e.element {
        place.push_str(&format!(" ({el})"));
    }
    ImportError::At {
        path: path.to_path_buf(),
        place,
        message: e.message,
    }
}

/// Overrides, then a last invariant check (a failure here is a bug in the importer, reported rather than panicking).
fn finish(
    mut graph: LaneGraph,
    path: &Path,
    options: &ImportOptions,
) -> Result<LaneGraph, ImportError> {
    for m in &options.major_roads {
        apply_major_road(&mut graph, m).map_err(|msg| ImportError::unsupported(path, msg))?;
    }
    let problems = graph.invariant_violations();
    if !problems.is_empty() {
        return Err(ImportError::unsupported(
            path,
            format!(
                "the imported graph is inconsistent: {}",
                problems.join("; ")
            ),
        ));
    }
    Ok(graph)
}

/// Make the roads `m.road` names major at junction `m.junction`, and every other road in there minor.
pub fn apply_major_road(graph: &mut LaneGraph, m: &MajorRoad) -> Result<(), String> {
    let j = graph
        .find_junction(&m.junction)
        .map_err(|e| format!("--major {}={}: {e}", m.junction, m.road))?;
    let roads = graph
        .find_roads(&m.road)
        .map_err(|e| format!("--major {}={}: {e}", m.junction, m.road))?;
    let incoming = &graph.junction(j).expect("found above").incoming;
    let major: Vec<_> = roads.into_iter().filter(|r| incoming.contains(r)).collect();
    if major.is_empty() {
        return Err(format!(
            "--major {}={}: no road named `{}` enters junction {j}",
            m.junction, m.road, m.road
        ));
    }
    for c in graph.connections.iter_mut().filter(|c| c.junction == j) {
        let row = if major.contains(&c.from_road) {
            RightOfWay::Major
        } else {
            RightOfWay::Minor
        };
        if c.right_of_way != row {
            c.right_of_way = row;
            c.right_of_way_overridden = true;
        }
    }
    Ok(())
}

/// A graph mapc wrote (recognised by its content, whatever its name) or any map file, imported with default
/// options.
pub fn load_any(path: &Path) -> Result<LaneGraph, ImportError> {
    load_any_with(path, &ImportOptions::default())
}

/// [`load_any`] with import options for maps (ignored for graph files). Any JSON object goes to the graph
/// loader, which names the format it found when it is not a graph.
pub fn load_any_with(path: &Path, options: &ImportOptions) -> Result<LaneGraph, ImportError> {
    if path.is_file() {
        let head = filekind::read_head(path).map_err(|e| ImportError::io(path, e))?;
        match filekind::sniff(&head) {
            Some(MapcFile::Graph) => return Ok(LaneGraph::load(path)?),
            Some(other) => {
                return Err(ImportError::unsupported(
                    path,
                    format!("is {}, not a map or a graph", other.name()),
                ));
            }
            None if filekind::is_json_object(&head) => return Ok(LaneGraph::load(path)?),
            None => {}
        }
    }
    import_path(path, options)
}
