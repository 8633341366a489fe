//! The standing hunt for bad-input defects: a fixed-seed corpus of mutated inputs of every kind mapc reads (SUMO
//! nets, OSM XML, OSM PBF, scenario TOML, graph JSON, policy JSON) and of hostile flag values, each run through the
//! binary. Every run must end with exit 0 or 2; a refusal must say why on standard error, with no panic; no run may
//! hang; and a refused command writes nothing. The corpus is the same at every run (the generator below is seeded),
//! so a failure here reproduces with `cargo test --test mutation -- --nocapture`, which prints each case it runs.
//!
//! `MAPC_MUTATION_CASES` sets how many cases each input kind gets (default sized to keep the test near a minute on
//! two cores); `MAPC_MUTATION_SEED` draws another corpus.

mod common;

use common::mutate::{Draw, HOSTILE_NUMBERS, mutate_bytes, mutate_text};
use common::{mapc_command, root, scratch_dir};
use std::path::{Path, PathBuf};
use std::process::Stdio;
use std::time::{Duration, Instant};

/// Where a mutated input goes and how mapc is asked to read it.
struct Kind {
    name: &'static str,
    /// The seed input, from the repository.
    seed_file: &'static str,
    /// The mutated input's file name (its extension tells mapc's readers what it is).
    file_name: &'static str,
    /// Text inputs get token mutations; binary ones byte mutations.
    text: bool,
    /// The command line: `{in}` is the mutated input, `{out}` a path in the case's output folder.
    args: &'static [&'static str],
}

/// A scenario's network file named relative to the scenario, made absolute so that the scenario can be mutated
/// in a scratch folder and still find its graph.
fn absolute_graph(text: &str) -> String {
    let scenarios = root().join("scenarios");
    text.lines()
        .map(|l| match l.strip_prefix("graph = \"") {
            Some(rest) => format!("graph = {:?}", scenarios.join(rest.trim_end_matches('"'))),
            None => l.to_string(),
        })
        .collect::<Vec<_>>()
        .join("\n")
}

/// A SUMO configuration's files made absolute (they are named relative to the configuration, which is mutated in a
/// scratch folder): `net-file`, `route-files` and `additional-files`, each a comma-separated list.
fn absolute_sumo_files(text: &str, folder: &Path) -> String {
    text.lines()
        .map(|l| {
            let option = ["net-file", "route-files", "additional-files"]
                .iter()
                .find(|o| l.trim_start().starts_with(&format!("<{o} value=\"")));
            let Some(o) = option else {
                return l.to_string();
            };
            let files = l.split('"').nth(1).unwrap_or_default();
            let absolute: Vec<String> = files
                .split(',')
                .map(|f| folder.join(f.trim()).display().to_string())
                .collect();
            format!("<{o} value=\"{}\"/>", absolute.join(","))
        })
        .collect::<Vec<_>>()
        .join("\n")
}

