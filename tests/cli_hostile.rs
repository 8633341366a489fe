//! The command line under hostile input: policy files with fields out of range, numeric flags out of theirs
//! (seeds that overflow, counts that would abort the process with a huge allocation), text that would steer the
//! terminal, and errors that must say each fact once and name the file. Each is refused with one clear message
//! and exit code 2, never a panic or an abort.

mod common;

use common::{refused, run_mapc, scratch_dir, steering};
use std::path::PathBuf;

/// The shipped Simple Merge policy with `edit` applied to its JSON, written as `<name>.json` in a scratch folder.
fn edited_policy(name: &str, edit: impl Fn(&mut serde_json::Value)) -> PathBuf {
    let text =
        std::fs::read_to_string(common::root().join("policies/simple_merge_outflow.json")).unwrap();
    let mut policy: serde_json::Value = serde_json::from_str(&text).unwrap();
    edit(&mut policy);
    let path = scratch_dir(name).join(format!("{name}.json"));
    std::fs::write(&path, serde_json::to_string(&policy).unwrap()).unwrap();
    path
}

#[test]
fn a_policy_file_is_range_checked_field_by_field() {
    let cases: [(&str, &str, serde_json::Value, &str); 7] = [
        ("accel-swapped", "accel_min", 3.0.into(), "spec.accel_min"),
        (
            "max-speed-negative",
            "max_speed",
            (-1.0).into(),
            "spec.max_speed",
        ),
        ("max-speed-zero", "max_speed", 0.0.into(), "spec.max_speed"),
        (
            "norm-length-negative",
            "norm_length",
            (-1.0).into(),
            "spec.norm_length",
        ),
        ("no-avs", "n_av", 0.into(), "spec.n_av"),
        ("n-av-huge", "n_av", 4_294_967_296u64.into(), "spec.n_av"),
        ("n-av-other", "n_av", 4.into(), "spec.obs_dim"),
    ];
    for (name, field, value, expected) in cases {
        let path = edited_policy(name, |p| p["spec"][field] = value.clone());
        let file = path.to_str().unwrap();
        let args = ["eval", "--policy", file, "--seeds", "1", "--no-baseline"];
        refused(&args, &[file, expected]);
        std::fs::remove_dir_all(path.parent().unwrap()).unwrap();
    }
    // the parameters are numbers too
    let path = edited_policy("adam-v-negative", |p| {
        p["state"]["adam"]["v"][3] = (-1.0).into();
    });
    let file = path.to_str().unwrap();
    refused(
        &["eval", "--policy", file, "--seeds", "1"],
        &[file, "state.adam.v[3]"],
    );
    std::fs::remove_dir_all(path.parent().unwrap()).unwrap();
}

#[test]
fn seeds_that_would_overflow_or_exhaust_memory_are_refused() {
    let trace = scratch_dir("overflow-trace").join("trace.csv");
    let trace = trace.to_str().unwrap();
    let policy = "policies/simple_merge_outflow.json";
    let last = "18446744073709551615";
    for args in [
        &[
            "sim",
            "--first-seed",
            last,
            "--seeds",
            "1",
            "--trace",
            trace,
        ][..],
        &["sim", "--first-seed", last, "--seeds", "1"],
        &[
            "eval",
            "--policy",
            policy,
            "--first-seed",
            last,
            "--seeds",
            "1",
        ],
    ] {
        refused(args, &["--first-seed", "18446744073709451615"]);
    }
    assert!(!std::path::Path::new(trace).exists());
    for command in [&["sim"][..], &["eval", "--policy", policy], &["bench"]] {
        for seeds in ["0", "1000000000"] {
            refused(&[command, &["--seeds", seeds]].concat(), &["--seeds"]);
        }
    }
}

