//! The range every number of a scenario must lie in, checked when it is loaded: times, counts, speeds, lengths
//! and driver parameters are refused outside them with the key, the value and the range named. The ranges are
//! wide (a typo, an infinity, a NaN or a vanishing number is what they catch, not an unusual choice); what they
//! guarantee is that a run is finite and its arithmetic stays in numbers: every departure time and step count
//! the simulator derives from them is a sane number.

use crate::Scenario;
use crate::bounds::{MAX_SIMULATED_S, Refusal, entry_capacity_vph};

/// A closed interval of allowed values, with the unit messages give it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Range {
    pub lo: f64,
    pub hi: f64,
    pub unit: &'static str,
}

const fn closed(lo: f64, hi: f64, unit: &'static str) -> Range {
    Range { lo, hi, unit }
}

/// Simulation step (SUMO's smallest is 1 ms; the simulator takes at most 10 s).
pub const STEP_S: Range = closed(0.001, 10.0, "s");
/// SUMO's time to teleport; 0 turns teleports off.
pub const TIME_TO_TELEPORT_S: Range = closed(0.0, MAX_SIMULATED_S, "s");
/// When a flow begins and ends: within the longest run a scenario may ask for.
pub const FLOW_TIME_S: Range = closed(0.0, MAX_SIMULATED_S, "s");
/// Any speed: departure, initial, limits (540 km/h).
pub const SPEED_MPS: Range = closed(0.0, 150.0, "m/s");
/// A speed something drives at or towards: a limit, a vehicle's top speed.
pub const DRIVING_SPEED_MPS: Range = closed(0.1, 150.0, "m/s");
pub const ACCEL_MPS2: Range = closed(0.1, 50.0, "m/s²");
pub const TAU_S: Range = closed(0.0, 60.0, "s");
pub const MIN_GAP_M: Range = closed(0.0, 100.0, "m");
pub const VEHICLE_LENGTH_M: Range = closed(0.1, 100.0, "m");
pub const IDM_DELTA: Range = closed(0.1, 20.0, "");
/// The mean of the drivers' speed factors: within the bounds SUMO (and mapc) redraw each driver's factor to.
pub const SPEED_FACTOR: Range = closed(0.2, 2.0, "");
pub const SPEED_DEV: Range = closed(0.0, 1.0, "");
pub const IMPATIENCE: Range = closed(0.0, 1.0, "");
/// Krauss' dawdling.
pub const SIGMA: Range = closed(0.0, 1.0, "");
/// LC2013's per-type parameters: `strategic` may be negative (no strategic changes), `assertive` divides gaps.
pub fn lane_change_range(name: &str) -> Range {
    match name {
        "strategic" => closed(-1000.0, 1000.0, ""),
        "assertive" => closed(0.01, 1000.0, ""),
        _ => closed(0.0, 1000.0, ""),
    }
}
/// IDM sub-step: with a step of at most 10 s, at most 10 000 sub-steps.
pub const IDM_STEPPING_S: Range = closed(0.001, 10.0, "s");
pub const INITIAL_VEHICLES: Range = closed(0.0, 100_000.0, "vehicles");
pub const N_AV: Range = closed(0.0, 1000.0, "AVs");
/// A window's lengths (for display) and the generator's roads: up to 1000 km.
pub const LENGTH_M: Range = closed(0.0, 1e6, "m");
pub const ROAD_LENGTH_M: Range = closed(1.0, 1e6, "m");
pub const INTERNAL_LENGTH_M: Range = closed(0.0, 1000.0, "m");
pub const LANES: Range = closed(1.0, 16.0, "lanes");

impl Range {
    /// A finite number within the range (NaN and the infinities never are).
    pub fn contains(&self, v: f64) -> bool {
        v.is_finite() && v >= self.lo && v <= self.hi
    }

    /// `[0, 604800] s`, `[0.1, 50] m/s²`.
    pub fn describe(&self) -> String {
        let unit = if self.unit.is_empty() {
            String::new()
        } else {
            format!(" {}", self.unit)
        };
        format!("[{}, {}]{unit}", show(self.lo), show(self.hi))
    }
}

/// A number as a message shows it: plain when short, else in exponent form (`1e308`, not 309 digits).
pub fn show(v: f64) -> String {
    mapc_graph::terminal::number(v)
}

