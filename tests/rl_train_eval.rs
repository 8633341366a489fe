//! End-to-end: a tiny training run of `mapc train` on the Simple Merge, resumed, then `mapc eval` of its policy.

use std::path::{Path, PathBuf};

mod common;

use common::mapc_command as mapc;

/// `mapc ARGS PATH`: the arguments, then one path (a run directory or a file), run to the end.
fn mapc_with<const N: usize>(
    args: [&str; N],
    path: impl AsRef<std::ffi::OsStr>,
) -> std::process::Output {
    mapc().args(args).arg(path).output().unwrap()
}

/// `mapc eval --json` of `policy` on `scenario` over `seeds` seeds (paths from the repository root).
fn eval_json(policy: &str, scenario: &str, seeds: &str, extra: &[&str]) -> serde_json::Value {
    let mut args = vec![
        "eval",
        "--seeds",
        seeds,
        "--json",
        "--scenario",
        scenario,
        "--policy",
        policy,
    ];
    args.extend_from_slice(extra);
    common::mapc_json(&args)
}

fn tmp(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("mapc-rl-e2e-{}-{name}", std::process::id()));
    std::fs::remove_dir_all(&d).ok();
    d
}

/// A few iterations of 600 steps (episodes of 300) with the fast preset; `setting`: the reward or the
/// distributed flags, and the minibatch.
fn tiny_train_with(dir: &PathBuf, iters: u64, setting: &[&str]) -> std::process::Output {
    mapc()
        .args(["train", "--scenario", "simple_merge", "--preset", "fast"])
        .args(setting)
        .args(["--iters", &iters.to_string(), "--batch", "600"])
        .args(["--horizon", "300", "--epochs", "2"])
        .args(["--checkpoint-every", "1", "--json", "-o"])
        .arg(dir)
        .output()
        .unwrap()
}

fn tiny_train(dir: &PathBuf, iters: u64) -> std::process::Output {
    tiny_train_with(dir, iters, &["--reward", "outflow", "--minibatch", "200"])
}

/// Runs a `mapc` command that must be refused: exit 2; returns the message.
fn refused(cmd: &mut std::process::Command) -> String {
    let out = cmd.output().unwrap();
    let err = String::from_utf8_lossy(&out.stderr).into_owned();
    assert_eq!(out.status.code(), Some(2), "{err}");
    err
}

/// `mapc eval` of a policy file that must be refused: exit 2; returns the message.
fn refused_policy(policy: &Path) -> String {
    refused(
        mapc()
            .args(["eval", "--seeds", "1", "--policy"])
            .arg(policy),
    )
}

/// The third row of a run's log without its wall time (a resumed run must match a straight one there).
fn row3(dir: &Path) -> Vec<String> {
    let csv = std::fs::read_to_string(dir.join("progress.csv")).unwrap();
    let line = csv.lines().nth(3).unwrap().to_string();
    let mut fields: Vec<String> = line.split(',').map(String::from).collect();
    fields.remove(2); // wall_s
    fields
}

fn read_json(path: &Path) -> serde_json::Value {
    serde_json::from_str(&std::fs::read_to_string(path).unwrap()).unwrap()
}

/// `best.json` must hold the policy whose training rollouts the log's best row by outflow describes (the first of
/// equal rows): the policy the row's iteration started from, which is the kept checkpoint of the iteration before
/// where one was kept. Returns it.
fn check_best(dir: &Path) -> serde_json::Value {
    let csv = std::fs::read_to_string(dir.join("progress.csv")).unwrap();
    let mut best_row: Option<(u64, f64)> = None;
    for line in csv.lines().skip(1) {
        let f: Vec<&str> = line.split(',').collect();
        let (it, outflow): (u64, f64) = (f[0].parse().unwrap(), f[4].parse().unwrap());
        if best_row.is_none_or(|(_, o)| outflow > o) {
            best_row = Some((it, outflow));
        }
    }
    let (it, outflow) = best_row.expect("rows");
    let best = read_json(&dir.join("best.json"));
    let sel = &best["selected"];
    assert_eq!(sel["by"], "outflow", "{sel}");
    assert_eq!(sel["row_iteration"], it, "{sel}\n{csv}");
    assert_eq!(sel["score"].as_f64().unwrap(), outflow, "{sel}\n{csv}");
    assert_eq!(best["state"]["iteration"], it - 1);
    let kept = dir
        .join("checkpoints")
        .join(format!("iteration-{:05}.json", it - 1));
    if kept.exists() {
        assert_eq!(best["state"]["model"], read_json(&kept)["state"]["model"]);
    }
    // no other checkpoint says it was selected
    assert!(
        read_json(&dir.join("checkpoint.json"))
            .get("selected")
            .is_none()
    );
    best
}

