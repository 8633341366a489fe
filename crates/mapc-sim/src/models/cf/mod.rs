//! Car-following models, after SUMO's `src/microsim/cfmodels/`: one model per file behind the small interface
//! [`CarFollowModel`] (the IDM, [`idm`]; Krauss, SUMO's default, [`krauss`]), and [`CfModel`], a vehicle type's model as the simulator stores it.
//!
//! Glossary:
//! - **gap**: from the ego's front to the leader's back, less the ego's min gap (SUMO's convention).
//! - **follow speed**: the speed for the next step behind a leader (SUMO's `followSpeed`).
//! - **stop speed**: the speed for the next step towards a point to stop at (SUMO's `stopSpeed`).
//! - **free speed**: the speed for the next step towards a lower limit further on (SUMO's `freeSpeed`).
//! - **secure gap**: the gap a follower needs behind a leader to be safe at their speeds (`getSecureGap`).
//! - **base parameters**: what every model has (SUMO's `MSCFModel` members): acceleration, deceleration,
//!   emergency deceleration, headway `tau`, min gap and the step; the step's own rules (acceleration bounds,
//!   junctions, insertion) read them from [`CfModel`], and [`kinematics`] computes from them.

pub mod idm;
pub mod kinematics;
pub mod krauss;

pub use idm::IdmParams;
pub use krauss::Krauss;

/// The safe stop speed behind a leader (before the emergency rule) that the lane changer computed for one gap and
/// leader speed, kept for the next step's plan: the positions and speeds do not change in between, so behind the
/// same leader the plan asks the same one (about half of Krauss' exact follow speeds in congested scenarios).
/// Read only where gap and leader speed are the same bits.
#[derive(Clone, Copy, Debug)]
pub struct StopShare {
    gap: u64,
    leader_speed: u64,
    stop_speed: f64,
}

/// Equal bits (an empty share's NaN equals itself).
impl PartialEq for StopShare {
    fn eq(&self, other: &Self) -> bool {
        (self.gap, self.leader_speed, self.stop_speed.to_bits())
            == (other.gap, other.leader_speed, other.stop_speed.to_bits())
    }
}

impl Default for StopShare {
    fn default() -> Self {
        // (a NaN gap's bits: no gap the simulator computes)
        StopShare {
            gap: u64::MAX,
            leader_speed: u64::MAX,
            stop_speed: f64::NAN,
        }
    }
}

impl StopShare {
    /// The stop speed kept for `gap` and `leader_speed`, if that is what was kept.
    #[inline(always)]
    pub fn get(&self, gap: f64, leader_speed: f64) -> Option<f64> {
        (self.gap == gap.to_bits() && self.leader_speed == leader_speed.to_bits())
            .then_some(self.stop_speed)
    }

    /// The stop speed kept for `gap` and `leader_speed`, else `stop_speed()` (the computation it stands for),
    /// kept from then on. Debug builds compare a kept one with the computation.
    #[inline(always)]
    pub fn get_or_keep(
        &mut self,
        gap: f64,
        leader_speed: f64,
        stop_speed: impl Fn() -> f64,
    ) -> f64 {
        if let Some(x) = self.get(gap, leader_speed) {
            debug_assert_eq!(x.to_bits(), stop_speed().to_bits());
            return x;
        }
        let x = stop_speed();
        *self = StopShare {
            gap: gap.to_bits(),
            leader_speed: leader_speed.to_bits(),
            stop_speed: x,
        };
        x
    }
}

/// What the simulator asks of a car-following model. The gaps exclude the min gap; `desired_speed` is the
/// vehicle's desired speed on its lane (limit times speed factor, capped by the type's maximum).
pub trait CarFollowModel {
    /// The speed after one step behind a leader `gap` ahead driving at `leader_speed`.
    fn follow_speed(&self, gap: f64, speed: f64, leader_speed: f64, desired_speed: f64) -> f64;

