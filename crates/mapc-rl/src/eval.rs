//! Evaluation of a policy on a scenario over fixed seeds, against the all-human baseline on the same seeds.
//! Every run, whatever drives its AVs (the humans, a policy on one region, on several windows, or every AV as an
//! agent), simulates the scenario's warm-up and measured horizon, and every figure is the simulation's own
//! measurement of it (`mapc_sim::RunMetrics`: outflow, inflow, speed, the flow past each measured merge and past
//! the corridor's end).

use std::path::Path;

use mapc_sim::{MeanCi, RunMetrics, SimSpec, Summary, VehicleId};
use serde::{Deserialize, Serialize};

use crate::checkpoint::Checkpoint;
use crate::deploy::{Deploy, Deployment, Withheld};
use crate::env::EpisodeMetrics;
use crate::env::distributed::{DistributedConfig, DistributedEnv};
use crate::env::merge::{MergeEnv, MergeEnvConfig};
use crate::env::obs::ObsNorm;
use crate::env::windows::WindowsEnv;
use crate::error::RlError;
use crate::eval_windows::CentralizedEnv;
use crate::ppo::gae::EpisodeEnd;
use crate::ppo::tensor::Model;
use crate::ppo::tensor::Scratch;
use crate::rng::mix_seed;
use crate::rollout::{ActionMode, EpisodeSettings, collect_agents_with, over_seeds};
use crate::stats::{WelchTest, welch_t_test};

/// Mean and 95% CI of one metric.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct Figure {
    pub mean: f64,
    pub ci95: f64,
}

impl From<MeanCi> for Figure {
    fn from(m: MeanCi) -> Self {
        Figure {
            mean: m.mean,
            ci95: m.ci95,
        }
    }
}

/// `mapc sim`'s summary shape: outflow, inflow, speed and mean trip duration over `seeds` runs.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct FigureSet {
    pub outflow: Figure,
    pub inflow: Figure,
    pub speed: Figure,
    /// Mean trip duration (s); absent from reports written before it was measured.
    #[serde(default)]
    pub travel_time: Figure,
    pub seeds: usize,
}

impl FigureSet {
    pub fn of(runs: &[EpisodeMetrics]) -> Self {
        let col = |f: fn(&EpisodeMetrics) -> f64| {
            Figure::from(MeanCi::of(&runs.iter().map(f).collect::<Vec<_>>()))
        };
        FigureSet {
            outflow: col(|m| m.outflow),
            inflow: col(|m| m.inflow),
            speed: col(|m| m.speed),
            travel_time: col(|m| m.travel_time),
            seeds: runs.len(),
        }
    }
    /// Whether both sets have an interval at all: one seed gives a mean but no confidence interval (the zero
    /// half-width `MeanCi` reports for n = 1 is not an interval).
    pub fn has_ci(&self) -> bool {
        self.seeds >= 2
    }
    /// Whether the 95% intervals of the outflow do not overlap; false where either side has no interval.
    pub fn outflow_ci_disjoint(&self, other: &FigureSet) -> bool {
        if !(self.has_ci() && other.has_ci()) {
            return false;
        }
        let (a, b) = (self.outflow, other.outflow);
        a.mean - a.ci95 > b.mean + b.ci95 || b.mean - b.ci95 > a.mean + a.ci95
    }
}

/// Welch tests of policy minus baseline.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Comparison {
    pub outflow: Option<WelchTest>,
    pub inflow: Option<WelchTest>,
    pub speed: Option<WelchTest>,
    /// Policy outflow relative to the baseline's, in percent.
    pub outflow_change_pct: f64,
    pub outflow_ci_disjoint: bool,
}