const KINDS: &[Kind] = &[
    Kind {
        name: "sumo-net",
        seed_file: "maps/simple_merge.net.xml",
        file_name: "m.net.xml",
        text: true,
        args: &["import", "{in}", "-o", "{out}/g.json"],
    },
    Kind {
        name: "sumo-net-window",
        // a map whose default corridor has merges to cut (the Simple Merge's net has no road of the default classes)
        seed_file: "maps/rongwu.net.xml",
        file_name: "m.net.xml",
        text: true,
        args: &["window", "{in}", "--all", "-o", "{out}/w.toml"],
    },
    Kind {
        name: "sumo-routes",
        seed_file: "scenarios/sumo/highway_ramp/highway-ramp.rou.xml",
        file_name: "r.rou.xml",
        text: true,
        args: &[
            "sim",
            "--net",
            "scenarios/sumo/highway_ramp/highway.net.xml",
            "--routes",
            "{in}",
            "--seeds",
            "1",
            "--json",
        ],
    },
    Kind {
        name: "sumo-trips",
        seed_file: "scenarios/sumo/route_choice/trips.rou.xml",
        file_name: "t.rou.xml",
        text: true,
        args: &[
            "sim",
            "--net",
            "scenarios/sumo/route_choice/diamond.net.xml",
            "--routes",
            "{in}",
            "--seeds",
            "1",
            "--json",
        ],
    },
    Kind {
        name: "sumo-config",
        // a configuration with a net, flows of several types, a ramp meter's static light and induction loops,
        // whose demand ends (with no end, or a negative one, the run lasts as SUMO's would: to the last arrival)
        seed_file: "scenarios/sumo/ramp_metering_1x3/1ramp_1x3.sumocfg",
        file_name: "c.sumocfg",
        text: true,
        args: &[
            "sim",
            "{in}",
            "--seeds",
            "1",
            "--json",
            "--tripinfo-output",
            "{out}/trips/t.xml",
            "--summary-output",
            "{out}/s.xml",
            "--detector-output",
            "{out}/loops",
        ],
    },
    Kind {
        name: "osm-xml",
        seed_file: "maps/a2_braunschweig.osm",
        file_name: "m.osm",
        text: true,
        args: &["import", "{in}", "-o", "{out}/g.json"],
    },
    Kind {
        name: "osm-pbf",
        seed_file: "maps/i696.osm.pbf",
        file_name: "m.osm.pbf",
        text: false,
        args: &["import", "{in}", "-o", "{out}/g.json"],
    },
    Kind {
        name: "scenario",
        seed_file: "scenarios/simple_merge.toml",
        file_name: "s.toml",
        text: true,
        args: &[
            "sim",
            "--scenario",
            "{in}",
            "--seeds",
            "1",
            "--json",
            "--trace",
            "{out}/t.csv",
        ],
    },
    Kind {
        name: "scenario-lanes",
        seed_file: "scenarios/i210_window_lanes.toml",
        file_name: "s.toml",
        text: true,
        args: &["sim", "--scenario", "{in}", "--seeds", "1", "--json"],
    },
    Kind {
        name: "graph",
        seed_file: "scenarios/i696_window.graph.json",
        file_name: "g.graph.json",
        text: true,
        args: &["render", "{in}", "-o", "{out}/g.svg"],
    },
    Kind {
        name: "policy",
        seed_file: "policies/simple_merge_flow.json",
        file_name: "p.json",
        text: true,
        args: &[
            "eval",
            "--policy",
            "{in}",
            "--scenario",
            "simple_merge",
            "--seeds",
            "1",
            "--json",
        ],
    },
];

/// Command lines whose `{n}` takes a hostile number (flags, not files).
const FLAG_LINES: &[&[&str]] = &[
    &[
        "sim",
        "--scenario",
        "simple_merge",
        "--seeds",
        "{n}",
        "--json",
    ],
    &[
        "sim",
        "--scenario",
        "simple_merge",
        "--seeds",
        "1",
        "--first-seed",
        "{n}",
    ],
    &[
        "sim",
        "--scenario",
        "simple_merge",
        "--seeds",
        "1",
        "--threads",
        "{n}",
    ],
    &[
        "eval",
        "--policy",
        "policies/simple_merge_flow.json",
        "--scenario",
        "simple_merge",
        "--seeds",
        "{n}",
    ],
    &[
        "train",
        "--scenario",
        "simple_merge",
        "--n-av",
        "{n}",
        "--preset",
        "fast",
        "--iters",
        "1",
        "--out",
        "{out}/run",
    ],
    &[
        "train",
        "--scenario",
        "simple_merge",
        "--gamma",
        "{n}",
        "--preset",
        "fast",
        "--iters",
        "1",
        "--out",
        "{out}/run",
    ],
    &[
        "eval",
        "--controller",
        "alinea",
        "--scenario",
        "scenarios/sumo/ramp_game_alinea/ramp_alinea.sumocfg",
        "--seeds",
        "1",
        "--alinea-setpoint",
        "{n}",
    ],
    &[
        "eval",
        "--controller",
        "alinea",
        "--scenario",
        "scenarios/sumo/ramp_game_alinea/ramp_alinea.sumocfg",
        "--seeds",
        "1",
        "--alinea-gain",
        "{n}",
    ],
    &[
        "sim",
        "scenarios/sumo/ramp_game_alinea/ramp_alinea.sumocfg",
        "--seeds",
        "1",
        "--av-share",
        "{n}",
        "--detector-output",
        "{out}/loops",
    ],
    &[
        "window",
        "maps/rongwu.net.xml",
        "--all",
        "--n-av",
        "{n}",
        "-o",
        "{out}/w.toml",
    ],
];

