//! The Krauss model, SUMO 1.8's default driver (`MSCFModel_Krauss` with the Euler update): the fastest speed from
//! which the driver can still stop behind its leader, given its reaction time `tau`, with one random slowdown a
//! step (dawdling, `sigma`). Speeds in m/s, distances in m, times in s.
//!
//! The leader's deceleration SUMO plans with (its apparent deceleration) is taken as the driver's own: exact where
//! all types brake alike, and where the leader brakes less hard (a car behind a truck: SUMO takes the larger of
//! the two).

use super::{CarFollowModel, StopShare, kinematics};
use crate::numeric::{FastMinMax, NUMERICAL_EPS, floor_exact};

/// SUMO's factor on the emergency deceleration a driver computes (`EMERGENCY_DECEL_AMPLIFIER`).
const EMERGENCY_DECEL_AMPLIFIER: f64 = 1.2;

/// One driver type's Krauss parameters.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Krauss {
    pub accel: f64,
    pub decel: f64,
    pub emergency_decel: f64,
    /// Reaction time (s): the headway the driver keeps to be able to stop.
    pub tau: f64,
    /// Dawdling in [0, 1]: each step the driver drives up to `sigma * accel * dt` slower than it could.
    pub sigma: f64,
    /// The type's maximum speed (SUMO's `maxNextSpeed` caps by it).
    pub max_speed: f64,
    /// Step length (s).
    pub dt: f64,
}

impl Krauss {
    /// SUMO's `maxNextSpeed`: one step of full acceleration, at most the type's maximum.
    #[inline]
    fn max_next_speed(&self, speed: f64) -> f64 {
        (speed + self.accel * self.dt).fmin(self.max_speed)
    }

    /// SUMO's `maximumSafeStopSpeedEuler`: the speed from which braking `decel` each step after a reaction time
    /// `headway` stops within `gap`.
    // inlined into the follow speed: the call spilled the follow speed's values around it (-1.1 % instructions on
    // the SUMO users' scenarios)
    #[inline]
    pub fn maximum_safe_stop_speed(&self, gap: f64, headway: f64) -> f64 {
        let g = gap - NUMERICAL_EPS;
        if g <= 0.0 {
            return 0.0;
        }
        let b = self.decel * self.dt;
        let t = headway;
        let s = self.dt;
        let n = kinematics::euler_stop_steps(g, b, s, t);
        let h = 0.5 * n * (n - 1.0) * b * s + n * b * t;
        let r = (g - h) / (n * s + t);
        n * b + r
    }

    /// SUMO's `maximumSafeFollowSpeed`: stop within the gap plus the leader's own braking distance; where that
    /// asks for more than the comfortable deceleration, brake only as hard as needed, up to the emergency
    /// deceleration (not on insertion).
    pub fn maximum_safe_follow_speed(
        &self,
        gap: f64,
        speed: f64,
        leader_speed: f64,
        on_insertion: bool,
    ) -> f64 {
        let x = self.safe_stop_behind(gap, leader_speed);
        self.follow_from_stop(x, gap, speed, leader_speed, on_insertion)
    }

    /// The first part of [`Self::maximum_safe_follow_speed`]: the speed that stops within the gap plus the leader's
    /// braking distance.
    #[inline]
    fn safe_stop_behind(&self, gap: f64, leader_speed: f64) -> f64 {
        let leader_brake = kinematics::brake_gap(self.dt, leader_speed, self.decel, 0.0);
        self.maximum_safe_stop_speed(gap + leader_brake, self.tau)
    }

    /// The rest of [`Self::maximum_safe_follow_speed`] given its first part `x`: the emergency rule.
    #[inline]
    fn follow_from_stop(
        &self,
        mut x: f64,
        gap: f64,
        speed: f64,
        leader_speed: f64,
        on_insertion: bool,
    ) -> f64 {
        let leader_decel = self.decel;
        // (the division only where the product by the step's reciprocal cannot decide the comparison)
        if self.decel != self.emergency_decel
            && !on_insertion
            && (speed - x) * (1.0 / self.dt) > (self.decel + NUMERICAL_EPS) * (1.0 - 1e-9)
        {
            let orig_safe_decel = (speed - x) / self.dt;
            if orig_safe_decel > self.decel + NUMERICAL_EPS {
                let safe_decel = (EMERGENCY_DECEL_AMPLIFIER
                    * self.emergency_deceleration(gap, speed, leader_speed, leader_decel))
                .fmax(self.decel)
                .fmin(orig_safe_decel);
                x = (speed - safe_decel * self.dt).fmax(0.0);
            }
        }
        x
    }