#[test]
fn every_numeric_flag_has_a_range() {
    let policy = "policies/simple_merge_outflow.json";
    let cases: &[(&[&str], &str)] = &[
        (&["sim", "--threads", "100000"], "--threads"),
        (&["sim", "--threads", "0"], "--threads"),
        (
            &["eval", "--policy", policy, "--threads", "5000"],
            "--threads",
        ),
        (&["bench", "--threads", "0"], "--threads"),
        (
            &["bench", "--single-core-seeds", "0"],
            "--single-core-seeds",
        ),
        (&["bench", "--sumo-seeds", "1000000000"], "--sumo-seeds"),
        (&["bench", "--train", "0"], "--train"),
        (&["train", "--n-av", "1000000"], "--n-av"),
        (&["train", "--n-av", "0"], "--n-av"),
        (&["train", "--gamma", "2"], "--gamma"),
        (&["train", "--lambda=-0.5"], "--lambda"),
        (&["train", "--lr", "nan"], "--lr"),
        (&["train", "--clip", "inf"], "--clip"),
        (&["train", "--kl-coeff=-1"], "--kl-coeff"),
        (&["train", "--kl-target", "0"], "--kl-target"),
        (&["train", "--epochs", "0"], "--epochs"),
        (&["train", "--batch", "0"], "--batch"),
        (&["train", "--minibatch", "100000000"], "--minibatch"),
        (&["train", "--horizon", "0"], "--horizon"),
        (&["train", "--iters", "100000000000"], "--iters"),
        (&["train", "--threads", "100000"], "--threads"),
        (&["train", "--checkpoint-every", "0"], "--checkpoint-every"),
        (&["train", "--distributed", "--eta1", "nan"], "--eta1"),
        (&["train", "--distributed", "--eta2", "1e300"], "--eta2"),
        (
            &["train", "--distributed", "--exit-bonus=-inf"],
            "--exit-bonus",
        ),
        (
            &["train", "--distributed", "--reward-share", "1.5"],
            "--reward-share",
        ),
        (
            &["pipeline", "maps/i696.osm", "-o", "x", "--seeds", "0"],
            "--seeds",
        ),
        (
            &["pipeline", "maps/i696.osm", "-o", "x", "--lane", "16"],
            "--lane",
        ),
        (
            &["plot", "timespace", "t.csv", "-o", "x.png", "--width", "0"],
            "--width",
        ),
        (
            &[
                "plot",
                "timespace",
                "t.csv",
                "-o",
                "x.png",
                "--height",
                "99999999",
            ],
            "--height",
        ),
        (
            &[
                "plot",
                "timespace",
                "t.csv",
                "-o",
                "x.png",
                "--speed-max",
                "0",
            ],
            "--speed-max",
        ),
        (
            &[
                "plot",
                "timespace",
                "t.csv",
                "-o",
                "x.png",
                "--start",
                "nan",
            ],
            "--start",
        ),
        (
            &["plot", "timespace", "t.csv", "-o", "x.png", "--lane", "200"],
            "--lane",
        ),
        (
            &[
                "plot",
                "training",
                "r",
                "-o",
                "x.png",
                "--baseline-outflow=-1",
            ],
            "--baseline-outflow",
        ),
        (
            &[
                "plot",
                "training",
                "r",
                "-o",
                "x.png",
                "--width",
                "4000000000",
            ],
            "--width",
        ),
        (
            &["render", "maps/i696.osm", "-o", "x.png", "--width", "0"],
            "--width",
        ),
        (
            &[
                "simplify",
                "maps/i696.osm",
                "-o",
                "x.json",
                "--feeder-length",
                "nan",
            ],
            "--feeder-length",
        ),
        (&["view", "simple_merge", "--max-rows", "0"], "--max-rows"),
        (
            &["window", "m.graph.json", "--all", "--n-av", "5000"],
            "--n-av",
        ),
        (
            &["window", "m.graph.json", "--all", "--main-vph=-1"],
            "--main-vph",
        ),
        (
            &["window", "m.graph.json", "--all", "--merge-vph", "inf"],
            "--merge-vph",
        ),
        (
            &[
                "window",
                "m.graph.json",
                "--all",
                "--fit",
                "--fit-floor",
                "0",
            ],
            "--fit-floor",
        ),
    ];
    for (args, flag) in cases {
        let err = refused(args, &[flag]);
        assert!(err.contains("invalid value"), "{args:?}: {err}");
    }
}

#[test]
fn scenario_text_and_bad_flag_values_reach_the_terminal_escaped() {
    let path = common::edited_scenario("simple_merge.toml", "hostile-name", |t| {
        t.replacen("name = \"", "name = \"\u{9b}31m\u{202e}", 1)
    });
    let out = run_mapc(&["scenario", "show", path.to_str().unwrap()]);
    let stdout = String::from_utf8(out.stdout).unwrap();
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    assert_eq!(steering(&stdout), vec![], "{stdout}");
    assert!(stdout.contains("\\u202e"), "{stdout}");
    // clap echoes a bad value in its message
    let err = refused(&["sim", "--seeds", "1\u{202e}\u{1b}[2J"], &["--seeds"]);
    assert_eq!(steering(&err), vec![], "{err}");
    assert!(err.contains("\\u202e"), "{err}");
    // help and version still go to standard output with success
    for flag in ["--help", "--version"] {
        let out = run_mapc(&[flag]);
        assert_eq!(out.status.code(), Some(0), "{flag}");
        assert!(!out.stdout.is_empty() && out.stderr.is_empty(), "{flag}");
    }
    let out = run_mapc(&["sim", "--no-such-flag"]);
    assert_eq!(out.status.code(), Some(2));
}

#[test]
fn a_missing_file_is_named_once_with_its_cause_once() {
    for args in [
        &["eval", "--policy", "no/such.json", "--seeds", "1"][..],
        &["view", "no/such.toml"],
        &["plot", "training", "no/such", "-o", "x.png"],
        &["train", "--resume", "no/such"],
    ] {
        let err = refused(args, &["no/such", "No such file or directory"]);
        assert_eq!(
            err.matches("No such file or directory").count(),
            1,
            "{args:?}: {err}"
        );
    }
}

#[test]
fn a_trace_that_cannot_be_written_names_its_file() {
    let dir = scratch_dir("trace-too-large");
    let trace = dir.join("trace.csv");
    // files may grow to 1 block (the shell's unit) and a longer write fails (SIGXFSZ ignored), as on a full disk
    let out = std::process::Command::new("sh")
        .arg("-c")
        .arg("ulimit -f 1 && trap '' XFSZ && exec \"$0\" \"$@\"")
        .arg(env!("CARGO_BIN_EXE_mapc"))
        .args(["sim", "--seeds", "1", "--trace"])
        .arg(&trace)
        .current_dir(common::root())
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(2), "{err}");
    assert!(err.contains(trace.to_str().unwrap()), "{err}");
    assert!(!err.contains("panicked"), "{err}");
    assert_eq!(
        std::fs::read_dir(&dir).unwrap().count(),
        0,
        "nothing is left"
    );
    std::fs::remove_dir_all(dir).unwrap();
}
