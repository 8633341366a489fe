//! A strict fingerprint of a scenario's runs, for speed work that must change nothing: a hash of every active
//! vehicle's id, road, lane index, exact position and speed after every step, and of every metric (lane changes
//! by reason included), over seeds 0-2 (`cargo run --release -p mapc-sim --example state_fingerprint -- SCENARIO`).
//! Also prints the vehicle-steps of the sim_speed bench's `--profile` run (its warm-up seed 999, then seeds 0-2
//! twice), to turn a profiler's instruction count into instructions per vehicle-step.

use mapc_scenario::ResolvedScenario;
use mapc_sim::{Simulation, spec_from_scenario};

struct Fnv(u64);

impl Fnv {
    fn word(&mut self, w: u64) {
        self.0 = (self.0 ^ w).wrapping_mul(0x0000_0100_0000_01b3);
    }
    fn f(&mut self, x: f64) {
        self.word(x.to_bits());
    }
}

fn main() {
    let name = std::env::args()
        .nth(1)
        .unwrap_or_else(|| "two_lane_merge".into());
    let rs = ResolvedScenario::load(&name).expect("scenario");
    let spec = spec_from_scenario(&rs).expect("spec");
    let mut h = Fnv(0xcbf2_9ce4_8422_2325);
    let mut vehicle_steps = 0;
    for seed in 0..3 {
        let mut sim = Simulation::from_spec(spec.clone(), seed).unwrap();
        while !sim.is_done() {
            sim.step().unwrap();
            for id in sim.active_ids() {
                let v = sim.vehicle(id).unwrap();
                h.word(id as u64);
                h.word(v.road.0 as u64);
                h.word(v.in_junction as u64);
                h.word(v.lane_index as u64);
                h.f(v.pos_m);
                h.f(v.speed);
            }
        }
        let m = sim.metrics();
        for x in [
            m.outflow_veh_h,
            m.inflow_veh_h,
            m.avg_speed_mps,
            m.mean_travel_time_s,
            m.mean_delay_s,
            m.end_flow_veh_h,
            m.lane_changes_per_veh_km,
        ] {
            h.f(x);
        }
        vehicle_steps += m.vehicle_steps;
        let r = &m.lane_changes_by_reason;
        for w in [
            m.vehicle_steps,
            m.lane_changes,
            r.strategic,
            r.cooperative,
            r.speed_gain,
            r.keep_right,
        ] {
            h.word(w);
        }
    }
    println!("{}: state fingerprint {:#018x}", rs.origin, h.0);
    let warm_up = Simulation::from_spec(spec, 999).unwrap().run().unwrap();
    println!(
        "{}: vehicle-steps of the bench's --profile run: {}",
        rs.origin,
        warm_up.vehicle_steps + 2 * vehicle_steps
    );
}