    /// [`Self::follow_speed`] as the lane-change model computes it (SUMO's `gComputeLC`): Krauss then leaves out
    /// its emergency-braking correction.
    #[inline(always)]
    fn follow_speed_lc(&self, gap: f64, speed: f64, leader_speed: f64, desired_speed: f64) -> f64 {
        self.follow_speed(gap, speed, leader_speed, desired_speed)
    }

    /// [`Self::follow_speed_lc`] (`lc`) or [`Self::follow_speed`] with the stop speed `share` keeps where it is
    /// this gap's and leader speed's, else keeping in `share` the one computed (for the next plan, or the next
    /// question behind the same leader). A model without a stop speed to share ignores it.
    #[inline(always)]
    fn follow_speed_sharing(
        &self,
        _share: &mut StopShare,
        lc: bool,
        gap: f64,
        speed: f64,
        leader_speed: f64,
        desired_speed: f64,
    ) -> f64 {
        if lc {
            self.follow_speed_lc(gap, speed, leader_speed, desired_speed)
        } else {
            self.follow_speed(gap, speed, leader_speed, desired_speed)
        }
    }

    /// The speed after one step that lets the vehicle stop within `gap`.
    fn stop_speed(&self, gap: f64, speed: f64, desired_speed: f64) -> f64;

    /// Whether [`Self::stop_speed`] is surely at least `v`, decided without computing it (false: ask it).
    #[inline(always)]
    fn stop_speed_at_least(&self, _gap: f64, _speed: f64, _v: f64) -> bool {
        false
    }

    /// The speed after one step towards `max_speed`, which applies `seen` metres ahead.
    fn free_speed(&self, speed: f64, seen: f64, max_speed: f64, desired_speed: f64) -> f64;

    /// The gap a vehicle at `speed` needs behind a leader at `leader_speed`.
    fn secure_gap(&self, speed: f64, leader_speed: f64) -> f64;

    /// Whether `gap` is surely at least `factor` times [`Self::secure_gap`], decided without computing it (a
    /// model with a costly secure gap gives a cheap bound; false: ask the secure gap).
    #[inline(always)]
    fn surely_secure(&self, _gap: f64, _speed: f64, _leader_speed: f64, _factor: f64) -> bool {
        false
    }

    /// The highest speed, at most `speed`, a vehicle may be inserted with at `gap` behind a leader.
    fn insertion_follow_speed(
        &self,
        speed: f64,
        gap: f64,
        leader_speed: f64,
        desired_speed: f64,
    ) -> f64;

    /// The part of [`Self::free_speed`] for `speed <= max_speed` that does not depend on the distance, for
    /// models whose free speed has one (IDM's); the planning step keeps it per limit and hands it to
    /// [`Self::free_speed_given`]. Other models return NaN.
    #[inline(always)]
    fn free_speed_below_limit(&self, _speed: f64, _max_speed: f64, _desired_speed: f64) -> f64 {
        f64::NAN
    }

    /// [`Self::free_speed`] for `speed <= max_speed`, given [`Self::free_speed_below_limit`]'s value `below`.
    #[inline(always)]
    fn free_speed_given(
        &self,
        _below: f64,
        speed: f64,
        seen: f64,
        max_speed: f64,
        desired_speed: f64,
    ) -> f64 {
        self.free_speed(speed, seen, max_speed, desired_speed)
    }

    /// Whether the driver slows at random each step ([`Self::dawdle`] needs a draw).
    #[inline(always)]
    fn dawdles(&self) -> bool {
        false
    }

    /// The next speed after the driver's random slowdown (SUMO's `patchSpeedBeforeLC`), between the step's
    /// bounds `v_min` and `v_max`, from a uniform draw `r` in [0, 1).
    #[inline(always)]
    fn dawdle(&self, _v_min: f64, v_max: f64, _r: f64) -> f64 {
        v_max
    }

    /// Whether [`Self::free_speed`] is never below its `max_speed` (Krauss' is not: it brakes towards the limit
    /// from above only), so that a limit no lower than a speed already planned cannot lower it.
    #[inline(always)]
    fn free_speed_at_least_limit(&self) -> bool {
        false
    }