/// What `mapc eval --json` prints: the policy's figures at the top level (as `mapc sim`), then the baseline.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct EvalReport {
    pub outflow: Figure,
    pub inflow: Figure,
    pub speed: Figure,
    /// Mean trip duration (s).
    #[serde(default)]
    pub travel_time: Figure,
    pub seeds: usize,
    pub policy: String,
    pub scenario: String,
    pub actions: String,
    pub baseline: Option<FigureSet>,
    pub comparison: Option<Comparison>,
    pub wall_s: f64,
    /// The flow past every merge the scenario measures (none measured: absent).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub merges: Option<Vec<MergeFlowReport>>,
    /// The flow past the corridor's end (the end of its main line).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub end_flow: Option<FlowComparison>,
    /// The policy's deployment rule, if it has one.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub deploy: Option<Deploy>,
    /// The windows its rule left to the humans (their AVs drove as humans), and why.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub withheld: Vec<Withheld>,
}

/// The scenario as `ck`'s policy drives it under its deployment rule ([`crate::deploy`]): windows for a
/// centralized policy, roads for a distributed one.
pub fn deployed_spec(
    ck: &Checkpoint,
    driver: &PolicyDriver,
    spec: &SimSpec,
) -> Result<Deployment, RlError> {
    let rule = ck.spec.deploy.unwrap_or(Deploy::Everywhere);
    let deployment = match driver {
        PolicyDriver::Distributed(_) => crate::deploy::deploy_by_road(spec, rule)?,
        PolicyDriver::Centralized(_) => crate::deploy::deploy(spec, rule)?,
    };
    if rule != Deploy::Measured || deployment.spec.is_none() {
        return Ok(deployment);
    }
    // `measured`: the policy against the humans on seeds no evaluation uses, with the actions it deploys with
    let seeds: Vec<u64> = (CALIBRATION_SEED..CALIBRATION_SEED + CALIBRATION_SEEDS).collect();
    let policy = driver.run_deployed(ck, spec, &deployment, &seeds, ActionMode::Mean)?;
    let human = run_human(spec, &seeds)?;
    let of = |runs: &[RunMetrics]| {
        FigureSet::of(&runs.iter().map(EpisodeMetrics::from).collect::<Vec<_>>())
    };
    Ok(
        match measured_refusal(&ck.spec.reward, &of(&policy), &of(&human)) {
            None => deployment,
            Some(reason) => Deployment {
                spec: None,
                withheld: vec![crate::deploy::Withheld {
                    window: "the control region".into(),
                    reason,
                }],
            },
        },
    )
}

/// Seeds of the `measured` rule's calibration: 20, from one million on, apart from any evaluation's.
pub const CALIBRATION_SEED: u64 = 1_000_000;
pub const CALIBRATION_SEEDS: u64 = 20;

/// Why the `measured` rule withholds a policy whose calibration runs are `p` against the humans' `h` (`None`: it
/// deploys it): its reward's measure must be higher with disjoint 95 % intervals, and its outflow not lower with
/// disjoint intervals.
pub fn measured_refusal(reward: &str, p: &FigureSet, h: &FigureSet) -> Option<String> {
    let above = |a: Figure, b: Figure| a.mean - a.ci95 > b.mean + b.ci95;
    let (name, pm, hm) = if reward == crate::env::merge::RewardKind::Speed.name() {
        ("speed", p.speed, h.speed)
    } else {
        ("outflow", p.outflow, h.outflow)
    };
    let seeds = CALIBRATION_SEEDS;
    if !above(pm, hm) {
        return Some(format!(
            "on {seeds} calibration seeds its {name} ({:.2} ± {:.2}) is not above the humans' ({:.2} ± {:.2}) \
             with disjoint intervals",
            pm.mean, pm.ci95, hm.mean, hm.ci95
        ));
    }
    if above(h.outflow, p.outflow) {
        return Some(format!(
            "on {seeds} calibration seeds its outflow ({:.2} ± {:.2}) is below the humans' ({:.2} ± {:.2})",
            p.outflow.mean, p.outflow.ci95, h.outflow.mean, h.outflow.ci95
        ));
    }
    None
}

