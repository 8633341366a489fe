//! Training is reproducible bit for bit: a short run of `mapc train` (the paper preset on the Simple Merge, with
//! smaller batches) writes the same log rows and the same weights on one thread and on two, and the same as
//! recorded here, so a change to the trainer that moves any bit of any shipped policy's training fails.
//!
//! The recorded digests hold for x86-64 machines: the update's matrix products and element-wise loops give the
//! same bits with AVX-512, with AVX2 or with neither (`ppo::tensor::matmul`, `ppo::tensor::simd`). Recorded again
//! when the gradient was written out and Adam's moments got their floor, and when the matrix products became
//! mapc's own (docs/perf.md, "The gradient written out", "The update's matrix products").

use std::path::{Path, PathBuf};

use sha2::{Digest, Sha256};

mod common;

fn tmp(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("mapc-train-repro-{}-{name}", std::process::id()));
    std::fs::remove_dir_all(&d).ok();
    d
}

/// `mapc train ARGS -o DIR` on `threads` rayon threads (`RAYON_NUM_THREADS`, as a user would set it).
fn train(dir: &Path, threads: usize, args: &[&str]) {
    let out = common::mapc_command()
        .env("RAYON_NUM_THREADS", threads.to_string())
        .arg("train")
        .args(args)
        .args(["--json", "-o"])
        .arg(dir)
        .output()
        .unwrap();
    common::assert_success(&out);
}

/// SHA-256 of what the run wrote that must not move: the log's rows without their wall time, the final weights
/// and Adam's moments (as the checkpoint writes them, each f32 in its shortest exact decimal form).
fn digest(dir: &Path) -> String {
    let mut h = Sha256::new();
    let csv = std::fs::read_to_string(dir.join("progress.csv")).unwrap();
    for line in csv.lines().skip(1) {
        let mut fields: Vec<&str> = line.split(',').collect();
        fields.remove(2); // wall_s
        h.update(fields.join(",").as_bytes());
        h.update(b"\n");
    }
    let ck: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(dir.join("checkpoint.json")).unwrap())
            .unwrap();
    let state = &ck["state"];
    assert!(state["model"]["params"].as_array().unwrap().len() > 1000);
    h.update(state["model"].to_string().as_bytes());
    h.update(state["adam"].to_string().as_bytes());
    h.finalize()
        .iter()
        .map(|b| format!("{b:02x}"))
        .collect::<String>()
}

/// Runs `args` on one thread and on two: both must write the same, and that must be `recorded`.
fn check_pinned(name: &str, args: &[&str], recorded: &str) {
    let digests: Vec<String> = [1, 2]
        .iter()
        .map(|&threads| {
            let dir = tmp(&format!("{name}-{threads}"));
            train(&dir, threads, args);
            let d = digest(&dir);
            std::fs::remove_dir_all(&dir).ok();
            d
        })
        .collect();
    assert_eq!(digests[0], digests[1], "{name}: one thread and two differ");
    assert_eq!(digests[0], recorded, "{name}: the run's bits moved");
}

#[test]
fn a_short_centralized_paper_run_is_pinned() {
    // 3 episodes of 1000 steps per iteration, minibatches of 128 (24 per epoch), 10 epochs
    check_pinned(
        "centralized",
        &[
            "--scenario",
            "simple_merge",
            "--reward",
            "outflow",
            "--preset",
            "paper",
            "--seed",
            "5",
            "--iters",
            "2",
            "--batch",
            "3000",
            "--horizon",
            "1000",
        ],
        "918f69b1473a826d049597504aaaf2778109ee5f09f8221a602d30b1cba686b8",
    );
}

#[test]
fn a_short_distributed_paper_run_is_pinned() {
    // 2 episodes of 1000 steps, every agent's steps in minibatches of 4096, 10 epochs
    check_pinned(
        "distributed",
        &[
            "--scenario",
            "simple_merge",
            "--distributed",
            "--preset",
            "paper",
            "--seed",
            "5",
            "--iters",
            "1",
            "--batch",
            "2000",
            "--horizon",
            "1000",
        ],
        "9aff54b2ad05de11e4e03415a76aaf59c95aa816c8ac72dbc322b6a146f381bc",
    );
}