#[test]
fn tiny_training_resume_and_eval() {
    let dir = tmp("run");
    let out = tiny_train(&dir, 2);
    common::assert_success(&out);
    let csv = std::fs::read_to_string(dir.join("progress.csv")).unwrap();
    let lines: Vec<&str> = csv.lines().collect();
    assert_eq!(
        lines[0],
        "iteration,env_steps,wall_s,mean_return,mean_outflow,mean_speed,policy_loss,value_loss,kl,entropy,kl_coeff"
    );
    assert_eq!(lines.len(), 3, "{csv}");
    assert!(lines[2].starts_with("2,1200,"), "{csv}");

    // Continue to 3 iterations; the same run done in one go must give the same third row (bit for bit, wall
    // time aside).
    let out = mapc_with(["train", "--iters", "3", "--json", "--resume"], &dir);
    common::assert_success(&out);
    let straight = tmp("straight");
    assert!(tiny_train(&straight, 3).status.success());
    assert_eq!(row3(&dir), row3(&straight));
    // the best policy too, and the report names it
    let (best, best_straight) = (check_best(&dir), check_best(&straight));
    assert_eq!(best["selected"], best_straight["selected"]);
    assert_eq!(best["state"]["model"], best_straight["state"]["model"]);
    let report: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    assert_eq!(report["best"]["by"], "outflow", "{report}");
    assert_eq!(
        report["best"]["row_iteration"],
        best["selected"]["row_iteration"]
    );
    // a resumed run keeps the criterion it started with
    let msg = refused(
        mapc()
            .args(["train", "--iters", "4", "--best-by", "speed", "--resume"])
            .arg(&dir),
    );
    assert!(msg.contains("--best-by outflow"), "{msg}");
    // the best policy is a checkpoint `mapc eval` reads
    let out = mapc_with(
        [
            "eval",
            "--seeds",
            "1",
            "--no-baseline",
            "--json",
            "--policy",
        ],
        dir.join("best.json"),
    );
    common::assert_success(&out);

    // Evaluate on 3 seeds: the JSON has mapc sim's shape plus the baseline and the test.
    let out = mapc_with(
        [
            "eval",
            "--scenario",
            "simple_merge",
            "--seeds",
            "3",
            "--json",
            "--policy",
        ],
        &dir,
    );
    common::assert_success(&out);
    let v: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    for k in ["outflow", "inflow", "speed"] {
        assert!(v[k]["mean"].as_f64().unwrap() > 0.0, "{v}");
        assert!(v[k]["ci95"].as_f64().unwrap() >= 0.0, "{v}");
        assert!(v["baseline"][k]["mean"].as_f64().unwrap() > 0.0, "{v}");
    }
    assert_eq!(v["seeds"], 3);
    assert!(v["comparison"]["outflow"]["p_value"].is_number(), "{v}");

    // The first seed's trajectories under the policy: mapc sim's trace columns, AVs marked as controlled, the
    // whole horizon.
    let trace = dir.join("policy_trace.csv");
    let out = mapc()
        .args(["eval", "--seeds", "1", "--no-baseline", "--trace"])
        .arg(&trace)
        .arg("--policy")
        .arg(&dir)
        .output()
        .unwrap();
    common::assert_success(&out);
    // a run directory is evaluated at its last checkpoint; the report points at the best policy beside it
    let said = String::from_utf8_lossy(&out.stdout);
    assert!(
        said.contains("after 3 iterations; its best by training outflow")
            && said.contains("best.json"),
        "{said}"
    );
    let csv = std::fs::read_to_string(&trace).unwrap();
    let mut lines = csv.lines();
    assert_eq!(
        lines.next().unwrap(),
        "time_s,vehicle_id,vehicle_type,road,pos_on_road_m,corridor_x_m,speed_mps,controlled,lane"
    );
    let rows: Vec<Vec<&str>> = lines.map(|l| l.split(',').collect()).collect();
    assert!(
        rows.iter().any(|r| r[7] == "true"),
        "no controlled AV in the trace"
    );
    let last_t: f64 = rows.last().unwrap()[0].parse().unwrap();
    assert!(last_t > 999.0, "trace ends at {last_t} s");

    // a best.json that cannot be read does not stop the evaluation of the run; the hint names the file
    std::fs::write(dir.join("best.json"), "{ not json").unwrap();
    let out = mapc_with(["eval", "--seeds", "1", "--no-baseline", "--policy"], &dir);
    common::assert_success(&out);
    let said = String::from_utf8_lossy(&out.stdout);
    assert!(
        said.contains("could not be read") && said.contains("best.json") && said.contains("line 1"),
        "{said}"
    );

    // a run without best.json (as runs from before it were) may pick a criterion when resumed; its best.json
    // starts with the rows to come
    std::fs::remove_file(dir.join("best.json")).unwrap();
    let out = mapc_with(
        ["train", "--iters", "4", "--best-by", "speed", "--resume"],
        &dir,
    );
    common::assert_success(&out);
    let best = read_json(&dir.join("best.json"));
    assert_eq!(best["selected"]["by"], "speed");
    assert_eq!(best["selected"]["row_iteration"], 4);
    assert_eq!(best["state"]["iteration"], 3);
    std::fs::remove_dir_all(&dir).ok();
    std::fs::remove_dir_all(&straight).ok();
}

