//! SUMO 1.8's `--tripinfo-output` and `--summary-output` files of a mapc run, and its induction loops' files
//! ([`detector_files`]) (watched through the simulator's
//! public API), same elements and attributes, so that
//! a SUMO user's scripts read mapc's runs unchanged. Built by watching the run step by step
//! ([`SumoOutputs::observe`] after each step); vehicles are named as SUMO names a flow's vehicles (`flow.N`),
//! lanes `edge_index` by the SUMO edge the road came from.
//!
//! What mapc does not model is written as SUMO writes it where nothing happens: no stops (`stopTime` 0), no
//! rerouting, no collisions. `timeLoss` is the trip's time over the time its route takes at the driver's desired
//! speed (SUMO sums the shortfall step by step; both are the delay behind free flow).

use crate::xml::escape as xml_escape;
use mapc_graph::{LaneGraph, RoadId};
use mapc_sim::{Simulation, VehicleId};
use std::collections::HashMap;
use std::fmt::Write as _;

/// Below this speed a vehicle is halting (SUMO's `SUMO_const_haltingSpeed`).
const HALTING_SPEED: f64 = 0.1;

#[derive(Clone, Debug, Default)]
struct Trip {
    depart: f64,
    /// Seconds between the departure its flow or `<vehicle>` asked for and its insertion.
    depart_delay: f64,
    depart_lane: String,
    depart_pos: f64,
    depart_speed: f64,
    waiting_s: f64,
    waiting_count: u32,
    halting: bool,
}

/// The outputs being gathered.
#[derive(Debug, Default)]
pub struct SumoOutputs {
    tripinfo: Option<String>,
    summary: Option<String>,
    trips: HashMap<VehicleId, Trip>,
    inserted: u64,
    arrived: u64,
    travel_sum: f64,
    /// Run time at the first step, where SUMO's clock is 0.
    begin_s: f64,
}

/// A SUMO lane id: the road's SUMO edge id (its label where it has none) and the lane's SUMO index (where the
/// import left out lanes closed to cars, the index among all the edge's lanes).
pub(crate) fn lane_name(g: &LaneGraph, road: RoadId, lane: u8) -> String {
    let r = g.road(road);
    let edge = r
        .and_then(|r| r.provenance.sumo_ids.first().cloned())
        .unwrap_or_else(|| road.to_string());
    let index = r.map_or(lane, |r| r.sumo_index_of_lane(lane));
    format!("{edge}_{index}")
}

/// SUMO's name of a vehicle: `flow.N`, the id of a `<vehicle>` or `<trip>`, or `veh.ID` for one that came from no
/// flow (the run must keep its vehicles' origins: [`Simulation::record_origins`]).
pub(crate) fn vehicle_name(sim: &Simulation, id: VehicleId) -> String {
    match sim.vehicle_origin(id) {
        Some((f, _)) if sim.spec().flows[f].single_vehicle => sim.spec().flows[f].id.clone(),
        Some((f, n)) => format!("{}.{n}", sim.spec().flows[f].id),
        None => format!("veh.{id}"),
    }
}

impl SumoOutputs {
    /// Gather the trip infos, the summary, or both, from `sim` before its first step (which it asks to keep its
    /// vehicles' origins).
    pub fn new(sim: &mut Simulation, tripinfo: bool, summary: bool) -> SumoOutputs {
        sim.record_origins();
        SumoOutputs {
            tripinfo: tripinfo.then(String::new),
            summary: summary.then(String::new),
            begin_s: sim.time_s(),
            ..SumoOutputs::default()
        }
    }

    /// When a vehicle was due to depart (its `<vehicle>`'s time, or its flow's departure of its number); `None`
    /// for a flow by probability, whose vehicles are drawn step by step.
    fn due_s(sim: &Simulation, id: VehicleId) -> Option<f64> {
        let (f, n) = sim.vehicle_origin(id)?;
        sim.spec().flows[f].departure_s(u64::from(n))
    }