/// The human episode of `seed` written as trace rows (what a policy whose rule withholds every window drives).
fn trace_human(
    spec: &SimSpec,
    seed: u64,
    out: &mut impl std::io::Write,
) -> Result<EpisodeMetrics, RlError> {
    let run = mapc_sim::trace_run(&spec.all_human(), seed, out).map_err(|e| RlError::Io {
        path: "trace".into(),
        source: e,
    })?;
    Ok(EpisodeMetrics::from(&run.metrics))
}

/// What to evaluate: a policy (its checkpoint and the file it came from) on a scenario (its name for the report,
/// its spec, the N_AV it sets) over `seeds`, with mean or sampled actions, and the human baseline unless
/// `baseline` is false.
#[derive(Clone, Copy)]
pub struct EvalRequest<'a> {
    pub ck: &'a Checkpoint,
    pub policy_file: &'a Path,
    pub scenario: &'a str,
    pub spec: &'a SimSpec,
    pub scenario_n_av: Option<usize>,
    pub seeds: &'a [u64],
    pub mode: ActionMode,
    pub baseline: bool,
}

/// A policy evaluated on a scenario over `seeds` (in parallel, results in seed order), with the human baseline on
/// the same seeds unless `baseline` is false: what `mapc eval` and the Python package's `evaluate` report. Also
/// returns how the policy drove and where, for a trace of the same episodes (the `measured` rule's calibration
/// is not run again).
pub fn evaluate(req: &EvalRequest) -> Result<(EvalReport, PolicyDriver, Deployment), RlError> {
    evaluate_traced(req, None).map(|(report, driver, deployment, _)| (report, driver, deployment))
}

/// [`evaluate`], a humans' run also written as trace rows to `human_trace` (no header), and its seed returned:
/// that run is the baseline's own, so the trace costs no run of its own. The first seed's, unless the rule
/// leaves every AV to the humans (then the policy's runs are theirs, and any seed shows both): then the first
/// seed whose run is not kept from an earlier step of the job ([`mapc_sim::KeptRuns`]), so that no seed runs
/// twice. Asked without a baseline, the first seed's trace is written from a run of its own.
pub fn evaluate_traced(
    req: &EvalRequest,
    human_trace: Option<&mut (dyn std::io::Write + Send)>,
) -> Result<(EvalReport, PolicyDriver, Deployment, u64), RlError> {
    let EvalRequest {
        ck,
        policy_file,
        scenario,
        spec,
        scenario_n_av,
        seeds,
        mode,
        baseline,
    } = *req;
    let start = std::time::Instant::now();
    let driver =
        PolicyDriver::for_scenario(ck, policy_file, scenario, Some(scenario_n_av.unwrap_or(5)))?;
    let deployment = deployed_spec(ck, &driver, spec)?;
    let traced = match (&deployment.spec, baseline) {
        (None, true) => {
            let humans = spec.all_human();
            let kept = mapc_sim::KeptRuns::of(&humans);
            seeds.iter().position(|&s| !kept.is_kept(s)).unwrap_or(0)
        }
        _ => 0,
    };
    let traced_seed = seeds.get(traced).copied().unwrap_or(0);
    let human = match (baseline, human_trace) {
        (true, trace) => Some(run_human_traced(spec, seeds, traced, trace)?),
        (false, Some(out)) => {
            if let Some(&first) = seeds.first() {
                trace_human(spec, first, &mut { out })?;
            }
            None
        }
        (false, None) => None,
    };
    let runs = match (&deployment.spec, &human) {
        // the rule leaves every AV to the humans: the policy's runs are the baseline's, not run twice
        (None, Some(human)) => human.clone(),
        _ => driver.run_deployed(ck, spec, &deployment, seeds, mode)?,
    };
    let (merges, end_flow) = flow_reports(spec, &runs, human.as_deref());
    let episodes = |v: &[RunMetrics]| -> Vec<EpisodeMetrics> { v.iter().map(Into::into).collect() };
    let (runs, human) = (episodes(&runs), human.as_deref().map(episodes));
    let figs = FigureSet::of(&runs);
    let (baseline, comparison) = match &human {
        Some(human) => (Some(FigureSet::of(human)), Some(compare(&runs, human))),
        None => (None, None),
    };
    let report = EvalReport {
        outflow: figs.outflow,
        inflow: figs.inflow,
        speed: figs.speed,
        travel_time: figs.travel_time,
        seeds: figs.seeds,
        policy: policy_file.display().to_string(),
        scenario: scenario.to_string(),
        actions: match mode {
            ActionMode::Sample => "sample",
            ActionMode::Mean => "mean",
        }
        .into(),
        baseline,
        comparison,
        wall_s: start.elapsed().as_secs_f64(),
        merges,
        end_flow,
        deploy: ck.spec.deploy,
        withheld: deployment.withheld.clone(),
    };
    Ok((report, driver, deployment, traced_seed))
}

