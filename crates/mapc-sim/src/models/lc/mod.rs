//! Lane-change models, after SUMO's `src/microsim/lcmodels/`: one model per file behind a small interface.
//!
//! Glossary:
//! - **state bits** ([`lca`]): SUMO's `LaneChangeAction` flags with SUMO's values, so a state can be compared with
//!   SUMO's `getLaneChangeState` output: the wish (left / right / stay), its reason (strategic, cooperative, speed
//!   gain, keep right), urgency, what blocks it, and the marks other vehicles leave (blocking leader / follower).
//! - **best lanes** ([`LaneQ`]): per lane of the current road, how far the route can be driven on it and its
//!   continuations before a lane change is needed (SUMO's `MSVehicle::LaneQ`), the vehicles' length on them
//!   (occupation) and the offset to the road's best lane (`bestLaneOffset`).
//! - **gap**: bumper to bumper minus the follower's minimum gap (SUMO's convention): a leader's gap is its back
//!   minus the ego's front minus the ego's min gap; a follower's gap is the ego's back minus the follower's front
//!   minus the follower's min gap. Negative means overlapping.
//! - **speed advice**: a speed a model asks its own vehicle to drive in the next step (SUMO's
//!   `addLCSpeedAdvice`), stored as an acceleration and applied by [`lc2013::Lc2013Memory::patch_speed`].
//! - **message**: a speed advice and state bits sent to a neighbour (SUMO's `informNeighLeader` /
//!   `informNeighFollower` through the `MSLCMessager`), or a request to keep room for the sender
//!   (`saveBlockerLength`).
//!
//! How a simulator drives a model each step (SUMO 1.8's order, with `lanechange.duration` 0: a change is
//! done in one step):
//! 1. Move: each vehicle's speed passes through `patch_speed(min, wanted, max)` (SUMO's `MSCFModel::finalizeSpeed`
//!    calls `patchSpeed` after the car-following speed), then the vehicle moves, then `prepare_step()`.
//! 2. Change lanes, road by road: vehicles are visited front to back across all the road's lanes (SUMO's
//!    `MSLaneChanger::findCandidate`: the largest position first). For each, the simulator builds
//!    [`Surroundings`] and calls `decide`; it delivers the returned [`Message`]s at once (vehicles behind read
//!    them in the same pass, vehicles ahead in their next `patch_speed`), moves the vehicle if the decision says
//!    so, and records an urgent blocked wish on the target lane (`Decision::urgent_blocked`, SUMO's
//!    `lastBlocked` / `firstBlocked` of that lane) for the vehicles visited after it.

pub mod lc2013;
pub mod safety;

pub use lc2013::{Lc2013, Lc2013Memory, Lc2013Params};

use crate::models::cf::CfModel;

/// What the simulator asks of a lane-change model (the part of SUMO's `MSAbstractLaneChangeModel` mapc uses), in
/// the order of the module docs: prepare each vehicle's memory after the move, decide vehicle by vehicle,
/// deliver the messages, and patch each next speed in the following move.
pub trait LaneChangeModel {
    /// A vehicle's own record between steps (advices received, probabilities, state bits).
    type Memory: Default + Clone + std::fmt::Debug;

    /// After the moves, before any message of the pass: forget the last step's advices and marks.
    fn prepare_step(&self, mem: &mut Self::Memory);

    /// One vehicle's decision in the pass, updating its memory.
    fn decide(&self, mem: &mut Self::Memory, s: &Surroundings) -> Decision;

    /// Deliver a message another vehicle's decision sent to this one (`own_speed`: its speed now).
    fn receive(&self, mem: &mut Self::Memory, message: &Message, own_speed: f64);

    /// The speed for the next step between the car-following bounds `min` and `max`, `wanted` being the
    /// car-following speed (SUMO's `patchSpeed`); `desired_speed` is the vehicle's highest speed on its lane,
    /// `best_lane_offset` that of its lane.
    #[allow(clippy::too_many_arguments)]
    fn patch_speed(
        &self,
        mem: &mut Self::Memory,
        speed: f64,
        params: &CfModel,
        desired_speed: f64,
        road_has_lane_changer: bool,
        best_lane_offset: i32,
        min: f64,
        wanted: f64,
        max: f64,
    ) -> f64;

    /// The vehicle's state bits (SUMO's `getLaneChangeState` of its own lane).
    fn state(&self, mem: &Self::Memory) -> u32;
}

