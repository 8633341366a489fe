//! A SUMO user's scenario run with Krauss drivers (scenarios/sumo/highway_ramp: six types, trucks among cars,
//! routes by the off-ramp): the figures of two seeds pinned bit for bit, and the same for any thread count.

use mapc_scenario::ResolvedScenario;
use mapc_sim::{RunMetrics, Simulation, spec_from_scenario};

fn scenario() -> mapc_sim::SimSpec {
    let cfg = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../../scenarios/sumo/highway_ramp/highway-ramp.sumocfg"
    );
    let rs = ResolvedScenario::load(cfg).unwrap();
    spec_from_scenario(&rs).unwrap()
}

fn fingerprint(m: &RunMetrics) -> String {
    format!(
        "arrived {} departed {} travel {:016x} speed {:016x} lane changes {}",
        m.arrived,
        m.departed,
        m.mean_travel_time_s.to_bits(),
        m.avg_speed_mps.to_bits(),
        m.lane_changes
    )
}

#[test]
fn the_krauss_run_is_pinned_bit_for_bit() {
    let spec = scenario();
    let got: Vec<String> = (0..2)
        .map(|seed| {
            fingerprint(
                &Simulation::from_spec(spec.clone(), seed)
                    .unwrap()
                    .run()
                    .unwrap(),
            )
        })
        .collect();
    let expected = [
        "arrived 449 departed 456 travel 4040ec8778132423 speed 4038593ab86cc21d lane changes 246",
        "arrived 449 departed 456 travel 4040f30eb5c400e6 speed 40384ea83f79538c lane changes 258",
    ];
    assert_eq!(got, expected, "the Krauss run changed: {got:#?}");
}

#[test]
fn the_krauss_run_is_the_same_for_any_thread_count() {
    let spec = scenario();
    let seeds: Vec<u64> = (0..4).collect();
    let one = rayon::ThreadPoolBuilder::new()
        .num_threads(1)
        .build()
        .unwrap();
    let two = rayon::ThreadPoolBuilder::new()
        .num_threads(2)
        .build()
        .unwrap();
    let a = one.install(|| run_baseline_spec_fingerprints(&spec, &seeds));
    let b = two.install(|| run_baseline_spec_fingerprints(&spec, &seeds));
    assert_eq!(a, b);
}

fn run_baseline_spec_fingerprints(spec: &mapc_sim::SimSpec, seeds: &[u64]) -> Vec<String> {
    mapc_sim::run_baseline_spec(spec, seeds)
        .unwrap()
        .iter()
        .map(fingerprint)
        .collect()
}
