//! A fuzz harness for mapc's readers, run in-process for as long as asked (no nightly toolchain needed, unlike
//! `cargo fuzz`): it mutates the shipped inputs of each kind (SUMO net, OSM XML, OSM PBF, scenario TOML, graph
//! JSON, policy JSON, a SUMO user's route and additional files), feeds each mutant to the reader as the binary would, and counts the answers. A panic or a
//! read slower than `--limit-s` is a finding: its input is kept under `--out` to reproduce it. A scenario that
//! loads is also simulated for a short horizon (panics of the simulator are findings too).
//!
//! ```text
//! cargo run --release --example fuzz_readers -- --seconds 600 --out target/fuzz
//! ```
//!
//! It prints one row per kind (inputs tried, accepted, refused, panics, hangs); docs/reliability.md keeps the
//! figures of the runs made before each release.

#[path = "../tests/common/mutate.rs"]
mod mutate;

use mutate::{Draw, mutate_bytes, mutate_text};
use std::panic::AssertUnwindSafe;
use std::path::{Path, PathBuf};
use std::sync::mpsc;
use std::time::{Duration, Instant};

#[derive(Clone, Copy, Debug, PartialEq)]
enum Kind {
    SumoNet,
    OsmXml,
    OsmPbf,
    Scenario,
    Graph,
    Policy,
    /// A SUMO route file, run on its own net (SUMO's ramp game).
    SumoRoutes,
    /// A SUMO additional file (a ramp meter's light and induction loops), run with its net and routes.
    SumoAdditional,
}

const KINDS: [(Kind, &str, &str); 10] = [
    (Kind::SumoNet, "sumo-net", "maps/simple_merge.net.xml"),
    // a city's net: sidewalks closed to cars, crossings, a light
    (
        Kind::SumoNet,
        "sumo-net-city",
        "scenarios/sumo/resco_ingolstadt1/ingolstadt1.net.xml",
    ),
    (Kind::OsmXml, "osm-xml", "maps/a2_braunschweig.osm"),
    (Kind::OsmPbf, "osm-pbf", "maps/i696.osm.pbf"),
    (Kind::Scenario, "scenario", "scenarios/simple_merge.toml"),
    (
        Kind::Scenario,
        "scenario-lanes",
        "scenarios/i210_window_lanes.toml",
    ),
    (Kind::Graph, "graph", "scenarios/i696_window.graph.json"),
    (
        Kind::Policy,
        "policy",
        "policies/simple_merge_distributed.json",
    ),
    (
        Kind::SumoRoutes,
        "sumo-routes",
        "scenarios/sumo/ramp_game/ramp/ramp.rou.xml",
    ),
    (
        Kind::SumoAdditional,
        "sumo-additional",
        "scenarios/sumo/ramp_metering_1x3/1ramp_1x3.add.xml",
    ),
];

/// A short run of a scenario that loaded (400 steps after at most 100 of warm-up): the point is what the
/// simulator does with what the reader let through.
fn run_short(rs: &mapc_scenario::ResolvedScenario) -> Result<(), String> {
    let mut spec = mapc_sim::spec_from_scenario(rs).map_err(|e| e.to_string())?;
    spec.horizon_steps = spec.horizon_steps.min(400);
    spec.warmup_steps = spec.warmup_steps.min(100);
    mapc_sim::Simulation::from_spec(spec, 0)
        .and_then(|mut s| s.run())
        .map(drop)
        .map_err(|e| e.to_string())
}

/// Which file of a SUMO scenario the mutant is.
enum SumoPart {
    /// The route file.
    Routes,
    /// The additional file, beside these route files.
    Additional { routes: &'static [&'static str] },
}

