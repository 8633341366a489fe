//! Every shipped scenario (the files under scenarios/ and the built-in ones) over the allowed ranges of the step,
//! the flows and the depart speeds, for a short horizon: the scenario is accepted, its run ends without a panic
//! and its metrics are sane numbers. A long step or a fast vehicle crosses short roads whole in one step (the
//! I-210 window has an 8 m road): a vehicle on a route that ends in a dead end once ran past its route's last
//! lane there.

use mapc_scenario::ranges::{SPEED_MPS, STEP_S};
use mapc_scenario::{ResolvedScenario, Scenario};
use mapc_sim::{RunMetrics, Simulation, spec_from_scenario};
use proptest::prelude::*;
use std::path::{Path, PathBuf};

/// Steps of each run: enough for the first vehicles to cross the short roads at any step.
const HORIZON_STEPS: u32 = 40;

/// The shipped scenarios: (where relative graph files are found, the name to report, the scenario).
fn shipped() -> &'static [(PathBuf, String, Scenario)] {
    static SHIPPED: std::sync::OnceLock<Vec<(PathBuf, String, Scenario)>> =
        std::sync::OnceLock::new();
    SHIPPED.get_or_init(|| {
        let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../scenarios");
        let mut files: Vec<PathBuf> = std::fs::read_dir(&dir)
            .unwrap()
            .map(|e| e.unwrap().path())
            .filter(|p| {
                p.extension().is_some_and(|x| x == "toml")
                    && mapc_graph::filekind::sniff_path(p) == Some(mapc_graph::MapcFile::Scenario)
            })
            .collect();
        files.sort();
        assert!(files.len() >= 10, "{files:?}");
        let mut out: Vec<(PathBuf, String, Scenario)> =
            ["simple_merge", "two_lane_merge", "lane_drop"]
                .iter()
                .map(|name| {
                    (
                        dir.clone(),
                        name.to_string(),
                        Scenario::builtin(name).unwrap(),
                    )
                })
                .collect();
        out.extend(files.into_iter().map(|p| {
            let sc = Scenario::load(&p).unwrap();
            (dir.clone(), p.display().to_string(), sc)
        }));
        out
    })
}

/// `sc` with step `step_s`, every flow at `share` of what its entry road takes per flow there, every depart speed
/// `depart_mps`, and a short horizon without warm-up.
fn varied(sc: &Scenario, step_s: f64, share: f64, depart_mps: f64) -> Scenario {
    let mut sc = sc.clone();
    sc.step_s = step_s;
    sc.warmup_steps = 0;
    sc.horizon_steps = HORIZON_STEPS;
    let capacity = mapc_scenario::bounds::entry_capacity_vph(step_s);
    let froms: Vec<String> = sc.flows.iter().map(|f| f.from.clone()).collect();
    for f in &mut sc.flows {
        let sharing = froms.iter().filter(|&from| *from == f.from).count() as f64;
        f.vehs_per_hour = share * capacity / sharing;
        f.depart_speed_mps = depart_mps;
    }
    sc
}

fn assert_sane(m: &RunMetrics, what: &str) {
    let mut numbers = vec![
        ("outflow", m.outflow_veh_h),
        ("inflow", m.inflow_veh_h),
        ("avg speed", m.avg_speed_mps),
        ("end flow", m.end_flow_veh_h),
        ("lane changes per veh-km", m.lane_changes_per_veh_km),
    ];
    // means over the vehicles that left: none without one
    if m.arrived > 0 {
        numbers.extend([
            ("travel time", m.mean_travel_time_s),
            ("delay", m.mean_delay_s),
        ]);
    }
    for (name, x) in numbers {
        assert!(x.is_finite() && x >= 0.0, "{what}: {name} {x}");
    }
    assert!(m.avg_speed_mps <= SPEED_MPS.hi, "{what}: {m:?}");
    assert!(
        m.merge_flows_veh_h
            .iter()
            .all(|x| x.is_finite() && *x >= 0.0),
        "{what}: {m:?}"
    );
}

/// Resolve and run `sc` (shipped as `origin` in `dir`) for seed `seed`; its metrics.
fn run(dir: &Path, origin: &str, sc: Scenario, seed: u64) -> RunMetrics {
    let what = format!("{origin} (step {} s, seed {seed})", sc.step_s);
    let rs = ResolvedScenario::resolve(sc, dir, origin).unwrap_or_else(|e| panic!("{what}: {e}"));
    let spec = spec_from_scenario(&rs).unwrap_or_else(|e| panic!("{what}: {e}"));
    let mut sim = Simulation::from_spec(spec, seed).unwrap_or_else(|e| panic!("{what}: {e}"));
    // a collision check is for steps the car-following model is made for; the long steps are checked for
    // their arithmetic
    sim.set_invariant_checks(false);
    let m = sim.run().unwrap_or_else(|e| panic!("{what}: {e}"));
    assert_sane(&m, &what);
    m
}

/// The reported cases on the I-210 window with its 8 m road: a 10 s (and 8 s) step with the main flows at
/// 100 veh/h, and a 2 s step with the main flows at 150 veh/h and the ramp's vehicles departing at 150 m/s.
#[test]
fn the_i210_window_runs_with_long_steps_and_fast_departures() {
    let (dir, origin, sc) = shipped()
        .iter()
        .find(|(_, o, _)| o.ends_with("i210_window_lanes.toml"))
        .unwrap();
    for (step_s, main_vph, ramp_depart) in
        [(10.0, 100.0, 7.5), (8.0, 100.0, 7.5), (2.0, 150.0, 150.0)]
    {
        let mut sc = sc.clone();
        sc.step_s = step_s;
        sc.horizon_steps = 400;
        for f in &mut sc.flows {
            if f.id.starts_with("main") {
                f.vehs_per_hour = main_vph;
            } else {
                f.depart_speed_mps = ramp_depart;
            }
        }
        for seed in 0..3 {
            let m = run(dir, origin, sc.clone(), seed);
            assert!(m.departed > 0, "{m:?}");
        }
    }
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 64, failure_persistence: None, ..ProptestConfig::default() })]

    #[test]
    fn every_shipped_scenario_runs_over_the_allowed_steps_flows_and_depart_speeds(
        which in any::<prop::sample::Index>(),
        step_s in prop_oneof![Just(STEP_S.hi), Just(8.0), Just(2.0), STEP_S.lo * 100.0..=STEP_S.hi],
        share in prop_oneof![Just(1.0), 0.0..=1.0f64],
        depart_mps in prop_oneof![Just(SPEED_MPS.hi), SPEED_MPS.lo..=SPEED_MPS.hi],
        seed in 0u64..4,
    ) {
        let (dir, origin, sc) = &shipped()[which.index(shipped().len())];
        run(dir, origin, varied(sc, step_s, share, depart_mps), seed);
    }
}
