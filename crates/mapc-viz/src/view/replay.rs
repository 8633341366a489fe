//! A simulator trace as the page plays it: one track per vehicle (its rows are consecutive frames), the rows
//! packed into typed arrays, and the metrics so far at every frame, computed as the simulator computes them.

use crate::VizError;
use crate::csvin::CsvInput;
use crate::timespace::TRACE_COLUMNS;
use std::collections::{BTreeSet, HashMap};
use std::path::{Path, PathBuf};

/// The run's clock: the simulator's time of frame 0 (the state before the first step), the step, and how many
/// frames the run has (warm-up and horizon steps, plus frame 0).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Clock {
    pub start_s: f64,
    pub step_s: f64,
    pub warmup_steps: u64,
    pub horizon_steps: u64,
}

impl Clock {
    pub fn frames(&self) -> usize {
        (self.warmup_steps + self.horizon_steps + 1) as usize
    }
}

/// One vehicle's rows: frames `first .. first + count`, stored from `offset` in the row arrays.
#[derive(Clone, Debug, PartialEq)]
pub struct Track {
    pub id: String,
    /// Index into [`Replay::types`].
    pub vtype: u16,
    pub first: u32,
    pub count: u32,
    pub offset: u32,
}

/// A trace, packed. Rows are stored vehicle after vehicle, each vehicle's frames in order.
#[derive(Clone, Debug)]
pub struct Replay {
    pub label: String,
    /// The trace file, or a name for a trace made in memory (errors name it).
    pub source: PathBuf,
    pub clock: Clock,
    /// Trace road labels (`R3`, `R1>R2` for a connection), in order of first appearance.
    pub lanes: Vec<String>,
    /// Corridor position of each lane's start (`corridor_x_m - pos_on_road_m`), for lanes on the main line.
    pub lane_corridor_start: Vec<Option<f64>>,
    pub types: Vec<String>,
    pub tracks: Vec<Track>,
    pub row_lane: Vec<u16>,
    /// Index of the lane on its road (trace column `lane`, 0 rightmost; 0 for traces without it).
    pub row_lane_index: Vec<u8>,
    pub row_pos: Vec<f32>,
    /// Centimetres per second.
    pub row_speed: Vec<u16>,
    /// Metrics after each frame's state, from the end of warm-up (0 before): vehicles that left per hour, vehicles
    /// that entered per hour, and the mean over frames of the mean speed.
    pub outflow_vph: Vec<f32>,
    pub inflow_vph: Vec<f32>,
    pub avg_speed_mps: Vec<f32>,
    /// Vehicles on the road at each frame.
    pub on_road: Vec<u32>,
    /// Every `decimation`-th frame is kept (1: all).
    pub decimation: usize,
    /// The run's metrics: the simulator's where the replay was run (set by the caller), else those of every frame
    /// of the trace (kept before any decimation, which may drop the last frames).
    pub totals: RunTotals,
}

/// A run's metrics over its whole measured time.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct RunTotals {
    pub outflow_veh_h: f64,
    pub inflow_veh_h: f64,
    pub avg_speed_mps: f64,
}

/// The largest lane index the packing holds.
const MAX_LANES: usize = u16::MAX as usize;

/// The frames a trace holds: every one (`every` 1), or one in `every` from `first` on.
struct FrameGrid {
    first: u32,
    every: u32,
}

impl FrameGrid {
    /// The grid of the frames a trace holds: its first, and the greatest common step between them.
    fn of(frames: &std::collections::BTreeSet<u32>) -> FrameGrid {
        let first = frames.first().copied().unwrap_or(0);
        let gcd = |mut a: u32, mut b: u32| {
            while b != 0 {
                (a, b) = (b, a % b);
            }
            a
        };
        let every = frames.iter().fold(0, |g, &f| gcd(g, f - first)).max(1);
        FrameGrid { first, every }
    }

    /// A thinned trace as a replay of its own frames: one step of `every` steps, from its first frame.
    fn rebase(
        &self,
        clock: Clock,
        mut vehicles: Vec<(String, u16, Vec<RawRow>)>,
    ) -> (Clock, Vec<(String, u16, Vec<RawRow>)>) {
        if self.every == 1 {
            return (clock, vehicles);
        }
        let (first, every) = (self.first, self.every);
        for (_, _, rows) in &mut vehicles {
            for row in rows.iter_mut() {
                row.frame = (row.frame - first) / every;
            }
        }
        let clock = Clock {
            start_s: clock.start_s + f64::from(first) * clock.step_s,
            step_s: clock.step_s * f64::from(every),
            warmup_steps: 0,
            horizon_steps: (clock.frames() as u64 - 1 - u64::from(first)) / u64::from(every),
        };
        (clock, vehicles)
    }
}

