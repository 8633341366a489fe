//! The arithmetic floor under the simulator's speed: what one correctly rounded division, and one call of SUMO's
//! IDM step (`IdmParams::next_speed`, two sub-steps, six divisions), cost on this machine when the calls are
//! independent (the best case: the divider is the only limit) and when each call waits for the previous one.
//! `cargo run --release -p mapc-sim --example arith_floor` (docs/perf_sim.md).

use mapc_sim::IdmParams;
use mapc_sim::models::cf::CarFollowModel;

/// IDM steps per Simple Merge vehicle-step, as counted by
/// `cargo bench -p mapc-sim --bench sim_speed --features count-idm -- --profile`.
const CALLS_PER_VEHICLE_STEP: f64 = 3.65;
use std::hint::black_box;
use std::time::Instant;

fn main() {
    let n = 20_000_000usize;
    let xs: Vec<f64> = (0..1024).map(|i| 1.0 + i as f64 * 0.37).collect();
    let ys: Vec<f64> = (0..1024).map(|i| 3.0 + i as f64 * 0.11).collect();

    // independent divisions, four accumulators (the sums' latency hidden)
    let t = Instant::now();
    let mut acc = [0.0f64; 4];
    for _ in 0..n / 1024 {
        for i in (0..1024).step_by(4) {
            for k in 0..4 {
                acc[k] += black_box(xs[i + k]) / ys[i + k];
            }
        }
    }
    black_box(acc);
    let div_ns = t.elapsed().as_secs_f64() / n as f64 * 1e9;

    // a chain of divisions, each waiting for the last
    let t = Instant::now();
    let mut x = 1.5f64;
    for _ in 0..n {
        x = black_box(1.000_001) / x + 0.5;
    }
    black_box(x);
    let chain_ns = t.elapsed().as_secs_f64() / n as f64 * 1e9;

    // IDM follow speeds: independent calls, then calls that take the previous result as their speed
    let p = IdmParams::new(2.6, 4.5, 9.0, 1.0, 2.5, 4.0, 0.5);
    let m = n / 10;
    let t = Instant::now();
    let mut s = 0.0;
    for k in 0..m {
        let i = k & 1023;
        s += p.follow_speed(black_box(xs[i] * 10.0), ys[i], xs[(i + 7) & 1023], 30.0);
    }
    black_box(s);
    let idm_ns = t.elapsed().as_secs_f64() / m as f64 * 1e9;
    let t = Instant::now();
    let mut v = 10.0;
    for k in 0..m {
        let i = k & 1023;
        v = p.follow_speed(black_box(xs[i] * 10.0), v, ys[i], 30.0);
    }
    black_box(v);
    let idm_chain_ns = t.elapsed().as_secs_f64() / m as f64 * 1e9;

    // four calls at once (two SSE2 pairs), as planning makes them
    let t = Instant::now();
    let mut s4 = 0.0;
    for k in 0..m / 4 {
        let i = (4 * k) & 1023;
        let r = p.next_speed_x4(
            black_box([xs[i] * 10.0, xs[i + 1] * 10.0, 1e6, xs[i + 3] * 10.0]),
            ys[i],
            [
                xs[(i + 7) & 1023],
                xs[(i + 8) & 1023],
                30.0,
                xs[(i + 9) & 1023],
            ],
            30.0,
            [true, true, false, true],
        );
        s4 += r[0] + r[1] + r[2] + r[3];
    }
    black_box(s4);
    let idm_x4_ns = t.elapsed().as_secs_f64() / m as f64 * 1e9;

    println!(
        "division, independent: {div_ns:.2} ns; in a chain: {chain_ns:.2} ns (with one addition)"
    );
    println!(
        "IDM next speed (2 sub-steps, 6 divisions): {idm_ns:.1} ns independent, {idm_chain_ns:.1} ns in a chain"
    );
    println!("IDM next speed, four calls at once (next_speed_x4): {idm_x4_ns:.1} ns per call");
    println!(
        "at {CALLS_PER_VEHICLE_STEP} IDM calls per vehicle-step (the Simple Merge's count), IDM alone costs \
         {:.0}-{:.0} ns of the \
         50 ns a vehicle-step may take at 2e7 vehicle-steps/s",
        CALLS_PER_VEHICLE_STEP * idm_ns,
        CALLS_PER_VEHICLE_STEP * idm_chain_ns
    );
}
