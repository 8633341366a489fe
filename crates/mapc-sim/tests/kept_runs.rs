//! The regime report's human runs kept for a job's later steps (`mapc_sim::keep_runs`, which `mapc pipeline`
//! turns on): a kept run gives the bits a new run gives, the report's runs serve the baseline's, and runs are kept
//! only when asked and only by the report. A test binary of its own: keeping is for the whole process.

use mapc_scenario::ResolvedScenario;
use mapc_sim::{Simulation, merge_regimes, run_baseline_spec, spec_from_scenario};

#[test]
fn kept_runs_give_the_bits_of_new_runs_and_are_not_run_again() {
    // congested, with AVs (which the humans' runs drive as humans)
    let rs = ResolvedScenario::load(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../../scenarios/two_lane_merge_jam_av.toml"
    ))
    .unwrap();
    let spec = spec_from_scenario(&rs).unwrap();
    assert!(spec.vehicle_types.iter().any(|t| t.controlled));
    let humans = spec.all_human();
    let seeds = [0, 1, 2];
    let new_run = |seed| {
        let m = Simulation::from_spec(humans.clone(), seed)
            .unwrap()
            .run()
            .unwrap();
        format!("{m:?}")
    };
    let new_runs: Vec<String> = seeds.iter().map(|&s| new_run(s)).collect();
    let regime =
        |seeds: &[u64]| serde_json::to_string(&merge_regimes(&spec, seeds).unwrap()).unwrap();
    let new_regime = regime(&seeds[..2]);
    let later_regime = regime(&[3, 4, 5]);
    // not kept unless asked
    regime(&seeds[..2]);
    assert_eq!(mapc_sim::runs_reused(), 0);

    mapc_sim::keep_runs();
    assert_eq!(regime(&seeds[..2]), new_regime);
    assert_eq!(mapc_sim::runs_reused(), 0);
    // the report again: both its runs kept
    assert_eq!(regime(&seeds[..2]), new_regime);
    assert_eq!(mapc_sim::runs_reused(), 2);
    // the baseline: seeds 0 and 1 are the report's runs, seed 2 is new
    let baseline: Vec<String> = run_baseline_spec(&humans, &seeds)
        .unwrap()
        .iter()
        .map(|m| format!("{m:?}"))
        .collect();
    assert_eq!(baseline, new_runs);
    assert_eq!(mapc_sim::runs_reused(), 4);
    // the baseline's own runs are not kept
    run_baseline_spec(&humans, &[5]).unwrap();
    run_baseline_spec(&humans, &[5]).unwrap();
    assert_eq!(mapc_sim::runs_reused(), 4);
    // a run the report did not observe is observed anew, and gives the same report as before
    assert_eq!(regime(&seeds[1..]), regime(&seeds[1..]));
    assert_eq!(mapc_sim::runs_reused(), 4 + 1 + 2);
    // another spec is another key: nothing reused
    let mut other = humans.clone();
    other.horizon_steps -= 1;
    run_baseline_spec(&other, &seeds[..1]).unwrap();
    assert_eq!(mapc_sim::runs_reused(), 7);
    // a spec with no AV is its own humans' spec (`mapc sim` takes the regime's runs as its own then)
    let kept = mapc_sim::KeptRuns::of(&humans);
    assert_eq!(format!("{:?}", kept.run(2).unwrap()), new_runs[2]);
    assert_eq!(mapc_sim::runs_reused(), 8);
    // an AV is exempt from teleports outside the humans' runs: its spec is another key
    mapc_sim::KeptRuns::of(&spec).run(2).unwrap();
    assert_eq!(mapc_sim::runs_reused(), 8);

    // the job's later seeds fill the report's last round: on two threads, three new seeds leave one idle, which
    // runs the first later seed neither kept nor the report's (6); it is kept, and the report is unchanged
    mapc_sim::will_run(&[0, 3, 6, 7]);
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(2)
        .build()
        .unwrap();
    assert_eq!(pool.install(|| regime(&[3, 4, 5])), later_regime);
    assert_eq!(mapc_sim::runs_reused(), 8);
    assert!(kept.is_kept(6) && !kept.is_kept(7));
    assert_eq!(format!("{:?}", kept.run(6).unwrap()), new_run(6));
    assert_eq!(mapc_sim::runs_reused(), 9);
    // a report whose runs fill their rounds runs nothing more
    mapc_sim::will_run(&[8, 9]);
    pool.install(|| regime(&[10, 11]));
    assert!(!kept.is_kept(8));
}
