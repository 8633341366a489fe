//! A trace holds the measured frames only, and stays within its bound of rows by writing one frame in 2, 4, ...

use mapc_scenario::ResolvedScenario;
use mapc_sim::{Simulation, TraceBudget, spec_from_scenario, trace_run};

fn frames(text: &str) -> Vec<f64> {
    let mut times: Vec<f64> = text
        .lines()
        .map(|l| l.split(',').next().unwrap().parse::<f64>().unwrap())
        .collect();
    times.dedup();
    times
}

#[test]
fn a_trace_starts_where_the_warm_up_ends() {
    let rs = ResolvedScenario::load("simple_merge").unwrap();
    let mut spec = spec_from_scenario(&rs).unwrap();
    spec.warmup_steps = 200;
    spec.horizon_steps = 100;
    let mut out = Vec::new();
    let run = trace_run(&spec, 0, &mut out).unwrap();
    let times = frames(&String::from_utf8(out).unwrap());
    // frames of steps 200..=300, each 0.5 s, from the scenario's start time
    assert_eq!(times.len(), 101);
    assert!((times[1] - times[0] - 0.5).abs() < 1e-9);
    assert!(
        run.note
            .unwrap()
            .contains("from the end of the warm-up (step 200)")
    );
}

#[test]
fn a_trace_past_its_bound_thins_its_frames_and_says_so() {
    let rs = ResolvedScenario::load("simple_merge").unwrap();
    let mut spec = spec_from_scenario(&rs).unwrap();
    // a filled merge at the first measured frame: some 60 000 rows over the 1600 frames; allow 10 000
    spec.warmup_steps = 400;
    spec.horizon_steps = 1600;
    let mut sim = Simulation::from_spec(spec.clone(), 0).unwrap();
    let mut budget = TraceBudget::with_max_rows(&spec, 10_000);
    let mut out = Vec::new();
    budget.write_frame(&sim, &mut out).unwrap();
    while !sim.is_done() {
        sim.step().unwrap();
        budget.write_frame(&sim, &mut out).unwrap();
    }
    assert!(budget.rows() <= 10_000, "{}", budget.rows());
    let text = String::from_utf8(out).unwrap();
    assert_eq!(text.lines().count() as u64, budget.rows());
    let times = frames(&text);
    // evenly spaced frames, further apart than one step
    let gap = times[1] - times[0];
    assert!(gap >= 2.0, "{gap}");
    assert!(
        times
            .windows(2)
            .all(|w| ((w[1] - w[0]) / gap).fract() < 1e-9)
    );
    assert!(budget.note().unwrap().contains("to stay under 10000 rows"));
    // within the bound, every frame: the shipped traces are unchanged
    let spec = spec_from_scenario(&rs).unwrap();
    let mut full = Vec::new();
    let run = trace_run(&spec, 0, &mut full).unwrap();
    assert_eq!(run.note, None);
    assert_eq!(frames(&String::from_utf8(full).unwrap()).len(), 2001);
}
