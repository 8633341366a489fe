//! # mapc-sim: a microscopic multi-lane traffic simulator calibrated to SUMO 1.8
//!
//! Glossary:
//! - **lane**: a road has one lane or several (index 0 rightmost); every connection across a junction is an
//!   *internal lane* (its length counts as distance driven). On a one-lane network nobody changes lanes; with
//!   several lanes drivers change lanes as SUMO 1.8's LC2013 does.
//! - **link**: a lane-to-lane connection at a junction; **major** links drive on, **minor** links yield,
//!   **zipper** links take turns with the other stream.
//! - **teleport**: a front driver standing longer than the scenario's `time_to_teleport_s` leaves and comes back
//!   further along its route (SUMO's time-to-teleport; off unless set), counted.
//! - **merge foe**: a link from another road into the same road; vehicles on merging links follow each other by
//!   their distance to the *merge point* (the end of the links).
//! - **car-following model**: how a driver type picks its speed behind leaders, before stops and limits
//!   ([`models::cf`], one model per file behind the `CarFollowModel` trait); today the **IDM**, the Intelligent
//!   Driver Model as SUMO computes it (two sub-steps per 0.5 s step).
//! - **safe speed**: the highest speed with which the vehicle can follow its leaders and stop where it must; it is
//!   never exceeded, and no vehicle ever moves into its leader (checked after every step in debug builds).
//! - **impatience**: base impatience + waiting time / 300 s; it shifts the foe arrival time a minor driver
//!   assumes towards the foe's arrival when braking, so waiting drivers take smaller gaps.
//! - **flow**: periodic departures (SUMO's vehsPerHour); a vehicle that cannot be inserted safely waits at its
//!   entry road and only counts once inserted. Past 1024 waiting at an entry, further ones are only counted and
//!   built when they reach the front (`demand/waiting.rs`); records of vehicles long gone are dropped in long runs
//!   (`demand/vehicle_table.rs`), so memory follows the road, not the demand or the horizon.
//! - **depart lane**: the entry road's lane a flow's vehicles enter on (SUMO's `departLane`): fixed for the flow
//!   (`first`, `best`, an index), or chosen at each insertion attempt (`random`, `free`: `sim/entry/lane_choice.rs`).
//! - **measure point**: a merge whose flow (vehicles entering the road after it) is counted per hour of measured
//!   time, like the flow past the corridor's end; both besides the paper's whole-horizon outflow.
//! - **regime**: per merge, the major road, the humans' speed near it against free flow and the queue before it
//!   ([`merge_regimes`]).
//! - **warm-up**: steps simulated before the horizon; every metric ignores them.
//! - **vehicle-step**: one vehicle simulated for one step (the unit of the speed figures).
//! - **best lanes**: per lane of a vehicle's road, how far its route goes on without a lane change, looking
//!   about 3000 m ahead ([`best_lanes`], SUMO's `updateBestLanes`, cached per route suffix and type).
//! - **lane-change model**: [`models::lc`] holds SUMO 1.8's LC2013 (`models/lc/lc2013/`), which the step's
//!   lane-change pass (`sim/step/lane_change.rs`) runs on every road of several lanes.
//!
//! ## Using it (for the environment and evaluation code)
//! ```ignore
//! let mut sim = Simulation::new(&resolved, seed)?;       // or Simulation::from_spec(spec, seed)
//! while !sim.is_done() {
//!     for id in sim.active_ids().collect::<Vec<_>>() {
//!         let v = sim.vehicle(id).unwrap();               // VehicleView: type, controlled, road, pos, speed, ...
//!         if v.controlled && sim.in_control_region(id) {
//!             let lead = sim.leader(id, 1000.0);          // Neighbor { id, gap_m, speed } across junctions
//!             let follow = sim.follower(id, 1000.0);      // may be on the merging road
//!             let junction = sim.distance_to_next_junction(id);
//!             let foe = sim.nearest_merge_foe(id, 200.0); // MergeFoe { id, dist_to_merge_m, speed }
//!             sim.set_acceleration(id, 0.5)?;             // applies in the next step only
//!         }
//!     }
//!     sim.step()?;
//!     let left = sim.arrived_last_step();                 // ids of vehicles that left in that step
//! }
//! let m: RunMetrics = sim.metrics();
//! let runs = run_baseline(&resolved, &(0..100).collect::<Vec<u64>>())?; // rayon, seed order
//! let s = Summary::of(&runs);                             // mean and Student-t 95% CI per metric
//! ```
//! Results are pinned bit for bit (policies are trained on them): the test
//! `results_are_bit_identical_to_the_recorded_ones` holds recorded metrics and state hashes; speed work must keep
//! every floating-point operation and its order (docs/perf_sim.md).
//! Time: `time_s()` is SUMO's clock (step 0 starts at the spec's `start_time_s`), `step_index()` counts steps.
//! Accelerations are clamped to [-decel, accel] and the resulting speed is capped by the safe speed, including
//! waiting at a minor link when a major vehicle has the right of way (SUMO's speed mode 9).

// `!(x > 0.0)` and the like reject NaN on purpose; `partial_cmp` would hide that.
#![allow(clippy::neg_cmp_op_on_partial_ord)]

// The layers, each using only those above it: numeric helpers, errors and the spec; the models, the network and
// the demand; what a run measures; the simulator; runs built on it (docs/architecture.md draws them).
mod error;
mod ids;
pub mod numeric;
pub use error::SimError;
pub mod spec;

pub mod demand;
pub mod models;
pub mod network;

pub mod measure;

pub mod sim;

pub mod runs;

pub use demand::vehicle_table::VehicleId;
pub use measure::detectors::DetectorInterval;
pub use measure::metrics::{
    BaselineReport, DetectorSummary, EntryCounts, EntrySummary, LaneChangeReasons, MeanCi,
    MergeFlow, RunMetrics, Summary, standstill_lines, t_quantile_975,
};
pub use measure::points::{MeasurePoint, Passage};
pub use models::cf::idm::IdmParams;
pub use network::Network;
pub use runs::alinea::{Alinea, AlineaConfig, run_with_alinea, trace_with_alinea};
pub use runs::kept::{KeptRuns, keep_runs, runs_reused, will_run};
pub use runs::regime::{
    Congestion, MergePriority, MergeRegime, REGIME_SEEDS, RegimeReport, merge_priorities,
    merge_regimes,
};
pub use runs::scenario::{run_baseline, run_baseline_spec, spec_from_scenario};
pub use runs::trace::{MAX_TRACE_ROWS, TraceBudget, TracedRun, trace_run, trace_sim};
pub use sim::{LaneRef, MergeFoe, Neighbor, SideNeighbors, Simulation, VehicleStatus, VehicleView};
pub use spec::{
    ControlWindowSpec, DepartLane, DetectorSpec, FlowSpec, InitialVehicleSpec, SimSpec,
    VehicleTypeSpec,
};

/// Header of trace CSV files. `road` is the road (`R3`) or the junction connection (`R1>R2`); `lane` the lane's
/// index on that road (0 rightmost; in a connection, the lane it came from). Traces written before `lane` was
/// added lack it: readers take 0.
pub const TRACE_HEADER: &str =
    "time_s,vehicle_id,vehicle_type,road,pos_on_road_m,corridor_x_m,speed_mps,controlled,lane";

#[cfg(test)]
mod bounds_tests;
#[cfg(test)]
mod tests;