struct RawRow {
    /// The trace's line, for errors.
    line: u32,
    frame: u32,
    lane: u16,
    lane_index: u8,
    pos: f32,
    speed: u16,
}

impl Replay {
    /// Read a trace CSV (`mapc sim --trace`, `mapc eval --trace`); `path` names it in errors. `clock` is the
    /// scenario's; a row whose time is not on the clock's steps, or a vehicle that leaves and comes back, is an
    /// error naming the line.
    pub fn read(
        path: &Path,
        input: Box<dyn std::io::Read>,
        clock: Clock,
        label: &str,
    ) -> Result<Replay, VizError> {
        let mut csv = CsvInput::from_reader(path, input)?;
        let idx = csv.require(&TRACE_COLUMNS)?;
        let [i_time, i_vid, i_type, i_road, i_pos, i_x, i_speed, _] = idx[..] else {
            unreachable!("require returns one index per name")
        };
        // optional: traces written before lanes were simulated lack it
        let i_lane_index = csv.column("lane");
        let fields = csv.fields();
        let frames = clock.frames();
        let mut lanes: Vec<String> = Vec::new();
        let mut lane_index: HashMap<String, u16> = HashMap::new();
        let mut lane_start: Vec<Option<f64>> = Vec::new();
        let mut types: Vec<String> = Vec::new();
        let mut vehicles: Vec<(String, u16, Vec<RawRow>)> = Vec::new();
        let mut vehicle_index: HashMap<String, usize> = HashMap::new();
        // a trace past its bound of rows holds one frame in `every` (mapc_sim::TraceBudget): the frames it holds
        // set the grid
        let mut seen_frames: std::collections::BTreeSet<u32> = std::collections::BTreeSet::new();
        csv.for_each_row(|rec, line| {
            let t = fields.required(rec, i_time, "time_s", line)?;
            let f = (t - clock.start_s) / clock.step_s;
            let frame = f.round();
            if (f - frame).abs() > 1e-3 || frame < 0.0 || frame >= frames as f64 {
                return Err(fields.error(
                    line,
                    "time_s",
                    format!(
                        "{t} s is not a step of this run ({} s from {} s, {frames} frames)",
                        clock.step_s, clock.start_s
                    ),
                ));
            }
            let frame = frame as u32;
            seen_frames.insert(frame);
            let road = rec.get(i_road).unwrap_or("").trim();
            let lane = match lane_index.get(road) {
                Some(l) => *l,
                None => {
                    if road.is_empty() {
                        return Err(fields.error(line, "road", "empty field".into()));
                    }
                    if lanes.len() >= MAX_LANES {
                        return Err(fields.error(
                            line,
                            "road",
                            format!("`{road}`: more than {MAX_LANES} roads in one trace"),
                        ));
                    }
                    lanes.push(road.to_string());
                    lane_start.push(None);
                    lane_index.insert(road.to_string(), (lanes.len() - 1) as u16);
                    (lanes.len() - 1) as u16
                }
            };
            let lane_index = match i_lane_index {
                Some(i) => {
                    let k = fields.number(rec, i, "lane", line)?.unwrap_or(0.0);
                    if !(0.0..=f64::from(u8::MAX)).contains(&k) || k.fract() != 0.0 {
                        return Err(fields.error(
                            line,
                            "lane",
                            format!("{k} is not a lane index (0 to {})", u8::MAX),
                        ));
                    }
                    k as u8
                }
                None => 0,
            };
            let pos = fields.required(rec, i_pos, "pos_on_road_m", line)?;
            if let Some(x) = fields.number(rec, i_x, "corridor_x_m", line)? {
                lane_start[lane as usize].get_or_insert(x - pos);
            }
            let speed = fields.required(rec, i_speed, "speed_mps", line)?;
            if !(0.0..=600.0).contains(&speed) {
                return Err(fields.error(line, "speed_mps", format!("{speed} m/s")));
            }
            let vid = rec.get(i_vid).unwrap_or("").trim();
            let vtype_name = rec.get(i_type).unwrap_or("").trim();
            let vtype = match types.iter().position(|t| t == vtype_name) {
                Some(k) => k as u16,
                None => {
                    types.push(vtype_name.to_string());
                    (types.len() - 1) as u16
                }
            };
            let v = match vehicle_index.get(vid) {
                Some(v) => *v,
                None => {
                    if vid.is_empty() {
                        return Err(fields.error(line, "vehicle_id", "empty field".into()));
                    }
                    vehicle_index.insert(vid.to_string(), vehicles.len());
                    vehicles.push((vid.to_string(), vtype, Vec::new()));
                    vehicles.len() - 1
                }
            };
            let rows = &mut vehicles[v].2;
            if let Some(last) = rows.last()
                && frame <= last.frame
            {
                return Err(fields.error(
                    line,
                    "time_s",
                    format!(
                        "vehicle {vid} was last seen at frame {} and is here at frame {frame}: a vehicle's rows \
                         must be consecutive frames of the trace",
                        last.frame
                    ),
                ));
            }
            rows.push(RawRow {
                line: line as u32,
                frame,
                lane,
                lane_index,
                pos: pos as f32,
                speed: (speed * 100.0).round() as u16,
            });
            Ok(())
        })?;
        let grid = FrameGrid::of(&seen_frames);
        for (vid, _, rows) in &vehicles {
            for w in rows.windows(2) {
                if w[0].frame + grid.every != w[1].frame {
                    return Err(fields.error(
                        u64::from(w[1].line),
                        "time_s",
                        format!(
                            "vehicle {vid} was last seen at frame {} and is here at frame {}: a vehicle's rows \
                             must be consecutive frames of the trace",
                            w[0].frame, w[1].frame
                        ),
                    ));
                }
            }
        }
        let (clock, vehicles) = grid.rebase(clock, vehicles);
        Ok(Replay::pack(
            path, label, clock, lanes, lane_start, types, vehicles,
        ))
    }

