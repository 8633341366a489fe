//! What the commands share: loading a scenario (with the built-in fallback) or any map, the trace writer, the
//! thread pool, the regime and lanes lines, and output names. Commands use this module, never one another.

use anyhow::Context;
use mapc_graph::LaneGraph;
use mapc_scenario::ResolvedScenario;
use mapc_scenario::transform::SimplifyOptions;
use mapc_sim::TRACE_HEADER;
use std::io::Write;
use std::path::{Path, PathBuf};

/// Which seeds a command runs, and on how many threads (`mapc sim`, `mapc eval`).
#[derive(clap::Args, Clone, Debug)]
pub struct SeedArgs {
    /// Number of seeds (seeds first_seed .. first_seed + N), 1 to 100 000.
    #[arg(long, default_value_t = 100, value_parser = super::flags::seeds())]
    pub seeds: u64,
    /// First seed (at most 2^64 - 1 - 100 000, so that every seed fits in 64 bits).
    #[arg(long, default_value_t = 0, value_parser = super::flags::first_seed())]
    pub first_seed: u64,
    /// Worker threads, 1 to 1024 (default: all cores). Results do not depend on it.
    #[arg(long, value_parser = super::flags::threads())]
    pub threads: Option<usize>,
}

impl SeedArgs {
    pub fn seeds(&self) -> Vec<u64> {
        (self.first_seed..self.first_seed + self.seeds).collect()
    }
}

/// The thread pool of a command's runs: `threads` workers, or one per core.
pub fn thread_pool(threads: Option<usize>) -> anyhow::Result<rayon::ThreadPool> {
    Ok(rayon::ThreadPoolBuilder::new()
        .num_threads(threads.unwrap_or(0))
        .build()?)
}

/// `--threads` for a command whose library runs on rayon's global pool (training, evaluation); the first call
/// of a process sets it (a second, as `mapc bench --train` after its own runs, keeps the first).
pub fn set_global_threads(threads: Option<usize>) {
    if let Some(t) = threads {
        rayon::ThreadPoolBuilder::new()
            .num_threads(t)
            .build_global()
            .ok();
    }
}

/// Used when the default scenario file is absent (running outside the repository).
const BUILTIN_FALLBACK: &str = "simple_merge";

pub const DEFAULT_SCENARIO: &str = "scenarios/simple_merge.toml";

/// Load a scenario by file or built-in name; the default file falls back to the built-in Simple Merge.
pub fn load_scenario(name: &str) -> anyhow::Result<ResolvedScenario> {
    let name = if name == DEFAULT_SCENARIO && !Path::new(name).exists() {
        BUILTIN_FALLBACK
    } else {
        name
    };
    ResolvedScenario::load(name).with_context(|| format!("loading scenario `{name}`"))
}

/// How a SUMO user's scenario is given: a `.sumocfg` as the scenario, or its files as `sumo -n -r -a` takes them.
#[derive(clap::Args, Clone, Debug, Default)]
pub struct SumoInputArgs {
    /// A SUMO network: run it with --routes and --additional, as `sumo -n NET -r R -a A` (SUMO's defaults for
    /// every other option).
    #[arg(long, value_name = "NET", requires = "routes")]
    pub net: Option<PathBuf>,
    /// SUMO route files (comma-separated), with --net.
    #[arg(long, value_name = "R1,R2", value_delimiter = ',')]
    pub routes: Vec<PathBuf>,
    /// SUMO additional files (comma-separated), with --net.
    #[arg(long, value_name = "A1,A2", value_delimiter = ',')]
    pub additional: Vec<PathBuf>,
    /// Drop what mapc does not simulate from a SUMO scenario (one warning per kind) instead of refusing it, as
    /// SUMO's --ignore-route-errors.
    #[arg(long)]
    pub skip_unsupported: bool,
}

