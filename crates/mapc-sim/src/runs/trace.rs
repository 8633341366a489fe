//! Trace runs: one seed to the horizon, the measured frames' vehicles written as CSV rows
//! ([`crate::TRACE_HEADER`]), within a bound on the rows ([`TraceBudget`]).

use crate::error::SimError;
use crate::measure::metrics::RunMetrics;
use crate::sim::Simulation;
use crate::spec::SimSpec;

/// At most this many rows (vehicles times frames) in a trace: about 120 MB of CSV. A 95 km corridor with its
/// lanes and an hour of warm-up once wrote 3.1 GB, and `mapc view` held it all in memory.
pub const MAX_TRACE_ROWS: u64 = 2_000_000;

/// Which frames a trace writes: those of the measured horizon (the warm-up is not measured and not drawn), one in
/// `every`, `every` set at the first measured frame so that its vehicles (a quarter more for growth) over the
/// frames to come stay within the bound, and kept (a replay needs evenly spaced frames); past the bound nothing
/// more is written.
#[derive(Clone, Debug)]
pub struct TraceBudget {
    from_step: u64,
    last_step: u64,
    every: u64,
    rows: u64,
    max_rows: u64,
    /// A frame had to be left out for the bound.
    cut: bool,
}

impl TraceBudget {
    pub fn new(spec: &SimSpec) -> TraceBudget {
        TraceBudget::with_max_rows(spec, MAX_TRACE_ROWS)
    }

    pub fn with_max_rows(spec: &SimSpec, max_rows: u64) -> TraceBudget {
        TraceBudget {
            from_step: spec.warmup_steps,
            last_step: spec.warmup_steps + spec.horizon_steps,
            every: 1,
            rows: 0,
            max_rows,
            cut: false,
        }
    }

    /// Writes the simulation's current frame if the budget takes it.
    pub fn write_frame(
        &mut self,
        sim: &Simulation,
        out: &mut impl std::io::Write,
    ) -> std::io::Result<()> {
        let step = sim.step_index();
        if step < self.from_step {
            return Ok(());
        }
        let vehicles = sim.active_count() as u64;
        if step == self.from_step {
            let frames = self.last_step - self.from_step + 1;
            let expected = (vehicles.max(1) as f64 * 1.25 * frames as f64) / self.max_rows as f64;
            self.every = (expected.ceil() as u64).clamp(1, frames);
        }
        if !(step - self.from_step).is_multiple_of(self.every) {
            return Ok(());
        }
        if self.rows + vehicles > self.max_rows {
            self.cut = true;
            return Ok(());
        }
        self.rows += vehicles;
        sim.write_trace_rows(out)
    }

    /// Rows written so far.
    pub fn rows(&self) -> u64 {
        self.rows
    }

    /// What was left out, for the user (`None`: every measured frame is in the trace).
    pub fn note(&self) -> Option<String> {
        let mut parts = Vec::new();
        if self.from_step > 0 {
            parts.push(format!(
                "from the end of the warm-up (step {})",
                self.from_step
            ));
        }
        if self.every > 1 {
            parts.push(format!(
                "one frame in {} to stay under {} rows",
                self.every, self.max_rows
            ));
        }
        if self.cut {
            parts.push(format!("cut at {} rows", self.max_rows));
        }
        (!parts.is_empty()).then(|| format!("the trace holds {}", parts.join(", ")))
    }
}

/// What a trace run measured, and what its trace left out.
#[derive(Clone, Debug)]
pub struct TracedRun {
    pub metrics: RunMetrics,
    pub note: Option<String>,
}

/// Run `seed` of `spec` to its horizon, writing the rows of the measured frames within [`TraceBudget`] (no
/// header): the state before the first step when there is no warm-up, and after every step. A simulation error
/// comes back as an I/O error of kind `Other` carrying its message.
pub fn trace_run(
    spec: &SimSpec,
    seed: u64,
    out: &mut impl std::io::Write,
) -> std::io::Result<TracedRun> {
    trace_run_with(spec, seed, out, |_| Ok(()), |_| Ok(()))
}

/// [`trace_run`] with a controller: `start` before the first frame, `after_step` after every step (ALINEA sets
/// its light there).
pub fn trace_run_with(
    spec: &SimSpec,
    seed: u64,
    out: &mut impl std::io::Write,
    start: impl FnOnce(&mut Simulation) -> Result<(), SimError>,
    after_step: impl FnMut(&mut Simulation) -> Result<(), SimError>,
) -> std::io::Result<TracedRun> {
    let mut sim = Simulation::from_spec(spec.clone(), seed).map_err(std::io::Error::other)?;
    start(&mut sim).map_err(std::io::Error::other)?;
    let note = trace_sim(&mut sim, out, after_step)?;
    Ok(TracedRun {
        metrics: sim.metrics(),
        note,
    })
}

/// Runs `sim` from where it stands to its horizon, writing its frames as [`trace_run`] does and calling
/// `after_step` after every step (before that step's frame: what it watches or sets is in the frame); returns what
/// the trace left out. For a caller that keeps the simulation (to read it at the end, or to watch it for other
/// outputs).
pub fn trace_sim(
    sim: &mut Simulation,
    out: &mut impl std::io::Write,
    mut after_step: impl FnMut(&mut Simulation) -> Result<(), SimError>,
) -> std::io::Result<Option<String>> {
    let mut budget = TraceBudget::new(sim.spec());
    budget.write_frame(sim, out)?;
    while !sim.is_done() {
        sim.step().map_err(std::io::Error::other)?;
        after_step(sim).map_err(std::io::Error::other)?;
        budget.write_frame(sim, out)?;
    }
    Ok(budget.note())
}
