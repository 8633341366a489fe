//! What a file mapc wrote is, read from its content rather than its name: a graph, a scenario or a policy is
//! recognised by the format name or keys inside it, so `x.graph`, `x.txt` or a file without an extension reads
//! back as what it is. Map files (OSM, SUMO) are told apart by `mapc-import`; this module only says "one of
//! mapc's own files, and which".

use std::io::Read;
use std::path::Path;

/// One of the files mapc writes for its next stages.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum MapcFile {
    /// A lane graph: JSON with `"format": "mapc-graph"` (any version; the loader checks it).
    Graph,
    /// A scenario: TOML with a `network` and `horizon_steps`.
    Scenario,
    /// A policy (a training checkpoint): JSON with `format_version` and `spec`.
    Policy,
    /// A distribution of merges to train on: TOML with `format = "mapc-merge-distribution"`.
    MergeDistribution,
}

impl MapcFile {
    /// How messages name it.
    pub fn name(self) -> &'static str {
        match self {
            MapcFile::Graph => "a mapc graph",
            MapcFile::Scenario => "a mapc scenario",
            MapcFile::Policy => "a mapc policy",
            MapcFile::MergeDistribution => "a mapc merge distribution",
        }
    }
}

/// How much of a file the sniffers read: the keys they look for come in the first lines of what mapc writes.
pub const HEAD_BYTES: usize = 64 * 1024;

/// Whether `head` (the first bytes of a file) starts a JSON object.
pub fn is_json_object(head: &[u8]) -> bool {
    head.iter()
        .find(|b| !b.is_ascii_whitespace())
        .is_some_and(|&b| b == b'{')
}

/// Which of mapc's own files `head` starts, if any.
pub fn sniff(head: &[u8]) -> Option<MapcFile> {
    let text = String::from_utf8_lossy(head);
    if is_json_object(head) {
        // A graph names its format in its first key; a policy starts with its version and spec.
        if json_key_is(&text, "format", "mapc-graph") {
            return Some(MapcFile::Graph);
        }
        if text.contains("\"format_version\"") && text.contains("\"spec\"") {
            return Some(MapcFile::Policy);
        }
        return None;
    }
    // TOML: a scenario always has these two keys at top level (`[network]` or `[network.simple_merge]`).
    let mut horizon = false;
    let mut network = false;
    for line in text.lines().map(str::trim) {
        if toml_key(line) == Some("format")
            && line
                .split_once('=')
                .is_some_and(|(_, v)| v.trim() == "\"mapc-merge-distribution\"")
        {
            return Some(MapcFile::MergeDistribution);
        }
        horizon |= toml_key(line) == Some("horizon_steps");
        network |= line.starts_with("[network") || toml_key(line) == Some("network");
    }
    (horizon && network).then_some(MapcFile::Scenario)
}

/// The first bytes of a file (up to [`HEAD_BYTES`]).
pub fn read_head(path: &Path) -> std::io::Result<Vec<u8>> {
    let mut head = Vec::with_capacity(4096);
    std::fs::File::open(path)?
        .take(HEAD_BYTES as u64)
        .read_to_end(&mut head)?;
    Ok(head)
}

/// Which of mapc's own files `path` is, if any; `None` also for a directory or a file that cannot be read (the
/// loader that opens it then says why).
pub fn sniff_path(path: &Path) -> Option<MapcFile> {
    if !path.is_file() {
        return None;
    }
    read_head(path).ok().and_then(|h| sniff(&h))
}

/// `"key": "value"` somewhere in `text`, spaces allowed around the colon.
fn json_key_is(text: &str, key: &str, value: &str) -> bool {
    let quoted = format!("\"{key}\"");
    text.match_indices(&quoted).any(|(i, _)| {
        let rest = text[i + quoted.len()..].trim_start();
        rest.strip_prefix(':')
            .map(str::trim_start)
            .is_some_and(|r| r.starts_with(&format!("\"{value}\"")))
    })
}

/// The key of a TOML `key = value` line.
fn toml_key(line: &str) -> Option<&str> {
    let (k, _) = line.split_once('=')?;
    let k = k.trim();
    (!k.is_empty() && k.chars().all(|c| c.is_ascii_alphanumeric() || c == '_')).then_some(k)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn shipped(name: &str) -> Vec<u8> {
        std::fs::read(
            Path::new(env!("CARGO_MANIFEST_DIR"))
                .join("../..")
                .join(name),
        )
        .unwrap()
    }

    #[test]
    fn shipped_files_are_recognised_by_content() {
        assert_eq!(
            sniff(&shipped("scenarios/i696_window.graph.json")),
            Some(MapcFile::Graph)
        );
        assert_eq!(
            sniff(&shipped("scenarios/simple_merge.toml")),
            Some(MapcFile::Scenario)
        );
        assert_eq!(
            sniff(&shipped("scenarios/i696_window.toml")),
            Some(MapcFile::Scenario)
        );
        assert_eq!(
            sniff(&shipped("policies/simple_merge_flow.json")),
            Some(MapcFile::Policy)
        );
        assert_eq!(sniff(&shipped("maps/i696.osm")[..4096]), None);
        assert_eq!(sniff(&shipped("maps/simple_merge.net.xml")), None);
        assert_eq!(sniff(b"{\"format\": \"geojson\"}"), None);
        assert_eq!(
            sniff(b"   {\"format\" :  \"mapc-graph\", \"version\": 9}"),
            Some(MapcFile::Graph)
        );
        assert_eq!(sniff(b"name = \"x\"\n"), None);
        assert_eq!(
            sniff(&shipped("scenarios/merge_mix.toml")),
            Some(MapcFile::MergeDistribution)
        );
    }
}