    /// SUMO's `calculateEmergencyDeceleration`: the deceleration that avoids a collision if the leader brakes at
    /// `leader_decel` (negative when the gap is gone, as SUMO returns it; the caller raises it to `decel`).
    fn emergency_deceleration(
        &self,
        gap: f64,
        speed: f64,
        leader_speed: f64,
        leader_decel: f64,
    ) -> f64 {
        let leader_brake_dist = 0.5 * leader_speed * leader_speed / leader_decel;
        let b1 = 0.5 * speed * speed / (gap + leader_brake_dist);
        if b1 <= leader_decel {
            return b1;
        }
        if gap <= 0.0 {
            return -(self.emergency_decel * self.dt);
        }
        0.5 * (speed * speed - leader_speed * leader_speed) / gap
    }

    /// SUMO's `dawdle2` for the speed `v_max` and a uniform draw `r` in [0, 1): slower by up to `sigma` times the
    /// acceleration of one step, or of the speed itself below it (SUMO compares the speed with the acceleration
    /// as numbers), never below zero.
    #[inline]
    pub fn dawdled(&self, v_max: f64, r: f64) -> f64 {
        let slower = if v_max < self.accel {
            self.sigma * v_max * r
        } else {
            self.sigma * self.accel * r
        };
        (v_max - slower * self.dt).fmax(0.0)
    }

    /// `maximum_safe_follow_speed(..).fmin(cap)`, the same bits, without the square root and divisions where the
    /// gap and the least of the leader's braking distance are long enough to stop from `cap` (most leaders of
    /// free-flowing traffic and of neighbour lanes): the safe follow speed is the safe stop speed of the gap plus
    /// the leader's braking distance, which only grows with the distance, or above it.
    /// With a `share`, its stop speed is taken where it is this gap's and leader speed's, else the one computed is
    /// kept there.
    #[inline(always)]
    fn safe_follow_speed_below(
        &self,
        share: Option<&mut StopShare>,
        gap: f64,
        speed: f64,
        leader_speed: f64,
        on_insertion: bool,
        cap: f64,
    ) -> f64 {
        let leader_brake = kinematics::brake_gap_at_least(self.dt, leader_speed, self.decel);
        if self.stops_within(gap + leader_brake, cap) {
            debug_assert!(
                self.maximum_safe_follow_speed(gap, speed, leader_speed, on_insertion) >= cap,
                "{self:?} gap {gap} v {speed} leader {leader_speed} cap {cap}"
            );
            return cap;
        }
        let Some(share) = share else {
            return self
                .maximum_safe_follow_speed(gap, speed, leader_speed, on_insertion)
                .fmin(cap);
        };
        let x = share.get_or_keep(gap, leader_speed, || {
            self.safe_stop_behind(gap, leader_speed)
        });
        self.follow_from_stop(x, gap, speed, leader_speed, on_insertion)
            .fmin(cap)
    }

    /// Whether a driver at `speed` surely stops within `gap` with its reaction time
    /// ([`kinematics::surely_stops_within`]): then the safe stop speed, and so the safe follow speed (the leader's
    /// braking distance only adds, and the emergency correction only raises it), are at least `speed`.
    #[inline(always)]
    fn stops_within(&self, gap: f64, speed: f64) -> bool {
        kinematics::surely_stops_within(self.tau, self.decel, gap, speed)
    }
}

impl CarFollowModel for Krauss {
    // the two follow speeds inlined where they are asked: most return at the shortcut's test, and the calls'
    // spills cost more than it (with the own leader's speed computed in the plan, -0.5 to -1 % instructions)
    #[inline]
    fn follow_speed(&self, gap: f64, speed: f64, leader_speed: f64, _desired_speed: f64) -> f64 {
        self.safe_follow_speed_below(
            None,
            gap,
            speed,
            leader_speed,
            false,
            self.max_next_speed(speed),
        )
    }

    /// SUMO 1.8 skips the emergency-braking correction while lanes are changed (`MSGlobals::gComputeLC`), as it
    /// does on insertion.
    #[inline]
    fn follow_speed_lc(&self, gap: f64, speed: f64, leader_speed: f64, _desired_speed: f64) -> f64 {
        self.safe_follow_speed_below(
            None,
            gap,
            speed,
            leader_speed,
            true,
            self.max_next_speed(speed),
        )
    }

    /// The lane changer's follow speed leaves out the emergency rule, as on insertion.
    #[inline]
    fn follow_speed_sharing(
        &self,
        share: &mut StopShare,
        lc: bool,
        gap: f64,
        speed: f64,
        leader_speed: f64,
        _desired_speed: f64,
    ) -> f64 {
        let cap = self.max_next_speed(speed);
        self.safe_follow_speed_below(Some(share), gap, speed, leader_speed, lc, cap)
    }

