//! `mapc pipeline`: the whole job on a real map, as the sequence of `mapc` commands a user would type. Each
//! command is printed before it runs, so the output doubles as a tutorial. Each seed runs once: the evaluation's
//! own runs of one seed write the humans' and the policy's traces, which the time-space diagram and the replay
//! then draw (with `--json`, the evaluation's report is the last JSON document printed).
//!
//! The paper's corridor and merge (`--via`, `--junction`) belong to the shipped I-696 map: they are the defaults
//! only where the imported map has those roads and that junction. On any other map the corridor is `mapc
//! simplify`'s default route and a window is cut at every merge of it that fits (`mapc window --all --fit`); the
//! pipeline says which it chose.
//!
//! The policy evaluated is built into mapc, so the pipeline runs from any folder: the Simple Merge policy on the
//! paper's map (its results as published), `merge_robust_congested` on any other, whose rule drives the AVs only at
//! merges in the Simple Merge's regime and leaves the others to the humans (the Simple Merge policy, which has no
//! rule, loses on merges unlike the one it was trained on). The copy used is written to the output folder, so the
//! printed commands run as shown.
//!
//! With `--keep-lanes` the same job runs multi-lane: the corridor keeps every lane (`mapc simplify
//! --keep-lanes`), the window is cut from it with its lanes, vehicles change lanes (LC2013), the time-space
//! diagram draws every lane (or `--lane N`), and the outputs are named `<map>_lanes*` so that they sit beside the
//! one-lane run's.

use std::path::{Path, PathBuf};
use std::time::Instant;

/// The paper's I-696 corridor: M-5 into I-96 westbound, joined by I-696 (docs/reference.md sec. 6).
const I696_VIA: [&str; 3] = ["osm-way:59440544", "osm-way:8667198", "osm-way:8708084"];
/// Where I-696 (way 124433709) joins the corridor.
const I696_MERGE: &str = "osm:61862553";

/// A shipped policy, built into the binary.
struct ShippedPolicy {
    file_name: &'static str,
    bytes: &'static [u8],
}

/// The paper's policy, evaluated on the paper's map.
const PAPER_POLICY: ShippedPolicy = ShippedPolicy {
    file_name: "simple_merge_outflow.json",
    bytes: include_bytes!("../../policies/simple_merge_outflow.json"),
};
/// The policy for any other map: its rule (`simple-merge-regime`) leaves every merge unlike the Simple Merge's to
/// the humans.
const OTHER_MAP_POLICY: ShippedPolicy = ShippedPolicy {
    file_name: "merge_robust_congested.json",
    bytes: include_bytes!("../../policies/merge_robust_congested.json"),
};

#[derive(clap::Args)]
pub struct Args {
    /// The map to run on.
    #[arg(default_value = "maps/i696.osm")]
    pub map: PathBuf,
    /// Output folder.
    #[arg(short, long, default_value = "out/pipeline")]
    pub output: PathBuf,
    /// Points the corridor must pass (`mapc simplify --via`); default: the paper's I-696 corridor on the I-696
    /// map, `mapc simplify`'s default route on any other.
    #[arg(long = "via", value_name = "ID")]
    pub via: Vec<String>,
    /// The merge to cut the transfer window around; default: where I-696 joins on the I-696 map, a window at
    /// every merge that fits (`mapc window --all --fit`) on any other.
    #[arg(long)]
    pub junction: Option<String>,
    /// The policy evaluated zero-shot in the window; default: one built into mapc (written to the output folder),
    /// the Simple Merge policy (policies/simple_merge_outflow.json) on the paper's I-696 map,
    /// policies/merge_robust_congested.json on any other (its rule leaves merges unlike the Simple Merge's to the
    /// humans).
    #[arg(long)]
    pub policy: Option<PathBuf>,
    /// Seeds for the baseline and the evaluation (1 to 100 000); default 100, fewer (at least 10) where the
    /// window's corridor is so long that 100 would take the job past a few minutes on two cores, said when so.
    #[arg(long, value_parser = super::flags::seeds())]
    pub seeds: Option<u64>,
    /// Keep every lane of the corridor (`mapc simplify --keep-lanes`): the whole job multi-lane, with lane changes.
    #[arg(long)]
    pub keep_lanes: bool,
    /// Draw only lane N (0 rightmost) in the time-space diagram; default every lane.
    #[arg(long, value_name = "N", value_parser = super::flags::lane())]
    pub lane: Option<u8>,
    /// Print each step's output as JSON.
    #[arg(long)]
    pub json: bool,
}