/// AVs in any scenario: a share of its flows' vehicles driven as AVs (`mapc_scenario::av_share`).
#[derive(clap::Args, Clone, Debug, Default)]
pub struct AvArgs {
    /// Make this fraction (0 to 1) of each flow's vehicles AVs: each flow is split into its humans and an `ID_av`
    /// flow of AVs (an AV copy of its type), as Flow's benchmarks give AVs their own inflow. A scenario without a
    /// `[control]` section gets the approach to its merges and lane drops (600 m before, 100 m past) as its
    /// controlled region, with 5 AVs controlled at once (`mapc train --n-av` sets another).
    #[arg(long, value_name = "P")]
    pub av_share: Option<f64>,
    /// Only these flows (by flow id or vehicle type, comma-separated) get AVs.
    #[arg(
        long,
        value_name = "ID,ID",
        value_delimiter = ',',
        requires = "av_share"
    )]
    pub av_flows: Vec<String>,
}

impl AvArgs {
    /// `rs` with the AVs asked for (unchanged without `--av-share`).
    pub fn apply(&self, rs: ResolvedScenario) -> anyhow::Result<ResolvedScenario> {
        match self.av_share {
            None => Ok(rs),
            Some(share) => Ok(rs.with_av_share(share, &self.av_flows)?),
        }
    }
}

/// The scenario `name` names (a scenario file, a `.sumocfg`, a built-in name), or the SUMO files of `sumo`;
/// what reading a SUMO scenario dropped is printed as warnings.
pub fn load_scenario_or_sumo(name: &str, sumo: &SumoInputArgs) -> anyhow::Result<ResolvedScenario> {
    load_scenario_or_sumo_saying(name, sumo, |_| true)
}

/// [`load_scenario_or_sumo`], printing only the warnings `say` keeps.
pub fn load_scenario_or_sumo_saying(
    name: &str,
    sumo: &SumoInputArgs,
    say: impl Fn(&str) -> bool,
) -> anyhow::Result<ResolvedScenario> {
    let options = mapc_scenario::sumo::ReadOptions {
        skip_unsupported: sumo.skip_unsupported,
    };
    let rs = match &sumo.net {
        Some(net) => {
            let read =
                mapc_scenario::sumo::from_files(net, &sumo.routes, &sumo.additional, &options)?;
            ResolvedScenario::from_sumo(read, &net.display().to_string())?
        }
        None => {
            let name = if name == DEFAULT_SCENARIO && !Path::new(name).exists() {
                BUILTIN_FALLBACK
            } else {
                name
            };
            ResolvedScenario::load_with(name, &options)
                .with_context(|| format!("loading scenario `{name}`"))?
        }
    };
    for note in rs.notes.iter().filter(|n| say(n)) {
        eprintln!("warning: {note}");
    }
    Ok(rs)
}

/// Seeds of the observed pass that reports the merges' regime.
pub use mapc_sim::REGIME_SEEDS;

/// The blocked entries and the merges' regime, a line each.
pub fn print_regime(regime: &mapc_sim::RegimeReport) {
    print_regime_lines(regime.seeds, &regime.lines());
}

pub fn print_regime_lines(seeds: usize, lines: &[String]) {
    if lines.is_empty() {
        return;
    }
    println!("  regime ({seeds} seeds):");
    for line in lines {
        println!("    {line}");
    }
}

/// Refuses now, naming the file, an output that a long run could not write at its end (a folder that cannot be
/// made, a read-only place, a directory), so that the run is not lost to it.
pub fn check_outputs<'a>(paths: impl IntoIterator<Item = Option<&'a Path>>) -> anyhow::Result<()> {
    for path in paths.into_iter().flatten() {
        mapc_graph::check_writable(path).with_context(|| format!("writing {}", path.display()))?;
    }
    Ok(())
}

