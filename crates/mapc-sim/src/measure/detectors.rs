//! Induction loops (SUMO's E1 detectors): a point on one lane that counts the vehicles passing it and the time
//! it is occupied, aggregated over fixed intervals. The figures are SUMO 1.8's (`MSInductLoop`): a vehicle enters
//! when its front passes the point and contributes when its back has passed it too; one that leaves the lane
//! first (a lane change, an arrival, a teleport) only adds to the occupancy. The times a front and a back pass
//! the point are interpolated inside the step as SUMO's Euler update does (distance over the new speed).
//!
//! The simulator reports, after each step's moves and before its lane changes (SUMO's loops see the moves as
//! they are made, and the lane changes come after), what the vehicles on a detector's lane did ([`Seen`]): a
//! vehicle that passes a loop and changes lanes in the same step has passed it; one changed onto the lane over
//! the point is on it from then. This module keeps the records and makes the intervals ([`DetectorInterval`]).

use crate::ids::VehicleId;
use crate::network::LaneIdx;
use crate::spec::DetectorSpec;

/// One vehicle as a detector sees it at the end of a step.
#[derive(Clone, Copy, Debug)]
pub struct Seen {
    pub id: VehicleId,
    /// Its lane now, and that lane's road (`None` inside a junction).
    pub lane: LaneIdx,
    pub road: Option<usize>,
    /// Front position on its lane (m) and speed over the step (m/s).
    pub pos: f64,
    pub speed: f64,
    pub length: f64,
    /// Distance driven since insertion (m): the front's position on the detector's lane once it has moved on.
    pub odometer: f64,
    /// Still in the network (not arrived, not teleporting).
    pub active: bool,
}

/// A vehicle whose front has passed the point and whose back has not.
#[derive(Clone, Copy, Debug)]
struct OnDetector {
    id: VehicleId,
    entry_s: f64,
    /// Odometer reading when its front was at the point.
    odometer_at_point: f64,
}

/// A passage that ended in the interval.
#[derive(Clone, Copy, Debug)]
struct Passage {
    entry_s: f64,
    leave_s: f64,
    length: f64,
    /// Its back passed the point (it left early otherwise).
    passed: bool,
}

/// The figures of one detector over one interval, as SUMO 1.8 writes them (`<interval .../>`). Speeds and the
/// length are -1 where no vehicle passed whole.
#[derive(Clone, Debug, PartialEq)]
pub struct DetectorInterval {
    /// Index in the spec's detectors.
    pub detector: usize,
    pub begin_s: f64,
    pub end_s: f64,
    /// Vehicles whose back passed the point.
    pub vehicles_passed: u64,
    /// `vehicles_passed` per hour of the interval.
    pub flow_per_hour: f64,
    /// Per cent of the interval a vehicle was over the point.
    pub occupancy_pct: f64,
    pub mean_speed: f64,
    pub harmonic_mean_speed: f64,
    pub mean_length: f64,
    /// Vehicles whose front reached the point.
    pub vehicles_entered: u64,
}

/// One detector's state.
#[derive(Clone, Debug)]
struct Loop {
    spec: DetectorSpec,
    /// The simulator's lane of the point, and its road's index.
    lane: LaneIdx,
    road: usize,
    on: Vec<OnDetector>,
    passages: Vec<Passage>,
    entered: u64,
    interval_begin_s: f64,
    /// Since [`Detectors::reset`]: vehicles passed whole, seconds occupied by finished passages.
    total_passed: u64,
    total_occupied_s: f64,
}

/// Every detector of a run and the intervals they completed.
#[derive(Clone, Debug, Default)]
pub struct Detectors {
    loops: Vec<Loop>,
    intervals: Vec<DetectorInterval>,
    /// Start of the run's measured time (the totals count from it).
    since_s: f64,
    /// A list of tracked vehicles to reuse: each step's observation fills a new one from the last.
    spare: Vec<OnDetector>,
}

/// The time (s, from the step's start) a point `to_go` metres ahead was reached in a step of `dt` at `speed`:
/// SUMO's Euler `passingTime`, within the step.
fn passing_time(to_go: f64, speed: f64, dt: f64) -> f64 {
    if speed <= 0.0 {
        return dt;
    }
    (to_go / speed).clamp(0.0, dt)
}

