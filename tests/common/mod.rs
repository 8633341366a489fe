//! Helpers shared by the end-to-end tests: running the `mapc` binary from the repository root, scratch folders,
//! and golden files (`MAPC_BLESS=1` rewrites them; with `CI` set a set `MAPC_BLESS` fails the test instead, so a
//! flag left on cannot turn the goldens into a test that cannot fail).
#![allow(dead_code)]

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

pub mod browser;
pub mod mutate;

/// The `--via` flags that route `maps/i696.osm` along the paper's I-696 corridor (the three ways of its main road).
pub const PAPER_VIA: [&str; 6] = [
    "--via",
    "osm-way:59440544",
    "--via",
    "osm-way:8667198",
    "--via",
    "osm-way:8708084",
];

/// The repository root (where `maps/` and `scenarios/` are).
pub fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

/// The `mapc` binary, to run from the repository root.
pub fn mapc_command() -> Command {
    let mut c = Command::new(env!("CARGO_BIN_EXE_mapc"));
    c.current_dir(root());
    c
}

/// Run `mapc ARGS` from the repository root.
pub fn run_mapc(args: &[&str]) -> Output {
    mapc_command()
        .args(args)
        .output()
        .expect("the mapc binary runs")
}

/// A fresh folder of this test process under Cargo's folder for integration tests' files (in target/, so
/// test runs leave nothing in the system's temporary folder).
pub fn scratch_dir(name: &str) -> PathBuf {
    let dir = PathBuf::from(env!("CARGO_TARGET_TMPDIR"))
        .join(format!("mapc-test-{name}-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

/// `mapc export SCENARIO --sumo DIR [EXTRA]` into a fresh folder named after `name`; the folder, once it succeeded.
pub fn export_for_sumo(scenario: &str, name: &str, extra: &[&str]) -> PathBuf {
    let dir = scratch_dir(name);
    let mut args = vec!["export", scenario, "--sumo", dir.to_str().unwrap()];
    args.extend_from_slice(extra);
    assert_success(&run_mapc(&args));
    dir
}

/// A path of this test process under Cargo's folder for integration tests' files with nothing there yet, for a
/// command that makes its output folder itself.
pub fn fresh_path(name: &str) -> PathBuf {
    let path = PathBuf::from(env!("CARGO_TARGET_TMPDIR"))
        .join(format!("mapc-test-{name}-{}", std::process::id()));
    if path.exists() {
        std::fs::remove_dir_all(&path).unwrap();
    }
    path
}

/// Whether golden files are being rewritten (`MAPC_BLESS=1`); never in CI.
pub fn blessing() -> bool {
    let bless = std::env::var_os("MAPC_BLESS").is_some_and(|v| !v.is_empty() && v != "0");
    assert!(
        !(bless && std::env::var_os("CI").is_some()),
        "MAPC_BLESS is set in CI: goldens must not be rewritten there"
    );
    bless
}

/// Compare `actual` with the golden JSON file at `path`, or write it when blessing.
pub fn check_golden(path: &Path, actual: &serde_json::Value) {
    let text = serde_json::to_string_pretty(actual).unwrap() + "\n";
    if blessing() {
        std::fs::create_dir_all(path.parent().unwrap()).unwrap();
        std::fs::write(path, &text).unwrap();
        return;
    }
    let golden = std::fs::read_to_string(path).unwrap_or_else(|e| {
        panic!(
            "{}: {e} (run with MAPC_BLESS=1 to create it)",
            path.display()
        )
    });
    let golden: serde_json::Value = serde_json::from_str(&golden).unwrap();
    assert_eq!(
        &golden,
        actual,
        "{} differs (MAPC_BLESS=1 rewrites it after a deliberate change)",
        path.display()
    );
}

/// Fail with the command's error output unless it succeeded.
pub fn assert_success(out: &Output) {
    assert!(
        out.status.success(),
        "mapc failed: {}",
        String::from_utf8_lossy(&out.stderr)
    );
}

/// Run `mapc ARGS`, expect success, and read its standard output as JSON.
pub fn mapc_json(args: &[&str]) -> serde_json::Value {
    let out = run_mapc(args);
    assert!(
        out.status.success(),
        "mapc {args:?} failed: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    serde_json::from_slice(&out.stdout).unwrap_or_else(|e| {
        panic!(
            "mapc {args:?}: not JSON ({e}): {}",
            String::from_utf8_lossy(&out.stdout)
        )
    })
}

/// Run `mapc ARGS` and expect it refused: exit code 2, no panic, and every one of `expected` in its message,
/// which is returned.
pub fn refused(args: &[&str], expected: &[&str]) -> String {
    let out = run_mapc(args);
    let stderr = String::from_utf8_lossy(&out.stderr).into_owned();
    assert_eq!(out.status.code(), Some(2), "mapc {args:?}: {stderr}");
    assert!(!stderr.contains("panicked"), "{stderr}");
    for e in expected {
        assert!(stderr.contains(e), "expected `{e}` in: {stderr}");
    }
    stderr
}

/// The shipped scenario `scenarios/<shipped>` with `edit` applied to its text, written as `<name>.toml` in a
/// scratch folder of its own (the edit must change something).
pub fn edited_scenario(shipped: &str, name: &str, edit: impl Fn(String) -> String) -> PathBuf {
    let dir = scratch_dir(name);
    let text = std::fs::read_to_string(root().join("scenarios").join(shipped)).unwrap();
    let edited = edit(text.clone());
    assert_ne!(edited, text, "the edit changed nothing");
    let path = dir.join(format!("{name}.toml"));
    std::fs::write(&path, edited).unwrap();
    path
}

/// The characters of a terminal's control channel: C0 but the line break, DEL, C1, and the bidirectional
/// embeddings, overrides and isolates.
pub fn steering(text: &str) -> Vec<char> {
    text.chars()
        .filter(|&c| {
            (c.is_control() && c != '\n')
                || matches!(c, '\u{202a}'..='\u{202e}' | '\u{2066}'..='\u{2069}')
        })
        .collect()
}
