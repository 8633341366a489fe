//! The Intelligent Driver Model as SUMO's car-following model `IDM` computes it (Euler update, internal
//! sub-stepping), plus the kinematic helpers SUMO's junction and insertion logic use (brake gap, maximum safe stop
//! speed, arrival times). All functions are pure; speeds in m/s, distances in m, times in s.

use super::{CarFollowModel, kinematics};
use crate::numeric::FastMinMax;
pub use crate::numeric::NUMERICAL_EPS;

/// Car-following parameters of one driver type.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct IdmParams {
    /// Maximum acceleration a (m/s^2).
    pub accel: f64,
    /// Comfortable deceleration b (m/s^2), also the deceleration the junction logic plans with.
    pub decel: f64,
    /// Deceleration a driver is physically able to apply when the safe speed demands it (m/s^2).
    pub emergency_decel: f64,
    /// Desired time headway T (s).
    pub tau: f64,
    /// Standstill gap s0 (m), front bumper to the leader's back bumper.
    pub min_gap: f64,
    /// Free-road exponent delta.
    pub delta: f64,
    /// Number of IDM sub-steps per simulation step (SUMO: round(step / 0.25), at least 1).
    pub iterations: u32,
    /// Step length (s).
    pub dt: f64,
    /// 2 sqrt(accel decel), IDM's braking term, computed once by the constructor (read-only: the fields above are
    /// set at construction and never changed).
    two_sqrt_ab: f64,
}

#[cfg(feature = "count-idm")]
static IDM_CALLS: std::sync::atomic::AtomicU64 = std::sync::atomic::AtomicU64::new(0);
#[cfg(feature = "count-idm")]
static IDM_BATCHES: std::sync::atomic::AtomicU64 = std::sync::atomic::AtomicU64::new(0);

/// Calls of [`IdmParams::next_speed_x4`] since the last call of this function (feature `count-idm`; each also
/// counts as four IDM steps in [`take_idm_calls`], the ones whose results are not read included).
#[cfg(feature = "count-idm")]
pub fn take_idm_batches() -> u64 {
    IDM_BATCHES.swap(0, std::sync::atomic::Ordering::Relaxed)
}

/// IDM steps computed since the last call of this function (feature `count-idm`): calls of
/// [`IdmParams::next_speed`] and four per [`IdmParams::next_speed_x4`] (debug builds, whose assertions repeat
/// batched steps as single calls, count more).
#[cfg(feature = "count-idm")]
pub fn take_idm_calls() -> u64 {
    IDM_CALLS.swap(0, std::sync::atomic::Ordering::Relaxed)
}

/// The arguments of [`IdmParams::next_speed_x4`], for its SSE2 path.
#[cfg(target_arch = "x86_64")]
#[derive(Clone, Copy)]
struct Steps4 {
    gap: [f64; 4],
    speed: f64,
    leader_speed: [f64; 4],
    desired_speed: f64,
    respect_min_gap: [bool; 4],
}

impl IdmParams {
    /// Parameters with SUMO's sub-stepping rule for the step `dt` (IDM stepping 0.25 s).
    pub fn new(
        accel: f64,
        decel: f64,
        emergency_decel: f64,
        tau: f64,
        min_gap: f64,
        delta: f64,
        dt: f64,
    ) -> Self {
        Self::with_stepping(accel, decel, emergency_decel, tau, min_gap, delta, dt, 0.25)
    }

    /// Parameters with `round(dt / stepping)` sub-steps (at least one).
    #[allow(clippy::too_many_arguments)]
    pub fn with_stepping(
        accel: f64,
        decel: f64,
        emergency_decel: f64,
        tau: f64,
        min_gap: f64,
        delta: f64,
        dt: f64,
        stepping: f64,
    ) -> Self {
        let iterations = ((dt / stepping + 0.5) as u32).max(1);
        IdmParams {
            accel,
            decel,
            emergency_decel,
            tau,
            min_gap,
            delta,
            iterations,
            dt,
            two_sqrt_ab: 2.0 * (accel * decel).sqrt(),
        }
    }

    #[inline(always)]
    fn two_sqrt_ab(&self) -> f64 {
        debug_assert_eq!(
            self.two_sqrt_ab.to_bits(),
            (2.0 * (self.accel * self.decel).sqrt()).to_bits(),
            "IdmParams changed after construction"
        );
        self.two_sqrt_ab
    }

    fn speed_ratio_pow(&self, x: f64) -> f64 {
        // delta = 4 is the common case; powi keeps it cheap and exact.
        if self.delta == 4.0 {
            let x2 = x * x;
            x2 * x2
        } else {
            x.powf(self.delta)
        }
    }