/// A case's own limit: far above any honest case's time, far below a hang's.
const CASE_LIMIT: Duration = Duration::from_secs(60);

fn cases_per_kind() -> usize {
    std::env::var("MAPC_MUTATION_CASES")
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(60)
}

fn corpus_seed() -> u64 {
    std::env::var("MAPC_MUTATION_SEED")
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(0x6d61_7063)
}

/// What one run left: its exit code (None: killed by a signal or the case limit), its standard error, its time.
struct Ran {
    code: Option<i32>,
    stderr: String,
    hung: bool,
}

fn run_case(args: &[String]) -> Ran {
    let mut child = mapc_command()
        .args(args)
        .env("MAPC_NO_PROGRESS", "1")
        .stdin(Stdio::null())
        .stdout(Stdio::null())
        .stderr(Stdio::piped())
        .spawn()
        .expect("the mapc binary runs");
    // standard error is read on its own thread so that a chatty run cannot block on a full pipe
    let mut pipe = child.stderr.take().unwrap();
    let reader = std::thread::spawn(move || {
        let mut s = Vec::new();
        std::io::Read::read_to_end(&mut pipe, &mut s).ok();
        String::from_utf8_lossy(&s).into_owned()
    });
    let start = Instant::now();
    let mut hung = false;
    let status = loop {
        if let Some(status) = child.try_wait().unwrap() {
            break status;
        }
        if start.elapsed() > CASE_LIMIT {
            child.kill().ok();
            hung = true;
            break child.wait().unwrap();
        }
        std::thread::sleep(Duration::from_millis(5));
    };
    Ran {
        code: status.code(),
        stderr: reader.join().unwrap(),
        hung,
    }
}

/// The files and folders a case left in its output folder (its input excepted).
fn left_behind(dir: &Path, input: &Path) -> Vec<PathBuf> {
    let mut left = Vec::new();
    let mut stack = vec![dir.to_path_buf()];
    while let Some(d) = stack.pop() {
        for e in std::fs::read_dir(&d).into_iter().flatten().flatten() {
            let p = e.path();
            if p.is_dir() {
                left.push(p.clone());
                stack.push(p);
            } else if p != input {
                left.push(p);
            }
        }
    }
    left
}

/// Checks one case's run; returns what went wrong, if anything.
fn judge(ran: &Ran, out_dir: &Path, input: &Path) -> Option<String> {
    if ran.hung {
        return Some(format!("no answer within {CASE_LIMIT:?}"));
    }
    if ran.stderr.contains("panicked") {
        return Some(format!("panicked: {}", ran.stderr));
    }
    match ran.code {
        Some(0) => None,
        Some(2) => {
            if ran.stderr.trim().is_empty() {
                return Some("exit 2 with no message".into());
            }
            let left = left_behind(out_dir, input);
            (!left.is_empty()).then(|| format!("refused, yet left {left:?}: {}", ran.stderr))
        }
        other => Some(format!("exit {other:?}: {}", ran.stderr)),
    }
}

fn fill(args: &[&str], input: &Path, out: &Path, n: &str) -> Vec<String> {
    args.iter()
        .map(|a| {
            a.replace("{in}", input.to_str().unwrap())
                .replace("{out}", out.to_str().unwrap())
                .replace("{n}", n)
        })
        .collect()
}

