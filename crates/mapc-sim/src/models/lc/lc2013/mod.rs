//! SUMO 1.8's default lane-change model LC2013 (`MSLCM_LC2013`), for changes done in one step (no sublanes,
//! `lanechange.duration` 0). Four motivations, checked in this order for each side:
//! - **strategic**: reach a lane that continues on the route before the current one ends; urgent once the
//!   usable distance per lane to cross is below the look-ahead distance (10 s at the remembered speed, twice that
//!   to the left, plus two vehicle lengths). An urgent, blocked change asks the blocking leader and follower for
//!   help and slows the ego to fall behind or to let a blocker in (`inform.rs`).
//! - **cooperative**: a vehicle that was told it blocks a follower's urgent change moves out of the way in the
//!   same direction when that costs it no speed.
//! - **speed gain**: the anticipated speeds of both lanes are compared each step and the relative gain summed in
//!   `speed_gain_probability`; a change follows past a threshold (0.2 to the left, 2.0 to the right).
//! - **keep right**: `keep_right_probability` grows with the time the vehicle could drive at full speed on the
//!   right lane; past 2.0 (after about 5 s of a free right lane) the vehicle moves right.
//!
//! Deterministic: with `lcSigma` 0 and `lcOvertakeRight` 0 (SUMO's defaults) LC2013 draws no random number.
//! Not modelled (absent from the freeway scenarios): scheduled stops, pedestrians, roundabouts, opposite-direction
//! overtaking, TraCI requests, sublanes, the ballistic update.

mod inform;
mod memory;
mod speed;
#[cfg(test)]
mod tests;

use super::safety::check_gaps;
use super::{BlockedAhead, Decision, Ego, LaneQ, Message, Other, Reason, Side, Surroundings, lca};
use crate::models::cf::idm::NUMERICAL_EPS;
use crate::models::cf::{CarFollowModel, CfModel, StopShare};
pub use memory::Lc2013Memory;
use speed::{anticipate_follow_speed, max2, min2};

/// Seconds of look-ahead at the remembered speed for strategic changes (`LOOK_FORWARD`).
const LOOK_FORWARD: f64 = 10.0;
/// Weight of the vehicles' length on the best lane in the usable distance (`JAM_FACTOR`).
const JAM_FACTOR: f64 = 1.0;
/// Share of the remembered look-ahead speed kept per second when the vehicle slows (`LOOK_AHEAD_SPEED_MEMORY`).
const LOOK_AHEAD_SPEED_MEMORY: f64 = 0.9;
/// Lowest look-ahead speed (`LOOK_AHEAD_MIN_SPEED`).
const LOOK_AHEAD_MIN_SPEED: f64 = 0.0;
/// Speed (m/s) by which a vehicle passes, or is passed, when cutting in (`HELP_OVERTAKE`).
const HELP_OVERTAKE: f64 = 10.0 / 3.6;
/// Lowest deceleration (m/s^2) to fall behind a leader that cannot be overtaken (`MIN_FALLBEHIND`).
const MIN_FALLBEHIND: f64 = 7.0 / 3.6;
/// Lowest speed dividing a speed gain (`RELGAIN_NORMALIZATION_MIN_SPEED`).
const RELGAIN_NORMALIZATION_MIN_SPEED: f64 = 10.0;
/// Lane changes per distance an urgent change plans with (`URGENCY`).
const URGENCY: f64 = 2.0;
/// Seconds of a free right lane after which the vehicle keeps right (`KEEP_RIGHT_TIME`).
const KEEP_RIGHT_TIME: f64 = 5.0;
/// Calibration of the keep-right acceptance time (`KEEP_RIGHT_ACCEPTANCE`).
const KEEP_RIGHT_ACCEPTANCE: f64 = 7.0;
/// A lane ahead leading elsewhere within this distance is a turn lane to avoid (`TURN_LANE_DIST`).
const TURN_LANE_DIST: f64 = 200.0;
/// Lanes longer than this are taken as no on-ramp (`MAX_ONRAMP_LENGTH`).
const MAX_ONRAMP_LENGTH: f64 = 200.0;
/// A stopped leader closer than this is overtaken (`REACT_TO_STOPPED_DISTANCE`).
const REACT_TO_STOPPED_DISTANCE: f64 = 100.0;
/// Above this speed a vehicle changing left asks a faster follower to slow (`CUT_IN_LEFT_SPEED_THRESHOLD`).
const CUT_IN_LEFT_SPEED_THRESHOLD: f64 = 27.0;
/// A vehicle below this speed is congested (SUMO's `MSVehicle::congested`: 60 km/h).
const CONGESTED_SPEED: f64 = 60.0 / 3.6;
/// SUMO's `SUMO_const_haltingSpeed`.
const HALTING_SPEED: f64 = 0.1;
/// SUMO's `POSITION_EPS`.
const POSITION_EPS: f64 = 0.1;

