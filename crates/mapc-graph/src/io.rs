//! Reading and writing graph files: JSON with a format name and version checked on load, written atomically.

use crate::model::{FORMAT_NAME, FORMAT_VERSION, LaneGraph};
use std::io::Write;
use std::path::{Path, PathBuf};

#[derive(Debug, thiserror::Error)]
pub enum GraphFileError {
    #[error("{path}: {source}")]
    Io {
        path: PathBuf,
        source: std::io::Error,
    },
    #[error("{path}: line {line}, column {column}: {message}")]
    Parse {
        path: PathBuf,
        line: usize,
        column: usize,
        message: String,
    },
    #[error("{path}: not a mapc graph file ({found}, expected `{FORMAT_NAME}`)")]
    NotAGraph { path: PathBuf, found: String },
    /// A road's lanes or a lane connection that cannot be: a gap in the lane numbering, a connection to a lane
    /// or road the graph lacks.
    /// `problem` names the element first (`road R3: ...`, `connection 12 (...): ...`).
    #[error("{path}: line {line}, {problem}")]
    Lanes {
        path: PathBuf,
        line: usize,
        problem: String,
    },
    #[error(
        "{path}: graph file version {found}, but this mapc reads version {FORMAT_VERSION}; re-run `mapc import` on the original map"
    )]
    Version { path: PathBuf, found: u32 },
}

/// Write `bytes` to `path` so that a reader never sees half a file: a temporary file beside it, then a rename.
pub fn write_atomically(path: &Path, bytes: &[u8]) -> std::io::Result<()> {
    write_atomically_with(path, |w| w.write_all(bytes))
}

/// [`write_atomically`] for output written piece by piece (traces): `body` writes into a buffered temporary file
/// beside `path`, which is renamed into place only when `body` and the flush succeed; on any error it is removed,
/// so neither a half file under the final name nor a stray temporary is left.
pub fn write_atomically_with(
    path: &Path,
    body: impl FnOnce(&mut std::io::BufWriter<std::fs::File>) -> std::io::Result<()>,
) -> std::io::Result<()> {
    let dir = path
        .parent()
        .filter(|d| !d.as_os_str().is_empty())
        .unwrap_or(Path::new("."));
    std::fs::create_dir_all(dir)?;
    let file_name = path
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_default();
    let tmp = dir.join(format!(".{file_name}.{}.tmp", std::process::id()));
    let result = (|| {
        let mut w = std::io::BufWriter::new(std::fs::File::create(&tmp)?);
        body(&mut w)?;
        let f = w.into_inner().map_err(|e| e.into_error())?;
        f.sync_all()?;
        std::fs::rename(&tmp, path)
    })();
    if result.is_err() {
        let _ = std::fs::remove_file(&tmp);
    }
    result
}

impl LaneGraph {
    pub fn to_json(&self) -> String {
        serde_json::to_string_pretty(self).expect("a lane graph always serialises")
    }

    pub fn save(&self, path: &Path) -> Result<(), GraphFileError> {
        write_atomically(path, self.to_json().as_bytes()).map_err(|source| GraphFileError::Io {
            path: path.to_path_buf(),
            source,
        })
    }

    pub fn load(path: &Path) -> Result<LaneGraph, GraphFileError> {
        let text = std::fs::read_to_string(path).map_err(|source| GraphFileError::Io {
            path: path.to_path_buf(),
            source,
        })?;
        Self::from_json(&text, path)
    }