    /// SUMO's `MSCFModel_IDM::_v`: the speed after one step behind a leader at bumper gap `gap` driving at
    /// `leader_speed`, integrating IDM's acceleration in `iterations` sub-steps (the gap shrinks between sub-steps;
    /// the leader is assumed to keep its speed). `respect_min_gap` adds s0 to both the gap and the desired gap.
    #[inline]
    pub fn next_speed(
        &self,
        gap: f64,
        speed: f64,
        leader_speed: f64,
        desired_speed: f64,
        respect_min_gap: bool,
    ) -> f64 {
        #[cfg(feature = "count-idm")]
        IDM_CALLS.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
        // The common sub-step counts get a loop the compiler unrolls, with the division by the count (a power of
        // two) done as the multiplication by its exact reciprocal: the same bits, without a division.
        match self.iterations {
            2 => self.next_speed_sub::<2>(gap, speed, leader_speed, desired_speed, respect_min_gap),
            1 => self.next_speed_sub::<1>(gap, speed, leader_speed, desired_speed, respect_min_gap),
            4 => self.next_speed_sub::<4>(gap, speed, leader_speed, desired_speed, respect_min_gap),
            n => {
                let n_f = n as f64;
                self.next_speed_with(
                    n,
                    |x| x / n_f,
                    gap,
                    speed,
                    leader_speed,
                    desired_speed,
                    respect_min_gap,
                )
            }
        }
    }

    #[inline(always)]
    fn next_speed_sub<const N: u32>(
        &self,
        gap: f64,
        speed: f64,
        leader_speed: f64,
        desired_speed: f64,
        respect_min_gap: bool,
    ) -> f64 {
        const { assert!(N.is_power_of_two()) };
        let inv_n = 1.0 / N as f64;
        self.next_speed_with(
            N,
            |x| x * inv_n,
            gap,
            speed,
            leader_speed,
            desired_speed,
            respect_min_gap,
        )
    }

    /// The IDM sub-step loop; `per_sub_step(x)` is `x / iterations`.
    #[allow(clippy::too_many_arguments)]
    #[inline(always)]
    fn next_speed_with(
        &self,
        iterations: u32,
        per_sub_step: impl Fn(f64) -> f64,
        gap: f64,
        speed: f64,
        leader_speed: f64,
        desired_speed: f64,
        respect_min_gap: bool,
    ) -> f64 {
        let two_sqrt_ab = self.two_sqrt_ab();
        let des = desired_speed.fmax(NUMERICAL_EPS);
        let mut v = speed;
        let mut g = if respect_min_gap {
            gap + self.min_gap
        } else {
            gap
        };
        for _ in 0..iterations {
            let dv = v - leader_speed;
            let mut s = (v * self.tau + v * dv / two_sqrt_ab).fmax(0.0);
            if respect_min_gap {
                s += self.min_gap;
            }
            g = g.fmax(NUMERICAL_EPS);
            let acc = self.accel * (1.0 - self.speed_ratio_pow(v / des) - (s * s) / (g * g));
            v = (v + per_sub_step(acc * self.dt)).fmax(0.0);
            g -= per_sub_step((v - leader_speed) * self.dt).fmax(0.0);
        }
        v.fmax(0.0)
    }

    /// Four independent [`Self::next_speed`] calls of one driver at once, the same bits as four calls: on x86-64
    /// two SSE2 pairs (part of the baseline target), whose divisions share the divider and whose chains overlap;
    /// one call after another elsewhere or for sub-step counts and exponents the pairs do not cover. A planning
    /// step makes most of its IDM calls (own leader, free speed, the vehicles on the next lanes) with arguments
    /// known at its start, so it computes them together.
    #[inline(always)]
    pub fn next_speed_x4(
        &self,
        gap: [f64; 4],
        speed: f64,
        leader_speed: [f64; 4],
        desired_speed: f64,
        respect_min_gap: [bool; 4],
    ) -> [f64; 4] {
        #[cfg(feature = "count-idm")]
        IDM_BATCHES.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
        #[cfg(target_arch = "x86_64")]
        if self.delta == 4.0 {
            let args = Steps4 {
                gap,
                speed,
                leader_speed,
                desired_speed,
                respect_min_gap,
            };
            match self.iterations {
                1 => return self.next_speed_x4_sse2::<1>(&args),
                2 => return self.next_speed_x4_sse2::<2>(&args),
                4 => return self.next_speed_x4_sse2::<4>(&args),
                _ => {}
            }
        }
        std::array::from_fn(|i| {
            self.next_speed(
                gap[i],
                speed,
                leader_speed[i],
                desired_speed,
                respect_min_gap[i],
            )
        })
    }