/// How a checkpoint's policy drives a scenario: the `N_AV` FIFO-controlled AVs of a centralized policy, or every
/// AV of the control region with a distributed one.
#[derive(Clone, Debug)]
pub enum PolicyDriver {
    Centralized(MergeEnvConfig),
    Distributed(DistributedConfig),
}

impl PolicyDriver {
    /// The driver of `ck` on `scenario` (`scenario_n_av`: its N_AV, which a centralized policy's observation
    /// must match; see [`env_config_for`]).
    pub fn for_scenario(
        ck: &Checkpoint,
        policy: &Path,
        scenario: &str,
        scenario_n_av: Option<usize>,
    ) -> Result<PolicyDriver, RlError> {
        match ck.spec.distributed_config() {
            Some(d) => Ok(PolicyDriver::Distributed(d)),
            None => {
                env_config_for(ck, policy, scenario, scenario_n_av).map(PolicyDriver::Centralized)
            }
        }
    }

    /// The policy on `spec` for each seed (in parallel, results in seed order), each run the simulation's measurement.
    pub fn run(
        &self,
        ck: &Checkpoint,
        spec: &SimSpec,
        seeds: &[u64],
        mode: ActionMode,
    ) -> Result<Vec<RunMetrics>, RlError> {
        let deployment = deployed_spec(ck, self, spec)?;
        self.run_deployed(ck, spec, &deployment, seeds, mode)
    }

    /// [`Self::run`] with the deployment already worked out: `spec` as the policy's rule leaves it, or the
    /// humans where it leaves no AV to the policy.
    fn run_deployed(
        &self,
        ck: &Checkpoint,
        spec: &SimSpec,
        deployment: &Deployment,
        seeds: &[u64],
        mode: ActionMode,
    ) -> Result<Vec<RunMetrics>, RlError> {
        let Some(spec) = deployment.spec.as_ref() else {
            return run_human(spec, seeds);
        };
        match self {
            PolicyDriver::Centralized(cfg) if !spec.control_windows.is_empty() => {
                run_centralized_policy::<WindowsEnv>(ck, spec, cfg, seeds, mode)
            }
            PolicyDriver::Centralized(cfg) => {
                run_centralized_policy::<MergeEnv>(ck, spec, cfg, seeds, mode)
            }
            PolicyDriver::Distributed(cfg) => run_distributed_policy(ck, spec, cfg, seeds, mode),
        }
    }

    /// The episode of `seed` (the one [`Self::run`] gives), every step's vehicles written as trace rows.
    pub fn trace(
        &self,
        ck: &Checkpoint,
        spec: &SimSpec,
        seed: u64,
        mode: ActionMode,
        out: &mut impl std::io::Write,
    ) -> Result<EpisodeMetrics, RlError> {
        let deployment = deployed_spec(ck, self, spec)?;
        self.trace_deployed(ck, spec, &deployment, seed, mode, out)
    }

