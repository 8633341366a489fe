//! The kinematics every car-following model shares, as SUMO's `MSCFModel` base computes them with the Euler
//! update: how far a vehicle needs to stop, the fastest it may drive to still stop within a gap, when and how
//! fast it reaches a point. Pure functions of the type's parameters; speeds in m/s, distances in m, times in s.

use crate::numeric::{FastMinMax, NUMERICAL_EPS, floor_near};

/// Distance needed to stop from `speed` braking `decel` each step of `dt`, plus `headway` seconds at `speed`
/// (SUMO's Euler `brakeGap`).
#[inline]
pub fn brake_gap(dt: f64, speed: f64, decel: f64, headway: f64) -> f64 {
    let reduction = decel * dt;
    if reduction <= 0.0 {
        return f64::INFINITY;
    }
    let steps = floor_near(speed * (1.0 / reduction), || speed / reduction);
    dt * (steps * speed - reduction * steps * (steps + 1.0) / 2.0) + speed * headway
}

/// An upper bound of Euler's braking distance from `speed` braking `decel` each step, plus `headway` seconds at
/// `speed` ([`brake_gap`]): `headway v + v^2 / (2 decel)`, the whole braking steps being a right Riemann sum of
/// the continuous stop.
#[inline(always)]
pub fn brake_gap_at_most(speed: f64, decel: f64, headway: f64) -> f64 {
    headway * speed + speed * speed * (0.5 / decel)
}

/// Whether a driver at `speed` surely stops within `gap` with a reaction time `headway`: the gap exceeds
/// [`brake_gap_at_most`] (here multiplied out, without its division) by a metre, which covers the rounding. Then
/// the safe stop speed of that gap and headway, and of any longer gap, is at least `speed`, and need not be
/// computed where only whether it reaches `speed` matters.
#[inline(always)]
pub fn surely_stops_within(headway: f64, decel: f64, gap: f64, speed: f64) -> bool {
    (gap - STOP_BOUND_MARGIN_M - headway * speed) * (2.0 * decel) >= speed * speed
}

/// A lower bound of Euler's braking distance from `speed` braking `decel` each step of `dt` ([`brake_gap`] with no
/// headway): the continuous stop's `v^2 / 2d` less what the whole braking steps save, `dt (d dt + v) / 2`, and a
/// relative margin far above rounding; never negative.
#[inline(always)]
pub fn brake_gap_at_least(dt: f64, speed: f64, decel: f64) -> f64 {
    if !(decel > 0.0 && speed >= 0.0) {
        return 0.0;
    }
    ((speed * speed * (0.5 / decel) - 0.5 * dt * (decel * dt + speed)) * (1.0 - 1e-9) - 1e-6)
        .fmax(0.0)
}

/// The margin (m) of [`surely_stops_within`]'s bound.
const STOP_BOUND_MARGIN_M: f64 = 1.0;

/// The largest speed from which a vehicle can still stop within `gap` braking at `decel` per step of `dt`
/// (SUMO's Euler `maximumSafeStopSpeed` with no headway).
pub fn maximum_safe_stop_speed(dt: f64, decel: f64, gap: f64) -> f64 {
    let g = gap - NUMERICAL_EPS;
    if g <= 0.0 {
        return 0.0;
    }
    let b = decel * dt;
    let (s, t) = (dt, 0.0);
    let n = euler_stop_steps(g, b, s, t);
    let h = 0.5 * n * (n - 1.0) * b * s + n * b * t;
    let r = (g - h) / (n * s + t);
    // n steps of driving: the last at speed r, each earlier one b faster
    (n - 1.0) * b + r
}

/// The whole steps of braking `b` per step of `s` after a reaction time `t` that fit in the distance `g` (the
/// `n` of SUMO's Euler `maximumSafeStopSpeed`): its formula's floor, bit for bit, with the divisions by `b` and
/// `s` as multiplications wherever that cannot change the floor ([`floor_near`]).
#[inline(always)]
pub(crate) fn euler_stop_steps(g: f64, b: f64, s: f64, t: f64) -> f64 {
    let (inv_b, inv_s) = (1.0 / b, 1.0 / s);
    let approx =
        0.5 - (t + ((s * s) + 4.0 * ((s * (2.0 * g * inv_b - t)) + t * t)).sqrt() * -0.5) * inv_s;
    floor_near(approx, || {
        0.5 - (t + ((s * s) + 4.0 * ((s * (2.0 * g / b - t)) + t * t)).sqrt() * -0.5) / s
    })
}

/// The lowest speed at which a vehicle now at `speed` can reach a point `dist` ahead when it brakes
/// (SUMO's `getMinimalArrivalSpeedEuler`): within one second of the point braking no longer helps; otherwise
/// braking starts after a reaction time of one headway `tau`. The last branch returns the deceleration, as SUMO
/// does.
pub fn minimal_arrival_speed_euler(tau: f64, decel: f64, dist: f64, speed: f64) -> f64 {
    if dist < speed {
        f64::INFINITY
    } else if 2.0 * (dist - speed * tau) * -decel + speed * speed >= 0.0 {
        speed_after_distance(dist - speed * tau, speed, -decel)
    } else {
        decel
    }
}

/// Time to cover `dist` starting at `speed` and reaching `arrival_speed`, accelerating (`accel`) or braking
/// (`decel`) at the type's limits and then cruising (SUMO's `getMinimalArrivalTime`).
pub fn minimal_arrival_time(
    accel: f64,
    decel: f64,
    dist: f64,
    speed: f64,
    arrival_speed: f64,
) -> f64 {
    if dist <= 0.0 {
        return 0.0;
    }
    if arrival_speed <= NUMERICAL_EPS && speed <= NUMERICAL_EPS {
        return 1e6;
    }
    let accel = if arrival_speed >= speed {
        accel
    } else {
        -decel
    };
    let accel_time = (arrival_speed - speed) / accel;
    let accel_way = accel_time * (arrival_speed + speed) * 0.5;
    if dist >= accel_way {
        // drive as fast as possible: brake as late as possible, or accelerate first and then hold the speed
        let cruise = speed.fmax(arrival_speed).fmax(0.1);
        return accel_time + (dist - accel_way) / cruise;
    }
    // the target speed is not reached: solve dist = v t + a t^2 / 2
    let disc = speed * speed + 2.0 * accel * dist;
    if disc <= 0.0 {
        return 1e6;
    }
    (disc.sqrt() - speed) / accel
}

/// Speed after `dist` metres accelerating at `accel` from `speed` (SUMO's `estimateSpeedAfterDistance`).
pub fn speed_after_distance(dist: f64, speed: f64, accel: f64) -> f64 {
    (2.0 * dist * accel + speed * speed).fmax(0.0).sqrt()
}