    /// Whether [`Self::plan_speeds`] computes anything: the plan gathers its arguments only then.
    #[inline(always)]
    fn batches_plan_speeds(&self) -> bool {
        true
    }

    /// The four speeds most plans need, known before planning: behind leaders 0, 2 and 3, and
    /// [`Self::free_speed_below_limit`] towards `leader_speed[1]` (`gap[1]` unused). One at a time unless a
    /// model computes them together; a model that gains nothing from the batch returns NaN for the entries the
    /// plan then computes where it reads them ([`BATCHED_NOT`]).
    #[inline(always)]
    fn plan_speeds(
        &self,
        gap: [f64; 4],
        speed: f64,
        leader_speed: [f64; 4],
        desired_speed: f64,
    ) -> [f64; 4] {
        [
            self.follow_speed(gap[0], speed, leader_speed[0], desired_speed),
            self.free_speed_below_limit(speed, leader_speed[1], desired_speed),
            self.follow_speed(gap[2], speed, leader_speed[2], desired_speed),
            self.follow_speed(gap[3], speed, leader_speed[3], desired_speed),
        ]
    }
}

/// [`CarFollowModel::plan_speeds`]' entry for a speed left to the plan to compute where it reads it.
pub const BATCHED_NOT: [f64; 4] = [f64::NAN; 4];

/// The models a vehicle type may drive with.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum CfKind {
    Idm(IdmParams),
    Krauss(Krauss),
}

/// A vehicle type's car following: the base parameters every model has and the model itself.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CfModel {
    /// Maximum acceleration (m/s^2).
    pub accel: f64,
    /// Comfortable deceleration (m/s^2), also the deceleration the junction logic plans with.
    pub decel: f64,
    /// Deceleration a driver is physically able to apply when the safe speed demands it (m/s^2).
    pub emergency_decel: f64,
    /// Desired time headway (s).
    pub tau: f64,
    /// Standstill gap (m), front bumper to the leader's back bumper.
    pub min_gap: f64,
    /// Step length (s).
    pub dt: f64,
    pub kind: CfKind,
}

impl CfModel {
    /// An IDM driver with IDM's parameters as the base ones.
    pub fn idm(p: IdmParams) -> CfModel {
        CfModel {
            accel: p.accel,
            decel: p.decel,
            emergency_decel: p.emergency_decel,
            tau: p.tau,
            min_gap: p.min_gap,
            dt: p.dt,
            kind: CfKind::Idm(p),
        }
    }

    /// A Krauss driver with Krauss' parameters as the base ones and `min_gap`.
    pub fn krauss(k: Krauss, min_gap: f64) -> CfModel {
        CfModel {
            accel: k.accel,
            decel: k.decel,
            emergency_decel: k.emergency_decel,
            tau: k.tau,
            min_gap,
            dt: k.dt,
            kind: CfKind::Krauss(k),
        }
    }

    /// [`kinematics::brake_gap`] with this type's step.
    #[inline]
    pub fn brake_gap(&self, speed: f64, decel: f64, headway: f64) -> f64 {
        kinematics::brake_gap(self.dt, speed, decel, headway)
    }

    /// [`kinematics::maximum_safe_stop_speed`] at this type's deceleration.
    #[inline]
    pub fn maximum_safe_stop_speed(&self, gap: f64, _speed: f64) -> f64 {
        kinematics::maximum_safe_stop_speed(self.dt, self.decel, gap)
    }

    /// [`kinematics::minimal_arrival_speed_euler`] with this type's headway and deceleration.
    #[inline]
    pub fn minimal_arrival_speed_euler(&self, dist: f64, speed: f64) -> f64 {
        kinematics::minimal_arrival_speed_euler(self.tau, self.decel, dist, speed)
    }

    /// [`kinematics::minimal_arrival_time`] at this type's acceleration and deceleration.
    #[inline]
    pub fn minimal_arrival_time(&self, dist: f64, speed: f64, arrival_speed: f64) -> f64 {
        kinematics::minimal_arrival_time(self.accel, self.decel, dist, speed, arrival_speed)
    }
}