/// Writes a trace CSV (header, then the rows `body` writes) atomically ([`write_streamed`]), so an interrupted or
/// failed run leaves neither half a trace under the final name nor a temporary file.
pub fn write_trace_file(
    path: &Path,
    body: impl FnOnce(&mut std::io::BufWriter<std::fs::File>) -> anyhow::Result<()>,
) -> anyhow::Result<()> {
    write_streamed(path, "the trace ", |w| {
        writeln!(w, "{TRACE_HEADER}")?;
        body(w)
    })
}

/// Writes `path` atomically (`mapc_graph::write_atomically_with`) as `body` streams it while a run goes on. The
/// writer speaks io::Error: an error of `body`'s own (the simulator's, the policy's, another file's) is kept aside
/// and returned as is; the file system's own refusal here (a full disk) names the file, called `what` (`the
/// trace `, or nothing).
pub fn write_streamed(
    path: &Path,
    what: &str,
    body: impl FnOnce(&mut std::io::BufWriter<std::fs::File>) -> anyhow::Result<()>,
) -> anyhow::Result<()> {
    let mut failure = None;
    let written = mapc_graph::write_atomically_with(path, |w| {
        body(w).map_err(|e| {
            let io = std::io::Error::other(e.to_string());
            failure = Some(e);
            io
        })
    });
    let named = || format!("writing {what}{}", path.display());
    if let Some(e) = failure {
        // (a bare refusal of the file system, not one that already names its file)
        let os_error = e.chain().count() == 1
            && e.downcast_ref::<std::io::Error>()
                .is_some_and(|io| io.get_ref().is_none());
        if os_error {
            return Err(e.context(named()));
        }
        return Err(e);
    }
    written.with_context(named)
}

/// Whether a map argument names a scenario rather than a map or graph: a file whose content is a scenario
/// (whatever its name; a `.toml` file that is not recognised is one too, so that its TOML error is reported), or
/// a built-in scenario name (simple_merge).
pub fn names_scenario(arg: &str) -> bool {
    let path = Path::new(arg);
    if path.is_file() && mapc_scenario::sumo::is_sumo_config(path) {
        return true;
    }
    if path.is_file() {
        return match mapc_graph::filekind::sniff_path(path) {
            Some(kind) => kind == mapc_graph::MapcFile::Scenario,
            None => path
                .extension()
                .is_some_and(|e| e.eq_ignore_ascii_case("toml")),
        };
    }
    !path.exists() && mapc_scenario::Scenario::builtin(arg).is_some()
}

/// Any map argument as a lane graph: a file mapc reads, a scenario file, or a built-in scenario name.
pub fn load_map(arg: &str) -> anyhow::Result<LaneGraph> {
    if names_scenario(arg) {
        let resolved = mapc_scenario::ResolvedScenario::load(arg)?;
        return Ok(resolved.graph);
    }
    Ok(mapc_import::load_any(Path::new(arg))?)
}

/// `maps/i696.osm` -> `i696`: the file name without the map or graph extensions (any case).
pub fn map_stem(path: &Path) -> String {
    let name = path
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_else(|| "map".into());
    let lower = name.to_ascii_lowercase();
    for ext in [
        ".corridor.graph.json",
        ".graph.json",
        ".osm.pbf",
        ".osm.xml",
        ".net.xml",
        ".osm",
        ".json",
        ".xml",
        ".pbf",
    ] {
        if lower.len() > ext.len() && lower.ends_with(ext) {
            return name[..name.len() - ext.len()].to_string();
        }
    }
    name
}

/// Lanes per road of a corridor or window that keeps several lanes a road, and the lanes that end there.
pub fn print_lanes(g: &mapc_graph::LaneGraph, roads: &[mapc_graph::RoadId]) {
    let mut parts = Vec::new();
    for r in roads.iter().filter_map(|r| g.road(*r)) {
        let ends: Vec<String> = r
            .lanes
            .iter()
            .filter_map(|l| {
                l.end
                    .map(|e| format!("lane {} {}", l.index, lane_end_name(e)))
            })
            .collect();
        parts.push(if ends.is_empty() {
            format!("{} {}", r.id, r.lanes.len())
        } else {
            format!("{} {} ({})", r.id, r.lanes.len(), ends.join(", "))
        });
    }
    println!("  lanes: {}", parts.join(", "));
}