    /// Parse graph JSON; `path` only names the source in errors. The header is checked before the body so that a
    /// file of another version says so instead of failing on some field.
    pub fn from_json(text: &str, path: &Path) -> Result<LaneGraph, GraphFileError> {
        #[derive(serde::Deserialize)]
        struct Header {
            format: Option<String>,
            version: Option<u32>,
        }
        let parse_err = |e: serde_json::Error| GraphFileError::Parse {
            path: path.to_path_buf(),
            line: e.line(),
            column: e.column(),
            message: e.to_string(),
        };
        let header: Header = serde_json::from_str(text).map_err(parse_err)?;
        let format = header.format.unwrap_or_default();
        if format != FORMAT_NAME {
            // Say what the file is when it is another of mapc's own files.
            let found = match crate::filekind::sniff(text.as_bytes()) {
                Some(kind) => format!("it is {}", kind.name()),
                None if format.is_empty() => "it has no `format` field".to_string(),
                None => format!("format is `{format}`"),
            };
            return Err(GraphFileError::NotAGraph {
                path: path.to_path_buf(),
                found,
            });
        }
        let version = header.version.unwrap_or(0);
        if version != FORMAT_VERSION {
            return Err(GraphFileError::Version {
                path: path.to_path_buf(),
                found: version,
            });
        }
        let graph: LaneGraph = serde_json::from_str(text).map_err(parse_err)?;
        match lane_problem(&graph, text) {
            Some((line, element, message)) => Err(GraphFileError::Lanes {
                path: path.to_path_buf(),
                line,
                problem: format!("{element}: {message}"),
            }),
            None => Ok(graph),
        }
    }
}

/// The first lane problem of a parsed graph, with the line of `text` where its element starts: a road whose lanes
/// are not numbered 0, 1, 2, ..., a connection naming a road or lane the graph lacks.
fn lane_problem(g: &LaneGraph, text: &str) -> Option<(usize, String, String)> {
    let line_at = |byte: usize| text[..byte.min(text.len())].matches('\n').count() + 1;
    for r in &g.roads {
        let why = if r.lanes.is_empty() {
            Some("has no lanes".to_string())
        } else {
            crate::validate::lane_numbering_problem(&r.lanes)
        };
        if let Some(why) = why {
            let needle = format!("\"id\": \"{}\"", r.id);
            let line = text.find(&needle).map_or(1, line_at);
            return Some((line, format!("road {}", r.id), format!("the road {why}")));
        }
    }
    // The n-th connection object is the n-th `"from_road"` after the `"connections"` key.
    let connections_at = text.find("\"connections\"").unwrap_or(0);
    let mut starts = text[connections_at..]
        .match_indices("\"from_road\"")
        .map(|(i, _)| connections_at + i);
    for (n, c) in g.connections.iter().enumerate() {
        let start = starts.next();
        let lanes_of = |id| g.road(id).map(|r| r.lanes.len());
        let problem = match (lanes_of(c.from_road), lanes_of(c.to_road)) {
            (None, _) => Some(format!("names road {}, which the graph lacks", c.from_road)),
            (_, None) => Some(format!("names road {}, which the graph lacks", c.to_road)),
            (Some(n_from), _) if c.from_lane as usize >= n_from => Some(format!(
                "from_lane {} names a missing lane: road {} has {n_from} lanes (0..{})",
                c.from_lane,
                c.from_road,
                n_from.saturating_sub(1)
            )),
            (_, Some(n_to)) if c.to_lane as usize >= n_to => Some(format!(
                "to_lane {} names a missing lane: road {} has {n_to} lanes (0..{})",
                c.to_lane,
                c.to_road,
                n_to.saturating_sub(1)
            )),
            _ => None,
        };
        if let Some(message) = problem {
            return Some((
                start.map_or(1, line_at),
                format!(
                    "connection {n} ({} lane {} -> {} lane {} at {})",
                    c.from_road, c.from_lane, c.to_road, c.to_lane, c.junction
                ),
                message,
            ));
        }
    }
    None
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_failed_streamed_write_leaves_nothing_and_a_good_one_replaces_the_file() {
        let dir = std::env::temp_dir().join(format!("mapc-io-test-{}", std::process::id()));
        let path = dir.join("trace.csv");
        write_atomically(&path, b"old\n").unwrap();
        let err = write_atomically_with(&path, |w| {
            w.write_all(b"half a tr")?;
            Err(std::io::Error::other("interrupted"))
        })
        .unwrap_err();
        assert_eq!(err.to_string(), "interrupted");
        assert_eq!(std::fs::read_to_string(&path).unwrap(), "old\n");
        let names: Vec<_> = std::fs::read_dir(&dir)
            .unwrap()
            .map(|e| e.unwrap().file_name())
            .collect();
        assert_eq!(names, vec![std::ffi::OsString::from("trace.csv")]);
        write_atomically_with(&path, |w| w.write_all(b"a,b\n1,2\n")).unwrap();
        assert_eq!(std::fs::read_to_string(&path).unwrap(), "a,b\n1,2\n");
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