    /// [`Self::trace`] with the deployment already worked out ([`deployed_spec`]).
    pub fn trace_deployed(
        &self,
        ck: &Checkpoint,
        spec: &SimSpec,
        deployment: &Deployment,
        seed: u64,
        mode: ActionMode,
        out: &mut impl std::io::Write,
    ) -> Result<EpisodeMetrics, RlError> {
        let Some(spec) = deployment.spec.as_ref() else {
            return trace_human(spec, seed, out);
        };
        match self {
            PolicyDriver::Centralized(cfg) if !spec.control_windows.is_empty() => {
                trace_centralized_policy::<WindowsEnv>(ck, spec, cfg, seed, mode, out)
            }
            PolicyDriver::Centralized(cfg) => {
                trace_centralized_policy::<MergeEnv>(ck, spec, cfg, seed, mode, out)
            }
            PolicyDriver::Distributed(cfg) => {
                trace_distributed_policy(ck, spec, cfg, seed, mode, out)
            }
        }
    }
}

/// The environment config for running a trained policy on a scenario with `scenario_n_av` controlled AVs
/// (`None`: the policy's). The observation normalisation is always the policy's own (zero-shot transfer keeps
/// the constants of training).
pub fn env_config_for(
    ck: &Checkpoint,
    policy: &Path,
    scenario: &str,
    scenario_n_av: Option<usize>,
) -> Result<MergeEnvConfig, RlError> {
    let n_av = scenario_n_av.unwrap_or(ck.spec.n_av);
    let per = crate::env::obs::per_av(ck.spec.lanes);
    if per * n_av != ck.spec.obs_dim {
        return Err(RlError::ObsMismatch {
            policy: policy.into(),
            expected: ck.spec.obs_dim,
            policy_n_av: ck.spec.n_av,
            scenario: scenario.into(),
            got: per * n_av,
            scenario_n_av: n_av,
        });
    }
    Ok(MergeEnvConfig {
        reward: ck
            .spec
            .reward
            .parse()
            .unwrap_or(crate::env::merge::RewardKind::Outflow),
        n_av,
        norm: ObsNorm {
            max_speed: ck.spec.max_speed,
            length: ck.spec.norm_length,
        },
        accel_min: ck.spec.accel_min,
        accel_max: ck.spec.accel_max,
        lanes: ck.spec.lanes,
    })
}

/// The action-noise stream of an evaluation episode (used by `--sample`), fixed by the environment seed.
pub(crate) fn eval_noise_seed(seed: u64) -> u64 {
    mix_seed(&[seed, 0xE7A1])
}

/// One evaluation episode per seed on the rayon pool (results in seed order): `episode` drives a whole
/// simulation (its warm-up and measured horizon) in a fresh environment of `make_env`, and the run's figures are
/// the simulation's measurement.
fn measured_runs<E>(
    make_env: &(dyn Fn() -> E + Sync),
    horizon: usize,
    seeds: &[u64],
    mode: ActionMode,
    episode: impl Fn(&mut E, &mut Scratch, EpisodeSettings) -> Result<RunMetrics, RlError> + Sync,
) -> Result<Vec<RunMetrics>, RlError> {
    let pairs: Vec<(u64, u64)> = seeds.iter().map(|&s| (s, eval_noise_seed(s))).collect();
    over_seeds(make_env, &pairs, horizon, mode, false, episode)
}

/// The simulation's measurement at the end of an episode.
fn measured(sim: Option<&mapc_sim::Simulation>) -> RunMetrics {
    sim.expect("an episode resets its environment").metrics()
}

/// Runs a centralized policy on `spec` for each seed (in parallel, results in seed order): on its one control
/// region (`E` = [`MergeEnv`]) or on every window of a several-window scenario (`E` = [`WindowsEnv`]).
pub fn run_centralized_policy<E: CentralizedEnv>(
    ck: &Checkpoint,
    spec: &SimSpec,
    cfg: &MergeEnvConfig,
    seeds: &[u64],
    mode: ActionMode,
) -> Result<Vec<RunMetrics>, RlError> {
    let horizon = E::build(spec.clone(), cfg.clone())?.episode_steps();
    let make_env = || E::build(spec.clone(), cfg.clone()).expect("validated above");
    measured_runs(
        &make_env,
        horizon,
        seeds,
        mode,
        |env: &mut E, scratch, settings| {
            env.run_policy_episode(&ck.state.model, scratch, settings, &mut |_| Ok(()))?;
            Ok(measured(env.sim()))
        },
    )
}