    fn pack(
        source: &Path,
        label: &str,
        clock: Clock,
        lanes: Vec<String>,
        lane_corridor_start: Vec<Option<f64>>,
        types: Vec<String>,
        mut vehicles: Vec<(String, u16, Vec<RawRow>)>,
    ) -> Replay {
        // entry order, so the page can stop scanning at the first vehicle that has not entered yet
        vehicles.sort_by_key(|(_, _, rows)| rows.first().map_or(0, |r| r.frame));
        let frames = clock.frames();
        let mut r = Replay {
            label: label.to_string(),
            source: source.to_path_buf(),
            clock,
            lanes,
            lane_corridor_start,
            types,
            tracks: Vec::with_capacity(vehicles.len()),
            row_lane: Vec::new(),
            row_lane_index: Vec::new(),
            row_pos: Vec::new(),
            row_speed: Vec::new(),
            outflow_vph: Vec::new(),
            inflow_vph: Vec::new(),
            avg_speed_mps: Vec::new(),
            on_road: vec![0; frames],
            decimation: 1,
            totals: RunTotals::default(),
        };
        let mut speed_sum = vec![0.0f64; frames];
        let mut exits = vec![0u32; frames + 1];
        let mut entries = vec![0u32; frames + 1];
        for (id, vtype, rows) in vehicles {
            let (Some(first), Some(last)) = (rows.first(), rows.last()) else {
                continue;
            };
            // Leaving before the last frame is leaving the network in the next step; appearing after frame 0
            // is entering in the step before.
            if (last.frame as usize) + 1 < frames {
                exits[last.frame as usize + 1] += 1;
            }
            if first.frame > 0 {
                entries[first.frame as usize] += 1;
            }
            r.tracks.push(Track {
                id,
                vtype,
                first: first.frame,
                count: rows.len() as u32,
                offset: r.row_lane.len() as u32,
            });
            for row in rows {
                r.on_road[row.frame as usize] += 1;
                speed_sum[row.frame as usize] += f64::from(row.speed) / 100.0;
                r.row_lane.push(row.lane);
                r.row_lane_index.push(row.lane_index);
                r.row_pos.push(row.pos);
                r.row_speed.push(row.speed);
            }
        }
        r.fill_metrics(&speed_sum, &exits, &entries);
        let last = |v: &[f32]| v.last().copied().map_or(0.0, f64::from);
        r.totals = RunTotals {
            outflow_veh_h: last(&r.outflow_vph),
            inflow_veh_h: last(&r.inflow_vph),
            avg_speed_mps: last(&r.avg_speed_mps),
        };
        r
    }