#[test]
fn policy_with_another_observation_size_is_a_clear_error() {
    let dir = tmp("nav3");
    let out = mapc()
        .args([
            "train",
            "--n-av",
            "3",
            "--iters",
            "1",
            "--batch",
            "100",
            "--horizon",
            "100",
            "--minibatch",
            "50",
        ])
        .args(["--epochs", "1", "--json", "-o"])
        .arg(&dir)
        .output()
        .unwrap();
    common::assert_success(&out);
    let err = refused(
        mapc()
            .args([
                "eval",
                "--seeds",
                "2",
                "--scenario",
                "simple_merge",
                "--policy",
            ])
            .arg(&dir),
    );
    assert!(
        err.contains("expects 15 observation values") && err.contains("gives 25"),
        "{err}"
    );
    std::fs::remove_dir_all(&dir).ok();
}

#[test]
fn a_corrupt_checkpoint_names_the_file() {
    let dir = tmp("corrupt");
    std::fs::create_dir_all(&dir).unwrap();
    let f = dir.join("policy.json");
    std::fs::write(&f, "{\"format_version\": 1, \"spec\": ").unwrap();
    let err = refused_policy(&f);
    assert!(
        err.contains("policy.json") && err.contains("line 1"),
        "{err}"
    );
    std::fs::remove_dir_all(&dir).ok();
}

fn tiny_distributed_train(dir: &PathBuf, iters: u64) -> std::process::Output {
    tiny_distributed_train_with(dir, iters, &["--keep-checkpoints"])
}

fn tiny_distributed_train_with(dir: &PathBuf, iters: u64, extra: &[&str]) -> std::process::Output {
    let mut setting = vec![
        "--distributed",
        "--features",
        "dist,merge",
        "--minibatch",
        "256",
    ];
    setting.extend_from_slice(extra);
    tiny_train_with(dir, iters, &setting)
}