    /// Take in the step `sim` just made.
    pub fn observe(&mut self, sim: &Simulation) {
        let g = &sim.spec().graph;
        let now = sim.time_s() - self.begin_s;
        let dt = sim.step_s();
        // SUMO's clock reads the configuration's `begin` at the first step
        let clock = sim.spec().clock_begin_s;
        // SUMO stamps what happens in a step with the step's begin: insertions and arrivals, as its summary
        let stamp = now - dt;
        for &id in sim.departed_last_step() {
            let v = sim.vehicle(id).expect("a vehicle that just departed");
            self.inserted += 1;
            self.trips.insert(
                id,
                Trip {
                    depart: stamp,
                    depart_delay: Self::due_s(sim, id).map_or(0.0, |due| (stamp - due).max(0.0)),
                    depart_lane: lane_name(g, v.road, v.lane_index),
                    depart_pos: v.pos_m,
                    depart_speed: v.speed,
                    ..Trip::default()
                },
            );
        }
        let (mut running, mut halting, mut speed_sum, mut rel_sum, mut wait_sum) =
            (0u64, 0u64, 0.0, 0.0, 0.0);
        for id in sim.active_ids() {
            let v = sim.vehicle(id).expect("an active vehicle");
            running += 1;
            speed_sum += v.speed;
            let lane_limit = g
                .road(v.road)
                .and_then(|r| r.lanes.get(v.lane_index as usize))
                .map_or(f64::NAN, |l| l.speed_mps);
            rel_sum += v.speed / lane_limit;
            // a vehicle just inserted stands at its depart speed until its first move (SUMO counts no wait)
            let just_departed = sim.departed_last_step().contains(&id);
            if let Some(t) = self.trips.get_mut(&id).filter(|_| !just_departed) {
                if v.speed < HALTING_SPEED {
                    t.waiting_s += dt;
                    if !t.halting {
                        t.waiting_count += 1;
                    }
                    t.halting = true;
                    halting += 1;
                } else {
                    t.halting = false;
                }
                wait_sum += t.waiting_s;
            }
        }
        for &id in sim.arrived_last_step() {
            let Some(t) = self.trips.remove(&id) else {
                continue;
            };
            let v = sim.vehicle(id).expect("a vehicle that just arrived");
            // SUMO reports the position the vehicle is to arrive at (the lane's end: mapc takes no other), not
            // where the last step took it
            let arrival_pos = g
                .road(v.road)
                .and_then(|r| r.lanes.get(v.lane_index as usize))
                .map_or(v.pos_m, |l| l.length_m);
            let duration = stamp - t.depart;
            self.arrived += 1;
            self.travel_sum += duration;
            if let Some(out) = &mut self.tripinfo {
                let name = xml_escape(&vehicle_name(sim, id));
                let _ = writeln!(
                    out,
                    "    <tripinfo id=\"{name}\" depart=\"{:.2}\" departLane=\"{}\" departPos=\"{:.2}\" departSpeed=\"{:.2}\" \
                     departDelay=\"{:.2}\" arrival=\"{:.2}\" arrivalLane=\"{}\" arrivalPos=\"{:.2}\" arrivalSpeed=\"{:.2}\" \
                     duration=\"{duration:.2}\" routeLength=\"{:.2}\" waitingTime=\"{:.2}\" waitingCount=\"{}\" stopTime=\"0.00\" \
                     timeLoss=\"{:.2}\" rerouteNo=\"0\" devices=\"tripinfo_{name}\" vType=\"{}\" speedFactor=\"{:.2}\" vaporized=\"\"/>",
                    t.depart + clock,
                    xml_escape(&t.depart_lane),
                    t.depart_pos,
                    t.depart_speed,
                    t.depart_delay,
                    stamp + clock,
                    xml_escape(&lane_name(g, v.road, v.lane_index)),
                    arrival_pos,
                    v.speed,
                    v.distance_m,
                    t.waiting_s,
                    t.waiting_count,
                    (duration - v.free_flow_s).max(0.0),
                    xml_escape(v.vehicle_type),
                    v.speed_factor,
                );
            }
        }
        if let Some(out) = &mut self.summary {
            let waiting = sim.waiting_to_enter() as u64;
            let mean = |sum: f64, n: u64| if n > 0 { sum / n as f64 } else { 0.0 };
            // SUMO writes the state after the step, stamped with the step's begin
            let _ = writeln!(
                out,
                "    <step time=\"{:.2}\" loaded=\"{}\" inserted=\"{}\" running=\"{running}\" waiting=\"{waiting}\" \
                 ended=\"{}\" arrived=\"{}\" collisions=\"0\" teleports=\"0\" halting=\"{halting}\" stopped=\"0\" \
                 meanWaitingTime=\"{:.2}\" meanTravelTime=\"{:.2}\" meanSpeed=\"{:.2}\" meanSpeedRelative=\"{:.2}\" duration=\"0\"/>",
                now - dt + clock,
                self.inserted + waiting,
                self.inserted,
                self.arrived,
                self.arrived,
                mean(wait_sum, running),
                if self.arrived > 0 {
                    self.travel_sum / self.arrived as f64
                } else {
                    -1.0
                },
                mean(speed_sum, running),
                mean(rel_sum, running),
            );
        }
    }

