//! The evaluation's figures are the simulation's own measurement, whatever drives the AVs, with or without a
//! warm-up.

use super::*;
use std::path::PathBuf;

fn root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../..")
}

/// The I-696 corridor with windows at J43, J37 and J60 (`scenarios/i696_all_windows.toml`).
fn all_windows() -> SimSpec {
    let path = root().join("scenarios/i696_all_windows.toml");
    let rs = mapc_scenario::ResolvedScenario::load(path.to_str().unwrap()).unwrap();
    mapc_sim::spec_from_scenario(&rs).unwrap()
}

/// `spec` with `warmup` steps before a horizon of `horizon` steps.
fn timed(mut spec: SimSpec, warmup: u64, horizon: u64) -> SimSpec {
    spec.warmup_steps = warmup;
    spec.horizon_steps = horizon;
    spec
}

fn robust() -> (Checkpoint, PathBuf) {
    let file = root().join("policies/merge_robust.json");
    (Checkpoint::load(&file).unwrap(), file)
}

fn eval(spec: &SimSpec, seeds: &[u64]) -> EvalReport {
    let (ck, file) = robust();
    evaluate(&EvalRequest {
        ck: &ck,
        policy_file: &file,
        scenario: "test",
        spec,
        scenario_n_av: Some(5),
        seeds,
        mode: ActionMode::Mean,
        baseline: true,
    })
    .unwrap()
    .0
}

/// Where merge_robust's rule leaves every window to the humans (J37 and J60 give the main road priority; J43's
/// window is taken out, its merge still measured), the evaluation reports the humans' figures bit for bit: every
/// merge's flow and the corridor's end are `mapc sim`'s, with and without a warm-up.
#[test]
fn every_window_left_to_the_humans_reports_the_humans_measurement() {
    let mut spec = all_windows();
    let j43 = spec.control_windows.remove(0);
    spec.control_region
        .as_mut()
        .unwrap()
        .retain(|r| !j43.roads.contains(r));
    assert_eq!(spec.measure_points.len(), 3, "{:?}", spec.measure_points);
    let seeds = [0, 1, 2];
    for (warmup, horizon) in [(0, 2000), (1000, 3000)] {
        let spec = timed(spec.clone(), warmup, horizon);
        let report = eval(&spec, &seeds);
        assert_eq!(report.withheld.len(), 2, "{:?}", report.withheld);
        let humans =
            mapc_sim::Summary::of(&mapc_sim::run_baseline_spec(&spec.all_human(), &seeds).unwrap());
        let merges = report.merges.as_ref().unwrap();
        assert_eq!(merges.len(), humans.merge_flows.len());
        for (m, h) in merges.iter().zip(&humans.merge_flows) {
            let h = Figure::from(*h);
            assert_eq!(m.figures.flow, h, "warm-up {warmup}: {m:?}");
            assert_eq!(m.figures.baseline, Some(h), "warm-up {warmup}: {m:?}");
        }
        let end = report.end_flow.as_ref().unwrap();
        assert_eq!(end.flow, Figure::from(humans.end_flow));
        assert_eq!(end.baseline, Some(Figure::from(humans.end_flow)));
        assert_eq!(report.outflow, Figure::from(humans.outflow));
    }
}

/// With the policy driving J43's window and a warm-up, the flows past the merges agree with the flow past the
/// corridor's end: every vehicle that leaves at the end passed J60 first, except those from the one merging road
/// after it (R72, 200 veh/h). Before, a policy's episode stopped a warm-up short of the horizon and a second
/// counter divided its counts by the whole horizon: J60 read 1309 veh/h against an outflow of 1994.
#[test]
fn under_a_policy_and_a_warmup_the_merges_agree_with_the_corridors_end() {
    let spec = timed(all_windows(), 1000, 3000);
    let seeds = [0, 1];
    let report = eval(&spec, &seeds);
    assert_eq!(report.withheld.len(), 2, "{:?}", report.withheld);
    let merges = report.merges.as_ref().unwrap();
    let j60 = merges.iter().find(|m| m.merge == "J60").unwrap();
    let end = report.end_flow.as_ref().unwrap();
    // the corridor's only exit is its end
    assert_eq!(end.flow, report.outflow);
    // R72's 200 veh/h, and 60 veh/h (25 vehicles over the 1500 s) for those between J60 and the end when the
    // measurement starts and ends
    assert!(
        j60.figures.flow.mean >= end.flow.mean - 260.0,
        "{:?} against the end's {:?}",
        j60.figures.flow,
        end.flow
    );
    // every run is the whole simulation
    let (ck, file) = robust();
    let driver = PolicyDriver::for_scenario(&ck, &file, "test", Some(5)).unwrap();
    for run in driver.run(&ck, &spec, &seeds, ActionMode::Mean).unwrap() {
        assert_eq!(run.steps, spec.horizon_steps, "{run:?}");
    }
}

#[test]
fn the_measured_rule_deploys_only_a_policy_that_beats_the_humans_on_its_own_measure() {
    let set = |outflow: (f64, f64), speed: (f64, f64)| FigureSet {
        outflow: Figure {
            mean: outflow.0,
            ci95: outflow.1,
        },
        inflow: Figure::default(),
        speed: Figure {
            mean: speed.0,
            ci95: speed.1,
        },
        travel_time: Figure::default(),
        seeds: 20,
    };
    let humans = set((3600.0, 0.0), (13.5, 0.1));
    // a speed policy faster with disjoint intervals, the same outflow: deployed
    assert_eq!(
        measured_refusal("speed", &set((3600.0, 0.0), (14.0, 0.1)), &humans),
        None
    );
    // faster, but its intervals overlap the humans': withheld
    let overlap = measured_refusal("speed", &set((3600.0, 0.0), (13.65, 0.1)), &humans).unwrap();
    assert!(overlap.contains("not above"), "{overlap}");
    // faster, but losing vehicles: withheld
    let loses = measured_refusal("speed", &set((3400.0, 10.0), (14.0, 0.1)), &humans).unwrap();
    assert!(loses.contains("below the humans'"), "{loses}");
    // an outflow policy is judged on its outflow
    assert!(measured_refusal("outflow", &set((3600.0, 0.0), (14.0, 0.1)), &humans).is_some());
    assert_eq!(
        measured_refusal("outflow", &set((3700.0, 5.0), (13.0, 0.1)), &humans),
        None
    );
}