pub fn run(args: Args) -> anyhow::Result<()> {
    let start = Instant::now();
    // the steps ask for the humans' runs of the same seeds (the window's regime, the deployment rule's, the
    // evaluation's baseline): each is run once
    mapc_sim::keep_runs();
    // the evaluation runs at least these seeds: the window's regime report may run some beside its own
    let eval_seeds = args.seeds.unwrap_or(FEWEST_AUTO_SEEDS);
    mapc_sim::will_run(&(0..eval_seeds).collect::<Vec<u64>>());
    let out = &args.output;
    // a map that cannot be read fails before anything is written
    std::fs::metadata(&args.map).map_err(|e| anyhow::anyhow!("{}: {e}", args.map.display()))?;
    // the output folder is made by the import's write: a map refused there leaves no folder behind
    mapc_graph::check_folder_creatable(out)
        .map_err(|e| anyhow::anyhow!("{}: {e}", out.display()))?;
    let map_stem = super::common::map_stem(&args.map);
    let file = |name: String| path_text(&out.join(name));
    let graph = file(format!("{map_stem}.graph.json"));
    // what follows the import is named apart when it keeps the lanes
    let stem = if args.keep_lanes {
        format!("{map_stem}_lanes")
    } else {
        map_stem.clone()
    };
    let corridor = file(format!("{stem}.corridor.graph.json"));
    let window = file(format!("{stem}_window.toml"));
    let human_trace = file(format!("{stem}_window_human_trace.csv"));
    let policy_trace = file(format!("{stem}_window_policy_trace.csv"));
    let map = path_text(&args.map);

    let mut first_steps: Vec<Vec<String>> = vec![
        cmd(&["import", &map, "-o", &graph]),
        cmd(&["junctions", &graph, "--kind", "merge"]),
        cmd(&["render", &graph, "-o", &file(format!("{map_stem}.png"))]),
    ];
    if args.json {
        for s in &mut first_steps[..2] {
            s.push("--json".to_string());
        }
    }
    for s in first_steps {
        run_step(&s)?;
    }
    // the imported graph tells whether the paper's corridor applies
    let paper_map = is_paper_map(&mapc_graph::LaneGraph::load(Path::new(&graph))?);
    let via: Vec<String> = match (args.via.is_empty(), paper_map) {
        (false, _) => args.via.clone(),
        (true, true) => I696_VIA.iter().map(|s| s.to_string()).collect(),
        (true, false) => Vec::new(),
    };
    let junction = match (&args.junction, paper_map) {
        (Some(j), _) => Some(j.clone()),
        (None, true) => Some(I696_MERGE.to_string()),
        (None, false) => None,
    };
    let policy = match &args.policy {
        Some(p) => p.clone(),
        None => {
            let shipped = if paper_map {
                PAPER_POLICY
            } else {
                OTHER_MAP_POLICY
            };
            let path = out.join(shipped.file_name);
            mapc_graph::write_atomically(&path, shipped.bytes)
                .map_err(|e| anyhow::anyhow!("{}: {e}", path.display()))?;
            path
        }
    };
    let policy = path_text(&policy);
    if !paper_map {
        eprintln!(
            "\npipeline: {map} is not the paper's I-696 map (its --via roads and --junction merge apply there only), so: {}; {}; {}",
            if via.is_empty() {
                "the corridor is `mapc simplify`'s default route".to_string()
            } else {
                format!("the corridor passes --via {}", via.join(", "))
            },
            match &junction {
                Some(j) => format!("the window is cut at --junction {j}"),
                None => "a window is cut at every merge of it that fits, fitted to what the map has (`mapc window --all --fit`)"
                    .to_string(),
            },
            if args.policy.is_some() {
                format!("the policy is --policy {policy}")
            } else {
                format!(
                    "the policy is mapc's merge_robust_congested ({policy}): its rule drives the AVs only at merges \
                     like the Simple Merge's (the main road yields, the humans congest it, one lane on every road) and \
                     leaves the others to the humans, where the Simple Merge policy, trained on one merge, loses"
                )
            }
        );
    }

    let mut steps: Vec<Vec<String>> = Vec::new();
    let mut simplify = cmd(&["simplify", &map, "-o", &corridor]);
    for v in &via {
        simplify.extend(["--via".to_string(), v.clone()]);
    }
    if args.keep_lanes {
        simplify.push("--keep-lanes".to_string());
    }
    steps.push(simplify);
    let mut window_step = cmd(&["window", &corridor]);
    match &junction {
        Some(j) => window_step.extend(["--junction".to_string(), j.clone()]),
        None => window_step.extend(["--all".to_string(), "--fit".to_string()]),
    }
    window_step.extend(cmd(&[
        "--match",
        "simple_merge",
        "-o",
        &window,
        "--render",
        &file(format!("{stem}_window.png")),
    ]));
    steps.push(window_step);
    run_steps(&mut steps, args.json)?;
    let seeds = match args.seeds {
        Some(n) => n,
        None => auto_seeds(&window)?,
    }
    .to_string();
    // the evaluation's own runs of one seed (the first, or the first no earlier step ran where the policy leaves
    // every window to the humans) are the traces the plot and the replay draw: each seed runs once in the job
    steps.push(cmd(&[
        "eval",
        "--policy",
        &policy,
        "--scenario",
        &window,
        "--seeds",
        &seeds,
        "--trace",
        &policy_trace,
        "--human-trace",
        &human_trace,
    ]));
    let mut plot = cmd(&[
        "plot",
        "timespace",
        &human_trace,
        "-o",
        &file(format!("{stem}_window_timespace.png")),
    ]);
    if let Some(lane) = args.lane {
        plot.extend(["--lane".to_string(), lane.to_string()]);
    }
    steps.push(plot);
    steps.push(cmd(&[
        "view",
        &window,
        "--trace",
        &human_trace,
        "--trace",
        &policy_trace,
        "-o",
        &file(format!("{stem}_window_replay.html")),
    ]));
    run_steps(&mut steps, args.json)?;
    eprintln!(
        "\npipeline done in {:.1} s; outputs in {}",
        start.elapsed().as_secs_f64(),
        out.display()
    );
    Ok(())
}

