//! Training as the commands run it (`mapc train`, `mapc bench --train`): the training flags, the scenario or
//! distribution they name, the run (resumed or new, from a policy or not), its loop with a progress bar, a CSV log
//! and atomic checkpoints. A toolkit module: no command of its own.

use super::common::{LoadedScenario, load_run_scenario as load_scenario};
use std::path::{Path, PathBuf};

use anyhow::{Context, bail};
use clap::Args as ClapArgs;
use indicatif::{ProgressBar, ProgressStyle};
use mapc_rl::checkpoint::{BestBy, PolicySpec};
use mapc_rl::env::Env;
use mapc_rl::env::distributed::{AgentReward, DistributedEnv, Features};
use mapc_rl::env::merge::{MergeEnv, MergeEnvConfig, RewardKind, SpecSource};
use mapc_rl::run::TrainRun;
use mapc_rl::{IterationStats, PpoConfig};
use mapc_scenario::distribution::LoadedDistribution;
use std::sync::Arc;

/// Train a centralized PPO policy, or with `--distributed` one shared by every AV (defaults: the paper's
/// hyperparameters; `--preset fast` for minutes on CPU).
#[derive(ClapArgs, Debug)]
pub struct Args {
    #[command(flatten)]
    pub avs: super::common::AvArgs,
    /// Scenario: `simple_merge`, a scenario file, or a merge distribution file (`format =
    /// "mapc-merge-distribution"`: each episode draws its merge from its seed).
    #[arg(long, default_value = "simple_merge")]
    pub scenario: String,
    /// Reward of a centralized policy: outflow (vehicles leaving the network, or the control region of a window
    /// scenario), flow (Flow's desired-velocity reward) or speed (average speed).
    #[arg(long, default_value = "outflow", conflicts_with = "distributed")]
    pub reward: String,
    /// Train a distributed policy: every AV in the control region runs the same policy on its own
    /// observation and gets its own reward (0.1 (-eta1 + eta2 * mean speed / V) per step, the exit bonus when it
    /// leaves); the presets become the paper's distributed hyperparameters.
    #[arg(long)]
    pub distributed: bool,
    /// What the observation adds to the paper's five values per AV. Distributed: the agents' state augmentations,
    /// `full` (default: dist, congestion, merge), `none`, or a list of dist, congestion, merge, lanes.
    /// Centralized: `none` (default) or `lanes`. `lanes`: the leader and follower on the lanes to the left and
    /// right (for multi-lane roads; a missing lane reads as an empty one, flagged).
    #[arg(long)]
    pub features: Option<String>,
    /// Distributed: weight of the selfish time penalty.
    #[arg(long, default_value_t = 0.9, requires = "distributed", value_parser = super::flags::within::<f64>(mapc_rl::limits::REWARD_WEIGHT))]
    pub eta1: f64,
    /// Distributed: weight of the collaborative average speed.
    #[arg(long, default_value_t = 0.1, requires = "distributed", value_parser = super::flags::within::<f64>(mapc_rl::limits::REWARD_WEIGHT))]
    pub eta2: f64,
    /// Distributed: reward in the step an agent leaves.
    #[arg(long, default_value_t = 20.0, requires = "distributed", value_parser = super::flags::within::<f64>(mapc_rl::limits::EXIT_BONUS))]
    pub exit_bonus: f64,
    /// Distributed: count the vehicles waiting to enter in the reward's mean speed, as standing (not in the
    /// paper; closes the loophole of holding back the entry).
    #[arg(long, requires = "distributed")]
    pub count_waiting: bool,
    /// Distributed: share of each step's mean agent reward that every agent gets in place of as much of its own,
    /// from 0 (its own reward: the paper) to 1 (all agents get the mean). Credits agents for what happens to
    /// the others (not in the paper).
    #[arg(
        long,
        default_value_t = 0.0,
        requires = "distributed",
        conflicts_with = "resume",
        value_parser = super::flags::within::<f64>(mapc_rl::limits::REWARD_SHARE)
    )]
    pub reward_share: f64,
    /// The value function: `shared` (one more output of the policy net, so both train the same hidden layers:
    /// RLlib's `vf_share_layers`, which the paper's distributed runs used) or `separate` (a net of its own, as
    /// in the paper's centralized runs) [preset: distributed shared, centralized separate].
    #[arg(long, value_enum, conflicts_with = "resume")]
    pub value_net: Option<ValueNet>,
    /// Training iterations (overrides the preset / config).
    #[arg(long, value_parser = super::flags::count::<u64>(mapc_rl::limits::ITERATIONS))]
    pub iters: Option<u64>,
    /// Run directory (checkpoint.json, progress.csv).
    #[arg(short = 'o', long)]
    pub out: Option<PathBuf>,
    /// Continue the run in this directory (its own scenario, reward and hyperparameters; --iters may extend it).
    #[arg(long, conflicts_with_all = ["out", "config", "preset"])]
    pub resume: Option<PathBuf>,
    /// Hyperparameter preset: paper (defaults) or fast.
    #[arg(long, default_value = "paper")]
    pub preset: String,
    /// TOML file of hyperparameters (keys of PpoConfig: lr, gamma, lambda, hidden, clip, vf_clip, vf_coeff,
    /// entropy_coeff, kl_coeff, kl_target, train_batch_size, minibatch, epochs, iterations, horizon, seed,
    /// grad_slices, lr_schedule = [[steps, lr], ...], shared_value); applied over the preset, under the flags.
    #[arg(long)]
    pub config: Option<PathBuf>,
    /// Run seed: initial weights, episode seeds, action noise and minibatch order derive from it [preset: 0].
    #[arg(long)]
    pub seed: Option<u64>,
    /// Adam learning rate [5e-4]; replaces the distributed presets' schedule by this constant rate.
    #[arg(long, value_parser = super::flags::within::<f32>(mapc_rl::limits::LR))]
    pub lr: Option<f32>,
    /// Environment steps per iteration [paper: 40000; fast: 12000].
    #[arg(long, value_parser = super::flags::count::<usize>(mapc_rl::limits::TRAIN_BATCH_SIZE))]
    pub batch: Option<usize>,
    /// SGD minibatch size in environment steps [paper: 128; fast: 1000].
    #[arg(long, value_parser = super::flags::count::<usize>(mapc_rl::limits::MINIBATCH))]
    pub minibatch: Option<usize>,
    /// SGD passes over each iteration's batch [paper: 10; fast: 8].
    #[arg(long, value_parser = super::flags::count::<usize>(mapc_rl::limits::EPOCHS))]
    pub epochs: Option<usize>,
    /// Discount factor [0.99].
    #[arg(long, value_parser = super::flags::within::<f32>(mapc_rl::limits::GAMMA))]
    pub gamma: Option<f32>,
    /// GAE lambda [0.97].
    #[arg(long, value_parser = super::flags::within::<f32>(mapc_rl::limits::LAMBDA))]
    pub lambda: Option<f32>,
    /// PPO's surrogate clip parameter [0.3].
    #[arg(long, value_parser = super::flags::within::<f32>(mapc_rl::limits::CLIP))]
    pub clip: Option<f32>,
    /// Initial KL penalty coefficient, adapted every iteration [0.2].
    #[arg(long, value_parser = super::flags::within::<f32>(mapc_rl::limits::KL_COEFF))]
    pub kl_coeff: Option<f32>,
    /// Target KL divergence per iteration [0.01].
    #[arg(long, value_parser = super::flags::within::<f32>(mapc_rl::limits::KL_TARGET))]
    pub kl_target: Option<f32>,
    /// Episode length in steps (default: the scenario's horizon).
    #[arg(long, value_parser = super::flags::count::<usize>(mapc_rl::limits::HORIZON))]
    pub horizon: Option<usize>,
    /// Controlled AVs of a centralized policy (default: the scenario's N_AV, 5 on Simple Merge).
    #[arg(long, conflicts_with = "distributed", value_parser = super::flags::count::<usize>(mapc_rl::limits::N_AV))]
    pub n_av: Option<usize>,
    /// Write a checkpoint every K iterations (and at the end).
    #[arg(long, default_value_t = 5, value_parser = super::flags::count::<u64>(1..=u64::MAX))]
    pub checkpoint_every: u64,
    /// Start a new centralized run from this policy's weights (a fresh optimiser; the architectures must agree).
    #[arg(long, conflicts_with_all = ["resume", "distributed"])]
    pub init: Option<PathBuf>,
    /// The merges the policy is meant for, written into its files (`mapc eval` follows it): `everywhere`, or
    /// `main-road-yields` (only merges where the main road yields, the Simple Merge's regime; a centralized policy
    /// then drives only such windows; a distributed one trains and drives only AVs whose next merge is one), or
    /// `main-road-yields-congested` (those of them that the humans congest, by the regime report's human runs),
    /// or `simple-merge-regime` (those with one lane on every road in and out, as the Simple Merge).
    #[arg(long, conflicts_with = "resume")]
    pub deploy: Option<mapc_rl::deploy::Deploy>,
    /// Also keep every checkpoint written, as RUN/checkpoints/iteration-NNNNN.json (`mapc eval --policy` reads
    /// them), to evaluate earlier policies of the run.
    #[arg(long)]
    pub keep_checkpoints: bool,
    /// What picks RUN/best.json, the policy whose training rollouts (sampled actions) scored highest: outflow,
    /// return or speed (RLlib Tune's `checkpoint_score_attr`). A resumed run keeps its own.
    #[arg(long, value_enum)]
    pub best_by: Option<BestByArg>,
    /// Worker threads for rollouts, 1 to 1024 (default: all cores).
    #[arg(long, value_parser = super::flags::threads())]
    pub threads: Option<usize>,
    /// Print the final iteration's figures as JSON (no progress bar).
    #[arg(long)]
    pub json: bool,
}

