//! Bad input to `mapc import`: one clear message naming the file and the place, exit code 2, never a panic.

mod common;

use common::{fresh_path, mapc_command, root, scratch_dir};
use std::path::{Path, PathBuf};

fn scratch(name: &str, bytes: &[u8]) -> PathBuf {
    let p = scratch_dir("import-errors").join(name);
    std::fs::write(&p, bytes).unwrap();
    p
}

/// Run `mapc import FILE`; expect exit 2 and a message with every one of `expected`.
fn fails_with(file: &Path, expected: &[&str]) -> String {
    command_fails_with("import", file, expected)
}

/// Run `mapc COMMAND FILE -o OUT`; expect exit 2, a message with every one of `expected`, and no OUT.
fn command_fails_with(command: &str, file: &Path, expected: &[&str]) -> String {
    let out_file = fresh_path("import-errors-never").with_extension("graph.json");
    let out = mapc_command()
        .args([
            command,
            file.to_str().unwrap(),
            "-o",
            out_file.to_str().unwrap(),
        ])
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&out.stderr).into_owned();
    assert_eq!(out.status.code(), Some(2), "{}: {stderr}", file.display());
    assert!(!stderr.contains("panicked"), "{stderr}");
    assert_eq!(stderr.trim().lines().count(), 1, "one line: {stderr}");
    assert!(
        stderr.contains(&file.display().to_string()),
        "the message names the file: {stderr}"
    );
    for e in expected {
        assert!(stderr.contains(e), "expected `{e}` in: {stderr}");
    }
    assert!(!out_file.exists(), "nothing is written on failure");
    stderr
}

fn map(name: &str) -> Vec<u8> {
    std::fs::read(root().join("maps").join(name)).unwrap()
}

#[test]
fn missing_and_empty_files() {
    fails_with(&root().join("maps/no_such_map.osm"), &["No such file"]);
    fails_with(&scratch("empty.osm", b""), &["empty"]);
}

#[test]
fn truncated_xml() {
    let osm = map("i696.osm");
    fails_with(
        &scratch("cut.osm", &osm[..osm.len() / 2]),
        &["line ", "truncated"],
    );
    let net = map("simple_merge.net.xml");
    fails_with(&scratch("cut.net.xml", &net[..net.len() - 200]), &["line "]);
    // Cut inside a tag.
    fails_with(
        &scratch(
            "cut_tag.osm",
            b"<?xml version=\"1.0\"?>\n<osm version=\"0.6\">\n  <node id=\"1\" lat=\"4",
        ),
        &["line 3"],
    );
}

#[test]
fn xml_that_is_not_osm() {
    fails_with(
        &scratch("net_in_disguise.osm", &map("simple_merge.net.xml")),
        &["not OSM", "<net>"],
    );
    fails_with(
        &scratch("osm_in_disguise.net.xml", &map("i696.osm")[..4000]),
        &["not a SUMO network"],
    );
    fails_with(
        &scratch("text.osm", b"hello, not xml at all"),
        &["not an XML file"],
    );
}

#[test]
fn coordinate_that_is_not_a_number() {
    let text = String::from_utf8(map("i696.osm")).unwrap();
    let bad = text.replacen("lat=\"42.4869153\"", "lat=\"42.48x9153\"", 1);
    assert_ne!(bad, text);
    let line = text[..text.find("lat=\"42.4869153\"").unwrap()]
        .lines()
        .count();
    fails_with(
        &scratch("badcoord.osm", bad.as_bytes()),
        &[
            &format!("line {line}"),
            "<node id=\"26913188\">",
            "not a number",
        ],
    );
}