/// The SUMO scenario of `net` with the mutant written as its `part`, read as `mapc sim --net --routes
/// --additional` reads it, then run briefly.
fn read_sumo(input: &[u8], scratch: &Path, net: &str, part: SumoPart) -> Result<(), String> {
    let path = scratch.join(match part {
        SumoPart::Routes => "r.rou.xml",
        SumoPart::Additional { .. } => "a.add.xml",
    });
    std::fs::write(&path, input).map_err(|e| e.to_string())?;
    let (routes, additional) = match part {
        SumoPart::Routes => (vec![path], vec![]),
        SumoPart::Additional { routes } => (routes.iter().map(PathBuf::from).collect(), vec![path]),
    };
    let options = mapc_scenario::sumo::ReadOptions::default();
    let read = mapc_scenario::sumo::from_files(Path::new(net), &routes, &additional, &options)
        .map_err(|e| e.to_string())?;
    let rs = mapc_scenario::ResolvedScenario::from_sumo(read, net).map_err(|e| e.to_string())?;
    run_short(&rs)
}

#[derive(Default)]
struct Tally {
    tried: u64,
    accepted: u64,
    refused: u64,
    panics: u64,
    hangs: u64,
}

/// Reads `input` as mapc reads a file of `kind`; Ok(()) when accepted, Err(message) when refused.
fn read(kind: Kind, input: &[u8], scratch: &Path) -> Result<(), String> {
    use mapc_import::{ImportOptions, MapFormat, import_bytes};
    let text = || std::str::from_utf8(input).map_err(|e| e.to_string());
    match kind {
        Kind::SumoNet => import_bytes(
            input,
            MapFormat::SumoNet,
            "m.net.xml",
            &ImportOptions::default(),
        )
        .map(drop)
        .map_err(|e| e.to_string()),
        Kind::OsmXml => import_bytes(input, MapFormat::OsmXml, "m.osm", &ImportOptions::default())
            .map(drop)
            .map_err(|e| e.to_string()),
        Kind::OsmPbf => import_bytes(
            input,
            MapFormat::OsmPbf,
            "m.osm.pbf",
            &ImportOptions::default(),
        )
        .map(drop)
        .map_err(|e| e.to_string()),
        Kind::Graph => mapc_graph::LaneGraph::from_json(text()?, Path::new("g.graph.json"))
            .map(drop)
            .map_err(|e| e.to_string()),
        Kind::Scenario => {
            let scenario = mapc_scenario::Scenario::from_toml(text()?, Path::new("s.toml"))
                .map_err(|e| e.to_string())?;
            let rs = mapc_scenario::ResolvedScenario::resolve(
                scenario,
                Path::new("scenarios"),
                "s.toml",
            )
            .map_err(|e| e.to_string())?;
            // (a graph named by the scenario is looked for in scenarios/)
            run_short(&rs)
        }
        Kind::SumoRoutes => read_sumo(
            input,
            scratch,
            "scenarios/sumo/ramp_game/ramp/ramp.net.xml",
            SumoPart::Routes,
        ),
        Kind::SumoAdditional => read_sumo(
            input,
            scratch,
            "scenarios/sumo/ramp_metering_1x3/1ramp_1x3.net.xml",
            SumoPart::Additional {
                routes: &["scenarios/sumo/ramp_metering_1x3/1ramp_1x3.rou.xml"],
            },
        ),
        Kind::Policy => {
            let path = scratch.join("p.json");
            std::fs::write(&path, input).map_err(|e| e.to_string())?;
            mapc_rl::checkpoint::Checkpoint::load(&path)
                .map(drop)
                .map_err(|e| e.to_string())
        }
    }
}

struct Options {
    seconds: u64,
    seed: u64,
    limit: Duration,
    out: PathBuf,
    only: Option<String>,
}