pub fn lane_end_name(e: mapc_graph::LaneEnd) -> &'static str {
    match e {
        mapc_graph::LaneEnd::Drop => "drops",
        mapc_graph::LaneEnd::Acceleration => "ends (acceleration lane)",
    }
}

/// A scenario resolved for the simulator: its spec, display name and N_AV (if the scenario sets one).
pub struct LoadedScenario {
    pub spec: mapc_sim::SimSpec,
    pub name: String,
    pub n_av: Option<usize>,
    /// Set when the horizon is too short for the network (`mapc_scenario::timing`).
    pub horizon_warning: Option<String>,
}

/// A scenario file or built-in name (the default file falling back to the built-in) resolved into a simulator
/// spec.
pub fn load_run_scenario(arg: &str) -> anyhow::Result<LoadedScenario> {
    load_run_scenario_with(arg, &AvArgs::default())
}

/// [`load_run_scenario`] with the AVs of `avs`.
pub fn load_run_scenario_with(arg: &str, avs: &AvArgs) -> anyhow::Result<LoadedScenario> {
    let resolved = avs.apply(load_scenario(arg)?)?;
    let spec =
        mapc_sim::spec_from_scenario(&resolved).with_context(|| format!("scenario {arg}"))?;
    let n_av = resolved.scenario.control.as_ref().map(|c| c.n_av as usize);
    Ok(LoadedScenario {
        spec,
        name: resolved.scenario.name.clone(),
        n_av,
        horizon_warning: mapc_scenario::timing::HorizonFit::of_resolved(&resolved).warning(),
    })
}

/// How `mapc simplify`, and `mapc window` given a raw map, choose the corridor.
#[derive(clap::Args, Clone, Debug)]
pub struct RouteArgs {
    /// A point the main road must pass, in order (repeat): `osm-way:WAY`, `osm:NODE`, a SUMO edge or junction id,
    /// `R3` or `J3`. Default: the longest through route over --classes (and roads of no class as fast as a
    /// ramp) that passes a junction where another road joins.
    #[arg(long = "via", value_name = "ID")]
    pub via: Vec<String>,
    /// Keep merging roads at most this long (metres) instead of back to where they start in the map.
    #[arg(long, value_name = "M", value_parser = super::flags::within::<f64>(mapc_scenario::ranges::ROAD_LENGTH_M))]
    pub feeder_length: Option<f64>,
    /// Keep diverging roads as exits (up to their next junction) instead of dropping them.
    #[arg(long)]
    pub keep_exits: bool,
    /// Road classes the main road may use where --via does not pin it (comma-separated).
    #[arg(
        long,
        value_delimiter = ',',
        default_value = "motorway,motorway_link,trunk,trunk_link"
    )]
    pub classes: Vec<String>,
    /// Keep footways, paths, cycleways and service roads that meet the main road as merging roads (by default
    /// they are dropped, and a junction only they join is no merge).
    #[arg(long)]
    pub minor_roads: bool,
    /// Keep every lane of the main and merging roads, with their lane-level connections, lane drops, gains and
    /// acceleration lanes (by default each road keeps its rightmost lane, as the paper's corridors do).
    #[arg(long)]
    pub keep_lanes: bool,
}

impl RouteArgs {
    pub fn options(&self) -> SimplifyOptions {
        SimplifyOptions {
            via: self.via.clone(),
            classes: self.classes.clone(),
            feeder_length_m: self.feeder_length,
            keep_exits: self.keep_exits,
            minor_roads: self.minor_roads,
            keep_lanes: self.keep_lanes,
        }
    }
}