/// Whether a map is the shipped I-696 extract the paper's route is given for: it has the roads and the merge.
fn is_paper_map(g: &mapc_graph::LaneGraph) -> bool {
    I696_VIA.iter().all(|v| g.find_roads(v).is_ok()) && g.find_junction(I696_MERGE).is_ok()
}

/// Runs `steps` in order (with `--json` where a step prints a report), leaving `steps` empty.
fn run_steps(steps: &mut Vec<Vec<String>>, json: bool) -> anyhow::Result<()> {
    for mut s in steps.drain(..) {
        // the evaluation's report stays the last JSON document printed
        if json && !matches!(s[0].as_str(), "render" | "plot" | "view") {
            s.push("--json".to_string());
        }
        run_step(&s)?;
    }
    Ok(())
}

/// Vehicle-steps the pipeline's evaluation may take by default (the policy's and the humans' runs together):
/// about two minutes on two cores at the multi-lane simulator's speed (docs/perf_sim.md).
const EVAL_BUDGET_VEHICLE_STEPS: f64 = 4.0e8;
/// The evaluation's default seeds, and the fewest it takes where a corridor is long.
const DEFAULT_SEEDS: u64 = 100;
const FEWEST_AUTO_SEEDS: u64 = 10;

/// The evaluation's seeds when none are asked: [`DEFAULT_SEEDS`], fewer where one seed's runs (the scenario's
/// estimated vehicle-steps, the same on every machine) would take the job past [`EVAL_BUDGET_VEHICLE_STEPS`].
fn auto_seeds(window: &str) -> anyhow::Result<u64> {
    let rs = mapc_scenario::ResolvedScenario::load(window)?;
    let fill_s = mapc_scenario::timing::HorizonFit::of_resolved(&rs).fill_s;
    let (steps, vehicles) = mapc_scenario::bounds::scenario_work(&rs.scenario, fill_s);
    let per_seed = 2.0 * steps as f64 * vehicles;
    let fits = (EVAL_BUDGET_VEHICLE_STEPS / per_seed).floor() as u64;
    let seeds = fits.clamp(FEWEST_AUTO_SEEDS, DEFAULT_SEEDS);
    if seeds < DEFAULT_SEEDS {
        eprintln!(
            "
pipeline: one seed of this window is about {:.1e} vehicle-steps (some {vehicles:.0} vehicles over \
             {steps} steps), so the evaluation takes {seeds} seeds, not {DEFAULT_SEEDS}, to end within minutes; \
             `--seeds {DEFAULT_SEEDS}` for the full evaluation",
            steps as f64 * vehicles
        );
    }
    Ok(seeds)
}

/// Print a step as the command a user would type, then run it.
fn run_step(words: &[String]) -> anyhow::Result<()> {
    eprintln!("\n$ mapc {}", words.join(" "));
    let start = Instant::now();
    crate::run_command_line(words)?;
    eprintln!("({:.1} s)", start.elapsed().as_secs_f64());
    Ok(())
}

fn cmd(words: &[&str]) -> Vec<String> {
    words.iter().map(|w| w.to_string()).collect()
}

fn path_text(p: &Path) -> String {
    p.to_string_lossy().into_owned()
}