fn options() -> Options {
    let mut o = Options {
        seconds: 60,
        seed: 1,
        limit: Duration::from_secs(20),
        out: PathBuf::from("target/fuzz"),
        only: None,
    };
    let args: Vec<String> = std::env::args().skip(1).collect();
    let mut i = 0;
    while i + 1 < args.len() {
        let v = &args[i + 1];
        let num = || {
            v.parse::<u64>()
                .unwrap_or_else(|_| panic!("{}: not a number: {v}", args[i]))
        };
        match args[i].as_str() {
            "--seconds" => o.seconds = num(),
            "--seed" => o.seed = num(),
            "--limit-s" => o.limit = Duration::from_secs(num()),
            "--out" => o.out = PathBuf::from(v),
            "--kind" => o.only = Some(v.clone()),
            other => panic!("unknown option {other} (--seconds, --seed, --limit-s, --out, --kind)"),
        }
        i += 2;
    }
    o
}

fn main() {
    let o = options();
    std::fs::create_dir_all(&o.out).expect("the output folder can be made");
    // the readers' own panics are findings, not noise on the terminal
    std::panic::set_hook(Box::new(|_| {}));
    let kinds: Vec<_> = KINDS
        .iter()
        .filter(|(_, name, _)| o.only.as_deref().is_none_or(|k| k == *name))
        .collect();
    let seeds: Vec<Vec<u8>> = kinds
        .iter()
        .map(|(_, _, file)| {
            std::fs::read(file)
                .unwrap_or_else(|e| panic!("{file}: {e} (run from the repository root)"))
        })
        .collect();
    let mut tallies: Vec<Tally> = kinds.iter().map(|_| Tally::default()).collect();
    let mut d = Draw(o.seed);
    let until = Instant::now() + Duration::from_secs(o.seconds);
    let mut hung = false;
    while Instant::now() < until && !hung {
        let k = d.below(kinds.len());
        let (kind, name, _) = *kinds[k];
        // one to four mutations in a row: single changes rarely get past a reader's first checks
        let mut input = seeds[k].clone();
        let mut what = Vec::new();
        for _ in 0..1 + d.below(4) {
            if input.is_empty() {
                break;
            }
            let w;
            (input, w) = match std::str::from_utf8(&input) {
                Ok(text) if kind != Kind::OsmPbf => {
                    let (t, w) = mutate_text(text, &mut d);
                    (t.into_bytes(), w)
                }
                _ => mutate_bytes(&input, &mut d),
            };
            what.push(w);
        }
        let t = &mut tallies[k];
        t.tried += 1;
        let scratch = o.out.join(format!("scratch-{name}"));
        std::fs::create_dir_all(&scratch).ok();
        // the read runs on its own thread so that a hang is seen (and the harness stops after keeping it)
        let (tx, rx) = mpsc::channel();
        let job_input = input.clone();
        std::thread::spawn(move || {
            let r = std::panic::catch_unwind(AssertUnwindSafe(|| read(kind, &job_input, &scratch)));
            tx.send(r).ok();
        });
        let keep = |tag: &str, n: u64| {
            let path = o.out.join(format!("{tag}-{name}-{n}"));
            std::fs::write(&path, &input).ok();
            std::fs::write(path.with_extension("txt"), what.join("\n")).ok();
            eprintln!(
                "{tag}: {name}: {} (input kept in {})",
                what.join("; "),
                path.display()
            );
        };
        match rx.recv_timeout(o.limit) {
            Ok(Ok(Ok(()))) => t.accepted += 1,
            Ok(Ok(Err(_))) => t.refused += 1,
            Ok(Err(_)) => {
                t.panics += 1;
                keep("panic", t.panics);
            }
            Err(_) => {
                t.hangs += 1;
                keep("hang", t.hangs);
                hung = true;
            }
        }
    }
    println!("| input | tried | accepted | refused | panics | hangs |");
    println!("|---|---|---|---|---|---|");
    for ((_, name, _), t) in kinds.iter().zip(&tallies) {
        println!(
            "| {name} | {} | {} | {} | {} | {} |",
            t.tried, t.accepted, t.refused, t.panics, t.hangs
        );
    }
    if tallies.iter().any(|t| t.panics + t.hangs > 0) {
        std::process::exit(1);
    }
}
