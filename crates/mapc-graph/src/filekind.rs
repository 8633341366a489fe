//! What a file mapc wrote is, read from its content rather than its name: a graph, a scenario or a policy is
//! recognised by the format name or keys inside it, so `x.graph`, `x.txt` or a file without an extension reads
//! back as what it is. Maps (OSM XML, OSM PBF, SUMO net.xml) are told by their first bytes too ([`sniff_map`]), so
//! a map given where a scenario or a policy is expected is named for what it is, with the commands that make one.

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

/// A map, as a person gives it to mapc (what `mapc-import` reads).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum MapKind {
    OsmXml,
    OsmPbf,
    SumoNet,
}

impl MapKind {
    /// How messages name it.
    pub fn name(self) -> &'static str {
        match self {
            MapKind::OsmXml => "an OSM XML map",
            MapKind::OsmPbf => "an OSM PBF map",
            MapKind::SumoNet => "a SUMO network (net.xml)",
        }
    }
}

/// Which map `head` starts, by content alone: a PBF starts with a length and `OSMHeader`; XML by its root element
/// (`<osm>`, `<net>`), found past the declaration and comments (netconvert's header comment names `<osm-files>`,
/// so a mere "contains `<osm`" would misread a SUMO net).
pub fn sniff_map(head: &[u8]) -> Option<MapKind> {
    if head.len() >= 13 && &head[4..7] == b"\x0a\x09O" && head[6..].starts_with(b"OSMHeader") {
        return Some(MapKind::OsmPbf);
    }
    match xml_root(head)? {
        "osm" => Some(MapKind::OsmXml),
        "net" => Some(MapKind::SumoNet),
        _ => None,
    }
}

/// What to say of the map at `path` given where `wanted` (a scenario or a policy) is expected: what it is, and
/// the commands that make a scenario of it.
pub fn map_given_for(kind: MapKind, path: &Path, wanted: MapcFile) -> String {
    let map = path.display();
    let scenario = format!(
        "`mapc window {map} --junction J -o scenario.toml` makes a scenario of it around merge J (`mapc junctions \
         {map} --kind merge` lists them; `mapc simplify {map}` shows the corridor first), and `mapc pipeline {map}` \
         does the whole job"
    );
    match wanted {
        MapcFile::Policy => format!(
            "is {}, not a policy: policies come from `mapc train --scenario SCENARIO`; {scenario}",
            kind.name()
        ),
        _ => format!(
            "is {}, not {}: {scenario}",
            kind.name(),
            wanted.name().replace("a mapc ", "a ")
        ),
    }
}

/// The name of the root element of the XML that `head` starts, skipping the declaration, comments, processing
/// instructions and a doctype; `None` when `head` is not XML or ends before the root.
fn xml_root(head: &[u8]) -> Option<&str> {
    let text = std::str::from_utf8(head).unwrap_or_else(|e| {
        std::str::from_utf8(&head[..e.valid_up_to()]).expect("valid up to here")
    });
    let mut rest = text.trim_start_matches('\u{feff}');
    loop {
        rest = rest.trim_start();
        if let Some(after) = rest.strip_prefix("<!--") {
            rest = &after[after.find("-->")? + 3..];
        } else if rest.starts_with("<?") || rest.starts_with("<!") {
            rest = &rest[rest.find('>')? + 1..];
        } else if let Some(after) = rest.strip_prefix('<') {
            let end = after
                .find(|c: char| c.is_whitespace() || c == '>' || c == '/')
                .unwrap_or(after.len());
            return (end > 0).then(|| &after[..end]);
        } else {
            return None;
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

    #[test]
    fn shipped_maps_are_recognised_by_content() {
        assert_eq!(
            sniff_map(&shipped("maps/i696.osm")[..4096]),
            Some(MapKind::OsmXml)
        );
        assert_eq!(
            sniff_map(&shipped("maps/simple_merge.net.xml")),
            Some(MapKind::SumoNet)
        );
        assert_eq!(
            sniff_map(&shipped("maps/i696.osm.pbf")[..4096]),
            Some(MapKind::OsmPbf)
        );
        for other in [
            "scenarios/simple_merge.toml",
            "scenarios/i696_window.graph.json",
        ] {
            assert_eq!(sniff_map(&shipped(other)), None, "{other}");
        }
        let said = map_given_for(
            MapKind::OsmXml,
            Path::new("maps/i696.osm"),
            MapcFile::Scenario,
        );
        assert!(
            said.starts_with("is an OSM XML map, not a scenario: "),
            "{said}"
        );
        assert!(said.contains("`mapc pipeline maps/i696.osm`"), "{said}");
    }
}
