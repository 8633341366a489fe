//! Is a distributed policy's change a social dilemma? Runs two checkpoints of one training run side by side on the
//! Simple Merge and asks, on the same seeds and for the same agents (vehicle ids follow the departure schedule):
//!
//! 1. does an agent that switches from BASE to DEVIANT, among agents that keep BASE, get a higher return?
//! 2. what does its switch cost the agents that kept BASE?
//! 3. is everyone worse off when all switch (DEVIANT everywhere against BASE everywhere)?
//! 4. does an agent that keeps BASE among DEVIANT agents lose by it?
//!
//! Yes to 1, 3 and 4 is a social dilemma: each agent's own policy gradient favours the switch, and all lose.
//!
//!     cargo run --release -p mapc-rl --example deviation -- BASE.json DEVIANT.json [SEEDS] [ONE_IN] [--sample]
//!
//! SEEDS: evaluation seeds 0.. (default 100); ONE_IN: one agent in this many deviates (default 8, by a hash of
//! its id, so the deviants are spread over the flow); `--sample`: sampled actions, the policy training
//! optimises (default: the Gaussian's mean, as `mapc eval`). Returns are each agent's own (undiscounted, no
//! reward share); a row's seeds are those where it found an agent to compare.

use std::path::Path;

use anyhow::{Context, bail};
use mapc_rl::Checkpoint;
use mapc_rl::eval::{MixedEpisode, run_mixed_population};
use mapc_rl::rng::mix_seed;
use mapc_rl::rollout::ActionMode;
use mapc_sim::{MeanCi, VehicleId};

fn main() -> anyhow::Result<()> {
    let mut args: Vec<String> = std::env::args().skip(1).collect();
    let mode = if args.iter().any(|a| a == "--sample") {
        args.retain(|a| a != "--sample");
        ActionMode::Sample
    } else {
        ActionMode::Mean
    };
    let [base_path, deviant_path, rest @ ..] = args.as_slice() else {
        bail!("usage: deviation BASE.json DEVIANT.json [SEEDS] [ONE_IN] [--sample]");
    };
    let n_seeds: u64 = rest
        .first()
        .map_or(Ok(100), |s| s.parse())
        .context("SEEDS")?;
    let one_in: u64 = rest.get(1).map_or(Ok(8), |s| s.parse()).context("ONE_IN")?;
    if one_in < 2 {
        bail!("ONE_IN must be at least 2");
    }
    let base = Checkpoint::load(Path::new(base_path))?;
    let deviant = Checkpoint::load(Path::new(deviant_path))?;
    let mut cfg = base
        .spec
        .distributed_config()
        .context("BASE is not a distributed policy")?;
    if deviant.spec.distributed_config() != Some(cfg) {
        bail!("the two policies were trained with different observations or rewards");
    }
    // each agent's own return, also for a run trained with a shared reward (rewards move no vehicle)
    cfg.reward.share = 0.0;
    let resolved = mapc_scenario::ResolvedScenario::load("simple_merge")?;
    let spec = mapc_sim::spec_from_scenario(&resolved)?;
    let seeds: Vec<u64> = (0..n_seeds).collect();
    let (b, d) = (&base.state.model, &deviant.state.model);
    let focal = move |id: VehicleId| mix_seed(&[id as u64, 0xDE71]).is_multiple_of(one_in);
    let run = |base, deviant, deviates: &(dyn Fn(VehicleId) -> bool + Sync)| {
        run_mixed_population(base, deviant, deviates, &spec, &cfg, &seeds, mode)
    };
    let all_base = run(b, b, &|_| false)?;
    let focal_deviate = run(b, d, &focal)?;
    let all_deviant = run(d, d, &|_| false)?;
    let focal_keep_base = run(d, b, &focal)?;

    println!(
        "{} seeds, one agent in {one_in} focal, actions: {mode:?}\n",
        seeds.len()
    );
    println!("population                         outflow (veh/h)      agents' mean return");
    for (name, eps) in [
        ("all BASE", &all_base),
        ("focal DEVIANT among BASE", &focal_deviate),
        ("all DEVIANT", &all_deviant),
        ("focal BASE among DEVIANT", &focal_keep_base),
    ] {
        let outflow = MeanCi::of(&eps.iter().map(|e| e.metrics.outflow).collect::<Vec<_>>());
        let ret = MeanCi::of(&per_seed(eps));
        println!(
            "{name:<34} {:>7.1} +- {:<6.1}     {:>7.2} +- {:.2}",
            outflow.mean, outflow.ci95, ret.mean, ret.ci95
        );
    }
    println!("\nchange in an agent's return, same seeds and agents (mean over seeds +- 95 % CI):");
    // which agents a row compares: the focal ones (Some(true)), the others (Some(false)), or all (None)
    let rows = [
        (
            "1. focal agents switch to DEVIANT",
            &focal_deviate,
            &all_base,
            Some(true),
        ),
        (
            "2. ... the others (kept BASE)",
            &focal_deviate,
            &all_base,
            Some(false),
        ),
        ("3. everyone switches", &all_deviant, &all_base, None),
        (
            "4. focal agents keep BASE among DEVIANT",
            &focal_keep_base,
            &all_deviant,
            Some(true),
        ),
    ];
    for (name, after, before, which) in rows {
        let select = |id: VehicleId| which.is_none_or(|f| focal(id) == f);
        let per_seed = paired_change(after, before, select);
        let change = MeanCi::of(&per_seed);
        println!(
            "{name:<42} {:>+7.3} +- {:.3}   ({} seeds)",
            change.mean,
            change.ci95,
            per_seed.len()
        );
    }
    Ok(())
}

/// Per seed, the agents' mean return.
fn per_seed(eps: &[MixedEpisode]) -> Vec<f64> {
    eps.iter()
        .filter_map(|e| mean(e.agents.iter().map(|a| a.ret)))
        .collect()
}

/// Per seed, the mean over the selected agents present in both episodes of (return after - return before).
fn paired_change(
    after: &[MixedEpisode],
    before: &[MixedEpisode],
    select: impl Fn(VehicleId) -> bool,
) -> Vec<f64> {
    after
        .iter()
        .zip(before)
        .filter_map(|(a, b)| {
            mean(a.agents.iter().filter(|x| select(x.id)).filter_map(|x| {
                let y = b.agents.iter().find(|y| y.id == x.id)?;
                Some(x.ret - y.ret)
            }))
        })
        .collect()
}

fn mean(xs: impl Iterator<Item = f64>) -> Option<f64> {
    let (n, s) = xs.fold((0usize, 0.0), |(n, s), x| (n + 1, s + x));
    (n > 0).then(|| s / n as f64)
}