/// LC2013's parameters (SUMO's `lc*` vehicle-type attributes); [`Default`] gives SUMO 1.8's defaults.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Lc2013Params {
    /// `lcStrategic`: scales the strategic look-ahead; negative disables strategic changes.
    pub strategic: f64,
    /// `lcCooperative`: willingness to change for others (1: whenever it costs no speed gain).
    pub cooperative: f64,
    /// `lcSpeedGain`: divides the speed-gain thresholds.
    pub speed_gain: f64,
    /// `lcKeepRight`: scales the keep-right wish.
    pub keep_right: f64,
    /// `lcLookaheadLeft`: the strategic look-ahead to the left relative to the right.
    pub lookahead_left: f64,
    /// `lcSpeedGainRight`: the speed-gain wish to the right relative to the left.
    pub speed_gain_right: f64,
    /// `lcAssertive`: divides the secure gaps of the safety check.
    pub assertive: f64,
    /// `lcCooperativeSpeed` (defaults to `lcCooperative`): weight of the speed advices of others.
    pub cooperative_speed: f64,
    /// SUMO's option `--lanechange.overtake-right` (false).
    pub allow_overtaking_right: bool,
}

impl Default for Lc2013Params {
    fn default() -> Self {
        Lc2013Params {
            strategic: 1.0,
            cooperative: 1.0,
            speed_gain: 1.0,
            keep_right: 1.0,
            lookahead_left: 2.0,
            speed_gain_right: 0.1,
            assertive: 1.0,
            cooperative_speed: 1.0,
            allow_overtaking_right: false,
        }
    }
}

/// The model for one vehicle type: its parameters and the thresholds derived from them.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Lc2013 {
    pub params: Lc2013Params,
    /// `myChangeProbThresholdRight`: (0.2 / lcSpeedGainRight) / lcSpeedGain = 2.0 by default.
    change_prob_threshold_right: f64,
    /// `myChangeProbThresholdLeft`: 0.2 / lcSpeedGain = 0.2 by default.
    change_prob_threshold_left: f64,
    /// SUMO's `getSafetyFactor`, `1 / lcAssertive`: asked for every vehicle's both sides, divided once.
    safety_factor: f64,
    /// The decay factors of the speed-gain wish for the step the simulator runs with.
    decay: StepDecay,
}

/// SUMO's `pow(0.5, TS)` and `pow(0.8, TS)`, by which the speed-gain wish decays each step, for one step length
/// `dt`, computed once ([`Lc2013::for_step`]): the library's `pow`, called per vehicle and step, was a tenth of
/// the model's time. Another step length computes them per call, with the same expressions.
#[derive(Clone, Copy, Debug, PartialEq)]
struct StepDecay {
    dt: f64,
    half: f64,
    four_fifths: f64,
}

impl StepDecay {
    fn new(dt: f64) -> Self {
        StepDecay {
            dt,
            half: half_pow(dt),
            four_fifths: four_fifths_pow(dt),
        }
    }
}

// Out of line and cold: inlined, the optimizer computes them for every vehicle, ahead of the test that needs them.
#[cold]
#[inline(never)]
fn half_pow(dt: f64) -> f64 {
    0.5f64.powf(dt)
}

