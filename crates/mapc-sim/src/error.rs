//! What can go wrong in a simulation: a network or spec it cannot run, a command for a vehicle it does not
//! have, or two vehicles overlapping (a broken invariant).

use crate::ids::VehicleId;

#[derive(Debug, thiserror::Error)]
pub enum SimError {
    #[error("network: {0}")]
    Network(String),
    #[error("scenario: {0}")]
    Spec(String),
    #[error("no vehicle {0}")]
    UnknownVehicle(VehicleId),
    #[error("vehicle {0} is not a controlled vehicle")]
    NotControlled(VehicleId),
    #[error("vehicle {vehicle}: acceleration {accel} is not a finite number")]
    BadAcceleration { vehicle: VehicleId, accel: f64 },
    #[error(
        "collision at t = {time_s} s: vehicle {follower} is {gap_m:.3} m into vehicle {leader} ({place})"
    )]
    Collision {
        time_s: f64,
        leader: VehicleId,
        follower: VehicleId,
        gap_m: f64,
        place: String,
    },
}
