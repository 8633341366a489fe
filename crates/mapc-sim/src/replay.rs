//! Replaying another simulator's state for vehicle-by-vehicle comparisons (docs/calibration.md): put every
//! vehicle where the other simulator had it, take one step, read every vehicle's next speed.

use crate::spec::SimSpec;
use crate::{SimError, Simulation};

/// One vehicle of a recorded state.
#[derive(Clone, Debug, PartialEq)]
pub struct ReplicaVehicle {
    pub id: String,
    /// Lane name in the recording (SUMO's, e.g. `left_0`, `:center_1_0`).
    pub lane: String,
    /// Front position on that lane (m).
    pub pos: f64,
    pub speed: f64,
    pub speed_factor: f64,
    /// Time spent below 0.1 m/s so far (s).
    pub waiting_s: f64,
}

/// A lane of SUMO's Simple Merge (the network of `../shared/sumo_ref`) as (road its route starts at, index of the
/// lane along that route) in mapc's built-in Simple Merge.
pub fn sumo_simple_merge_lane(lane: &str) -> Option<(&'static str, usize)> {
    Some(match lane {
        "inflow_highway_0" => ("R0", 0),
        ":left_0_0" => ("R0", 1),
        "left_0" => ("R0", 2),
        ":center_1_0" => ("R0", 3),
        "center_0" => ("R0", 4),
        "inflow_merge_0" => ("R2", 0),
        ":bottom_0_0" => ("R2", 1),
        "bottom_0" => ("R2", 2),
        ":center_0_0" => ("R2", 3),
        _ => return None,
    })
}

/// Replays a recorded Simple Merge state at `time_s` with vehicles of type `vtype` of `spec` (its flows and
/// initial vehicles are ignored), takes one step and returns every placed vehicle's next speed, in input order.
/// Vehicles on lanes the mapping does not know are left out.
pub fn replay_simple_merge_step(
    spec: &SimSpec,
    vtype: usize,
    time_s: f64,
    vehicles: &[ReplicaVehicle],
) -> Result<Vec<(String, f64)>, SimError> {
    let mut s = spec.clone();
    s.flows.clear();
    s.initial.clear();
    s.start_time_s = time_s;
    let mut sim = Simulation::from_spec(s, 0)?;
    let mut placed = Vec::with_capacity(vehicles.len());
    for v in vehicles {
        let Some((from, k)) = sumo_simple_merge_lane(&v.lane) else {
            continue;
        };
        let road = from
            .parse()
            .map_err(|e: String| SimError::Spec(format!("road {from}: {e}")))?;
        let id = sim.place_replica(vtype, road, k, v.pos, v.speed, v.speed_factor, v.waiting_s)?;
        placed.push((v.id.clone(), id));
    }
    sim.step()?;
    Ok(placed
        .into_iter()
        .filter_map(|(name, id)| sim.vehicle(id).map(|vv| (name, vv.speed)))
        .collect())
}
