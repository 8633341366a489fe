//! `mapc pipeline`: the whole job on a real map, as the sequence of `mapc` commands a user would type. Each
//! command is printed before it runs, so the output doubles as a tutorial. The evaluation comes last, so its
//! table ends the output.

use std::path::{Path, PathBuf};
use std::time::Instant;

/// The paper's I-696 corridor: M-5 into I-96 westbound, joined by I-696 (REFERENCE.md sec. 6).
const I696_VIA: [&str; 3] = ["osm-way:59440544", "osm-way:8667198", "osm-way:8708084"];
/// Where I-696 (way 124433709) joins the corridor.
const I696_MERGE: &str = "osm:61862553";

#[derive(clap::Args)]
pub struct Args {
    /// The map to run on.
    #[arg(default_value = "maps/i696.osm")]
    pub map: PathBuf,
    /// Output folder.
    #[arg(short, long, default_value = "out/pipeline")]
    pub output: PathBuf,
    /// Points the corridor must pass (`mapc simplify --via`); default: the paper's I-696 corridor.
    #[arg(long = "via", value_name = "ID")]
    pub via: Vec<String>,
    /// The merge to cut the transfer window around; default: where I-696 joins.
    #[arg(long, default_value = I696_MERGE)]
    pub junction: String,
    /// The Simple Merge policy evaluated zero-shot in the window.
    #[arg(long, default_value = "policies/simple_merge_outflow.json")]
    pub policy: PathBuf,
    /// Seeds for the baseline and the evaluation.
    #[arg(long, default_value_t = 100)]
    pub seeds: u64,
    /// Print each step's output as JSON.
    #[arg(long)]
    pub json: bool,
}

pub fn run(args: Args) -> anyhow::Result<()> {
    let start = Instant::now();
    let out = &args.output;
    // a map that cannot be read fails before anything is written
    std::fs::metadata(&args.map).map_err(|e| anyhow::anyhow!("{}: {e}", args.map.display()))?;
    std::fs::create_dir_all(out).map_err(|e| anyhow::anyhow!("{}: {e}", out.display()))?;
    let stem = super::simplify::map_stem(&args.map);
    let file = |name: String| path_text(&out.join(name));
    let graph = file(format!("{stem}.graph.json"));
    let corridor = file(format!("{stem}.corridor.graph.json"));
    let window = file(format!("{stem}_window.toml"));
    let trace = file(format!("{stem}_window_human_trace.csv"));
    let seeds = args.seeds.to_string();
    let map = path_text(&args.map);
    let via: Vec<String> = if args.via.is_empty() {
        I696_VIA.iter().map(|s| s.to_string()).collect()
    } else {
        args.via.clone()
    };

    let mut steps: Vec<Vec<String>> = vec![
        cmd(&["import", &map, "-o", &graph]),
        cmd(&["junctions", &graph, "--kind", "merge"]),
        cmd(&["render", &graph, "-o", &file(format!("{stem}.png"))]),
    ];
    let mut simplify = cmd(&["simplify", &map, "-o", &corridor]);
    for v in &via {
        simplify.extend(["--via".to_string(), v.clone()]);
    }
    steps.push(simplify);
    steps.push(cmd(&[
        "window",
        &corridor,
        "--junction",
        &args.junction,
        "--match",
        "simple_merge",
        "-o",
        &window,
        "--render",
        &file(format!("{stem}_window.png")),
    ]));
    steps.push(cmd(&[
        "sim",
        "--scenario",
        &window,
        "--seeds",
        "1",
        "--trace",
        &trace,
    ]));
    steps.push(cmd(&[
        "plot",
        "timespace",
        &trace,
        "-o",
        &file(format!("{stem}_window_timespace.png")),
    ]));
    steps.push(cmd(&[
        "view",
        &window,
        "--policy",
        &path_text(&args.policy),
        "--compare",
        "-o",
        &file(format!("{stem}_window_replay.html")),
    ]));
    steps.push(cmd(&[
        "eval",
        "--policy",
        &path_text(&args.policy),
        "--scenario",
        &window,
        "--seeds",
        &seeds,
    ]));
    if args.json {
        for s in &mut steps {
            if !matches!(s[0].as_str(), "render" | "plot") {
                s.push("--json".to_string());
            }
        }
    }
    for s in steps {
        eprintln!("\n$ mapc {}", s.join(" "));
        crate::run_command_line(&s)?;
    }
    eprintln!(
        "\npipeline done in {:.1} s; outputs in {}",
        start.elapsed().as_secs_f64(),
        out.display()
    );
    Ok(())
}

fn cmd(words: &[&str]) -> Vec<String> {
    words.iter().map(|w| w.to_string()).collect()
}

fn path_text(p: &Path) -> String {
    p.to_string_lossy().into_owned()
}
