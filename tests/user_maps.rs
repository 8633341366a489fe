//! What a user meets running mapc on a map of their own: help that sets nothing up and says what the commands do.

mod common;

use common::{assert_success, fresh_path, root, run_mapc};

/// `sumo_check --help` prints its usage with the standard library only: no SUMO environment is made for it.
#[test]
fn sumo_checks_help_sets_nothing_up() {
    let venv = fresh_path("sumo-venv");
    let out = std::process::Command::new(root().join("tools/sumo_check/sumo_check"))
        .arg("--help")
        .env("MAPC_SUMO_VENV", &venv)
        // were anything installed, it would fail at once rather than reach for the network
        .env("PIP_NO_INDEX", "1")
        .output()
        .unwrap();
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    assert!(
        stdout.contains("usage:") && stdout.contains("baseline"),
        "{stdout}"
    );
    assert!(!venv.exists(), "a virtual environment was made for --help");
}

#[test]
fn the_help_says_what_simplify_and_export_do() {
    let out = run_mapc(&["--help"]);
    assert_success(&out);
    let help = String::from_utf8_lossy(&out.stdout);
    let line = |command: &str| {
        help.lines()
            .find(|l| l.trim_start().starts_with(command))
            .unwrap_or_else(|| panic!("no {command} in {help}"))
            .to_string()
    };
    let simplify = line("simplify");
    assert!(
        !simplify.contains("single-lane") && simplify.contains("--keep-lanes"),
        "{simplify}"
    );
    let export = line("export");
    assert!(
        export.contains("GeoJSON") && export.contains("SUMO"),
        "{export}"
    );
}