/// Runs a centralized policy on one seed (mean or sampled actions, the same episode as
/// [`run_centralized_policy`] gives for that seed) and writes every step's vehicles as trace CSV rows
/// (`mapc_sim::TRACE_HEADER`, without the header).
pub fn trace_centralized_policy<E: CentralizedEnv>(
    ck: &Checkpoint,
    spec: &SimSpec,
    cfg: &MergeEnvConfig,
    seed: u64,
    mode: ActionMode,
    out: &mut impl std::io::Write,
) -> Result<EpisodeMetrics, RlError> {
    let mut env = E::build(spec.clone(), cfg.clone())?;
    let settings = trace_settings(seed, env.episode_steps(), mode);
    let mut budget = None;
    env.run_policy_episode(
        &ck.state.model,
        &mut crate::ppo::tensor::Scratch::default(),
        settings,
        &mut |env: &E| write_sim_rows(env.sim(), &mut budget, out),
    )
}

/// The evaluation episode of `seed`, without training data (what a trace runs).
fn trace_settings(seed: u64, horizon: usize, mode: ActionMode) -> crate::rollout::EpisodeSettings {
    crate::rollout::EpisodeSettings {
        env_seed: seed,
        noise_seed: eval_noise_seed(seed),
        horizon,
        mode,
        record: false,
    }
}

/// The simulation's trace rows for the current step, as the trace's budget takes them (nothing before the first
/// reset).
fn write_sim_rows(
    sim: Option<&mapc_sim::Simulation>,
    budget: &mut Option<mapc_sim::TraceBudget>,
    out: &mut impl std::io::Write,
) -> Result<(), RlError> {
    match sim {
        Some(sim) => budget
            .get_or_insert_with(|| mapc_sim::TraceBudget::new(sim.spec()))
            .write_frame(sim, out)
            .map_err(|e| RlError::Io {
                path: "trace".into(),
                source: e,
            }),
        None => Ok(()),
    }
}

/// The human baseline on the same seeds.
pub fn run_human(spec: &SimSpec, seeds: &[u64]) -> Result<Vec<RunMetrics>, RlError> {
    run_human_traced(spec, seeds, 0, None)
}

/// [`run_human`], the run of `seeds[traced]` also written as trace rows to `trace` (no header) beside the others'
/// runs.
pub fn run_human_traced(
    spec: &SimSpec,
    seeds: &[u64],
    traced: usize,
    trace: Option<&mut (dyn std::io::Write + Send)>,
) -> Result<Vec<RunMetrics>, RlError> {
    let humans = spec.all_human();
    let (Some(mut out), Some(&seed)) = (trace, seeds.get(traced)) else {
        return mapc_sim::run_baseline_spec(&humans, seeds)
            .map_err(|e| crate::env::scenario_error(spec, e));
    };
    let rest: Vec<u64> = seeds
        .iter()
        .enumerate()
        .filter(|&(i, _)| i != traced)
        .map(|(_, &s)| s)
        .collect();
    let (first, rest) = rayon::join(
        || mapc_sim::trace_run(&humans, seed, &mut out),
        || mapc_sim::run_baseline_spec(&humans, &rest),
    );
    let first = first.map_err(|e| RlError::Io {
        path: "trace".into(),
        source: e,
    })?;
    let mut runs = rest.map_err(|e| crate::env::scenario_error(spec, e))?;
    runs.insert(traced, first.metrics);
    Ok(runs)
}

/// One measured flow (veh/h): the policy's, the humans' on the same seeds, and the Welch test of the difference.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct FlowComparison {
    pub flow: Figure,
    pub baseline: Option<Figure>,
    pub welch: Option<WelchTest>,
}