/// `--best-by`.
#[derive(clap::ValueEnum, Clone, Copy, Debug, PartialEq, Eq)]
pub enum BestByArg {
    /// Mean outflow (veh/h), whatever the reward [default].
    Outflow,
    /// Mean episode return.
    Return,
    /// Mean speed (m/s).
    Speed,
}

impl From<BestByArg> for BestBy {
    fn from(a: BestByArg) -> BestBy {
        match a {
            BestByArg::Outflow => BestBy::Outflow,
            BestByArg::Return => BestBy::Return,
            BestByArg::Speed => BestBy::Speed,
        }
    }
}

/// Where the value function lives (`--value-net`).
#[derive(clap::ValueEnum, Clone, Copy, Debug, PartialEq, Eq)]
pub enum ValueNet {
    /// One more output of the policy net.
    Shared,
    /// A net of its own.
    Separate,
}

/// A merge distribution file, if `arg` names one (recognised by its content).
fn distribution_of(arg: &str) -> anyhow::Result<Option<LoadedDistribution>> {
    let path = Path::new(arg);
    if mapc_graph::filekind::sniff_path(path) != Some(mapc_graph::MapcFile::MergeDistribution) {
        return Ok(None);
    }
    Ok(Some(LoadedDistribution::load(path)?))
}

