//! The vehicle id every layer shares (errors, measurement, the simulator, its users).

/// Index of a vehicle, stable for the whole run (vehicles are numbered in creation order).
pub type VehicleId = u32;
