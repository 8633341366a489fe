//! Measurement points: vehicles past each measured merge (entering a road that starts at it) and past the
//! corridor's end (arriving at the end of the main line), counted over the measured time (after the warm-up).
//! Counting only reads the moves, so every other result stays as it was. This is the one measurement of every
//! run, whoever drives the AVs: a policy's evaluation reads it from [`crate::Simulation::metrics`] as the
//! humans' baseline does. On request ([`crate::Simulation::record_passages`]) each passage is also kept, so that
//! a test can follow every vehicle.

use crate::ids::VehicleId;
use crate::network::{LaneIdx, LaneKind, Network};

pub use crate::spec::MeasurePoint;

/// One vehicle passing a measure point or the corridor's end.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Passage {
    pub vehicle: VehicleId,
    /// The measure point (index into the spec's `measure_points`); `None`: the corridor's end.
    pub point: Option<usize>,
    /// Passed after the warm-up (counted in the run's metrics).
    pub counted: bool,
}

/// No point on this lane.
const NO_POINT: u32 = u32::MAX;

#[derive(Clone, Debug)]
pub(crate) struct MeasureAcc {
    /// Per lane, the point a vehicle passes when it enters the lane.
    lane_point: Vec<u32>,
    /// Vehicles past each point since the warm-up.
    pub(crate) counts: Vec<u64>,
    /// Per lane, whether it is a lane of the main line's last road (arrivals from it are past the corridor's end).
    end_lanes: Vec<bool>,
    pub(crate) end_count: u64,
    /// The warm-up is over: passages count.
    measuring: bool,
    /// Every passage, when asked for (off by default: it grows with the run).
    log: Option<Vec<Passage>>,
}

impl MeasureAcc {
    pub(crate) fn new(net: &Network, points: &[MeasurePoint], end_lane: Option<LaneIdx>) -> Self {
        let mut lane_point = vec![NO_POINT; net.lanes.len()];
        for (p, point) in points.iter().enumerate() {
            for (l, lane) in net.lanes.iter().enumerate() {
                if let LaneKind::Road(r) = lane.kind
                    && point.roads.contains(&net.road_ids[r])
                {
                    lane_point[l] = p as u32;
                }
            }
        }
        let end_road = end_lane.and_then(|l| net.road_of(l));
        let end_lanes = (0..net.lanes.len() as LaneIdx)
            .map(|l| Some(l) == end_lane || (end_road.is_some() && net.road_of(l) == end_road))
            .collect();
        MeasureAcc {
            lane_point,
            counts: vec![0; points.len()],
            end_lanes,
            end_count: 0,
            measuring: false,
            log: None,
        }
    }

    /// Vehicle `id` entered `lane`.
    #[inline]
    pub(crate) fn entered(&mut self, lane: LaneIdx, id: VehicleId) {
        let p = self.lane_point[lane as usize];
        if p != NO_POINT {
            self.counts[p as usize] += 1;
            self.note(id, Some(p as usize));
        }
    }

    /// Vehicle `id`, whose route ends on `last_lane`, arrived.
    #[inline]
    pub(crate) fn arrived(&mut self, last_lane: LaneIdx, id: VehicleId) {
        if self.end_lanes[last_lane as usize] {
            self.end_count += 1;
            self.note(id, None);
        }
    }

    fn note(&mut self, vehicle: VehicleId, point: Option<usize>) {
        if let Some(log) = &mut self.log {
            log.push(Passage {
                vehicle,
                point,
                counted: self.measuring,
            });
        }
    }

    /// The warm-up ended: count from zero.
    pub(crate) fn reset(&mut self) {
        self.counts.iter_mut().for_each(|c| *c = 0);
        self.end_count = 0;
        self.measuring = true;
    }

    /// Keep every passage from now on.
    pub(crate) fn record(&mut self) {
        self.log.get_or_insert_with(Vec::new);
    }

    pub(crate) fn passages(&self) -> &[Passage] {
        self.log.as_deref().unwrap_or(&[])
    }
}