/// Where a training run's episodes come from: one scenario, or a merge drawn per episode.
fn training_source(arg: &str, horizon_steps: u64) -> anyhow::Result<SpecSource> {
    Ok(match distribution_of(arg)? {
        Some(d) => SpecSource::Drawn {
            distribution: Arc::new(d),
            horizon_steps,
        },
        None => {
            let mut spec = load_scenario(arg)?.spec;
            spec.horizon_steps = horizon_steps;
            SpecSource::Fixed(Box::new(spec))
        }
    })
}

/// A training scenario: a scenario, or a merge distribution's seed-0 draw (its name, N_AV and horizon stand for
/// every draw's).
fn load_training_scenario(arg: &str) -> anyhow::Result<LoadedScenario> {
    let Some(d) = distribution_of(arg)? else {
        return load_scenario(arg);
    };
    let resolved = d.resolve(0)?;
    let spec =
        mapc_sim::spec_from_scenario(&resolved).with_context(|| format!("scenario {arg}"))?;
    Ok(LoadedScenario {
        spec,
        name: d.file.name.clone(),
        n_av: resolved.scenario.control.as_ref().map(|c| c.n_av as usize),
        horizon_warning: None,
    })
}

fn apply_flags(c: &mut PpoConfig, a: &Args) {
    macro_rules! set {
        ($field:ident, $flag:expr) => {
            if let Some(v) = $flag {
                c.$field = v;
            }
        };
    }
    set!(iterations, a.iters);
    set!(seed, a.seed);
    if let Some(lr) = a.lr {
        c.lr = lr;
        c.lr_schedule.clear();
    }
    set!(train_batch_size, a.batch);
    set!(minibatch, a.minibatch);
    set!(epochs, a.epochs);
    set!(gamma, a.gamma);
    set!(lambda, a.lambda);
    set!(clip, a.clip);
    set!(kl_coeff, a.kl_coeff);
    set!(kl_target, a.kl_target);
    set!(horizon, a.horizon);
    if let Some(v) = a.value_net {
        c.shared_value = v == ValueNet::Shared;
    }
}

fn read_config(path: &Path, base: PpoConfig) -> anyhow::Result<PpoConfig> {
    let text = mapc_graph::input::read_to_string(path)
        .with_context(|| format!("reading {}", path.display()))?;
    PpoConfig::from_toml_over(&text, &base).map_err(|e| anyhow::anyhow!("{}: {e}", path.display()))
}