/// SUMO's `LaneChangeAction` bits (`SUMOVehicleClass.h`), with SUMO's values.
pub mod lca {
    pub const STAY: u32 = 1;
    pub const LEFT: u32 = 1 << 1;
    pub const RIGHT: u32 = 1 << 2;
    pub const STRATEGIC: u32 = 1 << 3;
    pub const COOPERATIVE: u32 = 1 << 4;
    pub const SPEEDGAIN: u32 = 1 << 5;
    pub const KEEPRIGHT: u32 = 1 << 6;
    pub const TRACI: u32 = 1 << 7;
    pub const URGENT: u32 = 1 << 8;
    pub const BLOCKED_BY_LEFT_LEADER: u32 = 1 << 9;
    pub const BLOCKED_BY_LEFT_FOLLOWER: u32 = 1 << 10;
    pub const BLOCKED_BY_RIGHT_LEADER: u32 = 1 << 11;
    pub const BLOCKED_BY_RIGHT_FOLLOWER: u32 = 1 << 12;
    pub const OVERLAPPING: u32 = 1 << 13;
    pub const INSUFFICIENT_SPACE: u32 = 1 << 14;
    pub const SUBLANE: u32 = 1 << 15;
    pub const AMBLOCKINGLEADER: u32 = 1 << 16;
    pub const AMBLOCKINGFOLLOWER: u32 = 1 << 17;
    /// The sender of a message wants to move right (set in messages, read by the receiver).
    pub const MRIGHT: u32 = 1 << 18;
    /// The sender of a message wants to move left.
    pub const MLEFT: u32 = 1 << 19;
    pub const AMBLOCKINGFOLLOWER_DONTBRAKE: u32 = 1 << 21;
    pub const CHANGE_TO_HELP: u32 = 1 << 23;
    pub const AMBACKBLOCKER: u32 = 1 << 26;
    pub const AMBACKBLOCKER_STANDING: u32 = 1 << 27;
    pub const INSUFFICIENT_SPEED: u32 = 1 << 28;

    pub const WANTS_LANECHANGE: u32 = LEFT | RIGHT;
    pub const BLOCKED_LEFT: u32 = BLOCKED_BY_LEFT_LEADER | BLOCKED_BY_LEFT_FOLLOWER;
    pub const BLOCKED_RIGHT: u32 = BLOCKED_BY_RIGHT_LEADER | BLOCKED_BY_RIGHT_FOLLOWER;
    pub const BLOCKED_BY_LEADER: u32 = BLOCKED_BY_LEFT_LEADER | BLOCKED_BY_RIGHT_LEADER;
    pub const BLOCKED_BY_FOLLOWER: u32 = BLOCKED_BY_LEFT_FOLLOWER | BLOCKED_BY_RIGHT_FOLLOWER;
    pub const BLOCKED: u32 = BLOCKED_LEFT | BLOCKED_RIGHT | INSUFFICIENT_SPACE | INSUFFICIENT_SPEED;
    /// The bits a state keeps from one wish to the next within a step (marks left by other vehicles).
    pub const KEPT_MARKS: u32 = 0xffff_0000;
}

/// A side of the ego's lane; lane indices grow to the left (lane 0 is the rightmost), as in SUMO.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Side {
    Right,
    Left,
}

impl Side {
    /// SUMO's `laneOffset`: -1 right, +1 left.
    pub fn offset(self) -> i32 {
        match self {
            Side::Right => -1,
            Side::Left => 1,
        }
    }
    /// The wish bit (`LCA_RIGHT` / `LCA_LEFT`).
    pub fn wish(self) -> u32 {
        match self {
            Side::Right => lca::RIGHT,
            Side::Left => lca::LEFT,
        }
    }
    /// The direction bit of a message (`LCA_MRIGHT` / `LCA_MLEFT`).
    pub fn message_dir(self) -> u32 {
        match self {
            Side::Right => lca::MRIGHT,
            Side::Left => lca::MLEFT,
        }
    }
    fn blocked_by_leader(self) -> u32 {
        match self {
            Side::Right => lca::BLOCKED_BY_RIGHT_LEADER,
            Side::Left => lca::BLOCKED_BY_LEFT_LEADER,
        }
    }
    fn blocked_by_follower(self) -> u32 {
        match self {
            Side::Right => lca::BLOCKED_BY_RIGHT_FOLLOWER,
            Side::Left => lca::BLOCKED_BY_LEFT_FOLLOWER,
        }
    }
    fn opposite(self) -> Side {
        match self {
            Side::Right => Side::Left,
            Side::Left => Side::Right,
        }
    }
}