#[cold]
#[inline(never)]
fn four_fifths_pow(dt: f64) -> f64 {
    0.8f64.powf(dt)
}

impl Default for Lc2013 {
    fn default() -> Self {
        Lc2013::new(Lc2013Params::default())
    }
}

/// What one side's evaluation sees besides the memory.
struct SideView<'s, 'a> {
    s: &'s Surroundings<'a>,
    side: Side,
    lane: &'s super::NeighbourLane<'a>,
    safety_factor: f64,
    /// The side's gap-check bits ([`check_gaps`]), computed at the first read.
    blocked: std::cell::Cell<Option<u32>>,
}

impl SideView<'_, '_> {
    /// The side's gap-check bits.
    fn blocked(&self) -> u32 {
        if let Some(b) = self.blocked.get() {
            return b;
        }
        let b = check_gaps(&self.s.ego, self.side, self.lane, self.safety_factor);
        self.blocked.set(Some(b));
        b
    }
}

impl Lc2013 {
    pub fn new(params: Lc2013Params) -> Self {
        // SUMO 1.8 guards the division with NUMERICAL_EPS
        let change_prob_threshold_right =
            (0.2 / params.speed_gain_right) / max2(NUMERICAL_EPS, params.speed_gain);
        let change_prob_threshold_left = 0.2 / max2(NUMERICAL_EPS, params.speed_gain);
        Lc2013 {
            params,
            change_prob_threshold_right,
            change_prob_threshold_left,
            safety_factor: 1.0 / params.assertive,
            decay: StepDecay::new(0.0),
        }
    }

    /// The model for a simulation that steps `dt` seconds (the decay factors computed once).
    pub fn for_step(mut self, dt: f64) -> Self {
        self.decay = StepDecay::new(dt);
        self
    }

    /// `pow(0.5, dt)`.
    fn half_pow(&self, dt: f64) -> f64 {
        if dt == self.decay.dt {
            self.decay.half
        } else {
            half_pow(dt)
        }
    }

    /// `pow(0.8, dt)`.
    fn four_fifths_pow(&self, dt: f64) -> f64 {
        if dt == self.decay.dt {
            self.decay.four_fifths
        } else {
            four_fifths_pow(dt)
        }
    }

    /// SUMO's `getSafetyFactor`.
    pub fn safety_factor(&self) -> f64 {
        self.safety_factor
    }