    /// The simulator's definitions (`mapc_sim::RunMetrics`): arrivals and departures in the steps after warm-up
    /// per hour of those steps, and the mean over those steps of the mean speed of the state before each (steps
    /// with no vehicle, or all stopped, skipped). The value at frame f covers steps warm-up .. f.
    fn fill_metrics(&mut self, speed_sum: &[f64], exits: &[u32], entries: &[u32]) {
        let warmup = self.clock.warmup_steps as usize;
        let (mut arrived, mut departed, mut speeds, mut speed_steps) = (0u64, 0u64, 0.0f64, 0u64);
        for f in 0..self.on_road.len() {
            if f > warmup {
                arrived += u64::from(exits[f]);
                departed += u64::from(entries[f]);
                let n = self.on_road[f - 1];
                if n > 0 && speed_sum[f - 1] / f64::from(n) > 0.0 {
                    speeds += speed_sum[f - 1] / f64::from(n);
                    speed_steps += 1;
                }
            }
            let secs = (f.saturating_sub(warmup)) as f64 * self.clock.step_s;
            let per_hour = |n: u64| {
                if secs > 0.0 {
                    3600.0 * n as f64 / secs
                } else {
                    0.0
                }
            };
            self.outflow_vph.push(per_hour(arrived) as f32);
            self.inflow_vph.push(per_hour(departed) as f32);
            self.avg_speed_mps.push(if speed_steps > 0 {
                (speeds / speed_steps as f64) as f32
            } else {
                0.0
            });
        }
    }

    pub fn rows(&self) -> usize {
        self.row_lane.len()
    }

    /// Keep every `k`-th frame (k >= 2), so a long run fits the page; vehicles stay consecutive in the kept
    /// frames.
    pub fn decimate(&mut self, k: usize) {
        if k < 2 {
            return;
        }
        let keep = |f: u32| (f as usize).is_multiple_of(k);
        let (mut lane, mut lane_index, mut pos, mut speed) =
            (Vec::new(), Vec::new(), Vec::new(), Vec::new());
        let mut tracks = Vec::new();
        for t in &self.tracks {
            let kept: Vec<u32> = (t.first..t.first + t.count).filter(|f| keep(*f)).collect();
            let Some(&first) = kept.first() else { continue };
            let offset = lane.len() as u32;
            for f in &kept {
                let i = (t.offset + f - t.first) as usize;
                lane.push(self.row_lane[i]);
                lane_index.push(self.row_lane_index[i]);
                pos.push(self.row_pos[i]);
                speed.push(self.row_speed[i]);
            }
            tracks.push(Track {
                first: first / k as u32,
                count: kept.len() as u32,
                offset,
                ..t.clone()
            });
        }
        let every = |v: &Vec<f32>| v.iter().step_by(k).copied().collect::<Vec<f32>>();
        self.outflow_vph = every(&self.outflow_vph);
        self.inflow_vph = every(&self.inflow_vph);
        self.avg_speed_mps = every(&self.avg_speed_mps);
        self.on_road = self.on_road.iter().step_by(k).copied().collect();
        (self.row_lane, self.row_pos, self.row_speed, self.tracks) = (lane, pos, speed, tracks);
        self.row_lane_index = lane_index;
        self.decimation *= k;
    }