#[test]
fn corrupt_and_truncated_pbf() {
    let pbf = map("i696.osm.pbf");
    fails_with(
        &scratch("cut.osm.pbf", &pbf[..pbf.len() * 2 / 3]),
        &["byte ", "blob ", "truncated"],
    );
    let mut flipped = pbf.clone();
    for b in &mut flipped[400..600] {
        *b ^= 0x5a;
    }
    fails_with(&scratch("flipped.osm.pbf", &flipped), &["byte ", "blob "]);
    fails_with(
        &scratch("text.osm.pbf", b"this is not a pbf file at all"),
        &["byte 0", "not an OSM PBF"],
    );
}

#[test]
fn net_whose_connection_names_an_unknown_edge() {
    let text = String::from_utf8(map("simple_merge.net.xml")).unwrap();
    let bad = text.replacen(
        "<connection from=\"left\" to=\"center\"",
        "<connection from=\"left\" to=\"nowhere\"",
        1,
    );
    let line = text[..text
        .find("<connection from=\"left\" to=\"center\"")
        .unwrap()]
        .lines()
        .count();
    fails_with(
        &scratch("unknown_edge.net.xml", bad.as_bytes()),
        &[&format!("line {line}"), "`nowhere`", "edge"],
    );
}

#[test]
fn bad_options_are_errors_too() {
    let out = mapc_command()
        .args([
            "import",
            "maps/i696.osm",
            "--highways",
            "footway_of_gold",
            "-o",
            "/dev/null",
        ])
        .current_dir(root())
        .output()
        .unwrap();
    assert_eq!(out.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&out.stderr).contains("no road of the chosen highway classes"));
    let out = mapc_command()
        .args([
            "import",
            "maps/i696.osm",
            "--major",
            "osm:61862553=osm-way:1",
            "-o",
            "/dev/null",
        ])
        .current_dir(root())
        .output()
        .unwrap();
    assert_eq!(out.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&out.stderr).contains("osm-way:1"));
}

#[test]
fn a_duplicate_node_id_is_an_error_unless_it_is_the_same_node() {
    let text = String::from_utf8(map("i696.osm")).unwrap();
    let node = "  <node id=\"26913188\" lat=\"42.4869153\" lon=\"-83.4764083\"/>\n";
    assert!(text.contains(node));
    // The same id 100 km away: one of the two would stretch roads by as much.
    let moved = text.replacen(
        node,
        &format!("{node}  <node id=\"26913188\" lat=\"43.4869153\" lon=\"-83.4764083\"/>\n"),
        1,
    );
    let line = text[..text.find(node).unwrap()].lines().count() + 2;
    fails_with(
        &scratch("dup_node.osm", moved.as_bytes()),
        &[
            &format!("line {line}"),
            "node 26913188 appears twice",
            "duplicate id",
        ],
    );
    // The very same node twice is read, and counted.
    let twice = text.replacen(node, &format!("{node}{node}"), 1);
    let file = scratch("same_node_twice.osm", twice.as_bytes());
    let out = mapc_command()
        .args(["import", file.to_str().unwrap(), "--json", "-o"])
        .arg(file.with_extension("graph.json"))
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let summary: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    assert_eq!(summary["warnings"]["duplicate_node"], 1, "{summary}");
}

#[test]
fn a_duplicate_way_id_with_other_nodes_is_an_error() {
    let text = String::from_utf8(map("i696.osm")).unwrap();
    // a motorway way (ways of other classes are not read, so not compared)
    let tag = text.find("<tag k=\"highway\" v=\"motorway\"/>").unwrap();
    let at = text[..tag].rfind("<way id=\"").unwrap();
    let end = at + text[at..].find("</way>").unwrap() + "</way>".len();
    let way = &text[at..end];
    let id: String = way["<way id=\"".len()..]
        .chars()
        .take_while(|c| c.is_ascii_digit())
        .collect();
    // the same way again, its node list reversed
    let mut lines: Vec<&str> = way.lines().collect();
    let nds: Vec<usize> = (0..lines.len())
        .filter(|&i| lines[i].contains("<nd "))
        .collect();
    let (first, last) = (nds[0], *nds.last().unwrap());
    lines[first..=last].reverse();
    let twin = lines.join("\n");
    let bad = text.replacen(way, &format!("{way}\n  {twin}"), 1);
    let stderr = fails_with(
        &scratch("dup_way.osm", bad.as_bytes()),
        &[&format!("way {id} appears twice"), "duplicate id", "line "],
    );
    assert!(stderr.contains(&format!("<way id=\"{id}\">")), "{stderr}");
}