/// Why a vehicle changes (or wants to change) lanes.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Reason {
    /// To stay on its route (a lane that ends or leads elsewhere).
    Strategic,
    /// To make room for a vehicle that must enter its lane.
    Cooperative,
    /// To drive faster.
    SpeedGain,
    /// The obligation to keep right.
    KeepRight,
}

impl Reason {
    /// The reason named by a state's bits (SUMO sets exactly one per wish).
    pub fn of_state(state: u32) -> Option<Reason> {
        if state & lca::STRATEGIC != 0 {
            Some(Reason::Strategic)
        } else if state & lca::COOPERATIVE != 0 {
            Some(Reason::Cooperative)
        } else if state & lca::SPEEDGAIN != 0 {
            Some(Reason::SpeedGain)
        } else if state & lca::KEEPRIGHT != 0 {
            Some(Reason::KeepRight)
        } else {
            None
        }
    }
}

/// The ego vehicle, as the lane-change model sees it after this step's move.
#[derive(Clone, Copy, Debug)]
pub struct Ego<'a> {
    pub speed: f64,
    /// Car-following parameters, borrowed from the simulator's type table; `params.dt` is the step (SUMO's
    /// `TS`, and the action step).
    pub params: &'a CfModel,
    /// Vehicle length (m); `params.min_gap` completes SUMO's `getLengthWithGap`.
    pub length: f64,
    /// Front position on its lane (m from the lane's start).
    pub pos: f64,
    /// Its lane's index on the road (0 = rightmost).
    pub lane_index: usize,
    /// Its lane's length (m); SUMO takes a lane longer than 200 m as no on-ramp when asking a follower for help.
    pub lane_length: f64,
    /// Its lane's speed limit (m/s).
    pub lane_speed_limit: f64,
    /// Its own highest speed on its lane (speed factor x limit, capped by the type's maximum; SUMO's
    /// `getVehicleMaxSpeed`), also the IDM's desired speed.
    pub max_speed: f64,
}

impl Ego<'_> {
    pub fn length_with_gap(&self) -> f64 {
        self.length + self.params.min_gap
    }
}

/// Another vehicle: a leader or follower on the ego's lane or a neighbour lane, or a blocked vehicle ahead.
#[derive(Clone, Copy, Debug)]
pub struct Other<'a> {
    /// The simulator's id for it; messages are addressed with it, and it tells vehicles apart.
    pub id: u64,
    /// Gap to the ego (see the module glossary); for a blocked vehicle ahead ([`Surroundings::blocked_ahead`]),
    /// its back minus the ego's front minus the ego's min gap.
    pub gap: f64,
    pub speed: f64,
    /// Its speed one step before: its acceleration in the last step ([`Other::accel`]) is the difference over the
    /// step, divided only where it is read.
    pub speed_before: f64,
    /// Its type's car-following parameters, borrowed from the simulator's table (copied, they cost more than the
    /// model's gap checks).
    pub params: &'a CfModel,
    pub length: f64,
    /// Its own highest speed on its lane (SUMO's `getVehicleMaxSpeed`).
    pub max_speed: f64,
    /// Halted at a scheduled stop (SUMO's `isStopped`), not merely at speed 0.
    pub stopped: bool,
    /// Its lane-change state bits as last set (SUMO's `getOwnState`).
    pub lc_state: u32,
}

impl Other<'_> {
    pub fn length_with_gap(&self) -> f64 {
        self.length + self.params.min_gap
    }

    /// Its acceleration in the last step of `dt` seconds (SUMO's `getAcceleration`).
    pub fn accel(&self, dt: f64) -> f64 {
        (self.speed - self.speed_before) / dt
    }

    /// Whether [`Self::accel`] is positive, without the division where it cannot change the answer: a positive
    /// difference divided by a step of at most a second is never rounded to zero.
    #[inline]
    pub fn accelerates(&self, dt: f64) -> bool {
        let diff = self.speed - self.speed_before;
        let positive = diff > 0.0 && (dt <= 1.0 || diff / dt > 0.0);
        debug_assert_eq!(positive, self.accel(dt) > 0.0);
        positive
    }
}