/// Each call goes to the type's model.
macro_rules! by_model {
    ($self:ident, $m:ident => $e:expr) => {
        match &$self.kind {
            CfKind::Idm($m) => $e,
            CfKind::Krauss($m) => $e,
        }
    };
}

impl CarFollowModel for CfModel {
    #[inline(always)]
    fn follow_speed(&self, gap: f64, speed: f64, leader_speed: f64, desired_speed: f64) -> f64 {
        by_model!(self, m => m.follow_speed(gap, speed, leader_speed, desired_speed))
    }
    #[inline(always)]
    fn follow_speed_lc(&self, gap: f64, speed: f64, leader_speed: f64, desired_speed: f64) -> f64 {
        by_model!(self, m => m.follow_speed_lc(gap, speed, leader_speed, desired_speed))
    }
    #[inline(always)]
    fn follow_speed_sharing(
        &self,
        share: &mut StopShare,
        lc: bool,
        gap: f64,
        speed: f64,
        leader_speed: f64,
        desired_speed: f64,
    ) -> f64 {
        by_model!(self, m => m.follow_speed_sharing(share, lc, gap, speed, leader_speed, desired_speed))
    }
    #[inline(always)]
    fn stop_speed(&self, gap: f64, speed: f64, desired_speed: f64) -> f64 {
        by_model!(self, m => m.stop_speed(gap, speed, desired_speed))
    }
    #[inline(always)]
    fn stop_speed_at_least(&self, gap: f64, speed: f64, v: f64) -> bool {
        by_model!(self, m => m.stop_speed_at_least(gap, speed, v))
    }
    #[inline(always)]
    fn free_speed(&self, speed: f64, seen: f64, max_speed: f64, desired_speed: f64) -> f64 {
        by_model!(self, m => m.free_speed(speed, seen, max_speed, desired_speed))
    }
    #[inline(always)]
    fn secure_gap(&self, speed: f64, leader_speed: f64) -> f64 {
        by_model!(self, m => m.secure_gap(speed, leader_speed))
    }
    #[inline(always)]
    fn surely_secure(&self, gap: f64, speed: f64, leader_speed: f64, factor: f64) -> bool {
        by_model!(self, m => m.surely_secure(gap, speed, leader_speed, factor))
    }
    #[inline(always)]
    fn insertion_follow_speed(
        &self,
        speed: f64,
        gap: f64,
        leader_speed: f64,
        desired_speed: f64,
    ) -> f64 {
        by_model!(self, m => m.insertion_follow_speed(speed, gap, leader_speed, desired_speed))
    }
    #[inline(always)]
    fn free_speed_below_limit(&self, speed: f64, max_speed: f64, desired_speed: f64) -> f64 {
        by_model!(self, m => m.free_speed_below_limit(speed, max_speed, desired_speed))
    }
    #[inline(always)]
    fn free_speed_given(
        &self,
        below: f64,
        speed: f64,
        seen: f64,
        max_speed: f64,
        desired_speed: f64,
    ) -> f64 {
        by_model!(self, m => m.free_speed_given(below, speed, seen, max_speed, desired_speed))
    }
    #[inline(always)]
    fn dawdles(&self) -> bool {
        by_model!(self, m => m.dawdles())
    }
    #[inline(always)]
    fn free_speed_at_least_limit(&self) -> bool {
        by_model!(self, m => m.free_speed_at_least_limit())
    }
    #[inline(always)]
    fn dawdle(&self, v_min: f64, v_max: f64, r: f64) -> f64 {
        by_model!(self, m => m.dawdle(v_min, v_max, r))
    }
    #[inline(always)]
    fn plan_speeds(
        &self,
        gap: [f64; 4],
        speed: f64,
        leader_speed: [f64; 4],
        desired_speed: f64,
    ) -> [f64; 4] {
        by_model!(self, m => m.plan_speeds(gap, speed, leader_speed, desired_speed))
    }

    #[inline(always)]
    fn batches_plan_speeds(&self) -> bool {
        by_model!(self, m => m.batches_plan_speeds())
    }
}