    /// The trip-info file, if asked for.
    pub fn tripinfo_xml(&self) -> Option<String> {
        self.tripinfo.as_ref().map(|body| {
            format!(
                "<?xml version=\"1.0\" encoding=\"UTF-8\"?>\n\n<tripinfos xmlns:xsi=\"http://www.w3.org/2001/XMLSchema-instance\" \
                 xsi:noNamespaceSchemaLocation=\"http://sumo.dlr.de/xsd/tripinfo_file.xsd\">\n{body}</tripinfos>\n"
            )
        })
    }

    /// The summary file, if asked for.
    pub fn summary_xml(&self) -> Option<String> {
        self.summary.as_ref().map(|body| {
            format!(
                "<?xml version=\"1.0\" encoding=\"UTF-8\"?>\n\n<summary xmlns:xsi=\"http://www.w3.org/2001/XMLSchema-instance\" \
                 xsi:noNamespaceSchemaLocation=\"http://sumo.dlr.de/xsd/summary_file.xsd\">\n{body}</summary>\n"
            )
        })
    }
}

/// The induction loops' output files of a finished run, as SUMO 1.8 writes them (`<detector>` of
/// `<interval .../>`s, two decimals): `(file name, XML)`, one per file name in `files` (each detector's, in the
/// spec's order; `None`: `detectors.xml`), detectors that share a file interleaved as their intervals end.
pub fn detector_files(sim: &Simulation, files: &[Option<String>]) -> Vec<(String, String)> {
    let detectors = &sim.spec().detectors;
    let name_of = |d: usize| {
        files
            .get(d)
            .cloned()
            .flatten()
            .unwrap_or_else(|| "detectors.xml".to_string())
    };
    let mut out: Vec<(String, String)> = Vec::new();
    for d in 0..detectors.len() {
        let name = name_of(d);
        if !out.iter().any(|(n, _)| *n == name) {
            out.push((name, String::new()));
        }
    }
    for i in sim.detector_intervals() {
        let name = name_of(i.detector);
        let Some((_, body)) = out.iter_mut().find(|(n, _)| *n == name) else {
            continue;
        };
        let _ = writeln!(
            body,
            "    <interval begin=\"{:.2}\" end=\"{:.2}\" id=\"{}\" nVehContrib=\"{}\" flow=\"{:.2}\" \
             occupancy=\"{:.2}\" speed=\"{:.2}\" harmonicMeanSpeed=\"{:.2}\" length=\"{:.2}\" nVehEntered=\"{}\"/>",
            i.begin_s + sim.spec().clock_begin_s,
            i.end_s + sim.spec().clock_begin_s,
            xml_escape(&detectors[i.detector].id),
            i.vehicles_passed,
            i.flow_per_hour,
            i.occupancy_pct,
            i.mean_speed,
            i.harmonic_mean_speed,
            i.mean_length,
            i.vehicles_entered,
        );
    }
    out.into_iter()
        .map(|(name, body)| {
            let xml = format!(
                "<?xml version=\"1.0\" encoding=\"UTF-8\"?>\n\n<detector xmlns:xsi=\"http://www.w3.org/2001/XMLSchema-instance\" \
                 xsi:noNamespaceSchemaLocation=\"http://sumo.dlr.de/xsd/det_e1_file.xsd\">\n{body}</detector>\n"
            );
            (name, xml)
        })
        .collect()
}