#[test]
fn tiny_distributed_training_resume_and_eval() {
    let dir = tmp("dist");
    let out = tiny_distributed_train(&dir, 2);
    common::assert_success(&out);
    // the checkpoint says what the agents see and how they are rewarded
    let ck: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(dir.join("checkpoint.json")).unwrap())
            .unwrap();
    let spec = &ck["spec"];
    assert_eq!(spec["obs_dim"], 8, "{spec}");
    assert_eq!(spec["act_dim"], 1, "{spec}");
    assert_eq!(
        spec["distributed"]["features"]["congestion"], false,
        "{spec}"
    );
    assert_eq!(spec["distributed"]["reward"]["exit_bonus"], 20.0, "{spec}");
    // no reward share (the paper's setting) leaves the checkpoint as it was before the option existed
    assert!(
        spec["distributed"]["reward"].get("share").is_none(),
        "{spec}"
    );
    // the paper's distributed hyperparameters, learning-rate schedule included
    assert_eq!(
        ck["state"]["config"]["gamma"].as_f64().unwrap() as f32,
        0.998
    );
    assert!(
        ck["state"]["config"]["lr_schedule"].is_array(),
        "{}",
        ck["state"]["config"]
    );
    // --keep-checkpoints: one file per checkpoint written, the last equal to checkpoint.json
    let kept = |it: u64| {
        dir.join("checkpoints")
            .join(format!("iteration-{it:05}.json"))
    };
    assert!(kept(1).exists() && kept(2).exists());
    assert_eq!(
        std::fs::read(kept(2)).unwrap(),
        std::fs::read(dir.join("checkpoint.json")).unwrap()
    );

    // resumed to 3 iterations = 3 iterations in one go (wall time aside)
    let out = mapc_with(["train", "--iters", "3", "--json", "--resume"], &dir);
    common::assert_success(&out);
    let straight = tmp("dist-straight");
    common::assert_success(&tiny_distributed_train(&straight, 3));
    assert_eq!(row3(&dir), row3(&straight));
    let (best, best_straight) = (check_best(&dir), check_best(&straight));
    assert_eq!(best["selected"], best_straight["selected"]);
    assert_eq!(best["state"]["model"], best_straight["state"]["model"]);
    assert!(
        row3(&dir)[1] == "1800",
        "simulation steps: {:?}",
        row3(&dir)
    );

    // every AV drives with the policy in the evaluation; the trace marks them as controlled
    let trace = dir.join("trace.csv");
    let out = mapc()
        .args(["eval", "--seeds", "2", "--json", "--trace"])
        .arg(&trace)
        .arg("--policy")
        .arg(&dir)
        .output()
        .unwrap();
    common::assert_success(&out);
    let v: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    assert!(v["outflow"]["mean"].as_f64().unwrap() > 0.0, "{v}");
    assert!(v["comparison"]["outflow"]["p_value"].is_number(), "{v}");
    let csv = std::fs::read_to_string(&trace).unwrap();
    let header: Vec<&str> = csv.lines().next().unwrap().split(',').collect();
    let col = header.iter().position(|&c| c == "controlled").unwrap();
    let controlled: std::collections::HashSet<&str> = csv
        .lines()
        .skip(1)
        .map(|l| l.split(',').collect::<Vec<_>>())
        .filter(|f| f[col] == "true")
        .map(|f| f[1])
        .collect();
    assert!(
        controlled.len() > 5,
        "only {} controlled AVs",
        controlled.len()
    );

    // a checkpoint whose features do not match its observation size is refused, naming the file
    let path = dir.join("checkpoint.json");
    let text = std::fs::read_to_string(&path).unwrap();
    let bad = dir.join("bad.json");
    std::fs::write(
        &bad,
        text.replace("\"congestion\":false", "\"congestion\":true"),
    )
    .unwrap();
    let err = refused_policy(&bad);
    assert!(
        err.contains("bad.json") && err.contains("reads 9 values"),
        "{err}"
    );
    std::fs::remove_dir_all(&dir).ok();
    std::fs::remove_dir_all(&straight).ok();
}

#[test]
fn the_value_net_is_shared_or_separate() {
    // the distributed presets share the policy's layers (the paper's setting)
    let dir = tmp("dist-shared");
    common::assert_success(&tiny_distributed_train(&dir, 1));
    let ck: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(dir.join("checkpoint.json")).unwrap())
            .unwrap();
    let model = &ck["state"]["model"];
    assert_eq!(model["arch"]["shared_value"], true, "{}", model["arch"]);
    assert_eq!(ck["state"]["config"]["shared_value"], true);
    // the policy net alone, with one output more (mean, log-std, value): 8 -> 100 -> 50 -> 25 -> 3
    let trunk = 8 * 100 + 100 + 100 * 50 + 50 + 50 * 25 + 25;
    let params = model["params"].as_array().unwrap().len();
    assert_eq!(params, trunk + 25 * 3 + 3);
    // `--value-net separate` gives the value a net of its own, and its checkpoint does not mention the option
    // (as the centralized checkpoints, whose bytes it keeps)
    let separate = tmp("dist-separate");
    common::assert_success(&tiny_distributed_train_with(
        &separate,
        1,
        &["--value-net", "separate"],
    ));
    let text = std::fs::read_to_string(separate.join("checkpoint.json")).unwrap();
    assert!(!text.contains("shared_value"));
    let ck: serde_json::Value = serde_json::from_str(&text).unwrap();
    // policy 8 -> 100 -> 50 -> 25 -> 2 and value 8 -> 100 -> 50 -> 25 -> 1
    assert_eq!(
        ck["state"]["model"]["params"].as_array().unwrap().len(),
        2 * trunk + 25 * 2 + 2 + 25 + 1
    );
    // both evaluate
    for d in [&dir, &separate] {
        let out = mapc_with(
            [
                "eval",
                "--seeds",
                "1",
                "--json",
                "--no-baseline",
                "--policy",
            ],
            d,
        );
        common::assert_success(&out);
    }
    std::fs::remove_dir_all(&dir).ok();
    std::fs::remove_dir_all(&separate).ok();
}