    /// [`Self::next_speed_with`] for delta = 4 and `N` (a power of two) sub-steps, two lanes per SSE2 register:
    /// every operation is the scalar one, in the same order (`maxpd(a, b)` is `a > b ? a : b`, which is
    /// [`FastMinMax`]'s `b.fmax(a)`), so each lane's result has the scalar call's bits.
    #[cfg(target_arch = "x86_64")]
    #[inline(always)]
    fn next_speed_x4_sse2<const N: u32>(&self, args: &Steps4) -> [f64; 4] {
        use std::arch::x86_64::*;
        let Steps4 {
            gap,
            speed,
            leader_speed,
            desired_speed,
            respect_min_gap,
        } = *args;
        const { assert!(N.is_power_of_two()) };
        #[cfg(feature = "count-idm")]
        IDM_CALLS.fetch_add(4, std::sync::atomic::Ordering::Relaxed);
        debug_assert_eq!(self.delta, 4.0);
        // SAFETY: SSE2 is part of the x86-64 baseline; the intrinsics only compute on registers.
        unsafe {
            let inv_n = _mm_set1_pd(1.0 / N as f64);
            let two_sqrt_ab = _mm_set1_pd(self.two_sqrt_ab());
            let zero = _mm_setzero_pd();
            let one = _mm_set1_pd(1.0);
            let eps = _mm_set1_pd(NUMERICAL_EPS);
            let tau = _mm_set1_pd(self.tau);
            let accel = _mm_set1_pd(self.accel);
            let dt = _mm_set1_pd(self.dt);
            let min_gap = _mm_set1_pd(self.min_gap);
            let des = _mm_max_pd(eps, _mm_set1_pd(desired_speed));
            let mask =
                |a: bool, b: bool| _mm_castsi128_pd(_mm_set_epi64x(-(b as i64), -(a as i64)));
            let select = |m: __m128d, yes: __m128d, no: __m128d| {
                _mm_or_pd(_mm_and_pd(m, yes), _mm_andnot_pd(m, no))
            };
            let mg = [
                mask(respect_min_gap[0], respect_min_gap[1]),
                mask(respect_min_gap[2], respect_min_gap[3]),
            ];
            let leader = [
                _mm_set_pd(leader_speed[1], leader_speed[0]),
                _mm_set_pd(leader_speed[3], leader_speed[2]),
            ];
            let mut v = [_mm_set1_pd(speed); 2];
            let mut g = [0, 1].map(|h| {
                let gp = _mm_set_pd(gap[2 * h + 1], gap[2 * h]);
                select(mg[h], _mm_add_pd(gp, min_gap), gp)
            });
            for _ in 0..N {
                for h in 0..2 {
                    let dv = _mm_sub_pd(v[h], leader[h]);
                    let s = _mm_add_pd(
                        _mm_mul_pd(v[h], tau),
                        _mm_div_pd(_mm_mul_pd(v[h], dv), two_sqrt_ab),
                    );
                    let s = _mm_max_pd(zero, s);
                    let s = select(mg[h], _mm_add_pd(s, min_gap), s);
                    g[h] = _mm_max_pd(eps, g[h]);
                    let x = _mm_div_pd(v[h], des);
                    let x2 = _mm_mul_pd(x, x);
                    let pow = _mm_mul_pd(x2, x2);
                    let inter = _mm_div_pd(_mm_mul_pd(s, s), _mm_mul_pd(g[h], g[h]));
                    let acc = _mm_mul_pd(accel, _mm_sub_pd(_mm_sub_pd(one, pow), inter));
                    v[h] = _mm_max_pd(
                        zero,
                        _mm_add_pd(v[h], _mm_mul_pd(_mm_mul_pd(acc, dt), inv_n)),
                    );
                    let closing = _mm_mul_pd(_mm_mul_pd(_mm_sub_pd(v[h], leader[h]), dt), inv_n);
                    g[h] = _mm_sub_pd(g[h], _mm_max_pd(zero, closing));
                }
            }
            let mut out = [0.0; 4];
            _mm_storeu_pd(out.as_mut_ptr(), _mm_max_pd(zero, v[0]));
            _mm_storeu_pd(out.as_mut_ptr().add(2), _mm_max_pd(zero, v[1]));
            out
        }
    }

