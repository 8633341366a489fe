//! `mapc`: turn real road maps into traffic scenarios and train AV policies that reduce congestion.

// Shadow the standard printing macros for the whole binary (macro_rules! scope is textual: these come before
// `mod cmd`), so no line reaches the terminal with a map's escape sequences in it, however it was built.
macro_rules! println {
    () => { ::std::println!() };
    ($($arg:tt)*) => { ::std::println!("{}", ::mapc_graph::terminal::printable(&::std::format!($($arg)*))) };
}
macro_rules! eprintln {
    () => { ::std::eprintln!() };
    ($($arg:tt)*) => { ::std::eprintln!("{}", ::mapc_graph::terminal::printable(&::std::format!($($arg)*))) };
}
macro_rules! print {
    ($($arg:tt)*) => { ::std::print!("{}", ::mapc_graph::terminal::printable(&::std::format!($($arg)*))) };
}

mod cmd;

use clap::{Parser, Subcommand};
use std::process::ExitCode;

/// mimalloc rather than glibc's malloc: training's many small tensors spent 13 % of an iteration in the
/// allocator (the results do not depend on where memory comes from).
#[global_allocator]
static ALLOCATOR: mimalloc::MiMalloc = mimalloc::MiMalloc;

#[derive(Parser)]
#[command(name = "mapc", version, about, long_about = None, propagate_version = true)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand)]
enum Command {
    /// Read an OSM (.osm, .osm.pbf) or SUMO (.net.xml) map into a lane graph file.
    Import(cmd::import::Args),
    /// List a map's junctions (merges, diverges) with their roads.
    Junctions(cmd::junctions::Args),
    /// Export a map as GeoJSON, or a map or scenario as SUMO 1.8 inputs (--sumo).
    Export(cmd::export::Args),
    /// Draw a map as PNG or SVG.
    Render(cmd::render::Args),
    /// Reduce a highway to a corridor with its merging roads: one lane per road, or every lane with --keep-lanes.
    Simplify(cmd::simplify::Args),
    /// Cut a window around a merge, matched to a source scenario's lengths.
    Window(cmd::window::Args),
    /// Inspect scenario files.
    #[command(subcommand)]
    Scenario(cmd::scenario::Command),
    /// Run the all-human baseline of a scenario over many seeds.
    Sim(cmd::sim::Args),
    /// Measure the simulator's speed.
    Bench(cmd::bench::Args),
    /// Train an AV policy with PPO.
    Train(cmd::train::Args),
    /// Evaluate a policy against the human baseline.
    Eval(cmd::eval::Args),
    /// Draw time-space diagrams and training curves.
    #[command(subcommand)]
    Plot(cmd::plot::Command),
    /// Watch a scenario, a policy or a map in the browser: one self-contained HTML page.
    View(cmd::view::Args),
    /// Run the whole job on a map: import, render, simplify, window, baseline, zero-shot evaluation.
    Pipeline(cmd::pipeline::Args),
}

fn dispatch(command: Command) -> anyhow::Result<()> {
    match command {
        Command::Import(a) => cmd::import::run(a),
        Command::Junctions(a) => cmd::junctions::run(a),
        Command::Export(a) => cmd::export::run(a),
        Command::Render(a) => cmd::render::run(a),
        Command::Simplify(a) => cmd::simplify::run(a),
        Command::Window(a) => cmd::window::run(a),
        Command::Scenario(c) => cmd::scenario::run(c),
        Command::Sim(a) => cmd::sim::run(a),
        Command::Bench(a) => cmd::bench::run(a),
        Command::Train(a) => cmd::train::run(a),
        Command::Eval(a) => cmd::eval::run(a),
        Command::Plot(c) => cmd::plot::run(c),
        Command::Pipeline(a) => cmd::pipeline::run(a),
        Command::View(a) => cmd::view::run(a),
    }
}

/// Run one `mapc` command line (without the program name), as the pipeline does.
pub(crate) fn run_command_line(words: &[String]) -> anyhow::Result<()> {
    let cli =
        Cli::try_parse_from(std::iter::once("mapc".to_string()).chain(words.iter().cloned()))?;
    dispatch(cli.command)
}

fn main() -> ExitCode {
    if let Err(e) = mapc_sim::numeric::check_cpu() {
        eprintln!("error: {e}");
        return ExitCode::FAILURE;
    }
    restore_default_sigpipe();
    keep_freed_memory();
    let cli = match Cli::try_parse() {
        Ok(cli) => cli,
        Err(e) => return usage(&e),
    };
    match dispatch(cli.command) {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            // Bad input is the usual cause; every message names the file and the place.
            eprintln!("error: {}", message(&e));
            ExitCode::from(2)
        }
    }
}

/// An error and its causes, each fact once: most of the workspace's errors already print their cause after the
/// file's name (`{path}: {source}`), so a cause whose text the message holds already is left out.
fn message(e: &anyhow::Error) -> String {
    let mut text = e.to_string();
    for cause in e.chain().skip(1) {
        let cause = cause.to_string();
        if !text.contains(&cause) {
            text = format!("{text}: {cause}");
        }
    }
    text
}

/// What clap has to say about the command line (help, version or a usage error), through `printable` like every
/// other line: a bad flag's value is echoed in the message, and it may hold escape sequences. Help and version go
/// to standard output with exit code 0, a usage error to standard error with 2.
fn usage(e: &clap::Error) -> ExitCode {
    let text = e.render().to_string();
    let text = text.strip_suffix('\n').unwrap_or(&text);
    if e.use_stderr() {
        eprintln!("{text}");
        ExitCode::from(2)
    } else {
        println!("{text}");
        ExitCode::SUCCESS
    }
}

/// Training frees and reallocates the same megabyte-sized tensors thousands of times per iteration. glibc's
/// malloc serves such blocks with `mmap` and returns freed heap tops to the system, so each reuse paid page faults
/// and zeroed pages: about 10 % of a distributed training iteration's wall time went to the kernel. Keeping freed
/// memory in the process (8 MB more peak memory in a distributed training run) removes that; no result changes.
/// 32 MiB is the largest mmap threshold every glibc accepts (older ones refuse more, and a refused threshold with
/// the trim setting would leave the 128 KiB default fixed: the opposite of the intent), and above the trainer's
/// per-minibatch tensors.
fn keep_freed_memory() {
    #[cfg(all(target_os = "linux", target_env = "gnu"))]
    // SAFETY: called first thing in main, before any allocation of note and before other threads exist;
    // mallopt only changes allocator parameters.
    unsafe {
        if libc::mallopt(libc::M_MMAP_THRESHOLD, 32 << 20) == 1 {
            libc::mallopt(libc::M_TRIM_THRESHOLD, 1 << 30);
        }
    }
}

/// `mapc junctions MAP | head` should end quietly when `head` closes the pipe, as Unix tools do, instead of
/// panicking in `println!` (Rust ignores SIGPIPE by default).
fn restore_default_sigpipe() {
    #[cfg(unix)]
    // SAFETY: called first thing in main, before any other thread exists; SIG_DFL is a valid disposition.
    unsafe {
        libc::signal(libc::SIGPIPE, libc::SIG_DFL);
    }
}