    /// One vehicle's turn in the lane-change pass (SUMO's `MSLaneChanger::change` with this model): the right
    /// side first, then the left; the first wish that is not blocked is done. Updates the memory (a change
    /// resets it, as SUMO's `changed`).
    // inlined into the pass's turn (its one caller): the decision's fields are then written in place
    #[inline]
    pub fn decide(&self, mem: &mut Lc2013Memory, s: &Surroundings) -> Decision {
        let mut d = Decision::default();
        // the own lane's anticipated speed, by whether a leader accelerates: both sides read it alike
        let mut own_lane_vsafe = [None; 2];
        // Each side's gap check is done when its bits can be read: for an urgent wish (which informs the
        // blockers), for any wish (the change), and, once either side wishes, for both (the state the next step's
        // speed reads beside the wish; others read only wish bits). Without a wish nobody reads them: most
        // vehicles skip both checks.
        let gaps = |side: Side| {
            let lane = match side {
                Side::Right => s.right.as_ref(),
                Side::Left => s.left.as_ref(),
            };
            lane.map_or(0, |lane| {
                check_gaps(&s.ego, side, lane, self.safety_factor())
            })
        };
        let mut checked = [false; 2];
        for side in [Side::Right, Side::Left] {
            let lane = match side {
                Side::Right => s.right.as_ref(),
                Side::Left => s.left.as_ref(),
            };
            let Some(lane) = lane else { continue };
            let view = SideView {
                s,
                side,
                lane,
                safety_factor: self.safety_factor(),
                blocked: std::cell::Cell::new(None),
            };
            let wish_state = self.wants_change(mem, &view, &mut own_lane_vsafe, &mut d.messages);
            let state = if wish_state & lca::WANTS_LANECHANGE != 0 || view.blocked.get().is_some() {
                checked[side as usize] = true;
                wish_state | view.blocked()
            } else {
                wish_state
            };
            match side {
                Side::Right => d.state_right = state,
                Side::Left => d.state_left = state,
            }
            if state & side.wish() != 0 && state & lca::BLOCKED == 0 {
                if !checked[Side::Right as usize] {
                    d.state_right |= gaps(Side::Right);
                }
                mem.own_state = state;
                d.change = Some(side);
                d.reason = Reason::of_state(state);
                let target = (s.ego.lane_index as i64 + side.offset() as i64) as usize;
                mem.changed(s.best_lanes[target].best_lane_offset);
                return d;
            }
            if state & side.wish() != 0 && state & lca::URGENT != 0 {
                d.urgent_blocked.push(side);
            }
        }
        if (d.state_right | d.state_left) & lca::WANTS_LANECHANGE != 0 {
            if !checked[Side::Right as usize] {
                d.state_right |= gaps(Side::Right);
            }
            if !checked[Side::Left as usize] {
                d.state_left |= gaps(Side::Left);
            }
        }
        debug_assert!({
            let gap_bits = lca::BLOCKED_LEFT | lca::BLOCKED_RIGHT | lca::OVERLAPPING;
            (d.state_right | d.state_left) & lca::WANTS_LANECHANGE == 0
                || (d.state_right & gap_bits == gaps(Side::Right)
                    && d.state_left & gap_bits == gaps(Side::Left))
        });
        if d.state_right & lca::URGENT != 0 && d.state_left & lca::URGENT != 0 {
            // wants both ways: the right wins
            d.state_left = 0;
        }
        mem.own_state = d.state_right | d.state_left;
        d.reason = if d.state_right & lca::RIGHT != 0 {
            Reason::of_state(d.state_right)
        } else if d.state_left & lca::LEFT != 0 {
            Reason::of_state(d.state_left)
        } else {
            None
        };
        d
    }