impl FlowComparison {
    /// `flow(run)` over the policy's runs and the humans'.
    fn of(
        policy: &[RunMetrics],
        human: Option<&[RunMetrics]>,
        flow: impl Fn(&RunMetrics) -> f64,
    ) -> Self {
        let p: Vec<f64> = policy.iter().map(&flow).collect();
        let b: Option<Vec<f64>> = human.map(|h| h.iter().map(&flow).collect());
        FlowComparison {
            flow: MeanCi::of(&p).into(),
            baseline: b.as_ref().map(|b| MeanCi::of(b).into()),
            welch: b.as_ref().and_then(|b| welch_t_test(&p, b)),
        }
    }
}

/// The flow past one measured merge.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct MergeFlowReport {
    /// The window the merge belongs to (as the scenario names the window's first merge); none outside windows.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub window: Option<String>,
    /// The merge junction (`J43`).
    pub merge: String,
    #[serde(flatten)]
    pub figures: FlowComparison,
}

/// The flow past every merge `spec` measures (in its order; `None` when it measures none) and past the corridor's
/// end, from the runs' own measurement.
pub fn flow_reports(
    spec: &SimSpec,
    policy: &[RunMetrics],
    human: Option<&[RunMetrics]>,
) -> (Option<Vec<MergeFlowReport>>, Option<FlowComparison>) {
    let end = FlowComparison::of(policy, human, |r| r.end_flow_veh_h);
    if spec.measure_points.is_empty() {
        return (None, Some(end));
    }
    let merges = spec
        .measure_junctions()
        .into_iter()
        .zip(&spec.measure_points)
        .enumerate()
        .map(|(k, (junction, point))| MergeFlowReport {
            window: junction.and_then(|j| {
                spec.control_windows
                    .iter()
                    .find(|w| w.merges.contains(&j))
                    .map(|w| w.name.clone())
            }),
            merge: junction.map_or_else(|| point.name.clone(), |j| j.to_string()),
            figures: FlowComparison::of(policy, human, |r| {
                r.merge_flows_veh_h.get(k).copied().unwrap_or(f64::NAN)
            }),
        })
        .collect();
    (Some(merges), Some(end))
}

/// Welch tests and the outflow change of `policy` against `baseline`.
pub fn compare(policy: &[EpisodeMetrics], baseline: &[EpisodeMetrics]) -> Comparison {
    let col =
        |r: &[EpisodeMetrics], f: fn(&EpisodeMetrics) -> f64| r.iter().map(f).collect::<Vec<_>>();
    let (p, b) = (FigureSet::of(policy), FigureSet::of(baseline));
    Comparison {
        outflow: welch_t_test(&col(policy, |m| m.outflow), &col(baseline, |m| m.outflow)),
        inflow: welch_t_test(&col(policy, |m| m.inflow), &col(baseline, |m| m.inflow)),
        speed: welch_t_test(&col(policy, |m| m.speed), &col(baseline, |m| m.speed)),
        outflow_change_pct: 100.0 * (p.outflow.mean / b.outflow.mean - 1.0),
        outflow_ci_disjoint: p.outflow_ci_disjoint(&b),
    }
}

/// Summary of simulator runs in the evaluation's shape (for `Summary` users).
pub fn figures_of_summary(s: &Summary) -> FigureSet {
    FigureSet {
        outflow: s.outflow.into(),
        inflow: s.inflow.into(),
        speed: s.speed.into(),
        travel_time: s.travel_time.into(),
        seeds: s.seeds,
    }
}

/// Runs a distributed policy on `spec` for each seed: every AV in the control region drives with it (in
/// parallel over seeds, results in seed order).
pub fn run_distributed_policy(
    ck: &Checkpoint,
    spec: &SimSpec,
    cfg: &DistributedConfig,
    seeds: &[u64],
    mode: ActionMode,
) -> Result<Vec<RunMetrics>, RlError> {
    let horizon = DistributedEnv::new(spec.clone(), *cfg)?.horizon();
    let make_env = || DistributedEnv::new(spec.clone(), *cfg).expect("validated above");
    measured_runs(&make_env, horizon, seeds, mode, |env, scratch, settings| {
        let model = &ck.state.model;
        crate::rollout::run_agents_episode(env, &|_| model, scratch, settings, &mut |_| Ok(()))?;
        Ok(measured(env.simulation()))
    })
}

