//! Room beyond a junction (SUMO 1.8's `MSVehicle::checkRewindLinkLanes`, under SUMO's rules): a driver does not
//! enter a junction whose links have foes unless the lanes after it hold room for it up to the first vehicle
//! that stands (or waits at its own next link); it stops before the junction instead, and its request there is
//! withdrawn, so that it never blocks the crossing streams from inside. Without it, the queues of a congested
//! city network ran into its junctions and locked them (RESCO's cologne3, docs/sumo_scenarios.md).
//!
//! The plan records the junctions it crosses in its look-ahead ([`Crossing`]); this module walks them as SUMO
//! walks its drive items: each junction as its entry (onto the connection) and its exit (onto the lane after).

use super::*;
use crate::network::signals::SignalState;

/// Junctions recorded per plan (farther ones are not looked at).
pub(in crate::sim) const MAX_CROSSINGS: usize = 4;

/// Where SUMO stops before a link it has priority at (`DIST_TO_STOPLINE_EXPECT_PRIORITY`, m).
const PRIORITY_STOP_OFFSET_M: f64 = 1.0;

/// A junction crossed in a plan's look-ahead.
#[derive(Clone, Copy, Debug, Default)]
pub(in crate::sim) struct Crossing {
    pub(in crate::sim) link: LinkIdx,
    /// Distance from the vehicle's front to the link's stop line (negative: already on the connection, only its
    /// exit is ahead).
    pub(in crate::sim) dist: f64,
    /// The plan's speed at the link (SUMO's `myVLinkPass` there).
    pub(in crate::sim) v_pass: f64,
    /// The link's request in the plan's items, if it made one.
    pub(in crate::sim) item: Option<u8>,
    /// The vehicle is on the connection already: only the exit is ahead.
    pub(in crate::sim) exit_only: bool,
}

/// One of SUMO's drive items: a junction's entry or exit, or the end of the look-ahead.
#[derive(Clone, Copy, Debug)]
struct Part {
    crossing: Option<usize>,
    exit: bool,
    available: f64,
    had_stopped: bool,
    request: bool,
}

/// A lane as the room check reads it, kept for one step (planning moves nobody): its vehicles' lengths with min
/// gaps summed front first, and SUMO's room till its last standing vehicle. Every driver near a junction reads
/// the same few lanes; summed for each of them, a congested run spent a sixth of its time here.
#[derive(Clone, Debug, Default)]
pub(in crate::sim) struct LaneRoom {
    /// The step it is of, plus one (0: none yet).
    step: u64,
    /// `prefix[k]`: the first `k` vehicles' lengths with min gaps, summed in queue order as `Iterator::sum` sums.
    prefix: Vec<f64>,
    /// [`Simulation::space_till_last_standing`] for a driver not on the lane, and whether a vehicle stands there.
    room: f64,
    stopped: bool,
}

impl Simulation {
    /// The lane's [`LaneRoom`] of this step, computed on its first read.
    fn lane_room(&mut self, lane: LaneIdx) -> &LaneRoom {
        let tag = self.step + 1;
        if self.lane_room.len() < self.net.lanes.len() {
            self.lane_room
                .resize(self.net.lanes.len(), LaneRoom::default());
        }
        if self.lane_room[lane as usize].step != tag {
            let mut memo = std::mem::take(&mut self.lane_room[lane as usize]);
            memo.prefix.clear();
            // (the start `Iterator::sum` folds from, so that every prefix has its bits)
            let mut acc: f64 = std::iter::empty::<f64>().sum();
            memo.prefix.push(acc);
            for &o in self.lane_veh[lane as usize].iter() {
                acc += self.brutto_length(o);
                memo.prefix.push(acc);
            }
            let mut stopped = false;
            memo.room = self.space_till_last_standing(VehicleId::MAX, lane, &mut stopped);
            memo.stopped = stopped;
            memo.step = tag;
            self.lane_room[lane as usize] = memo;
        }
        &self.lane_room[lane as usize]
    }

    /// Under SUMO's rules, whether the junction of `link` has links with foes (SUMO's `keepClear`: a driver does
    /// not enter it without room beyond).
    #[inline]
    pub(in crate::sim) fn keeps_clear(&self, link: LinkIdx) -> bool {
        self.link_keeps_clear[link as usize]
    }