#[test]
fn a_sumo_lane_of_speed_zero_is_an_error_naming_the_lane() {
    let text = String::from_utf8(map("simple_merge.net.xml")).unwrap();
    let lane = "<lane id=\"left_0\" index=\"0\" speed=\"30.00\"";
    let line = text[..text.find(lane).unwrap()].lines().count();
    let bad = text.replacen(lane, "<lane id=\"left_0\" index=\"0\" speed=\"0.00\"", 1);
    fails_with(
        &scratch("speed0.net.xml", bad.as_bytes()),
        &[&format!("line {line}"), "lane `left_0` has speed 0"],
    );
}

#[test]
fn a_duplicate_sumo_junction_id_is_an_error() {
    let text = String::from_utf8(map("simple_merge.net.xml")).unwrap();
    let junction = "<junction id=\"bottom\"";
    // a copy of `center` goes in before `bottom`: the original `center`, a line further down, is the second one
    let line = text[..text.find("<junction id=\"center\"").unwrap()]
        .lines()
        .count()
        + 1;
    let bad = text.replacen(
        junction,
        "<junction id=\"center\" type=\"dead_end\" x=\"0\" y=\"0\" incLanes=\"\"/>\n    <junction id=\"bottom\"",
        1,
    );
    fails_with(
        &scratch("dup_junction.net.xml", bad.as_bytes()),
        &[&format!("line {line}"), "`center`", "duplicate id"],
    );
}

/// The line of the first `needle` in `text` (1-based).
fn line_of(text: &str, needle: &str) -> usize {
    text[..text.find(needle).unwrap()].matches('\n').count() + 1
}

#[test]
fn a_sumo_connection_to_a_missing_lane_is_an_error_naming_it() {
    let text = String::from_utf8(map("simple_merge.net.xml")).unwrap();
    let from = "<connection from=\"left\" to=\"center\" fromLane=\"0\"";
    let bad = text.replacen(
        from,
        "<connection from=\"left\" to=\"center\" fromLane=\"1\"",
        1,
    );
    fails_with(
        &scratch("from_lane.net.xml", bad.as_bytes()),
        &[
            &format!("line {}", line_of(&text, from)),
            "<connection from=\"left\" to=\"center\">",
            "fromLane=\"1\" names a missing lane: edge `left` has 1 lane",
        ],
    );
    let to = "<connection from=\"bottom\" to=\"center\" fromLane=\"0\" toLane=\"0\"";
    let bad = text.replacen(
        to,
        "<connection from=\"bottom\" to=\"center\" fromLane=\"0\" toLane=\"3\"",
        1,
    );
    fails_with(
        &scratch("to_lane.net.xml", bad.as_bytes()),
        &[
            &format!("line {}", line_of(&text, to)),
            "toLane=\"3\" names a missing lane: edge `center` has 1 lane",
        ],
    );
}

#[test]
fn a_sumo_edge_with_a_gap_in_its_lane_indices_is_an_error() {
    let text = String::from_utf8(map("us_merge.net.xml")).unwrap();
    let lane = "<lane id=\"center_1\" index=\"1\"";
    let bad = text.replacen(lane, "<lane id=\"center_1\" index=\"2\"", 1);
    fails_with(
        &scratch("lane_gap.net.xml", bad.as_bytes()),
        &[
            &format!("line {}", line_of(&text, "<edge id=\"center\"")),
            "<edge id=\"center\">",
            "lane indices are not 0, 1, 2, ...: its 2 lanes have indices 0, 2",
        ],
    );
}