/// The neighbours on a lane next to the ego's: the nearest vehicle whose front is ahead of the ego's front and
/// the nearest at or behind it, which may drive alongside with a negative gap (SUMO's `getRealLeader` /
/// `getRealFollower`: the lane changer's last vehicle visited on that lane and its next; across the lane's end
/// only within the ego's braking distance; a vehicle that would be both is only the leader).
#[derive(Clone, Copy, Debug, Default)]
pub struct NeighbourLane<'a> {
    pub leader: Option<Other<'a>>,
    pub follower: Option<Other<'a>>,
}

/// One lane of the ego's road as the route sees it (SUMO's `MSVehicle::LaneQ`, from `updateBestLanes`, which
/// looks ahead at least 4 roads and 3000 m, or the brake distance at full speed).
#[derive(Clone, Copy, Debug)]
pub struct LaneQ {
    /// Distance (m) from this lane's start that the route can be followed on it and its best continuations
    /// without a lane change (SUMO's `length`).
    pub length: f64,
    /// Summed length with min gap (m) of the vehicles on its best continuations after this road
    /// (`nextOccupation`) plus those on this lane already visited in this step's pass, i.e. ahead of the ego or
    /// changed onto it (the lane changer's `dens`; SUMO's `occupation` = `dens + nextOccupation`).
    pub occupation: f64,
    /// Lanes to move (negative: right) to reach the road's best lane (`bestLaneOffset`).
    pub best_lane_offset: i32,
    /// The last lane of its best continuation has outgoing links: it is no dead end, so with a short `length` it
    /// is a lane that turns off the route (SUMO: `bestContinuations.back()->getLinkCont().size() != 0`).
    pub leads_elsewhere: bool,
}

/// What the model is given for one vehicle in the lane-change pass.
#[derive(Clone, Debug)]
pub struct Surroundings<'a> {
    pub ego: Ego<'a>,
    /// The leader on the ego's lane (across its end).
    pub leader: Option<Other<'a>>,
    /// The lane to the right, if it exists and the vehicle may use it (SUMO's `mayChange(-1)`).
    pub right: Option<NeighbourLane<'a>>,
    /// The lane to the left, if it exists and the vehicle may use it.
    pub left: Option<NeighbourLane<'a>>,
    /// One entry per lane of the road, by lane index.
    pub best_lanes: &'a [LaneQ],
    /// Vehicles ahead on a neighbour lane that urgently want into the ego's lane but were blocked, as recorded
    /// in this pass: the last recorded and the first (SUMO's `lastBlocked`, `firstBlocked`; `first` only when it
    /// is another vehicle than `last`).
    pub blocked_ahead: BlockedAhead<'a>,
    /// The road has more than one lane (SUMO's `hasLaneChanger`); on single-lane roads the memory is cleared.
    pub road_has_lane_changer: bool,
}

/// See [`Surroundings::blocked_ahead`].
#[derive(Clone, Copy, Debug, Default)]
pub struct BlockedAhead<'a> {
    pub last: Option<Other<'a>>,
    pub first: Option<Other<'a>>,
}

/// Something a model asks of another vehicle.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Message {
    /// Drive at most `speed` in the next step (when it lies between that vehicle's bounds), and add `state` to its
    /// state bits (SUMO's `inform`); a speed of `f64::MAX` only sets the bits.
    SpeedAdvice { to: u64, speed: f64, state: u32 },
    /// Keep `length` metres free before the end of the lane for the sender (SUMO's `saveBlockerLength`).
    KeepRoom { to: u64, length: f64 },
}

/// The outcome of one vehicle's lane-change pass.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Decision {
    /// The lane change to do now (already safe), if any.
    pub change: Option<Side>,
    /// The reason of the change, or of the wish when none is done.
    pub reason: Option<Reason>,
    /// Its state towards each side (SUMO's `checkChange` result: wish, reason and blocked bits); 0 where no lane.
    /// The gap checks' bits are there once either side wishes to change (only then are they read: the next
    /// step's speed reads them beside a wish, the others read only the wish bits).
    pub state_right: u32,
    pub state_left: u32,
    /// An urgent wish towards this side was blocked: the simulator records the vehicle as that lane's
    /// `lastBlocked` (and `firstBlocked` when none yet) for the vehicles visited after it.
    pub urgent_blocked: Vec<Side>,
    /// To deliver at once.
    pub messages: Vec<Message>,
}