    /// SUMO's `checkRewindLinkLanes` for vehicle `id` (at queue index `qi` of its lane) and its plan: where the
    /// room beyond a junction it would enter is shorter than the vehicle, the requests from there on are
    /// withdrawn (`will_pass` false) and the plan holds the driver before the first of them
    /// (`Plan::hold_dist`, `Plan::hold_speed`).
    pub(in crate::sim) fn check_room_beyond(&mut self, id: VehicleId, qi: usize, plan: &mut Plan) {
        let n = plan.n_crossings as usize;
        if !plan.crossings[..n]
            .iter()
            .any(|c| !c.exit_only && self.keeps_clear(c.link))
        {
            return;
        }
        // the lanes read below, each summed once a step
        let own_lane = self.veh[id as usize].lane;
        self.lane_room(own_lane);
        for c in &plan.crossings[..n] {
            let lk = self.link_at(c.link as usize);
            let (via, to) = (lk.via_lane, lk.to_lane);
            self.lane_room(via);
            self.lane_room(to);
        }
        // Nothing stands or waits on the lanes beyond, every request is made and no light ahead holds red: the
        // room is never short of a standing queue, and the walk below would change nothing (most drivers).
        let light_time = self.time_s - self.spec.start_time_s;
        let quiet = plan.crossings[..n].iter().all(|c| {
            let lk = self.link_at(c.link as usize);
            let clear = |lane: LaneIdx| {
                lane != own_lane
                    && !self.lane_room[lane as usize].stopped
                    && self.lane_veh[lane as usize]
                        .last()
                        .is_none_or(|&o| !self.veh[o as usize].waits_at_link)
            };
            c.v_pass > 0.0
                && clear(lk.to_lane)
                && clear(lk.via_lane)
                && !self.holds_red(c.link, light_time)
        });
        if quiet {
            return;
        }
        // (a lane the driver is on itself is read without its memo: the driver is not its own obstacle)
        let room_on = |s: &Self, lane: LaneIdx, found: &mut bool| -> f64 {
            if lane == own_lane {
                return s.space_till_last_standing(id, lane, found);
            }
            let memo = &s.lane_room[lane as usize];
            *found |= memo.stopped;
            memo.room
        };
        let v = &self.veh[id as usize];
        let p = &self.types[v.vtype as usize];
        let own_length = v.length + p.min_gap;
        let mut parts = [Part {
            crossing: None,
            exit: false,
            available: 0.0,
            had_stopped: false,
            request: false,
        }; 2 * MAX_CROSSINGS + 1];
        let mut m = 0;
        for (i, c) in plan.crossings[..n].iter().enumerate() {
            let request = c.v_pass > 0.0;
            if !c.exit_only {
                parts[m] = Part {
                    crossing: Some(i),
                    exit: false,
                    available: 0.0,
                    had_stopped: false,
                    request,
                };
                m += 1;
            }
            parts[m] = Part {
                crossing: Some(i),
                exit: true,
                available: 0.0,
                had_stopped: false,
                request,
            };
            m += 1;
        }
        // the end of the look-ahead
        m += 1;
        let parts = &mut parts[..m];

        // the room up to the first vehicle that stands, less the vehicles ahead on the own lane
        let mut seen_space = -self.lane_room[own_lane as usize].prefix[qi];
        debug_assert_eq!(
            seen_space.to_bits(),
            (-self.lane_veh[own_lane as usize].0[..qi]
                .iter()
                .map(|&o| self.brutto_length(o))
                .sum::<f64>())
            .to_bits()
        );
        let mut found_stopped = false;
        for part in parts.iter_mut() {
            let Some(ci) = part.crossing.filter(|_| !found_stopped) else {
                if found_stopped {
                    part.available = seen_space;
                } else {
                    part.available += seen_space;
                }
                part.had_stopped = found_stopped;
                continue;
            };
            let lk = self.link_at(plan.crossings[ci].link as usize);
            if !part.exit {
                if self.keeps_clear(plan.crossings[ci].link) {
                    let prefix = &self.lane_room[lk.via_lane as usize].prefix;
                    seen_space -= prefix[prefix.len() - 1];
                } else {
                    seen_space += room_on(self, lk.via_lane, &mut found_stopped);
                }
                part.available = seen_space;
                continue;
            }
            let lane = lk.to_lane;
            match self.lane_veh[lane as usize].last() {
                Some(&last) if last != id => {
                    let mut stopped = false;
                    seen_space += room_on(self, lane, &mut stopped);
                    if stopped || self.veh[last as usize].waits_at_link {
                        found_stopped = true;
                        part.had_stopped = true;
                    }
                }
                _ => {
                    if self.lane_at(lane as usize).length > v.length {
                        seen_space += self.lane_at(lane as usize).length;
                    }
                }
            }
            part.available = seen_space;
        }
        // the room carries back over the links the driver may pass
        for i in (1..m).rev() {
            let (item, next) = (parts[i - 1], parts[i]);
            let Some(ci) = item.crossing else { continue };
            let can_leave = item.exit || next.crossing.is_none() || next.request;
            let opened = can_leave
                && (item.exit
                    || i == 1
                    || self.has_priority(plan.crossings[ci].link, light_time)
                    || !self.holds_red(plan.crossings[ci].link, light_time));
            // (a link into an internal junction lets the driver on into the junction whatever the foes)
            let is_cont = |part: &Part| {
                part.crossing.is_some_and(|ci| {
                    !part.exit && self.link_at(plan.crossings[ci].link as usize).yields_inside
                })
            };
            let mut allows = (is_cont(&item) || opened) && !item.had_stopped;
            if !opened {
                found_stopped = true;
                if i > 1 && is_cont(&parts[i - 2]) {
                    allows = true;
                }
            }
            if allows {
                parts[i - 1].available = next.available;
            }
        }
        if !found_stopped {
            return;
        }
        let Some(first) = parts.iter().position(|part| {
            part.crossing.is_some_and(|ci| {
                !part.exit
                    && self.keeps_clear(plan.crossings[ci].link)
                    && part.available - own_length < 0.0
            })
        }) else {
            return;
        };
        // the requests from there on are withdrawn where the driver can still stop before them
        let brake_gap = p.brake_gap(v.speed, p.decel, 0.0);
        let dt = self.spec.step_s;
        for part in &parts[first..] {
            let Some(ci) = part.crossing else { continue };
            let c = plan.crossings[ci];
            let lk = self.link_at(c.link as usize);
            let dist = if part.exit {
                c.dist + self.lane_at(lk.via_lane as usize).length
            } else {
                c.dist
            };
            if !(dist >= brake_gap || (dist > 0.0 && v.speed < p.decel * dt)) {
                continue;
            }
            if let Some(k) = c.item.filter(|_| !part.exit) {
                plan.items[k as usize].will_pass = false;
            }
            if plan.hold_dist.is_infinite() {
                let offset = if part.exit || self.has_priority(c.link, light_time) {
                    PRIORITY_STOP_OFFSET_M
                } else {
                    POSITION_EPS
                };
                let des = self.desired_speed(v, v.lane);
                plan.hold_dist = dist;
                plan.hold_speed =
                    c.v_pass
                        .fmin(p.stop_speed((dist - offset).fmax(0.0), v.speed, des));
            }
        }
    }