/// A graph file whose lanes cannot be: a road listing its lanes with a gap, a connection to a lane or road the
/// graph lacks. Every command that reads a graph (here `simplify`) says so naming the file, the line and the road
/// or connection.
#[test]
fn a_graph_file_with_bad_lanes_is_an_error_naming_the_element() {
    let good = scratch("us_merge.graph.json", b"");
    let out = mapc_command()
        .args([
            "import",
            root().join("maps/us_merge.net.xml").to_str().unwrap(),
            "-o",
            good.to_str().unwrap(),
        ])
        .output()
        .unwrap();
    assert!(out.status.success());
    let graph: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&good).unwrap()).unwrap();
    let two_lane = graph["roads"]
        .as_array()
        .unwrap()
        .iter()
        .position(|r| r["lanes"].as_array().unwrap().len() == 2)
        .expect("us_merge has a road of two lanes");
    let road_id = graph["roads"][two_lane]["id"].as_str().unwrap().to_string();

    let mut gap = graph.clone();
    gap["roads"][two_lane]["lanes"][1]["index"] = 2.into();
    let text = serde_json::to_string_pretty(&gap).unwrap();
    command_fails_with(
        "simplify",
        &scratch("gap.graph.json", text.as_bytes()),
        &[
            &format!("line {}", line_of(&text, &format!("\"id\": \"{road_id}\""))),
            &format!("road {road_id}"),
            "lists lane index 2 in place 1 of its 2 lanes",
        ],
    );

    let mut missing = graph.clone();
    let k = graph["connections"]
        .as_array()
        .unwrap()
        .iter()
        .position(|c| c["to_road"] == road_id.as_str())
        .expect("a connection into the two-lane road");
    missing["connections"][k]["to_lane"] = 5.into();
    let text = serde_json::to_string_pretty(&missing).unwrap();
    let connections_at = text.find("\"connections\"").unwrap();
    let start = text[connections_at..]
        .match_indices("\"from_road\"")
        .nth(k)
        .unwrap()
        .0
        + connections_at;
    command_fails_with(
        "simplify",
        &scratch("missing_lane.graph.json", text.as_bytes()),
        &[
            &format!("line {}", text[..start].matches('\n').count() + 1),
            &format!("connection {k} ("),
            &format!("to_lane 5 names a missing lane: road {road_id} has 2 lanes"),
        ],
    );
}

#[test]
fn a_sumo_edge_between_missing_junctions_is_an_error_naming_it() {
    let text = String::from_utf8(map("simple_merge.net.xml")).unwrap();
    let edge = "<edge id=\"left\" from=\"left\" to=\"center\"";
    for (attr, bad_edge) in [
        ("from", "<edge id=\"left\" from=\"nowhere\" to=\"center\""),
        ("to", "<edge id=\"left\" from=\"left\" to=\"nowhere\""),
    ] {
        let bad = text.replacen(edge, bad_edge, 1);
        fails_with(
            &scratch(&format!("{attr}_junction.net.xml"), bad.as_bytes()),
            &[
                &format!("line {}", line_of(&text, edge)),
                "<edge id=\"left\">",
                &format!("`{attr}` names junction `nowhere`, which the net lacks"),
            ],
        );
    }
}

#[test]
fn a_request_whose_cont_is_not_a_boolean_is_an_error_naming_it() {
    // `cont` says whether the link leads into an internal junction: a value SUMO would not read as a boolean
    let text = String::from_utf8(map("simple_merge.net.xml")).unwrap();
    let request = "<request index=\"1\" response=\"01\" foes=\"01\" cont=\"0\"/>";
    let bad = text.replacen(
        request,
        "<request index=\"1\" response=\"01\" foes=\"01\" cont=\"maybe\"/>",
        1,
    );
    fails_with(
        &scratch("cont.net.xml", bad.as_bytes()),
        &[
            &format!("line {}", line_of(&text, request)),
            "<request",
            "`cont` is `maybe`, not true or false",
        ],
    );
}
