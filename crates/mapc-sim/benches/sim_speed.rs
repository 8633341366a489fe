//! Simulator speed: vehicle-steps per second on one core, and the wall time of the 100-seed baseline on two
//! threads (`cargo bench -p mapc-sim --bench sim_speed [-- SCENARIO]`). The same figures come from `mapc bench`.

use mapc_scenario::ResolvedScenario;
use mapc_sim::{Simulation, run_baseline_spec, spec_from_scenario};
use std::time::Instant;

fn main() {
    let name = std::env::args()
        .skip(1)
        .find(|a| !a.starts_with('-'))
        .unwrap_or_else(|| "simple_merge".into());
    // cargo runs benches in the crate's folder: a path relative to the workspace root works too
    let in_root = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../..")
        .join(&name);
    let name = if !std::path::Path::new(&name).exists() && in_root.exists() {
        in_root.to_string_lossy().into_owned()
    } else {
        name
    };
    let rs = ResolvedScenario::load(&name).expect("scenario");
    let spec = spec_from_scenario(&rs).expect("spec");

    // warm up caches and the allocator
    Simulation::from_spec(spec.clone(), 999)
        .unwrap()
        .run()
        .unwrap();

    // `--profile`: a short run for a profiler (3 seeds, no baseline)
    let profile = std::env::args().any(|a| a == "--profile");
    let seeds = if profile { 3u64 } else { 20 };
    #[cfg(feature = "count-idm")]
    {
        mapc_sim::models::cf::idm::take_idm_calls();
        mapc_sim::models::cf::idm::take_idm_batches();
    }
    let start = Instant::now();
    let mut vehicle_steps = 0u64;
    let mut steps = 0u64;
    for seed in 0..seeds {
        let mut sim = Simulation::from_spec(spec.clone(), seed).unwrap();
        sim.set_invariant_checks(false);
        let m = sim.run().unwrap();
        vehicle_steps += m.vehicle_steps;
        steps += m.steps;
    }
    let wall = start.elapsed().as_secs_f64();
    #[cfg(feature = "count-idm")]
    {
        let calls = mapc_sim::models::cf::idm::take_idm_calls() as f64;
        let batches = mapc_sim::models::cf::idm::take_idm_batches() as f64;
        println!(
            "{}: {:.2} IDM steps per vehicle-step: {:.2} batches of four (next_speed_x4, unread lanes \
             included), {:.2} single calls (next_speed)",
            rs.origin,
            calls / vehicle_steps as f64,
            batches / vehicle_steps as f64,
            (calls - 4.0 * batches) / vehicle_steps as f64
        );
    }
    if profile {
        // a fingerprint of the results, to compare builds bit for bit
        let mut fp = 0xcbf2_9ce4_8422_2325u64;
        for seed in 0..seeds {
            let mut sim = Simulation::from_spec(spec.clone(), seed).unwrap();
            let m = sim.run().unwrap();
            let (routes, lanes) = sim.routes_held();
            println!(
                "{}: seed {seed}: {routes} routes held at the end, {lanes} route lanes",
                rs.origin
            );
            for x in [
                m.outflow_veh_h,
                m.inflow_veh_h,
                m.avg_speed_mps,
                m.mean_travel_time_s,
                m.mean_delay_s,
            ] {
                fp = (fp ^ x.to_bits()).wrapping_mul(0x0000_0100_0000_01b3);
            }
            fp = (fp ^ m.vehicle_steps).wrapping_mul(0x0000_0100_0000_01b3);
        }
        println!("{}: results fingerprint {fp:#018x}", rs.origin);
    }
    println!(
        "{}: one core: {seeds} seeds in {wall:.3} s: {:.3e} vehicle-steps/s, {:.0} steps/s, {:.1} vehicles on average",
        rs.origin,
        vehicle_steps as f64 / wall,
        steps as f64 / wall,
        vehicle_steps as f64 / steps as f64
    );
    if profile {
        return;
    }
    for threads in [1usize, 2] {
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap();
        let seeds: Vec<u64> = (0..100).collect();
        let start = Instant::now();
        let runs = pool.install(|| run_baseline_spec(&spec, &seeds).unwrap());
        println!(
            "{}: 100-seed baseline on {threads} thread(s): {:.3} s ({} runs)",
            rs.origin,
            start.elapsed().as_secs_f64(),
            runs.len()
        );
    }
}