#[test]
fn mutated_inputs_and_flags_end_in_exit_0_or_2() {
    let mut d = Draw(corpus_seed());
    let base = scratch_dir("mutation");
    let mut failures = Vec::new();
    let mut runs = 0;
    // per kind of input: runs, exit 0, exit 2 (printed for docs/reliability.md)
    let mut tally: Vec<(String, u32, u32, u32)> = Vec::new();
    let mut count = |kind: &str, code: Option<i32>| {
        if tally.last().is_none_or(|t| t.0 != kind) {
            tally.push((kind.to_string(), 0, 0, 0));
        }
        let t = tally.last_mut().unwrap();
        t.1 += 1;
        match code {
            Some(0) => t.2 += 1,
            Some(2) => t.3 += 1,
            _ => {}
        }
    };
    let started = Instant::now();
    for kind in KINDS {
        let mut seed = std::fs::read(root().join(kind.seed_file)).unwrap();
        if kind.seed_file.ends_with(".toml") {
            seed = absolute_graph(std::str::from_utf8(&seed).unwrap()).into_bytes();
        }
        if kind.seed_file.ends_with(".sumocfg") {
            let folder = root().join(kind.seed_file);
            let folder = folder.parent().unwrap();
            seed = absolute_sumo_files(std::str::from_utf8(&seed).unwrap(), folder).into_bytes();
        }
        for case in 0..cases_per_kind() {
            let dir = base.join(format!("{}-{case}", kind.name));
            std::fs::create_dir_all(&dir).unwrap();
            let input = dir.join(kind.file_name);
            let what = if kind.text {
                let (text, what) = mutate_text(std::str::from_utf8(&seed).unwrap(), &mut d);
                std::fs::write(&input, text).unwrap();
                what
            } else {
                let (bytes, what) = mutate_bytes(&seed, &mut d);
                std::fs::write(&input, bytes).unwrap();
                what
            };
            let args = fill(kind.args, &input, &dir, "");
            println!("{} {case}: {what}: mapc {}", kind.name, args.join(" "));
            let ran = run_case(&args);
            runs += 1;
            count(kind.name, ran.code);
            if let Some(wrong) = judge(&ran, &dir, &input) {
                failures.push(format!("{} case {case} ({what}): {wrong}", kind.name));
            }
        }
    }
    for (i, line) in FLAG_LINES.iter().enumerate() {
        for case in 0..cases_per_kind().div_ceil(3) {
            let dir = base.join(format!("flags-{i}-{case}"));
            std::fs::create_dir_all(&dir).unwrap();
            let n = *d.pick(HOSTILE_NUMBERS);
            let args = fill(line, Path::new(""), &dir, n);
            println!("flags {i} {case}: mapc {}", args.join(" "));
            let ran = run_case(&args);
            runs += 1;
            count(&format!("flags: mapc {}", line[0]), ran.code);
            // a flag value mapc took may have run a whole (short) job: only a refusal must leave nothing
            if let Some(wrong) = judge(&ran, &dir, Path::new("")) {
                failures.push(format!("flags `{}` with `{n}`: {wrong}", args.join(" ")));
            }
        }
    }
    println!("| input | runs | exit 0 | exit 2 |\n|---|---|---|---|");
    for (kind, n, ok, refused) in &tally {
        println!("| {kind} | {n} | {ok} | {refused} |");
    }
    println!("{runs} runs in {:.1?}", started.elapsed());
    assert!(
        failures.is_empty(),
        "{} of {runs} mutated runs went wrong:\n{}",
        failures.len(),
        failures.join("\n")
    );
    std::fs::remove_dir_all(base).ok();
}

/// The judge itself can fail: a panic, a crash, a hang, a silent refusal and a refusal that left a file are each
/// caught (a test that cannot fail would prove nothing above).
#[test]
fn the_judge_catches_each_kind_of_wrong_answer() {
    let dir = scratch_dir("mutation-judge");
    let input = dir.join("in.toml");
    std::fs::write(&input, "x").unwrap();
    let ran = |code: Option<i32>, stderr: &str, hung: bool| Ran {
        code,
        stderr: stderr.to_string(),
        hung,
    };
    assert!(judge(&ran(Some(0), "", false), &dir, &input).is_none());
    assert!(
        judge(
            &ran(Some(2), "error: x.toml: line 1: bad", false),
            &dir,
            &input
        )
        .is_none()
    );
    for wrong in [
        ran(Some(101), "thread 'main' panicked at src/x.rs:1:1", false),
        ran(None, "", false),
        ran(
            Some(134),
            "memory allocation of 8000000000 bytes failed",
            false,
        ),
        ran(None, "", true),
        ran(Some(2), "  ", false),
        ran(Some(1), "error", false),
    ] {
        assert!(
            judge(&wrong, &dir, &input).is_some(),
            "{:?} {}",
            wrong.code,
            wrong.stderr
        );
    }
    // an empty folder left by a refusal is caught too
    std::fs::create_dir(dir.join("loops")).unwrap();
    assert!(judge(&ran(Some(2), "error: refused", false), &dir, &input).is_some());
    std::fs::remove_dir(dir.join("loops")).unwrap();
    std::fs::write(dir.join("out.toml"), "half").unwrap();
    assert!(judge(&ran(Some(2), "error: refused", false), &dir, &input).is_some());
    std::fs::remove_dir_all(dir).unwrap();
}