    /// SUMO's `_wantsChange` for one side: the wish and its reason (or a reason to stay), plus the messages
    /// and speed advices of an urgent change.
    // out of line: inlined into `decide`, the work of both sides was hoisted and done for every vehicle, most of
    // which have a lane on one side only
    #[inline(never)]
    fn wants_change(
        &self,
        mem: &mut Lc2013Memory,
        v: &SideView,
        own_lane_vsafe: &mut [Option<f64>; 2],
        msgs: &mut Vec<Message>,
    ) -> u32 {
        let s = v.s;
        let ego = &s.ego;
        let dt = ego.params.dt;
        let offset = v.side.offset();
        let right = v.side == Side::Right;
        let idx = ego.lane_index;
        let neigh_idx = (idx as i64 + offset as i64) as usize;
        let curr: &LaneQ = &s.best_lanes[idx];
        let neigh: &LaneQ = &s.best_lanes[neigh_idx];
        let mut current_dist = curr.length;
        let neigh_dist = neigh.length;
        let mut best_lane_offset = curr.best_lane_offset;
        if best_lane_offset == 0 && neigh.best_lane_offset == 0 {
            // both lanes are as good: treat the side looked at as the best
            best_lane_offset = offset;
        }
        let best = &s.best_lanes[(idx as i64 + best_lane_offset as i64) as usize];
        let pos = ego.pos;
        let wish = v.side.wish();
        let my_dir = v.side.message_dir();
        let counter_wish = v.side.opposite().wish();
        let change_to_best = (right && best_lane_offset < 0) || (!right && best_lane_offset > 0);
        let neigh_lead = v.lane.leader.as_ref();
        // the stop speed behind the neighbour leader, asked by the overtaking check and the lane's anticipated speed
        let neigh_share = &mut StopShare::default();
        let leader = s.leader.as_ref();

        let mut ret = mem.own_state & lca::KEPT_MARKS;
        ret = self.slow_down_for_blocked(mem, ego, s.blocked_ahead.last.as_ref(), ret);
        if let Some(first) = &s.blocked_ahead.first {
            ret = self.slow_down_for_blocked(mem, ego, Some(first), ret);
        }

        // the look-ahead speed follows increases at once and decreases slowly
        if ego.speed > mem.look_ahead_speed {
            mem.look_ahead_speed = ego.speed;
        } else {
            let memory_factor = 1.0 - (1.0 - LOOK_AHEAD_SPEED_MEMORY) * dt;
            mem.look_ahead_speed = max2(
                LOOK_AHEAD_MIN_SPEED,
                memory_factor * mem.look_ahead_speed + (1.0 - memory_factor) * ego.speed,
            );
        }
        let mut la_dist = mem.look_ahead_speed
            * LOOK_FORWARD
            * self.params.strategic
            * if right {
                1.0
            } else {
                self.params.lookahead_left
            };
        la_dist += ego.length_with_gap() * 2.0;
        if let Some(l) =
            leader.filter(|l| best_lane_offset == 0 && l.stopped && l.gap < current_dist - pos)
        {
            // halved: the change there and back is checked against twice the distance
            la_dist = 0.5 * (ego.length_with_gap() + l.length_with_gap() + l.gap);
        } else if let Some(nl) = neigh_lead
            .filter(|nl| best_lane_offset == offset && nl.stopped && nl.gap < current_dist - pos)
        {
            la_dist = ego.length_with_gap() + nl.length_with_gap() + nl.gap;
        }
        if self.params.strategic < 0.0 {
            la_dist = -1e3;
        }

        let usable_dist = current_dist - pos - best.occupation * JAM_FACTOR;
        let max_jam = max2(neigh.occupation, curr.occupation);
        let neigh_left_place = max2(0.0, neigh_dist - pos - max_jam);
        let v_max = ego.max_speed;
        let mut this_lane_vsafe = v_max;
        let check_overtake_right = !self.params.allow_overtaking_right && !congested(ego.speed);

        let mut change_left_to_avoid_overtake_right = false;
        if change_to_best
            && best_lane_offset == curr.best_lane_offset
            && current_dist_disallows(usable_dist, best_lane_offset, la_dist)
        {
            ret |= wish | lca::STRATEGIC | lca::URGENT;
        } else {
            if let Some(nl) = neigh_lead.filter(|_| check_overtake_right && !right) {
                // a slower leader on the left is not overtaken on the right: follow it, or move left
                let delta_v = max2(v_max - nl.max_speed, ego.speed - nl.speed);
                if delta_v > 0.0 {
                    let p = &ego.params;
                    let v_max_decel = max2(0.0, ego.speed - p.decel * dt);
                    let v_safe_follow = p.follow_speed_sharing(
                        neigh_share,
                        true,
                        nl.gap,
                        ego.speed,
                        nl.speed,
                        v_max,
                    );
                    let v_stay_behind = nl.speed - HELP_OVERTAKE;
                    let mut v_safe = if v_safe_follow >= v_max_decel {
                        v_safe_follow
                    } else {
                        max2(v_max_decel, v_stay_behind)
                    };
                    if mem.speed_gain_probability < self.change_prob_threshold_left {
                        v_safe = max2(v_safe, nl.speed);
                    }
                    this_lane_vsafe = min2(this_lane_vsafe, v_safe);
                    mem.add_speed_advice(v_safe, ego.speed, dt);
                    // the wish to go left only grows shortly before braking would be needed
                    let delta_gap_future = delta_v * 8.0;
                    let v_safe_future =
                        p.follow_speed_lc(nl.gap - delta_gap_future, ego.speed, nl.speed, v_max);
                    if v_safe_future < v_safe {
                        let relative_gain = delta_v / max2(v_max, RELGAIN_NORMALIZATION_MIN_SPEED);
                        mem.speed_gain_probability += dt * relative_gain;
                        change_left_to_avoid_overtake_right = true;
                    }
                }
            }
            let overtake_dist = leader.map_or(-1.0, |l| l.gap + ego.length + l.length_with_gap());
            let overtake_stopped = leader.is_some_and(|l| {
                l.stopped
                    && l.gap < REACT_TO_STOPPED_DISTANCE
                    && min2(neigh_dist, current_dist) - pos > overtake_dist
                    && (!check_overtake_right || !right)
                    && neigh_lead.is_none_or(|nl| !nl.stopped || nl.gap > overtake_dist)
            });
            if overtake_stopped {
                // not to get stuck behind a stopped leader
                current_dist = pos + leader.map_or(0.0, |l| l.gap);
                ret |= wish | lca::STRATEGIC | lca::URGENT;
            } else if !change_to_best
                && current_dist_disallows(neigh_left_place, best_lane_offset.abs() + 2, la_dist)
            {
                // away from the best lane, and no time to come back
                ret |= lca::STAY | lca::STRATEGIC;
            } else if best_lane_offset == 0 && neigh_left_place * 2.0 < la_dist {
                // on the best lane close to where the neighbour lane ends
                ret |= lca::STAY | lca::STRATEGIC;
            } else if best_lane_offset == 0
                && leader.is_none_or(|l| !l.stopped)
                && neigh.leads_elsewhere
                && neigh_dist < TURN_LANE_DIST
            {
                // do not leave the best lane for a lane that turns off soon
                ret |= lca::STAY | lca::STRATEGIC;
            }
        }
        if ret & lca::STAY != 0 {
            return ret;
        }
        if ret & lca::URGENT != 0 {
            mem.left_space = current_dist - pos;
            if change_to_best && best_lane_offset.abs() > 1 {
                // a vehicle changing the other way one lane further may be hidden
                mem.leading_blocker_length =
                    max2(if right { 20.0 } else { 40.0 }, mem.leading_blocker_length);
            }
            // let a neighbour that must change the other way merge in before the end of the lane
            self.save_blocker_length(mem, ego, neigh_lead, counter_wish, msgs);
            if let Some(first) = &s.blocked_ahead.first_or_last()
                && neigh_lead.is_none_or(|nl| nl.id != first.id)
            {
                self.save_blocker_length(mem, ego, Some(first), counter_wish, msgs);
            }
            let remaining_lanes = best_lane_offset.abs().max(1) as f64;
            // SUMO bounds this by STEPS2TIME(TS), a thousandth of the step (TS is already in seconds): kept
            let remaining_seconds = max2(
                dt / 1000.0,
                mem.left_space
                    / max2(mem.look_ahead_speed, NUMERICAL_EPS)
                    / remaining_lanes
                    / URGENCY,
            );
            let planned_speed = self.inform_leader(
                mem,
                ego,
                v.blocked(),
                my_dir,
                neigh_lead,
                remaining_seconds,
                msgs,
            );
            if planned_speed >= 0.0 {
                self.inform_follower(
                    mem,
                    ego,
                    v.blocked(),
                    my_dir,
                    v.lane.follower.as_ref(),
                    remaining_seconds,
                    planned_speed,
                    msgs,
                );
            }
            return ret;
        }

        // a high speed gain the other way prevents cooperative changes
        let inconvenience = min2(
            1.0,
            if offset < 0 {
                mem.speed_gain_probability / self.change_prob_threshold_right
            } else {
                -mem.speed_gain_probability / self.change_prob_threshold_left
            },
        );
        let speed_gain_inconvenient = inconvenience > self.params.cooperative;

        if right
            && best_lane_offset == 0
            && ego.lane_speed_limit > 80.0 / 3.6
            && mem.look_ahead_speed > HALTING_SPEED
        {
            // on a highway, do not get stranded on an ending on-ramp lane
            return ret | lca::STAY | lca::STRATEGIC;
        }

        if mem.own_state & (lca::AMBLOCKINGFOLLOWER | lca::AMBLOCKINGFOLLOWER_DONTBRAKE) != 0
            && !speed_gain_inconvenient
            && mem.own_state & my_dir != 0
            && (change_to_best
                || current_dist_allows(neigh_dist, best_lane_offset.abs() + 1, la_dist))
        {
            // make room for the vehicle that must enter this lane, moving the way it moves
            return ret | wish | lca::COOPERATIVE | lca::URGENT;
        }

        // anticipated speeds; with an accelerating leader, compare the speeds one second ahead
        let accelerating_leader = neigh_lead.is_some_and(|l| l.accelerates(dt))
            || leader.is_some_and(|l| l.accelerates(dt));
        let neigh_lane_vsafe = anticipate_follow_speed(
            ego,
            neigh_lead,
            neigh_dist,
            v_max,
            accelerating_leader,
            Some(neigh_share),
        );
        // (`current_dist` is the lane's best length here on both sides: only a stopped leader's overtaking
        // shortens it, and that returns above)
        let share = &mut mem.stop_share;
        let own = *own_lane_vsafe[accelerating_leader as usize].get_or_insert_with(|| {
            anticipate_follow_speed(
                ego,
                leader,
                current_dist,
                v_max,
                accelerating_leader,
                Some(share),
            )
        });
        debug_assert_eq!(
            own.to_bits(),
            anticipate_follow_speed(ego, leader, current_dist, v_max, accelerating_leader, None)
                .to_bits()
        );
        this_lane_vsafe = min2(this_lane_vsafe, own);
        let relative_gain = (neigh_lane_vsafe - this_lane_vsafe)
            / max2(neigh_lane_vsafe, RELGAIN_NORMALIZATION_MIN_SPEED);

        if right {
            if this_lane_vsafe - 5.0 / 3.6 > neigh_lane_vsafe {
                // the current lane is clearly faster than the right one
                if mem.speed_gain_probability < 0.0 {
                    mem.speed_gain_probability *= self.half_pow(dt);
                }
            } else {
                if mem.speed_gain_probability < 0.0 || relative_gain > 0.0 {
                    mem.speed_gain_probability -= dt * relative_gain;
                }
                if let Some(req) = self.keep_right(
                    mem,
                    ego,
                    neigh_lead,
                    leader,
                    neigh_dist,
                    check_overtake_right,
                ) {
                    return ret | wish | req;
                }
            }
            if mem.speed_gain_probability < -self.change_prob_threshold_right
                && neigh_dist / max2(0.1, ego.speed) > 20.0
            {
                return ret | wish | lca::SPEEDGAIN;
            }
        } else {
            if this_lane_vsafe > neigh_lane_vsafe {
                if mem.speed_gain_probability > 0.0 {
                    mem.speed_gain_probability *= self.half_pow(dt);
                }
            } else if this_lane_vsafe == neigh_lane_vsafe {
                if mem.speed_gain_probability > 0.0 {
                    mem.speed_gain_probability *= self.four_fifths_pow(dt);
                }
            } else {
                mem.speed_gain_probability += dt * relative_gain;
            }
            if mem.speed_gain_probability > self.change_prob_threshold_left
                && (relative_gain > NUMERICAL_EPS || change_left_to_avoid_overtake_right)
                && neigh_dist / max2(0.1, ego.speed) > 20.0
            {
                return ret | wish | lca::SPEEDGAIN;
            }
        }
        if change_to_best
            && best_lane_offset == curr.best_lane_offset
            && relative_gain >= 0.0
            && if right {
                mem.speed_gain_probability < 0.0
            } else {
                mem.speed_gain_probability > 0.0
            }
        {
            // towards the best lane when that costs no speed
            return ret | wish | lca::STRATEGIC;
        }
        ret
    }