    /// Types whose vehicles are AVs, for colouring: those named in `av_types`.
    pub fn av_type_flags(&self, av_types: &BTreeSet<String>) -> Vec<bool> {
        self.types.iter().map(|t| av_types.contains(t)).collect()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const HEADER: &str =
        "time_s,vehicle_id,vehicle_type,road,pos_on_road_m,corridor_x_m,speed_mps,controlled";

    fn clock() -> Clock {
        Clock {
            start_s: 1.0,
            step_s: 0.5,
            warmup_steps: 0,
            horizon_steps: 8,
        }
    }

    fn read(text: String) -> Result<Replay, VizError> {
        Replay::read(
            Path::new("t.csv"),
            Box::new(std::io::Cursor::new(text.into_bytes())),
            clock(),
            "t",
        )
    }

    /// Vehicle `v` on R0 from frame `first` for `n` frames at 10 m/s.
    fn rows(v: u32, first: u32, n: u32) -> String {
        (first..first + n)
            .map(|f| {
                let x = 5.0 * (f - first) as f64;
                format!("{},{v},human,R0,{x},{x},10.0,false\n", 1.0 + 0.5 * f as f64)
            })
            .collect()
    }

    #[test]
    fn departures_and_arrivals_are_counted_in_the_steps_they_happen() {
        // vehicle 0 is there from the start and leaves after frame 3; vehicle 1 enters at frame 2 and stays
        let r = read(format!("{HEADER}\n{}{}", rows(0, 0, 4), rows(1, 2, 7))).unwrap();
        assert_eq!(r.tracks.len(), 2);
        assert_eq!(r.on_road, [1, 1, 2, 2, 1, 1, 1, 1, 1]);
        // 1 arrival and 1 departure over 8 steps of 0.5 s
        assert_eq!(*r.outflow_vph.last().unwrap(), 900.0);
        assert_eq!(*r.inflow_vph.last().unwrap(), 900.0);
        assert_eq!(r.outflow_vph[3], 0.0);
        assert_eq!(r.outflow_vph[4], 3600.0 / 2.0);
        assert_eq!(*r.avg_speed_mps.last().unwrap(), 10.0);
        assert_eq!(r.lane_corridor_start, [Some(0.0)]);
    }

    #[test]
    fn the_lane_column_is_read_and_old_traces_without_it_are_on_lane_0() {
        let old = read(format!("{HEADER}\n{}", rows(0, 0, 2))).unwrap();
        assert_eq!(old.row_lane_index, [0, 0]);
        let new = read(format!(
            "{HEADER},lane\n1.0,0,human,R0,0,0,10,false,1\n1.5,0,human,R0,5,5,10,false,0\n"
        ))
        .unwrap();
        assert_eq!(new.row_lane_index, [1, 0]);
        let bad = read(format!("{HEADER},lane\n1.0,0,human,R0,0,0,10,false,-1\n")).unwrap_err();
        assert!(
            bad.to_string().contains("line 2") && bad.to_string().contains("lane"),
            "{bad}"
        );
    }

    #[test]
    fn decimation_keeps_every_kth_frame_and_consecutive_tracks() {
        let mut r = read(format!("{HEADER}\n{}{}", rows(0, 0, 4), rows(1, 2, 7))).unwrap();
        let full = r.clone();
        r.decimate(2);
        assert_eq!(r.decimation, 2);
        assert_eq!(r.on_road, [1, 2, 1, 1, 1]);
        assert_eq!(r.rows(), 6); // frames 0, 2 of vehicle 0; 2, 4, 6, 8 of vehicle 1
        assert_eq!((r.tracks[0].first, r.tracks[0].count), (0, 2));
        assert_eq!((r.tracks[1].first, r.tracks[1].count), (1, 4));
        assert_eq!(r.outflow_vph.last(), full.outflow_vph.last());
    }

    #[test]
    fn a_thinned_trace_is_a_replay_of_its_own_frames() {
        // one frame in 2 from frame 2 (a warm-up of 2 steps, then a trace past its bound)
        let thinned = |v: u32, frames: &[u32]| -> String {
            frames
                .iter()
                .map(|f| {
                    format!(
                        "{},{v},human,R0,{f},{f},10.0,false\n",
                        1.0 + 0.5 * *f as f64
                    )
                })
                .collect()
        };
        let r = read(format!(
            "{HEADER}\n{}{}",
            thinned(0, &[2, 4, 6]),
            thinned(1, &[4, 6, 8])
        ))
        .unwrap();
        assert_eq!((r.clock.start_s, r.clock.step_s), (2.0, 1.0));
        assert_eq!((r.clock.warmup_steps, r.clock.horizon_steps), (0, 3));
        assert_eq!(r.on_road, [1, 2, 2, 1]);
        // a vehicle missing from one of the trace's frames is still an error
        let gap = read(format!(
            "{HEADER}\n{}{}",
            thinned(0, &[2, 6]),
            thinned(1, &[4])
        ))
        .unwrap_err();
        assert!(gap.to_string().contains("line 3"), "{gap}");
    }

    #[test]
    fn rows_off_the_clock_or_with_a_gap_are_named_by_line() {
        let off = read(format!("{HEADER}\n1.25,0,human,R0,0,0,1,false\n")).unwrap_err();
        assert!(off.to_string().contains("line 2"), "{off}");
        let late = read(format!("{HEADER}\n99.0,0,human,R0,0,0,1,false\n")).unwrap_err();
        assert!(
            late.to_string().contains("not a step of this run"),
            "{late}"
        );
        let gap = read(format!("{HEADER}\n{}{}", rows(0, 0, 2), rows(0, 3, 1))).unwrap_err();
        assert!(gap.to_string().contains("line 4"), "{gap}");
        let speed = read(format!("{HEADER}\n1.0,0,human,R0,0,0,-3,false\n")).unwrap_err();
        assert!(speed.to_string().contains("speed_mps"), "{speed}");
    }
}