    /// SUMO's Krauss `stopSpeed`: the reaction time towards a stop point is one step.
    fn stop_speed(&self, gap: f64, speed: f64, _desired_speed: f64) -> f64 {
        self.maximum_safe_stop_speed(gap, self.dt)
            .fmin(self.max_next_speed(speed))
    }

    /// The stop speed is the safe stop speed with a reaction time of one step, capped by one step of full
    /// acceleration: at least `v` where both are ([`kinematics::surely_stops_within`]).
    #[inline(always)]
    fn stop_speed_at_least(&self, gap: f64, speed: f64, v: f64) -> bool {
        v <= self.max_next_speed(speed)
            && kinematics::surely_stops_within(self.dt, self.decel, gap, v)
    }

    /// SUMO's `MSCFModel::freeSpeed` (Euler): brake `decel` each step from this speed to reach `max_speed` where
    /// it starts, `seen` metres ahead.
    fn free_speed(&self, _speed: f64, seen: f64, max_speed: f64, _desired_speed: f64) -> f64 {
        let v = max_speed * self.dt;
        if seen < v {
            return max_speed;
        }
        let b = self.decel * self.dt * self.dt;
        let y = ((((b + 2.0 * v) * (b + 2.0 * v) + 8.0 * b * seen).sqrt() - b) * 0.5 - v) / b;
        let y = y.fmax(0.0);
        let y_full = floor_exact(y);
        let exact_gap =
            (y_full * y_full + y_full) * 0.5 * b + y_full * v + if y > y_full { v } else { 0.0 };
        let full_speed_gain = y_full * (self.decel * self.dt);
        (seen - exact_gap).fmax(0.0) / (y_full + 1.0) / self.dt + full_speed_gain + max_speed
    }

    /// SUMO's `getSecureGap`: own braking distance with the reaction time, less the leader's.
    fn secure_gap(&self, speed: f64, leader_speed: f64) -> f64 {
        (kinematics::brake_gap(self.dt, speed, self.decel, self.tau)
            - kinematics::brake_gap(self.dt, leader_speed, self.decel, 0.0))
        .fmax(0.0)
    }

    /// The secure gap is at most the follower's most braking distance ([`kinematics::brake_gap_at_most`]) less
    /// the leader's least ([`kinematics::brake_gap_at_least`]); a relative margin far above rounding.
    #[inline(always)]
    fn surely_secure(&self, gap: f64, speed: f64, leader_speed: f64, factor: f64) -> bool {
        let d = self.decel;
        if !(d > 0.0 && speed >= 0.0 && leader_speed >= 0.0 && factor >= 0.0) {
            return false;
        }
        let follower_at_most = kinematics::brake_gap_at_most(speed, d, self.tau);
        let leader_at_least = kinematics::brake_gap_at_least(self.dt, leader_speed, d);
        let secure_at_most = ((follower_at_most - leader_at_least).fmax(0.0)) * (1.0 + 1e-9) + 1e-6;
        gap >= secure_at_most * factor
    }

    /// SUMO's `insertionFollowSpeed` (Euler): the safe follow speed without the emergency rule.
    fn insertion_follow_speed(
        &self,
        speed: f64,
        gap: f64,
        leader_speed: f64,
        _desired_speed: f64,
    ) -> f64 {
        if self.stops_within(gap, speed) {
            return speed;
        }
        speed.fmin(self.maximum_safe_follow_speed(gap, speed, leader_speed, true))
    }

    #[inline]
    fn dawdle(&self, v_min: f64, v_max: f64, r: f64) -> f64 {
        v_min.fmax(self.dawdled(v_max, r))
    }

    #[inline]
    fn dawdles(&self) -> bool {
        true
    }

    #[inline(always)]
    fn free_speed_at_least_limit(&self) -> bool {
        true
    }

    /// Krauss' speeds have no vector form: each is computed where the plan reads it, and only then (most plans
    /// never reach the lanes ahead).
    #[inline(always)]
    fn plan_speeds(
        &self,
        _gap: [f64; 4],
        _speed: f64,
        _leader_speed: [f64; 4],
        _desired_speed: f64,
    ) -> [f64; 4] {
        super::BATCHED_NOT
    }

    #[inline(always)]
    fn batches_plan_speeds(&self) -> bool {
        false
    }
}

#[cfg(test)]
#[path = "krauss_tests.rs"]
mod tests;
