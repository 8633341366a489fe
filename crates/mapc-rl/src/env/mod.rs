pub mod distributed;
pub mod merge;
pub mod obs;
pub mod windows;

use mapc_sim::{SimSpec, Simulation, VehicleId};

use crate::error::RlError;

/// The result of one environment step.
#[derive(Clone, Debug)]
pub struct Transition {
    pub obs: Vec<f32>,
    pub reward: f32,
    /// The episode reached a terminal state (not a time limit).
    pub terminal: bool,
}

/// Episode-level traffic figures reported by an environment.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct EpisodeMetrics {
    /// veh/h.
    pub outflow: f64,
    /// veh/h.
    pub inflow: f64,
    /// m/s.
    pub speed: f64,
    /// Mean trip duration of the vehicles that arrived (s).
    pub travel_time: f64,
}

impl From<&mapc_sim::RunMetrics> for EpisodeMetrics {
    fn from(r: &mapc_sim::RunMetrics) -> Self {
        EpisodeMetrics {
            outflow: r.outflow_veh_h,
            inflow: r.inflow_veh_h,
            speed: r.avg_speed_mps,
            travel_time: r.mean_travel_time_s,
        }
    }
}

/// A reinforcement-learning environment with a fixed observation and action size.
pub trait Env {
    fn obs_dim(&self) -> usize;
    fn act_dim(&self) -> usize;
    /// Starts a new episode; the seed fixes everything random inside the environment.
    fn reset(&mut self, seed: u64) -> Result<Vec<f32>, RlError>;
    /// Applies an (unclipped) action: the environment clips it to its bounds.
    fn step(&mut self, action: &[f32]) -> Result<Transition, RlError>;
    /// Figures of the episode so far.
    fn metrics(&self) -> EpisodeMetrics;
}

/// A problem of `spec` (or of building a simulation from it), reported against the scenario's file.
pub(crate) fn scenario_error(spec: &SimSpec, e: impl std::fmt::Display) -> RlError {
    RlError::Scenario {
        scenario: spec.graph.source.file.clone(),
        msg: e.to_string(),
    }
}

/// `spec` checked for the simulator, its problems reported against the scenario's file.
pub(crate) fn validate_spec(spec: &SimSpec) -> Result<(), RlError> {
    spec.validate().map_err(|e| scenario_error(spec, e))
}

/// An error of the running simulation (a bad command, a broken invariant).
pub(crate) fn sim_error(e: impl std::fmt::Display) -> RlError {
    RlError::Scenario {
        scenario: "simulation".into(),
        msg: e.to_string(),
    }
}

/// A new episode's simulation of `spec` (invariant checks off: the environments step it millions of times).
pub(crate) fn episode_simulation(spec: &SimSpec, seed: u64) -> Result<Simulation, RlError> {
    let mut sim = Simulation::from_spec(spec.clone(), seed).map_err(|e| scenario_error(spec, e))?;
    sim.set_invariant_checks(false);
    Ok(sim)
}

/// What the observation sees of AV `id` (neighbours within `len` m, the normalisation length): its leader and
/// follower in its own lane, and with `lanes` the leader and follower on each adjacent lane of its road.
pub(crate) fn av_view(sim: &Simulation, id: VehicleId, len: f64, lanes: bool) -> obs::AvView {
    let pair = |n: Option<mapc_sim::Neighbor>| n.map(|n| (n.speed, n.gap_m));
    let side = |side| {
        sim.side_neighbors(id, side, len).map(|s| obs::SideView {
            leader: pair(s.leader),
            follower: pair(s.follower),
        })
    };
    let (left, right) = if lanes {
        use mapc_sim::models::lc::Side;
        (side(Side::Left), side(Side::Right))
    } else {
        (None, None)
    };
    obs::AvView {
        speed: sim.vehicle(id).map_or(0.0, |v| v.speed),
        leader: pair(sim.leader(id, len)),
        follower: pair(sim.follower(id, len)),
        left,
        right,
    }
}

/// Refuse the step's actions if any is not a number: every acceleration that enters an environment (from a
/// policy, a controller, Python) goes through here before any is applied, so a bad one leaves the episode as it
/// was. `place(k)` says how the caller names action `k` (`action[3]`, `agent vehicle 12 (actions[0])`).
pub(crate) fn check_actions(
    actions: impl IntoIterator<Item = f32>,
    place: impl Fn(usize) -> String,
) -> Result<(), RlError> {
    match actions
        .into_iter()
        .enumerate()
        .find(|(_, a)| !a.is_finite())
    {
        Some((k, value)) => Err(RlError::Action {
            index: k,
            place: place(k),
            value,
        }),
        None => Ok(()),
    }
}

/// Give AV `id` a checked acceleration ([`check_actions`]) for the next step, clamped to `[lo, hi]`.
pub(crate) fn apply_action(
    sim: &mut Simulation,
    id: VehicleId,
    a: f32,
    (lo, hi): (f64, f64),
) -> Result<(), RlError> {
    sim.set_acceleration(id, (a as f64).clamp(lo, hi))
        .map_err(sim_error)
}

#[cfg(test)]
mod action_tests;
#[cfg(test)]
mod reward_tests;
