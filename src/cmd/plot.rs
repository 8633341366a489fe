//! `mapc plot` (being written).

#[derive(clap::Subcommand)]
pub enum Command {
    /// Time-space diagram of a trace.
    Timespace,
    /// Training curves of a run.
    Training,
}

pub fn run(_c: Command) -> anyhow::Result<()> {
    anyhow::bail!("`mapc plot` is not built yet")
}