    /// [`Self::free_speed`]'s last rule: close to the new limit, do not exceed it.
    #[inline]
    pub fn free_speed_near_limit(&self, v: f64, seen: f64, max_speed: f64) -> f64 {
        if seen < self.secure_gap(max_speed, 0.0) {
            v.fmin(max_speed)
        } else {
            v
        }
    }

    /// SUMO's Euler `brakeGap` with this type's step ([`kinematics::brake_gap`]).
    pub fn brake_gap(&self, speed: f64, decel: f64, headway: f64) -> f64 {
        kinematics::brake_gap(self.dt, speed, decel, headway)
    }

    /// SUMO's Euler `maximumSafeStopSpeed` ([`kinematics::maximum_safe_stop_speed`]).
    pub fn maximum_safe_stop_speed(&self, gap: f64, _speed: f64) -> f64 {
        kinematics::maximum_safe_stop_speed(self.dt, self.decel, gap)
    }
}

impl CarFollowModel for IdmParams {
    /// Speed behind a moving leader (`gap` already excludes the min gap).
    fn follow_speed(&self, gap: f64, speed: f64, leader_speed: f64, desired_speed: f64) -> f64 {
        self.next_speed(gap, speed, leader_speed, desired_speed, true)
    }

    /// Speed that lets the vehicle stop within `gap` (a stop line, the end of the road).
    fn stop_speed(&self, gap: f64, speed: f64, desired_speed: f64) -> f64 {
        if gap < 0.01 {
            return 0.0;
        }
        // SUMO 1.8's IDM stop speed keeps the min gap on both sides (`_v` with its default respectMinGap)
        let v = self.next_speed(gap, speed, 0.0, desired_speed, true);
        if speed < NUMERICAL_EPS && v < NUMERICAL_EPS {
            // IDM alone never starts towards a close stop point; fall back to the kinematic bound.
            return self.maximum_safe_stop_speed(gap, speed);
        }
        v
    }

    /// Speed on free road towards `max_speed`, which applies `seen` metres ahead (SUMO's IDM `freeSpeed`).
    fn free_speed(&self, speed: f64, seen: f64, max_speed: f64, desired_speed: f64) -> f64 {
        let v = if speed <= max_speed {
            self.free_speed_below_limit(speed, max_speed, desired_speed)
        } else {
            let sec_gap = self.secure_gap(max_speed, 0.0);
            self.next_speed(seen.fmax(sec_gap), speed, 0.0, desired_speed, false)
        };
        self.free_speed_near_limit(v, seen, max_speed)
    }

    /// [`CarFollowModel::free_speed`]'s IDM step for `speed <= max_speed` (independent of the distance).
    #[inline]
    fn free_speed_below_limit(&self, speed: f64, max_speed: f64, desired_speed: f64) -> f64 {
        self.next_speed(1e6, speed, max_speed, desired_speed, false)
    }

    /// IDM's desired dynamic gap without s0 (SUMO's `getSecureGap` for IDM).
    fn secure_gap(&self, speed: f64, leader_speed: f64) -> f64 {
        (speed * self.tau + speed * (speed - leader_speed) / self.two_sqrt_ab()).fmax(0.0)
    }

    /// The highest speed a vehicle may be inserted with at `gap` behind a leader, starting from `speed`
    /// (SUMO's `insertionFollowSpeed`).
    fn insertion_follow_speed(
        &self,
        speed: f64,
        gap: f64,
        leader_speed: f64,
        desired_speed: f64,
    ) -> f64 {
        let mut v = speed;
        for _ in 0..64 {
            if gap >= self.secure_gap(v, leader_speed) {
                return v;
            }
            let v2 = self.follow_speed(gap, v, leader_speed, desired_speed);
            let v3 = self.follow_speed(gap, v2, leader_speed, desired_speed);
            if v2 - v3 < 1.0 {
                return v2;
            }
            v = v2;
        }
        v
    }

    #[inline(always)]
    fn free_speed_given(
        &self,
        below: f64,
        _speed: f64,
        seen: f64,
        max_speed: f64,
        _desired_speed: f64,
    ) -> f64 {
        self.free_speed_near_limit(below, seen, max_speed)
    }

    /// One [`IdmParams::next_speed_x4`] call.
    #[inline(always)]
    fn plan_speeds(
        &self,
        gap: [f64; 4],
        speed: f64,
        leader_speed: [f64; 4],
        desired_speed: f64,
    ) -> [f64; 4] {
        self.next_speed_x4(
            gap,
            speed,
            leader_speed,
            desired_speed,
            [true, false, true, true],
        )
    }
}

#[cfg(test)]
#[path = "idm_tests.rs"]
mod tests;