/// `mapc train` without its report: the run once its iterations are done and saved, and its last log row.
pub fn train(args: Args) -> anyhow::Result<(TrainRun, Option<IterationStats>)> {
    super::common::set_global_threads(args.threads);
    let mut run = if let Some(dir) = &args.resume {
        let mut r = TrainRun::resume(dir, args.checkpoint_every)?;
        if let Some(n) = args.iters {
            r.state.config.iterations = n;
        }
        r
    } else {
        let reward: RewardKind = args.reward.parse().map_err(anyhow::Error::msg)?;
        let preset = if args.distributed {
            PpoConfig::distributed_preset(&args.preset)
        } else {
            PpoConfig::preset(&args.preset)
        };
        let mut config =
            preset.with_context(|| format!("unknown preset `{}` (paper, fast)", args.preset))?;
        if let Some(p) = &args.config {
            config = read_config(p, config)?;
        }
        apply_flags(&mut config, &args);
        // with AVs asked for, the run trains on its own scenario file (RUN_DIR/scenario.toml), which a resumed
        // run and the policy's users read back
        let with_avs = match args.avs.av_share {
            None => None,
            Some(_) => {
                let rs = args
                    .avs
                    .apply(super::common::load_scenario(&args.scenario)?)?;
                Some(rs.scenario_with_absolute_paths())
            }
        };
        let av_out = with_avs.as_ref().map(|sc| {
            args.out.clone().unwrap_or_else(|| {
                PathBuf::from(format!("out/train-{}-av-{}", sc.name, args.reward))
            })
        });
        let scenario_arg = match &av_out {
            None => args.scenario.clone(),
            Some(out) => out.join("scenario.toml").display().to_string(),
        };
        if let (Some(s), Some(out)) = (&with_avs, &av_out) {
            if mapc_rl::checkpoint::checkpoint_path(out).exists() {
                bail!(
                    "{} already holds a run; continue it with --resume {} or choose another -o",
                    out.display(),
                    out.display()
                );
            }
            std::fs::create_dir_all(out).with_context(|| format!("creating {}", out.display()))?;
            s.save(Path::new(&scenario_arg))?;
        }
        let sc = load_training_scenario(&scenario_arg)?;
        if args.distributed && distribution_of(&scenario_arg)?.is_some() {
            bail!(
                "{}: a merge distribution trains centralized policies only",
                args.scenario
            );
        }
        if args.horizon.is_none() {
            config.horizon = sc.spec.horizon_steps as usize;
        }
        // the flags are checked as they are parsed; a preset or a config file's keys here
        mapc_rl::limits::check_config(&config, "").map_err(|e| match &args.config {
            Some(p) => anyhow::anyhow!("{}: {e}", p.display()),
            None => anyhow::anyhow!("hyperparameters: {e}"),
        })?;
        let n_av = args.n_av.or(sc.n_av).unwrap_or(5);
        let mut spec = PolicySpec::centralized(&scenario_arg, reward.name(), n_av);
        if !args.distributed
            && let Some(f) = &args.features
        {
            let features = Features::parse(f).map_err(anyhow::Error::msg)?;
            if features.dist || features.congestion || features.merge_info {
                bail!(
                    "--features {f}: a centralized policy observes only `lanes` besides the paper's five values (dist, congestion and merge are --distributed augmentations)"
                );
            }
            if features.lanes {
                spec = spec.with_lanes();
            }
        }
        if args.distributed {
            let features = Features::parse(args.features.as_deref().unwrap_or("full"))
                .map_err(anyhow::Error::msg)?;
            spec = PolicySpec::distributed(
                &scenario_arg,
                n_av,
                features,
                AgentReward {
                    eta1: args.eta1,
                    eta2: args.eta2,
                    exit_bonus: args.exit_bonus,
                    count_waiting: args.count_waiting,
                    share: args.reward_share,
                },
            );
        }
        let out = av_out.unwrap_or_else(|| {
            args.out
                .clone()
                .unwrap_or_else(|| PathBuf::from(format!("out/train-{}-{}", sc.name, spec.reward)))
        });
        spec.deploy = args.deploy;
        let mut run = TrainRun::create(&out, spec, config, args.checkpoint_every)?;
        if let Some(init) = &args.init {
            start_from_policy(&mut run, init)?;
        }
        run
    };
    run.keep_checkpoints = args.keep_checkpoints;
    if let Some(by) = args.best_by {
        run.set_best_by(by.into())?;
    }
    let sc = load_training_scenario(&run.spec.scenario)?;
    let mut spec = sc.spec.clone();
    spec.horizon_steps = run.state.config.horizon as u64;
    if let Some(dcfg) = run.spec.distributed_config() {
        // a distributed policy trains where its rule lets it drive: only the AVs whose next merge admits it are
        // agents (the others drive as humans)
        if let Some(rule) = run.spec.deploy {
            spec = mapc_rl::deploy::deploy_by_road(&spec, rule)?
                .spec
                .with_context(|| {
                    format!(
                        "{}: no road leads to a merge where `--deploy {rule}` lets the policy drive",
                        run.spec.scenario
                    )
                })?;
        }
        // (the sizes agree: `Checkpoint::load` checks a resumed run's, a new run derives them from the features)
        DistributedEnv::new(spec.clone(), dcfg)?;
        let factory = move || DistributedEnv::new(spec.clone(), dcfg).expect("validated above");
        let last = train_loop(&mut run, &args, &mut |r| r.step_agents(&factory))?;
        return Ok((run, last));
    }
    let env_cfg = MergeEnvConfig {
        reward: run.spec.reward.parse().map_err(anyhow::Error::msg)?,
        n_av: run.spec.n_av,
        norm: mapc_rl::env::obs::ObsNorm {
            max_speed: run.spec.max_speed,
            length: run.spec.norm_length,
        },
        accel_min: run.spec.accel_min,
        accel_max: run.spec.accel_max,
        lanes: run.spec.lanes,
    };
    let source = training_source(&run.spec.scenario, spec.horizon_steps)?;
    let probe = MergeEnv::with_source(source.clone(), env_cfg.clone())?;
    if probe.obs_dim() != run.spec.obs_dim {
        bail!(
            "run expects {} observation values, scenario gives {}",
            run.spec.obs_dim,
            probe.obs_dim()
        );
    }
    let factory = move || -> Box<dyn Env> {
        Box::new(MergeEnv::with_source(source.clone(), env_cfg.clone()).expect("validated"))
    };
    let last = train_loop(&mut run, &args, &mut |r| r.step(&factory))?;
    Ok((run, last))
}