/// `key = value` checked against `range`.
pub fn check(key: impl Into<String>, value: f64, range: Range) -> Result<(), Refusal> {
    if range.contains(value) {
        return Ok(());
    }
    Err(Refusal {
        key: key.into(),
        message: format!(
            "{} is outside the allowed range {}",
            show(value),
            range.describe()
        ),
    })
}

/// Every number of `s` within its range, in the file's order; the first one outside is refused.
pub fn check_scenario(s: &Scenario) -> Result<(), Refusal> {
    check("step_s", s.step_s, STEP_S)?;
    if let Some(t) = s.time_to_teleport_s {
        check("time_to_teleport_s", t, TIME_TO_TELEPORT_S)?;
    }
    if s.horizon_steps == 0 {
        return Err(Refusal {
            key: "horizon_steps".into(),
            message: "0 is outside the allowed range: at least 1 step".into(),
        });
    }
    if let crate::NetworkSpec::SimpleMerge(p) = &s.network {
        let key = |f: &str| format!("network.simple_merge.{f}");
        for (f, v) in [
            ("inflow_edge_m", p.inflow_edge_m),
            ("pre_merge_m", p.pre_merge_m),
            ("merge_m", p.merge_m),
            ("post_merge_m", p.post_merge_m),
        ] {
            check(key(f), v, ROAD_LENGTH_M)?;
        }
        for (f, v) in [
            ("main_internal_m", p.main_internal_m),
            ("ramp_internal_m", p.ramp_internal_m),
            ("through_internal_m", p.through_internal_m),
        ] {
            check(key(f), v, INTERNAL_LENGTH_M)?;
        }
        check(key("speed_limit_mps"), p.speed_limit_mps, DRIVING_SPEED_MPS)?;
        check(
            key("ramp_internal_speed_mps"),
            p.ramp_internal_speed_mps,
            DRIVING_SPEED_MPS,
        )?;
        check(key("lanes"), p.lanes as f64, LANES)?;
    }
    if let crate::NetworkSpec::LaneDrop(p) = &s.network {
        let key = |f: &str| format!("network.lane_drop.{f}");
        check(key("upstream_m"), p.upstream_m, ROAD_LENGTH_M)?;
        check(key("downstream_m"), p.downstream_m, ROAD_LENGTH_M)?;
        check(
            key("through_internal_m"),
            p.through_internal_m,
            INTERNAL_LENGTH_M,
        )?;
        check(key("speed_limit_mps"), p.speed_limit_mps, DRIVING_SPEED_MPS)?;
        check(key("lanes_before"), p.lanes_before as f64, LANES)?;
        check(key("lanes_after"), p.lanes_after as f64, LANES)?;
    }
    if let crate::NetworkSpec::FlowBottleneck(p) = &s.network {
        let key = |f: &str| format!("network.flow_bottleneck.{f}");
        for (i, &l) in p.lengths_m.iter().enumerate() {
            check(key(&format!("lengths_m[{i}]")), l, ROAD_LENGTH_M)?;
        }
        for (i, &l) in p.zipper_internal_m.iter().enumerate() {
            check(
                key(&format!("zipper_internal_m[{i}]")),
                l,
                INTERNAL_LENGTH_M,
            )?;
        }
        check(
            key("through_internal_m"),
            p.through_internal_m,
            INTERNAL_LENGTH_M,
        )?;
        check(key("speed_limit_mps"), p.speed_limit_mps, DRIVING_SPEED_MPS)?;
    }
    for (name, t) in &s.vehicle_types {
        let key = |f: &str| format!("vehicle_types.{name}.{f}");
        for (f, v, range) in [
            ("accel", t.accel, ACCEL_MPS2),
            ("decel", t.decel, ACCEL_MPS2),
            ("tau", t.tau, TAU_S),
            ("min_gap", t.min_gap, MIN_GAP_M),
            ("max_speed", t.max_speed, DRIVING_SPEED_MPS),
            ("delta", t.delta, IDM_DELTA),
            ("speed_factor", t.speed_factor, SPEED_FACTOR),
            ("speed_dev", t.speed_dev, SPEED_DEV),
            ("impatience", t.impatience, IMPATIENCE),
            ("length", t.length, VEHICLE_LENGTH_M),
            ("idm_stepping_s", t.idm_stepping_s, IDM_STEPPING_S),
        ] {
            check(key(f), v, range)?;
        }
        if let Some(sigma) = t.sigma {
            check(key("sigma"), sigma, SIGMA)?;
        }
        if let Some(e) = t.emergency_decel {
            check(key("emergency_decel"), e, closed(t.decel, 50.0, "m/s²"))?;
        }
        for (f, _, v) in t.lane_change.given() {
            check(key(&format!("lane_change.{f}")), v, lane_change_range(f))?;
        }
    }
    let vph = closed(0.0, entry_capacity_vph(s.step_s), "veh/h");
    for (i, f) in s.flows.iter().enumerate() {
        let key = |k: &str| format!("flows[{i}].{k}");
        // a finite demand above the entry's capacity is refused by `bounds::check_demand`, which names every flow
        // that enters there
        if !(f.vehs_per_hour.is_finite() && f.vehs_per_hour >= 0.0) {
            check(key("vehs_per_hour"), f.vehs_per_hour, vph)?;
        }
        check(key("depart_speed_mps"), f.depart_speed_mps, SPEED_MPS)?;
        check(key("begin_s"), f.begin_s, FLOW_TIME_S)?;
        if let Some(end) = f.end_s {
            check(key("end_s"), end, FLOW_TIME_S)?;
            if end <= f.begin_s {
                return Err(Refusal {
                    key: key("end_s"),
                    message: format!(
                        "{} is not after begin_s ({}): the flow would send no vehicle",
                        show(end),
                        show(f.begin_s)
                    ),
                });
            }
        }
    }
    if let Some(iv) = &s.initial_vehicles {
        check("initial_vehicles.count", iv.count as f64, INITIAL_VEHICLES)?;
        check("initial_vehicles.speed_mps", iv.speed_mps, SPEED_MPS)?;
    }
    if let Some(c) = &s.control {
        check("control.n_av", c.n_av as f64, N_AV)?;
        let lengths = |key: String, up: f64, merge: f64, down: f64| -> Result<(), Refusal> {
            check(format!("{key}.upstream_m"), up, LENGTH_M)?;
            check(format!("{key}.merge_m"), merge, LENGTH_M)?;
            check(format!("{key}.downstream_m"), down, LENGTH_M)
        };
        if let Some(w) = &c.window {
            lengths(
                "control.window".into(),
                w.upstream_m,
                w.merge_m,
                w.downstream_m,
            )?;
        }
        for (k, w) in c.windows.iter().enumerate() {
            lengths(
                format!("control.windows[{k}]"),
                w.upstream_m,
                w.merge_m,
                w.downstream_m,
            )?;
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_papers_scenario_is_within_every_range() {
        assert_eq!(check_scenario(&Scenario::simple_merge()), Ok(()));
    }

    #[test]
    fn a_value_outside_names_the_key_the_value_and_the_range() {
        let mut s = Scenario::simple_merge();
        s.flows[2].begin_s = -1e308;
        let r = check_scenario(&s).unwrap_err();
        assert_eq!(r.key, "flows[2].begin_s");
        assert_eq!(
            r.message,
            "-1e308 is outside the allowed range [0, 604800] s"
        );
        let mut s = Scenario::simple_merge();
        s.vehicle_types.get_mut("av").unwrap().accel = f64::NAN;
        let r = check_scenario(&s).unwrap_err();
        assert_eq!(
            (r.key.as_str(), r.message.as_str()),
            (
                "vehicle_types.av.accel",
                "NaN is outside the allowed range [0.1, 50] m/s²"
            )
        );
        let mut s = Scenario::simple_merge();
        s.flows[0].end_s = Some(1.0);
        let r = check_scenario(&s).unwrap_err();
        assert!(r.message.contains("not after begin_s (1)"), "{r:?}");
        let mut s = Scenario::simple_merge();
        s.step_s = f64::INFINITY;
        assert!(
            check_scenario(&s)
                .unwrap_err()
                .message
                .starts_with("inf is outside")
        );
    }

    #[test]
    fn numbers_show_short() {
        assert_eq!(show(1e308), "1e308");
        assert_eq!(show(-1e-300), "-1e-300");
        assert_eq!(show(172800.0), "172800");
        assert_eq!(show(0.5), "0.5");
        assert_eq!(show(f64::NEG_INFINITY), "-inf");
    }
}