/// The evaluation episodes of a distributed setting, one per seed (its noise stream fixed by the seed), each
/// agent driving with `policy_of(agent)`.
fn agent_episodes<'m>(
    spec: &SimSpec,
    cfg: &DistributedConfig,
    seeds: &[u64],
    policy_of: &(dyn Fn(VehicleId) -> &'m Model + Sync),
    mode: ActionMode,
    record: bool,
) -> Result<Vec<crate::rollout::AgentsEpisode>, RlError> {
    let probe = DistributedEnv::new(spec.clone(), *cfg)?;
    let horizon = probe.horizon();
    let factory = || DistributedEnv::new(spec.clone(), *cfg).expect("validated above");
    let pairs: Vec<(u64, u64)> = seeds.iter().map(|&s| (s, eval_noise_seed(s))).collect();
    collect_agents_with(&factory, policy_of, &pairs, horizon, mode, record)
}

/// [`trace_centralized_policy`] for a distributed policy (the same episode as [`run_distributed_policy`] gives).
pub fn trace_distributed_policy(
    ck: &Checkpoint,
    spec: &SimSpec,
    cfg: &DistributedConfig,
    seed: u64,
    mode: ActionMode,
    out: &mut impl std::io::Write,
) -> Result<EpisodeMetrics, RlError> {
    let mut env = DistributedEnv::new(spec.clone(), *cfg)?;
    let settings = trace_settings(seed, env.horizon(), mode);
    let mut budget = None;
    let ep = crate::rollout::run_agents_episode(
        &mut env,
        &|_| &ck.state.model,
        &mut crate::ppo::tensor::Scratch::default(),
        settings,
        &mut |env: &DistributedEnv| write_sim_rows(env.simulation(), &mut budget, out),
    )?;
    Ok(ep.metrics)
}

/// One agent's own result in a distributed episode.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct AgentOutcome {
    pub id: VehicleId,
    /// The sum of its rewards (undiscounted).
    pub ret: f64,
    /// It left the control region before the horizon (its last step carried the exit bonus).
    pub left: bool,
    /// Steps it acted.
    pub steps: usize,
}

/// A mixed-population episode: the traffic figures and every agent's outcome (in the order they first acted).
#[derive(Clone, Debug, PartialEq)]
pub struct MixedEpisode {
    pub metrics: EpisodeMetrics,
    pub agents: Vec<AgentOutcome>,
}

/// Runs two distributed policies side by side: the agents for which `deviates(agent)` holds drive with
/// `deviant`, the others with `base` (actions: the Gaussian's mean as in `mapc eval`, or sampled as in
/// training, the noise fixed by the seed; each seed in parallel, results in seed order). Vehicle ids follow the
/// departure schedule, so the same agent can be compared across populations on one seed: whether a policy
/// change pays the agent that makes it, and what it costs the others. Returns are those of `cfg`'s reward.
pub fn run_mixed_population(
    base: &Model,
    deviant: &Model,
    deviates: &(dyn Fn(VehicleId) -> bool + Sync),
    spec: &SimSpec,
    cfg: &DistributedConfig,
    seeds: &[u64],
    mode: ActionMode,
) -> Result<Vec<MixedEpisode>, RlError> {
    let policy_of = |id: VehicleId| if deviates(id) { deviant } else { base };
    // recorded: the per-agent trajectories carry the returns
    let eps = agent_episodes(spec, cfg, seeds, &policy_of, mode, true)?;
    Ok(eps
        .into_iter()
        .map(|e| MixedEpisode {
            metrics: e.metrics,
            agents: e
                .agents
                .iter()
                .zip(&e.trajectories)
                .map(|(&id, t)| AgentOutcome {
                    id,
                    ret: t.total_reward(),
                    left: matches!(t.end, Some(EpisodeEnd::Terminal)),
                    steps: t.len(),
                })
                .collect(),
        })
        .collect())
}

#[cfg(test)]
#[path = "eval_tests.rs"]
mod tests;