    /// SUMO's `getSpaceTillLastStanding`: the room on `lane` from its start to the first vehicle (from upstream)
    /// that stands, plus that vehicle's braking distance, less the vehicles before it; the whole lane less every
    /// vehicle when none stands.
    fn space_till_last_standing(
        &self,
        ego: VehicleId,
        lane: LaneIdx,
        found_stopped: &mut bool,
    ) -> f64 {
        let mut lengths = 0.0;
        for &o in self.lane_veh[lane as usize].iter().rev() {
            let ov = &self.veh[o as usize];
            if ov.speed < super::moves::HALTING_SPEED && o != ego {
                *found_stopped = true;
                let op = &self.types[ov.vtype as usize];
                return ov.pos - ov.length + op.brake_gap(ov.speed, op.decel, op.tau) - lengths;
            }
            lengths += self.brutto_length(o);
        }
        self.lane_at(lane as usize).length - lengths
    }

    /// Whether the link has priority now (SUMO's `havePriority`: an unregulated major link, or a light's major
    /// green).
    fn has_priority(&self, link: LinkIdx, light_time: f64) -> bool {
        let lk = self.link_at(link as usize);
        match self.signal_of(lk, light_time) {
            Some(s) => s == SignalState::Green,
            None => lk.major,
        }
    }

    /// Whether the link's light shows red or yellow.
    fn holds_red(&self, link: LinkIdx, light_time: f64) -> bool {
        let lk = self.link_at(link as usize);
        matches!(
            self.signal_of(lk, light_time),
            Some(SignalState::Red | SignalState::Yellow)
        )
    }
}