/// Whether a vehicle at `pos` with `speed` and `length` on a loop's lane, not tracked by the loop, may enter it in
/// a step of `dt`: its front is at or past the point `p`, and its back was before it at the step's start (its front
/// passed it in the step, or it was put over it). [`Detectors::observe`] takes in no other untracked vehicle, so
/// the simulator shows it only these.
#[inline]
pub fn may_enter(p: f64, pos: f64, speed: f64, length: f64, dt: f64) -> bool {
    pos >= p && (pos - speed * dt) - length < p
}

impl Loop {
    fn push(&mut self, since: f64, p: Passage) {
        if p.leave_s > since {
            self.total_passed += p.passed as u64;
            self.total_occupied_s += p.leave_s - p.entry_s.max(since);
        }
        self.passages.push(p);
    }
}

impl Detectors {
    /// Detectors at `specs`, each on the simulator lane `lanes[i]` of the road index `roads[i]`.
    pub fn new(specs: &[DetectorSpec], lanes: &[(LaneIdx, usize)], begin_s: f64) -> Detectors {
        Detectors {
            loops: specs
                .iter()
                .zip(lanes)
                .map(|(spec, &(lane, road))| Loop {
                    spec: spec.clone(),
                    lane,
                    road,
                    on: Vec::new(),
                    passages: Vec::new(),
                    entered: 0,
                    interval_begin_s: begin_s,
                    total_passed: 0,
                    total_occupied_s: 0.0,
                })
                .collect(),
            intervals: Vec::new(),
            since_s: begin_s,
            spare: Vec::new(),
        }
    }

    pub fn is_empty(&self) -> bool {
        self.loops.is_empty()
    }

    pub fn len(&self) -> usize {
        self.loops.len()
    }

    /// The lane of a detector.
    pub fn lane(&self, detector: usize) -> LaneIdx {
        self.loops[detector].lane
    }

    /// The position of a detector's point on its lane (m).
    pub fn pos(&self, detector: usize) -> f64 {
        self.loops[detector].spec.pos_m
    }

