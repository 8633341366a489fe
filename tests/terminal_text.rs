//! A map's text reaches the terminal as text: ids, names and classes holding escape sequences (a window title, a
//! screen clear, the one-byte C1 introducer) or a bidirectional override are printed escaped (`\u001b`) by every
//! command, in its report, its JSON and its error messages, so they cannot steer the terminal.

mod common;

use common::{run_mapc, scratch_dir, steering};
use std::path::{Path, PathBuf};
use std::process::Output;

/// Retitles the window, clears the screen, starts a colour with the C1 control sequence introducer, then turns the
/// rest of the line around. No white space: SUMO separates lane ids with spaces.
const HOSTILE: &str = "&#27;]0;pwned&#7;&#27;[2J&#x9b;31m&#x202e;";

/// The shipped Simple Merge net with its merging road's edge and junction ids (`bottom`) and its road type made
/// hostile; `broken` also makes one connection name a lane the edge lacks, so the import is refused with the id.
fn hostile_net(dir: &Path, broken: bool) -> PathBuf {
    let net = std::fs::read_to_string(common::root().join("maps/simple_merge.net.xml")).unwrap();
    let mut net = net
        .replace("bottom", &format!("bottom{HOSTILE}"))
        .replace("mergeType", &format!("merge{HOSTILE}"));
    if broken {
        let good = format!(r#"<connection from="bottom{HOSTILE}" to="center" fromLane="0""#);
        assert!(net.contains(&good));
        net = net.replace(
            &good,
            &format!(r#"<connection from="bottom{HOSTILE}" to="center" fromLane="3""#),
        );
    }
    let path = dir.join(if broken {
        "broken.net.xml"
    } else {
        "hostile.net.xml"
    });
    std::fs::write(&path, net).unwrap();
    path
}

fn printed(out: &Output) -> (String, String) {
    (
        String::from_utf8(out.stdout.clone()).unwrap(),
        String::from_utf8(out.stderr.clone()).unwrap(),
    )
}

#[test]
fn hostile_ids_names_and_classes_are_printed_escaped() {
    let dir = scratch_dir("terminal-text");
    let net = hostile_net(&dir, false);
    let net = net.to_str().unwrap();
    let corridor = dir.join("corridor.graph.json");
    let window = dir.join("window.toml");
    let graph = dir.join("hostile.graph.json");
    let runs: Vec<Vec<&str>> = vec![
        vec!["import", net, "-o", graph.to_str().unwrap()],
        vec!["junctions", net],
        vec![
            "simplify",
            net,
            "--classes",
            "highwayType",
            "-o",
            corridor.to_str().unwrap(),
        ],
        vec![
            "window",
            corridor.to_str().unwrap(),
            "--junction",
            "center",
            "-o",
            window.to_str().unwrap(),
        ],
        vec!["scenario", "show", window.to_str().unwrap()],
    ];
    for args in &runs {
        let out = run_mapc(args);
        let (stdout, stderr) = printed(&out);
        assert!(out.status.success(), "mapc {args:?}: {stderr}");
        assert_eq!(
            steering(&stdout),
            Vec::<char>::new(),
            "mapc {args:?} printed: {stdout}"
        );
        assert_eq!(
            steering(&stderr),
            Vec::<char>::new(),
            "mapc {args:?} printed: {stderr}"
        );
    }
    // The ids are there, escaped, where a person reads them.
    let (listed, _) = printed(&run_mapc(&["junctions", net]));
    assert!(
        listed.contains("bottom\\u001b]0;pwned\\u0007\\u001b[2J\\u009b31m\\u202e"),
        "{listed}"
    );
    // JSON stays valid and carries the map's text unchanged.
    let (json, _) = printed(&run_mapc(&["junctions", net, "--json"]));
    assert_eq!(steering(&json), Vec::<char>::new());
    let value: serde_json::Value = serde_json::from_str(&json).unwrap();
    assert!(
        value
            .to_string()
            .contains("bottom\\u001b]0;pwned\\u0007\\u001b[2J"),
        "{value}"
    );
    assert!(serde_json::to_string(&value).unwrap().contains('\u{202e}'));
}

#[test]
fn an_error_naming_a_hostile_id_is_printed_escaped() {
    let dir = scratch_dir("terminal-text-error");
    let net = hostile_net(&dir, true);
    let out = run_mapc(&[
        "import",
        net.to_str().unwrap(),
        "-o",
        dir.join("x.graph.json").to_str().unwrap(),
    ]);
    let (_, stderr) = printed(&out);
    assert_eq!(out.status.code(), Some(2), "{stderr}");
    assert!(stderr.contains("bottom\\u001b]0;pwned"), "{stderr}");
    assert_eq!(steering(&stderr), Vec::<char>::new(), "{stderr}");
}
