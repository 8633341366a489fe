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
    /// A graph that breaks what mapc's importers guarantee: ids repeated or out of order, a road and its
    /// junctions that do not name each other, a lane numbering with a gap, a connection to a lane or road the graph
    /// lacks, a length, speed or width no road has. `place` is `line N, ` where the element is found in the file;
    /// `problem` names the element first (`road R3: ...`, `connection 12 (...): ...`).
    #[error("{path}: {place}{problem}")]
    Invalid {
        path: PathBuf,
        place: String,
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

/// Whether [`write_atomically`] can write `path`: the path is no directory, and its folder takes files or can be
/// made ([`check_folder_creatable`]). Asked before a long run, so that the run does not end in a refusal that loses
/// it; it leaves nothing behind, so that a command refused after it has written nothing.
pub fn check_writable(path: &Path) -> std::io::Result<()> {
    if path.is_dir() {
        return Err(std::io::Error::new(
            std::io::ErrorKind::IsADirectory,
            "is a directory",
        ));
    }
    check_folder_creatable(folder_of(path))
}

/// Whether folder `dir` takes files, or can be made and would: the nearest of it and the folders above it that
/// exists must be a folder and take a temporary file (made there and removed at once). Nothing is made.
pub fn check_folder_creatable(dir: &Path) -> std::io::Result<()> {
    let mut existing = dir;
    loop {
        match std::fs::metadata(existing) {
            Ok(m) if m.is_dir() => break,
            Ok(_) => {
                return Err(std::io::Error::new(
                    std::io::ErrorKind::NotADirectory,
                    format!("{} is not a folder", existing.display()),
                ));
            }
            Err(e) if e.kind() == std::io::ErrorKind::NotFound => match existing.parent() {
                Some(up) => {
                    existing = if up.as_os_str().is_empty() {
                        Path::new(".")
                    } else {
                        up
                    }
                }
                None => return Err(e),
            },
            Err(e) => return Err(e),
        }
    }
    let probe = existing.join(temporary_name("mapc-write-check", std::process::id()));
    std::fs::OpenOptions::new()
        .write(true)
        .create_new(true)
        .open(&probe)?;
    std::fs::remove_file(&probe)
}

/// The folder `path` is written in (`.` for a bare file name).
fn folder_of(path: &Path) -> &Path {
    path.parent()
        .filter(|d| !d.as_os_str().is_empty())
        .unwrap_or(Path::new("."))
}

/// [`write_atomically`] for output written piece by piece (traces): `body` writes into a buffered temporary file
/// beside `path`, which is renamed into place only when `body` and the flush succeed; on any error it is removed,
/// so neither a half file under the final name nor a stray temporary is left.
pub fn write_atomically_with(
    path: &Path,
    body: impl FnOnce(&mut std::io::BufWriter<std::fs::File>) -> std::io::Result<()>,
) -> std::io::Result<()> {
    let tmp = written_temporary(path, body)?;
    std::fs::rename(&tmp, path).inspect_err(|_| {
        let _ = std::fs::remove_file(&tmp);
    })
}

/// Several files that belong together (a scenario and its graph) written all or none: every one is written to
/// its temporary first, and only when all are complete are they renamed into place. A path that is a directory
/// is refused before anything is written. The error names the path that failed.
pub fn write_all_atomically(files: &[(&Path, &[u8])]) -> Result<(), (PathBuf, std::io::Error)> {
    for (path, _) in files {
        if path.is_dir() {
            return Err((
                path.to_path_buf(),
                std::io::Error::new(std::io::ErrorKind::IsADirectory, "is a directory"),
            ));
        }
    }
    let mut temporaries = Vec::new();
    let remove_all = |temporaries: &[PathBuf]| {
        for t in temporaries {
            let _ = std::fs::remove_file(t);
        }
    };
    for (path, bytes) in files {
        match written_temporary(path, |w| w.write_all(bytes)) {
            Ok(tmp) => temporaries.push(tmp),
            Err(e) => {
                remove_all(&temporaries);
                return Err((path.to_path_buf(), e));
            }
        }
    }
    for (k, ((path, _), tmp)) in files.iter().zip(&temporaries).enumerate() {
        if let Err(e) = std::fs::rename(tmp, path) {
            remove_all(&temporaries[k..]);
            return Err((path.to_path_buf(), e));
        }
    }
    Ok(())
}

/// The temporary beside `path` that `body` wrote and that was flushed to disk, ready to be renamed; on any error
/// it is removed. Temporaries of earlier writes to `path` whose writer was killed are removed first.
fn written_temporary(
    path: &Path,
    body: impl FnOnce(&mut std::io::BufWriter<std::fs::File>) -> std::io::Result<()>,
) -> std::io::Result<PathBuf> {
    let dir = folder_of(path);
    std::fs::create_dir_all(dir)?;
    let file_name = path
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_default();
    remove_stale_temporaries(dir, &file_name);
    let tmp = dir.join(temporary_name(&file_name, std::process::id()));
    let result = (|| {
        let mut w = std::io::BufWriter::new(std::fs::File::create(&tmp)?);
        body(&mut w)?;
        let f = w.into_inner().map_err(|e| e.into_error())?;
        f.sync_all()
    })();
    match result {
        Ok(()) => Ok(tmp),
        Err(e) => {
            let _ = std::fs::remove_file(&tmp);
            Err(e)
        }
    }
}

/// The hidden temporary a process writes `file_name` through: `.NAME.PID.tmp`.
fn temporary_name(file_name: &str, pid: u32) -> String {
    format!(".{file_name}.{pid}.tmp")
}

/// A temporary older than this is stale whatever its writer (its process id may have been reused).
const STALE_TEMPORARY_AGE: std::time::Duration = std::time::Duration::from_secs(24 * 3600);

/// Remove the temporaries of `file_name` in `dir` that a killed writer left: those of this naming whose process
/// no longer runs, or older than [`STALE_TEMPORARY_AGE`]. A temporary another running process is writing is kept.
fn remove_stale_temporaries(dir: &Path, file_name: &str) {
    let Ok(entries) = std::fs::read_dir(dir) else {
        return;
    };
    let prefix = format!(".{file_name}.");
    for entry in entries.flatten() {
        let name = entry.file_name();
        let Some(pid) = name
            .to_str()
            .and_then(|n| n.strip_prefix(&prefix))
            .and_then(|rest| rest.strip_suffix(".tmp"))
            .and_then(|pid| pid.parse::<u32>().ok())
        else {
            continue;
        };
        let old = entry
            .metadata()
            .and_then(|m| m.modified())
            .ok()
            .and_then(|t| t.elapsed().ok())
            .is_some_and(|age| age > STALE_TEMPORARY_AGE);
        if pid != std::process::id() && (old || !process_runs(pid)) {
            let _ = std::fs::remove_file(entry.path());
        }
    }
}

/// Whether process `pid` runs; where that cannot be told (no `/proc`), it is taken to run, and only the age of
/// its temporaries makes them stale.
fn process_runs(pid: u32) -> bool {
    let proc = Path::new("/proc");
    !proc.join("self").exists() || proc.join(pid.to_string()).exists()
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
        let text = crate::input::read_to_string(path).map_err(|source| GraphFileError::Io {
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
        match graph_problem(&graph, text) {
            Some((line, problem)) => Err(GraphFileError::Invalid {
                path: path.to_path_buf(),
                place: line.map(|l| format!("line {l}, ")).unwrap_or_default(),
                problem,
            }),
            None => Ok(graph),
        }
    }
}

/// The first problem of a parsed graph, with the line of `text` where its element starts when it is found: ids
/// repeated or out of order first (lookups by id rely on them), then the lanes and connections, then every other
/// invariant ([`LaneGraph::invariant_violations`]).
fn graph_problem(g: &LaneGraph, text: &str) -> Option<(Option<usize>, String)> {
    let line_at = |byte: usize| text[..byte.min(text.len())].matches('\n').count() + 1;
    let line_of_id = |id: &str| text.find(&format!("\"id\": \"{id}\"")).map(line_at);
    let violations = g.invariant_violations();
    let first_violation = || {
        let v = violations.first()?;
        // every violation names its element first: `road R3 ...`, `junction J2 ...`
        let id = v.split_whitespace().nth(1).unwrap_or("");
        Some((line_of_id(id), v.clone()))
    };
    if violations
        .first()
        .is_some_and(|v| v.contains("appears twice") || v.contains("sorted by id"))
    {
        return first_violation();
    }
    for r in &g.roads {
        let why = if r.lanes.is_empty() {
            Some("has no lanes".to_string())
        } else {
            crate::validate::lane_numbering_problem(&r.lanes)
        };
        if let Some(why) = why {
            let line = line_of_id(&r.id.to_string());
            return Some((line, format!("road {}: the road {why}", r.id)));
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
                Some(start.map_or(1, line_at)),
                format!(
                    "connection {n} ({} lane {} -> {} lane {} at {}): {message}",
                    c.from_road, c.from_lane, c.to_road, c.to_lane, c.junction
                ),
            ));
        }
    }
    first_violation()
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

    #[test]
    fn a_killed_writers_temporary_is_removed_by_the_next_write_and_a_live_ones_kept() {
        let dir = std::env::temp_dir().join(format!("mapc-io-stale-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let path = dir.join("big.graph.json");
        // no process has pid u32::MAX - 1 (Linux caps pids far lower); pid 1 always runs
        let dead = dir.join(temporary_name("big.graph.json", u32::MAX - 1));
        let live = dir.join(temporary_name("big.graph.json", 1));
        let other = dir.join(temporary_name("other.json", u32::MAX - 1));
        for t in [&dead, &live, &other] {
            std::fs::write(t, b"half").unwrap();
        }
        write_atomically(&path, b"{}").unwrap();
        assert!(!dead.exists(), "a dead writer's temporary is left");
        assert_eq!(live.exists(), Path::new("/proc/self").exists());
        assert!(
            other.exists(),
            "another file's temporary is not this write's to remove"
        );
        std::fs::remove_dir_all(&dir).unwrap();
    }

    #[test]
    fn files_written_together_are_all_or_none() {
        let dir = std::env::temp_dir().join(format!("mapc-io-together-{}", std::process::id()));
        std::fs::create_dir_all(dir.join("taken")).unwrap();
        let graph = dir.join("w.graph.json");
        let (failed, _) = write_all_atomically(&[
            (graph.as_path(), b"{}".as_slice()),
            (dir.join("taken").as_path(), b"x".as_slice()),
        ])
        .unwrap_err();
        assert_eq!(failed, dir.join("taken"));
        let mut names: Vec<_> = std::fs::read_dir(&dir)
            .unwrap()
            .map(|e| e.unwrap().file_name())
            .collect();
        names.sort();
        assert_eq!(names, vec![std::ffi::OsString::from("taken")]);
        let toml = dir.join("w.toml");
        write_all_atomically(&[(graph.as_path(), b"{}"), (toml.as_path(), b"a = 1")]).unwrap();
        assert_eq!(std::fs::read_to_string(&toml).unwrap(), "a = 1");
        std::fs::remove_dir_all(&dir).unwrap();
    }

    /// The tiny merge's JSON with one edit, loaded: the error's text.
    fn load_edited(edit: impl Fn(&mut serde_json::Value)) -> String {
        let mut v = serde_json::to_value(crate::tests::tiny_merge()).unwrap();
        edit(&mut v);
        let text = serde_json::to_string_pretty(&v).unwrap();
        LaneGraph::from_json(&text, Path::new("bad.graph.json"))
            .unwrap_err()
            .to_string()
    }

    #[test]
    fn a_graph_that_breaks_what_the_importers_guarantee_is_refused_naming_the_element() {
        use serde_json::json;
        type Break = Box<dyn Fn(&mut serde_json::Value)>;
        let cases: [(&str, Break); 6] = [
            (
                "road R2 names missing junction J9",
                Box::new(|v| v["roads"][2]["to"] = json!("J9")),
            ),
            (
                "junction J3 lists missing road R7",
                Box::new(|v| v["junctions"][3]["incoming"] = json!(["R2", "R7"])),
            ),
            (
                "road R1 has length_m -1",
                Box::new(|v| v["roads"][1]["length_m"] = json!(-1.0)),
            ),
            (
                "road R0 lane 0 speed_mps 1e-300 is outside [0.1, 1000] m/s",
                Box::new(|v| v["roads"][0]["lanes"][0]["speed_mps"] = json!(1e-300)),
            ),
            (
                "road R1 appears twice",
                Box::new(|v| v["roads"][2]["id"] = json!("R1")),
            ),
            (
                "connection R0 -> R2 at J2: via_length_m -1 is outside [0, 1e6] m",
                Box::new(|v| v["connections"][0]["via_length_m"] = json!(-1.0)),
            ),
        ];
        for (expected, edit) in cases {
            let err = load_edited(edit);
            assert!(err.starts_with("bad.graph.json: "), "{err}");
            assert!(err.contains(expected), "expected `{expected}` in: {err}");
        }
        let err = load_edited(|v| v["connections"][0]["via_length_m"] = json!(null));
        assert!(
            err.starts_with("bad.graph.json: line ") && err.contains("null"),
            "{err}"
        );
        // the line of the road is named
        let err = load_edited(|v| v["roads"][1]["length_m"] = json!(-1.0));
        assert!(err.starts_with("bad.graph.json: line "), "{err}");
    }
}