    /// The keep-right motivation (only evaluated when the right lane is about as fast); `Some(LCA_KEEPRIGHT)`
    /// once the summed wish passes the right threshold.
    fn keep_right(
        &self,
        mem: &mut Lc2013Memory,
        ego: &Ego,
        neigh_lead: Option<&Other>,
        leader: Option<&Other>,
        neigh_dist: f64,
        check_overtake_right: bool,
    ) -> Option<u32> {
        let dt = ego.params.dt;
        let v_max = ego.max_speed;
        let p = &ego.params;
        let acceptance_time =
            KEEP_RIGHT_ACCEPTANCE * v_max * max2(1.0, ego.speed) / ego.lane_speed_limit;
        let mut full_speed_gap = max2(0.0, neigh_dist - p.brake_gap(v_max, p.decel, p.tau));
        let mut full_speed_driving_seconds = min2(acceptance_time, full_speed_gap / v_max);
        if let Some(nl) = neigh_lead.filter(|nl| nl.speed < v_max) {
            full_speed_gap = max2(
                0.0,
                min2(full_speed_gap, nl.gap - p.secure_gap(v_max, nl.speed)),
            );
            full_speed_driving_seconds = min2(
                full_speed_driving_seconds,
                full_speed_gap / (v_max - nl.speed),
            );
        }
        // stay if a slow leader could not be overtaken on the right
        if let Some(l) = leader.filter(|l| check_overtake_right && l.max_speed < v_max) {
            full_speed_gap = min2(full_speed_gap, l.gap);
            full_speed_driving_seconds = min2(
                full_speed_driving_seconds,
                full_speed_gap / (v_max - l.speed),
            );
            // tie breaker (SUMO's #1312)
            let relative_gain =
                (v_max - l.max_speed) / max2(v_max, RELGAIN_NORMALIZATION_MIN_SPEED);
            mem.speed_gain_probability += dt * relative_gain;
        }
        let delta_prob = self.change_prob_threshold_right
            * (full_speed_driving_seconds / acceptance_time)
            / KEEP_RIGHT_TIME;
        mem.keep_right_probability -= dt * delta_prob;
        (mem.keep_right_probability * self.params.keep_right < -self.change_prob_threshold_right)
            .then_some(lca::KEEPRIGHT)
    }
}