/// `--init`: a new run takes the weights of a policy with the same architecture and observation layout.
fn start_from_policy(run: &mut TrainRun, init: &Path) -> anyhow::Result<()> {
    let ck = mapc_rl::Checkpoint::load(&mapc_rl::checkpoint::policy_file(init))?;
    let (a, b) = (&ck.spec, &run.spec);
    if ck.spec.distributed.is_some()
        || (a.obs_dim, a.act_dim, a.max_speed, a.norm_length)
            != (b.obs_dim, b.act_dim, b.max_speed, b.norm_length)
        || ck.state.config.hidden != run.state.config.hidden
        || ck.state.config.shared_value != run.state.config.shared_value
    {
        bail!(
            "--init {}: its policy ({} observation values, {} actions, hidden {:?}) does not fit this run's ({}, {}, {:?})",
            init.display(),
            a.obs_dim,
            a.act_dim,
            ck.state.config.hidden,
            b.obs_dim,
            b.act_dim,
            run.state.config.hidden
        );
    }
    run.state.model = ck.state.model;
    Ok(())
}

/// Runs the remaining iterations with a progress bar, then saves and reports.
fn train_loop(
    run: &mut TrainRun,
    args: &Args,
    step: &mut dyn FnMut(&mut TrainRun) -> Result<IterationStats, mapc_rl::RlError>,
) -> anyhow::Result<Option<IterationStats>> {
    let total = run.state.config.iterations;
    let bar = if args.json {
        ProgressBar::hidden()
    } else {
        ProgressBar::new(total)
    };
    bar.set_style(
        ProgressStyle::with_template("{elapsed_precise} [{bar:30}] {pos}/{len} {msg}")
            .expect("static template")
            .progress_chars("=> "),
    );
    bar.set_position(run.state.iteration);
    let mut last: Option<IterationStats> = run.log.rows.last().cloned();
    while !run.done() {
        let s = step(run)?;
        bar.set_position(s.iteration);
        bar.set_message(format!(
            "return {:.2}  outflow {:.0} veh/h  speed {:.2} m/s  kl {:.4}",
            s.mean_return, s.mean_outflow, s.mean_speed, s.kl
        ));
        last = Some(s);
    }
    run.save()?;
    bar.finish();
    Ok(last)
}