#[test]
fn a_reward_share_is_kept_in_the_checkpoint() {
    let dir = tmp("dist-share");
    common::assert_success(&tiny_distributed_train_with(
        &dir,
        1,
        &["--reward-share", "0.5"],
    ));
    let ck = read_json(&dir.join("checkpoint.json"));
    assert_eq!(
        ck["spec"]["distributed"]["reward"]["share"], 0.5,
        "{}",
        ck["spec"]
    );
    // a resumed run trains with the share it was started with: the flag cannot change it
    let err = refused(
        mapc()
            .args([
                "train",
                "--distributed",
                "--reward-share",
                "0.2",
                "--resume",
            ])
            .arg(&dir),
    );
    assert!(
        err.contains("--reward-share") && err.contains("--resume"),
        "{err}"
    );
    std::fs::remove_dir_all(&dir).ok();
}

#[test]
fn distributed_flags_are_checked() {
    // a learning-rate schedule must go forward in steps
    let cfg = tmp("schedule").with_extension("toml");
    std::fs::write(&cfg, "lr_schedule = [[0, 5e-4], [0, 1e-4]]\n").unwrap();
    let err = refused(
        mapc()
            .args(["train", "--distributed", "--iters", "1", "--config"])
            .arg(&cfg)
            .arg("-o")
            .arg(tmp("bad-schedule")),
    );
    assert!(err.contains("steps must increase"), "{err}");
    std::fs::remove_file(&cfg).ok();
    // an unknown feature names itself; --reward belongs to centralized policies
    let err = refused(
        mapc()
            .args(["train", "--distributed", "--features", "dist,radar"])
            .args(["--iters", "1", "-o"])
            .arg(tmp("bad-features")),
    );
    assert!(err.contains("radar"), "{err}");
    // a reward share is a fraction
    for bad in ["1.5", "nan", "-1"] {
        let err = refused(
            mapc()
                .args(["train", "--distributed", &format!("--reward-share={bad}")])
                .args(["--iters", "1", "-o"])
                .arg(tmp("bad-share")),
        );
        assert!(
            err.contains("--reward-share") && err.contains("outside the allowed range [0, 1]"),
            "{bad}: {err}"
        );
    }
    let err = refused(mapc().args([
        "train",
        "--distributed",
        "--reward",
        "speed",
        "--iters",
        "1",
    ]));
    assert!(
        err.contains("--reward") && err.contains("--distributed"),
        "{err}"
    );
}

#[test]
fn the_shipped_distributed_policy_beats_the_humans() {
    // policies/simple_merge_distributed.json (docs/results.md): +13.3 % over 100 seeds; on seeds 0-4 it gives
    // 1769.76 veh/h, +13.7 % over the humans (mean actions: the same numbers every run)
    let out = mapc()
        .args(["eval", "--seeds", "5", "--json", "--policy"])
        .arg(common::root().join("policies/simple_merge_distributed.json"))
        .output()
        .unwrap();
    common::assert_success(&out);
    let v: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    let change = v["comparison"]["outflow_change_pct"].as_f64().unwrap();
    assert!(change > 8.0, "{v}");
    assert!(v["speed"]["mean"].as_f64().unwrap() > 14.0, "{v}");
}