    /// The vehicles each detector is tracking (to be looked up wherever they are now).
    pub fn tracked(&self, detector: usize) -> impl Iterator<Item = VehicleId> + '_ {
        self.loops[detector].on.iter().map(|o| o.id)
    }

    /// Take in the step from `t` to `t + dt` for `detector`: `on_lane` are the vehicles on its lane now (those
    /// that [`may_enter`] it at least), `tracked` the vehicles it was tracking (as [`Detectors::tracked`] listed
    /// them), wherever they are.
    pub fn observe(
        &mut self,
        detector: usize,
        t: f64,
        dt: f64,
        on_lane: &[Seen],
        tracked: &[Seen],
    ) {
        let since = self.since_s;
        let lp = &mut self.loops[detector];
        let lane_road = Some(lp.road);
        let p = lp.spec.pos_m;
        // those it was tracking: their back passes, or they leave the lane another way
        let mut still = std::mem::take(&mut self.spare);
        still.clear();
        let was_on = std::mem::take(&mut lp.on);
        for (o, s) in was_on.iter().zip(tracked) {
            debug_assert_eq!(o.id, s.id);
            // a lane change off the detector's road lane (a junction passage keeps it tracked)
            let changed_lane = s.lane != lp.lane && s.road == lane_road;
            if !s.active || changed_lane {
                lp.push(
                    since,
                    Passage {
                        entry_s: o.entry_s,
                        // a lane change is made after the last step's moves, which ended at `t`
                        leave_s: if changed_lane { t } else { t + dt },
                        length: s.length,
                        passed: false,
                    },
                );
                continue;
            }
            let back_past = s.odometer - o.odometer_at_point - s.length;
            if back_past > 0.0 {
                let back_before = back_past - s.speed * dt;
                lp.push(
                    since,
                    Passage {
                        entry_s: o.entry_s,
                        leave_s: t + passing_time(-back_before, s.speed, dt),
                        length: s.length,
                        passed: true,
                    },
                );
            } else {
                still.push(*o);
            }
        }
        // those on the lane it does not track: a front that passed the point in the step, or a vehicle put
        // over it (inserted, changed lanes, teleported there)
        for s in on_lane {
            if !may_enter(p, s.pos, s.speed, s.length, dt) || was_on.iter().any(|o| o.id == s.id) {
                continue;
            }
            let front_before = s.pos - s.speed * dt;
            let entry_s = if front_before < p {
                t + passing_time(p - front_before, s.speed, dt)
            } else {
                // put over it since the last step (a lane change onto it)
                t
            };
            // a front that passed this step whose back passed too (or one whose back already had)
            let odometer_at_point = s.odometer - (s.pos - p);
            lp.entered += 1;
            let back_past = s.pos - s.length - p;
            if back_past > 0.0 {
                let back_before = back_past - s.speed * dt;
                lp.push(
                    since,
                    Passage {
                        entry_s,
                        leave_s: t + passing_time(-back_before, s.speed, dt),
                        length: s.length,
                        passed: true,
                    },
                );
            } else {
                still.push(OnDetector {
                    id: s.id,
                    entry_s,
                    odometer_at_point,
                });
            }
        }
        lp.on = still;
        self.spare = was_on;
        // an interval ends with the step that reaches it (SUMO writes at the step's end)
        let now = t + dt;
        if now - lp.interval_begin_s >= lp.spec.period_s - 1e-9 {
            let begin = lp.interval_begin_s;
            self.close_interval(detector, begin, now);
        }
    }

    /// The interval of `detector` from `begin` to `end` made from its records, which then start again.
    fn close_interval(&mut self, detector: usize, begin: f64, end: f64) {
        let lp = &mut self.loops[detector];
        let span = end - begin;
        let mut occupied = 0.0;
        let (mut n, mut speed_sum, mut inv_speed_sum, mut length_sum) = (0u64, 0.0, 0.0, 0.0);
        for ps in &lp.passages {
            occupied += (ps.leave_s - ps.entry_s.max(begin)).min(span);
            if ps.passed {
                let v = ps.length / (ps.leave_s - ps.entry_s).max(crate::numeric::NUMERICAL_EPS);
                n += 1;
                speed_sum += v;
                inv_speed_sum += 1.0 / v;
                length_sum += ps.length;
            }
        }
        for o in &lp.on {
            occupied += end - o.entry_s.max(begin);
        }
        let per = |sum: f64| if n > 0 { sum / n as f64 } else { -1.0 };
        self.intervals.push(DetectorInterval {
            detector,
            begin_s: begin,
            end_s: end,
            vehicles_passed: n,
            flow_per_hour: n as f64 / span * 3600.0,
            occupancy_pct: occupied / span * 100.0,
            mean_speed: per(speed_sum),
            harmonic_mean_speed: if n > 0 {
                n as f64 / inv_speed_sum
            } else {
                -1.0
            },
            mean_length: per(length_sum),
            vehicles_entered: lp.entered,
        });
        lp.passages.clear();
        lp.entered = 0;
        lp.interval_begin_s = end;
    }

    /// The partial intervals at the end of a run (SUMO writes them when it closes), up to `end`.
    pub fn close(&mut self, end: f64) {
        for d in 0..self.loops.len() {
            let begin = self.loops[d].interval_begin_s;
            if begin < end - 1e-9 {
                self.close_interval(d, begin, end);
            }
        }
    }

    /// The totals start again at `t` (the end of a warm-up); intervals go on.
    pub fn reset(&mut self, t: f64) {
        self.since_s = t;
        for lp in &mut self.loops {
            lp.total_passed = 0;
            lp.total_occupied_s = 0.0;
        }
    }

    /// Per detector, since the last reset up to `now`: the vehicles passed whole and the seconds occupied.
    pub fn totals(&self, now: f64) -> impl Iterator<Item = (u64, f64)> + '_ {
        self.loops.iter().map(move |lp| {
            let on: f64 = lp
                .on
                .iter()
                .map(|o| now - o.entry_s.max(self.since_s))
                .sum();
            (lp.total_passed, lp.total_occupied_s + on)
        })
    }

    /// The completed intervals, in order of completion.
    pub fn intervals(&self) -> &[DetectorInterval] {
        &self.intervals
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn spec(period_s: f64) -> DetectorSpec {
        DetectorSpec {
            id: "d".into(),
            road: mapc_graph::RoadId(0),
            lane: 0,
            pos_m: 50.0,
            period_s,
            vehicle_types: Vec::new(),
        }
    }

    fn seen(pos: f64, speed: f64, odometer: f64) -> Seen {
        Seen {
            id: 7,
            lane: 3,
            road: Some(1),
            pos,
            speed,
            length: 5.0,
            odometer,
            active: true,
        }
    }

    /// A 5 m car at 4 m/s in 1 s steps: its front passes 50 m half-way through the step from 48 to 52 m
    /// ((50 - 48) / 4 = 0.5 s), its back (47 then 51 m) 0.75 s into the next ((50 - 47) / 4); over the point
    /// 1.25 s of the 2 s interval, at 5 / 1.25 = 4 m/s.
    #[test]
    fn a_passage_worked_by_hand() {
        let mut d = Detectors::new(&[spec(10.0)], &[(3, 1)], 0.0);
        let s = seen(52.0, 4.0, 52.0);
        d.observe(0, 0.0, 1.0, &[s], &[]);
        assert_eq!(d.tracked(0).count(), 1);
        let s = seen(56.0, 4.0, 56.0);
        d.observe(0, 1.0, 1.0, &[s], &[s]);
        assert_eq!(d.tracked(0).count(), 0);
        d.close(2.0);
        let i = &d.intervals()[0];
        assert_eq!((i.begin_s, i.end_s), (0.0, 2.0));
        assert_eq!((i.vehicles_passed, i.vehicles_entered), (1, 1));
        assert!((i.flow_per_hour - 1800.0).abs() < 1e-9);
        assert!((i.occupancy_pct - 62.5).abs() < 1e-9, "{i:?}");
        assert!((i.mean_speed - 4.0).abs() < 1e-9);
        assert!((i.harmonic_mean_speed - 4.0).abs() < 1e-9);
        assert_eq!(i.mean_length, 5.0);
    }

    /// A fast car passes whole within one step: entered and left in it.
    #[test]
    fn a_whole_passage_within_one_step() {
        let mut d = Detectors::new(&[spec(10.0)], &[(3, 1)], 0.0);
        // front 45.5 -> 55.5 (enters at 0.45 s), back 40.5 -> 50.5 (leaves at 0.95 s)
        d.observe(0, 0.0, 1.0, &[seen(55.5, 10.0, 55.5)], &[]);
        assert_eq!(d.tracked(0).count(), 0);
        d.close(1.0);
        let i = &d.intervals()[0];
        assert_eq!(i.vehicles_passed, 1);
        assert!((i.occupancy_pct - 50.0).abs() < 1e-9, "{i:?}");
        assert!((i.mean_speed - 10.0).abs() < 1e-9);
    }

    #[test]
    fn an_empty_interval_is_written_as_sumo_writes_it() {
        let mut d = Detectors::new(&[spec(2.0)], &[(3, 1)], 0.0);
        d.observe(0, 0.0, 1.0, &[], &[]);
        d.observe(0, 1.0, 1.0, &[], &[]);
        let i = &d.intervals()[0];
        assert_eq!((i.begin_s, i.end_s, i.vehicles_passed), (0.0, 2.0, 0));
        assert_eq!(
            (i.mean_speed, i.harmonic_mean_speed, i.mean_length),
            (-1.0, -1.0, -1.0)
        );
        assert_eq!(i.occupancy_pct, 0.0);
        d.close(2.0);
        assert_eq!(
            d.intervals().len(),
            1,
            "no second interval at an exact boundary"
        );
    }

    #[test]
    fn a_lane_change_off_the_point_only_adds_occupancy() {
        let mut d = Detectors::new(&[spec(10.0)], &[(3, 1)], 0.0);
        d.observe(0, 0.0, 1.0, &[seen(52.0, 2.0, 52.0)], &[]);
        let mut moved = seen(54.0, 2.0, 54.0);
        moved.lane = 4;
        d.observe(0, 1.0, 1.0, &[], &[moved]);
        d.close(4.0);
        let i = &d.intervals()[0];
        assert_eq!((i.vehicles_passed, i.vehicles_entered), (0, 1));
        // over the point from 0 s (front from 50 to 52 at 2 m/s: 0 s into the step) to the end of the step whose
        // lane changes took it off (the loops see a step's moves before its lane changes, as SUMO's): 1 s
        assert!((i.occupancy_pct - 1.0 / 4.0 * 100.0).abs() < 1e-9, "{i:?}");
        assert_eq!(i.mean_speed, -1.0);
    }

    #[test]
    fn a_vehicle_changed_onto_the_lane_over_the_point_passes_it() {
        let mut d = Detectors::new(&[spec(10.0)], &[(3, 1)], 0.0);
        d.observe(0, 0.0, 1.0, &[], &[]);
        // changed onto the lane after the last moves with its front at 54 m and its back at 49 m, then moved 2 m:
        // its back passes 50 m in this step, and it is counted once
        d.observe(0, 1.0, 1.0, &[seen(56.0, 2.0, 56.0)], &[]);
        d.observe(0, 2.0, 1.0, &[seen(58.0, 2.0, 58.0)], &[]);
        d.close(4.0);
        let i = &d.intervals()[0];
        assert_eq!((i.vehicles_passed, i.vehicles_entered), (1, 1), "{i:?}");
    }
}