impl<'a> BlockedAhead<'a> {
    /// SUMO's `firstBlocked`, which is `lastBlocked` when only one was recorded.
    fn first_or_last(&self) -> Option<Other<'a>> {
        self.first.or(self.last)
    }
}

/// SUMO's `MSVehicle::congested`.
fn congested(speed: f64) -> bool {
    speed < CONGESTED_SPEED
}

/// SUMO's `currentDistDisallows`: the distance per lane to cross is below the look-ahead.
fn current_dist_disallows(dist: f64, lanes: i32, look_ahead: f64) -> bool {
    dist / (lanes.abs() as f64) < look_ahead
}

/// SUMO's `currentDistAllows`.
fn current_dist_allows(dist: f64, lanes: i32, look_ahead: f64) -> bool {
    dist / (lanes.abs() as f64) > look_ahead
}

impl super::LaneChangeModel for Lc2013 {
    type Memory = Lc2013Memory;

    #[inline]
    fn prepare_step(&self, mem: &mut Lc2013Memory) {
        mem.prepare_step();
    }

    #[inline]
    fn decide(&self, mem: &mut Lc2013Memory, s: &Surroundings) -> Decision {
        Lc2013::decide(self, mem, s)
    }

    /// Advices are read with the step this model was made for ([`Lc2013::for_step`]).
    #[inline]
    fn receive(&self, mem: &mut Lc2013Memory, message: &Message, own_speed: f64) {
        match *message {
            Message::SpeedAdvice { speed, state, .. } => {
                mem.inform(speed, state, own_speed, self.decay.dt)
            }
            Message::KeepRoom { length, .. } => mem.keep_room(length),
        }
    }

    #[inline]
    fn patch_speed(
        &self,
        mem: &mut Lc2013Memory,
        speed: f64,
        params: &CfModel,
        desired_speed: f64,
        road_has_lane_changer: bool,
        best_lane_offset: i32,
        min: f64,
        wanted: f64,
        max: f64,
    ) -> f64 {
        mem.patch_speed(
            self,
            speed,
            params,
            desired_speed,
            road_has_lane_changer,
            best_lane_offset,
            min,
            wanted,
            max,
        )
    }

    #[inline]
    fn state(&self, mem: &Lc2013Memory) -> u32 {
        mem.own_state
    }
}