#[test]
fn the_shipped_shared_reward_policy_beats_the_humans_and_transfers() {
    // policies/simple_merge_distributed_shared.json (docs/results.md, trained with --reward-share 0.5
    // --count-waiting): +18.2 % over 100 seeds and +9.0 % zero-shot in the I-696 window; on seeds 0-4 (mean
    // actions: the same numbers every run) 1827.36 veh/h, +17.4 %, and +6.5 % in the window
    let policy = "policies/simple_merge_distributed_shared.json";
    let eval = |scenario: &str| eval_json(policy, scenario, "5", &[]);
    let merge = eval("scenarios/simple_merge.toml");
    let change = merge["comparison"]["outflow_change_pct"].as_f64().unwrap();
    assert!(change > 14.0, "{merge}");
    let window = eval("scenarios/i696_window.toml");
    let change = window["comparison"]["outflow_change_pct"].as_f64().unwrap();
    assert!(change > 2.0, "{window}");
}

/// A tiny run on the shipped merge distribution, started from the shipped outflow policy: it trains, starts from
/// that policy's weights, resumes exactly (the draws follow the episodes' seeds), and refuses what does not fit.
#[test]
fn a_merge_distribution_trains_from_a_policy_and_resumes_exactly() {
    let mix = ["--scenario", "scenarios/merge_mix.toml"];
    let train = |dir: &PathBuf, iters: u64, init: bool| {
        let mut c = mapc();
        c.args(["train", "--preset", "fast"]).args(mix);
        if init {
            c.args(["--init", "policies/simple_merge_outflow.json"]);
        }
        c.args([
            "--iters",
            &iters.to_string(),
            "--batch",
            "600",
            "--minibatch",
            "200",
        ])
        .args([
            "--horizon",
            "300",
            "--epochs",
            "2",
            "--checkpoint-every",
            "1",
            "--json",
            "-o",
        ])
        .arg(dir)
        .output()
        .unwrap()
    };
    let dir = tmp("mix");
    common::assert_success(&train(&dir, 2, true));
    let resumed = mapc_with(["train", "--iters", "3", "--json", "--resume"], &dir);
    common::assert_success(&resumed);
    let straight = tmp("mix-straight");
    common::assert_success(&train(&straight, 3, true));
    assert_eq!(row3(&dir), row3(&straight));
    // --init took the shipped weights: a run from scratch differs in its first row
    let scratch = tmp("mix-scratch");
    common::assert_success(&train(&scratch, 1, false));
    let first = |d: &Path| {
        std::fs::read_to_string(d.join("progress.csv"))
            .unwrap()
            .lines()
            .nth(1)
            .unwrap()
            .to_string()
    };
    assert_ne!(
        first(&dir).split(',').nth(3),
        first(&scratch).split(',').nth(3)
    );
    // a policy of another size, and the distributed trainer, are refused
    let other = tmp("mix-other");
    let err = refused(
        mapc()
            .args([
                "train",
                "--preset",
                "fast",
                "--n-av",
                "3",
                "--init",
                "policies/simple_merge_outflow.json",
            ])
            .args(mix)
            .args(["--iters", "1", "-o"])
            .arg(&other),
    );
    assert!(err.contains("does not fit"), "{err}");
    let err = refused(
        mapc()
            .args(["train", "--distributed", "--preset", "fast"])
            .args(mix)
            .args(["--iters", "1", "-o"])
            .arg(tmp("mix-dist")),
    );
    assert!(err.contains("centralized policies only"), "{err}");
    for d in [dir, straight, scratch, other] {
        std::fs::remove_dir_all(d).ok();
    }
}

/// policies/merge_robust.json controls only merges where the main road yields (docs/results.md, "A policy for any
/// merge"): where the main road has priority its AVs drive as humans, bit for bit; in the Simple Merge's regime
/// it gains; a window of a several-window scenario outside that regime is named, and its merge still measured.
#[test]
fn the_robust_policy_is_deployed_only_where_the_main_road_yields() {
    let eval = |scenario: &str, extra: &[&str]| {
        eval_json("policies/merge_robust.json", scenario, "3", extra)
    };
    let arizona = eval("scenarios/merges/arizona_5134463770.toml", &[]);
    assert_eq!(
        arizona["outflow"], arizona["baseline"]["outflow"],
        "{arizona}"
    );
    let reason = arizona["withheld"][0]["reason"].as_str().unwrap();
    assert!(reason.contains("the main road has priority"), "{arizona}");
    // the rule can be lifted: the policy then drives there and differs from the humans
    let lifted = eval(
        "scenarios/merges/arizona_5134463770.toml",
        &["--deploy", "everywhere"],
    );
    assert_ne!(lifted["outflow"], lifted["baseline"]["outflow"], "{lifted}");
    assert!(lifted.get("withheld").is_none(), "{lifted}");
    let merge = eval("simple_merge", &[]);
    assert!(merge.get("withheld").is_none(), "{merge}");
    assert!(
        merge["comparison"]["outflow_change_pct"].as_f64().unwrap() > 14.0,
        "{merge}"
    );
    // I-696 with three merges: J43 yields to its ramp (controlled), J59 and J37 do not (left to the humans)
    let three = eval("scenarios/i696_3merge.toml", &[]);
    let withheld: Vec<&str> = three["withheld"]
        .as_array()
        .unwrap()
        .iter()
        .map(|w| w["window"].as_str().unwrap())
        .collect();
    assert_eq!(
        withheld,
        ["window osm:62339771", "window osm:61860453"],
        "{three}"
    );
    assert_eq!(three["merges"].as_array().unwrap().len(), 3, "{three}");
}

/// policies/merge_robust_congested.json is merge_robust's policy under the rule `simple-merge-regime`: the main
/// road yields, the humans congest the merge, one lane per road (docs/results.md, "Multi-lane windows"). In the
/// multi-lane I-696 window, where merge_robust's right-of-way rule drives and loses, its AVs drive as humans, bit
/// for bit, and the report says why; in the one-lane I-696 window, congested, it drives as merge_robust does.
#[test]
fn the_simple_merge_regime_leaves_the_multi_lane_window_to_the_humans_and_keeps_the_jammed_one() {
    let eval =
        |policy: &str, scenario: &str, extra: &[&str]| eval_json(policy, scenario, "2", extra);
    let congested = "policies/merge_robust_congested.json";
    let lanes = eval(congested, "scenarios/i696_window_lanes.toml", &[]);
    assert_eq!(lanes["deploy"], "simple_merge_regime", "{lanes}");
    assert_eq!(lanes["outflow"], lanes["baseline"]["outflow"], "{lanes}");
    let reason = lanes["withheld"][0]["reason"].as_str().unwrap();
    assert!(reason.contains("has 3 lanes"), "{lanes}");
    // the congestion alone withholds it too: it flows
    let dense = eval(
        congested,
        "scenarios/i696_window_lanes.toml",
        &["--deploy", "main-road-yields-congested"],
    );
    let reason = dense["withheld"][0]["reason"].as_str().unwrap();
    assert!(
        reason.contains("is dense under humans, not congested"),
        "{dense}"
    );
    let one_lane = eval(congested, "scenarios/i696_window.toml", &[]);
    assert!(one_lane.get("withheld").is_none(), "{one_lane}");
    let robust = eval(
        "policies/merge_robust.json",
        "scenarios/i696_window.toml",
        &[],
    );
    assert_eq!(one_lane["outflow"], robust["outflow"]);
    assert_ne!(one_lane["outflow"], one_lane["baseline"]["outflow"]);
}

/// policies/two_lane_merge_jam_lanes_outflow.json (trained with the adjacent lanes in the congested two-lane merge)
/// carries `main-road-yields-congested`: it drives there, and leaves the dense two-lane merge it was not trained in
/// to the humans, naming its regime (docs/results.md, "Multi-lane windows").
#[test]
fn the_congested_two_lane_policy_drives_only_where_the_humans_congest_the_merge() {
    let eval = |scenario: &str| {
        eval_json(
            "policies/two_lane_merge_jam_lanes_outflow.json",
            scenario,
            "2",
            &[],
        )
    };
    let jam = eval("scenarios/two_lane_merge_jam_av.toml");
    assert_eq!(jam["deploy"], "main_road_yields_congested", "{jam}");
    assert!(jam.get("withheld").is_none(), "{jam}");
    assert_ne!(jam["outflow"], jam["baseline"]["outflow"], "{jam}");
    let dense = eval("scenarios/two_lane_merge_av.toml");
    assert_eq!(dense["outflow"], dense["baseline"]["outflow"], "{dense}");
    let reason = dense["withheld"][0]["reason"].as_str().unwrap();
    assert!(
        reason.starts_with("merge J2 (center) is dense under humans, not congested"),
        "{dense}"
    );
}
