//! SUMO 1.8's floating-car data (`--fcd-output`) of a mapc run: after each step a `<timestep time>` with a
//! `<vehicle id x y angle type speed pos lane slope/>` per vehicle on the network, sorted by id as SUMO's vehicle
//! table is, so that a SUMO user's trajectory scripts read mapc's runs unchanged.
//!
//! Positions are SUMO's: the front's point on its lane's shape, the lane position scaled by the shape's length
//! over the lane's length; the angle (navigation degrees, north 0, clockwise) is that of the line from the back to
//! the front, the back on the lane behind where it reaches there (`Simulation::back_place`; where the route no
//! longer knows that lane, after a lane change, the lane's start, as SUMO draws a back out of the network). A lane's shape is the one its SUMO net drew (`Lane::shape`), else the one `mapc export --sumo`
//! writes (the road's centre line moved sideways by whole lane widths, [`crate::net`]); on a junction's
//! connection a vehicle is on one of its internal lanes (`Connection::via_lanes`), named and placed as SUMO does,
//! else on the straight line from the lane it leaves to the lane it enters, named and drawn as `mapc export --sumo`
//! writes that connection's internal lane.

use crate::junctions::{InternalEdges, links_by_junction};
use crate::names::SumoNames;
use crate::run_outputs::{lane_name, vehicle_name};
use crate::xml::escape as xml_escape;
use mapc_graph::{ConnectionLanes, RoadId};
use mapc_sim::{LaneRef, Simulation, VehicleId};
use std::collections::HashMap;
use std::io::Write;

/// A polyline with the lane length it stands for.
#[derive(Clone, Debug)]
pub struct LaneGeometry {
    points: Vec<[f64; 2]>,
    /// Distance along the polyline to each point.
    along: Vec<f64>,
    /// The polyline's length over the lane's (SUMO's `myLengthGeometryFactor`).
    factor: f64,
    length_m: f64,
}

impl LaneGeometry {
    /// `points` (at least one) standing for a lane `length_m` long.
    pub fn new(points: Vec<[f64; 2]>, length_m: f64) -> LaneGeometry {
        let mut along = Vec::with_capacity(points.len());
        let mut seen = 0.0;
        for (i, p) in points.iter().enumerate() {
            if i > 0 {
                let q = points[i - 1];
                seen += (p[0] - q[0]).hypot(p[1] - q[1]);
            }
            along.push(seen);
        }
        let factor = if length_m > 0.0 && seen > 0.0 {
            seen / length_m
        } else {
            1.0
        };
        LaneGeometry {
            points,
            along,
            factor,
            length_m,
        }
    }

    /// The lane's length (m), as lane positions count it.
    pub fn length_m(&self) -> f64 {
        self.length_m
    }

    /// The point at lane position `pos`: on the shape, its last point beyond its end (SUMO's
    /// `geometryPositionAtOffset`); `None` before the start, where SUMO's is invalid.
    pub fn point_at(&self, pos: f64) -> Option<[f64; 2]> {
        let offset = pos * self.factor;
        if offset < 0.0 {
            return None;
        }
        let last = *self.points.last()?;
        for i in 1..self.points.len() {
            if self.along[i] > offset {
                let (a, b) = (self.points[i - 1], self.points[i]);
                let t = (offset - self.along[i - 1]) / (self.along[i] - self.along[i - 1]);
                return Some([a[0] + (b[0] - a[0]) * t, a[1] + (b[1] - a[1]) * t]);
            }
        }
        Some(last)
    }

    /// The direction of the segment at lane position `pos` (radians, counter-clockwise from east).
    fn rotation_at(&self, pos: f64) -> f64 {
        let offset = pos * self.factor;
        let n = self.points.len();
        if n < 2 {
            return 0.0;
        }
        let i = (1..n).find(|&i| self.along[i] > offset).unwrap_or(n - 1);
        let (a, b) = (self.points[i - 1], self.points[i]);
        (b[1] - a[1]).atan2(b[0] - a[0])
    }

    /// Where a vehicle with its front at `pos` and `length` long is drawn: its front's point and its angle in
    /// navigation degrees, from the back's point on the lane, or the lane's start where the back is behind it
    /// (SUMO's `computeAngle` without the lanes behind).
    pub fn place(&self, pos: f64, length: f64) -> Option<([f64; 2], f64)> {
        let front = self.point_at(pos)?;
        let back = self.point_at(pos - length).or_else(|| self.point_at(0.0))?;
        Some((front, self.heading(pos, front, back)))
    }

    /// SUMO's angle of a vehicle with its front at `pos` (`front`) and its back at `back`: the line between them
    /// in navigation degrees, the lane's own direction where they coincide.
    fn heading(&self, pos: f64, front: [f64; 2], back: [f64; 2]) -> f64 {
        navi_degree(if front != back {
            (front[1] - back[1]).atan2(front[0] - back[0])
        } else {
            self.rotation_at(pos)
        })
    }
}

/// SUMO's `GeomHelper::naviDegree`: radians counter-clockwise from east to degrees clockwise from north, in
/// [0, 360).
pub fn navi_degree(angle: f64) -> f64 {
    let mut d = (std::f64::consts::FRAC_PI_2 - angle).to_degrees();
    while d < 0.0 {
        d += 360.0;
    }
    while d >= 360.0 {
        d -= 360.0;
    }
    d
}

/// A junction connection by its lanes: (from road, from lane, to road, to lane).
type ConnectionKey = (RoadId, u8, RoadId, u8);

/// A lane as the file names and draws it.
#[derive(Debug)]
struct Drawn {
    geometry: LaneGeometry,
    /// SUMO's lane id.
    name: String,
}

/// The floating-car data of one run, written step by step.
#[derive(Debug, Default)]
pub struct FcdOutput {
    lanes: HashMap<(RoadId, u8), Drawn>,
    /// A junction connection's internal lanes, each with its start along the connection.
    vias: HashMap<ConnectionKey, Vec<(f64, Drawn)>>,
    names: HashMap<VehicleId, String>,
    rows: Vec<(String, String)>,
    begin_s: f64,
}

impl FcdOutput {
    /// The output of `sim`'s run, before its first step (which it asks to keep its vehicles' origins, for their
    /// names).
    pub fn new(sim: &mut Simulation) -> FcdOutput {
        sim.record_origins();
        let g = &sim.spec().graph;
        let mut lanes = HashMap::new();
        for road in &g.roads {
            for (k, lane) in road.lanes.iter().enumerate() {
                let shape = if lane.shape.len() >= 2 {
                    lane.shape.clone()
                } else {
                    crate::net::lane_shape(road, k)
                };
                let drawn = Drawn {
                    geometry: LaneGeometry::new(shape, lane.length_m),
                    name: lane_name(g, road.id, k as u8),
                };
                lanes.insert((road.id, k as u8), drawn);
            }
        }
        // a connection without internal lanes of its own is named as `mapc export --sumo` names it
        let grouping = if sim.spec().sumo_junction_lane_changes {
            InternalEdges::SideBySide
        } else {
            InternalEdges::PerConnection
        };
        let exported: HashMap<ConnectionLanes, String> =
            links_by_junction(g, &SumoNames::of(g), grouping)
                .into_values()
                .flatten()
                .map(|l| (l.connection.lanes(), l.via()))
                .collect();
        let mut vias = HashMap::new();
        for c in &g.connections {
            let (Some(from), Some(to)) = (
                lanes.get(&(c.from_road, c.from_lane)),
                lanes.get(&(c.to_road, c.to_lane)),
            ) else {
                continue;
            };
            let drawn_inside =
                !c.via_lanes.is_empty() && c.via_lanes.iter().all(|l| l.shape.len() >= 2);
            let parts: Vec<(f64, Drawn)> = if drawn_inside {
                let mut start = 0.0;
                c.via_lanes
                    .iter()
                    .map(|l| {
                        let geometry = LaneGeometry::new(l.shape.clone(), l.length_m);
                        let part = (
                            start,
                            Drawn {
                                geometry,
                                name: l.id.clone(),
                            },
                        );
                        start += l.length_m;
                        part
                    })
                    .collect()
            } else {
                // the straight line from the lane it leaves to the lane it enters, as the export draws it
                let (Some(&a), Some(&b)) =
                    (from.geometry.points.last(), to.geometry.points.first())
                else {
                    continue;
                };
                let Some(name) = exported.get(&c.lanes()) else {
                    continue;
                };
                let geometry = LaneGeometry::new(vec![a, b], c.via_length_m);
                vec![(
                    0.0,
                    Drawn {
                        geometry,
                        name: name.clone(),
                    },
                )]
            };
            vias.insert((c.from_road, c.from_lane, c.to_road, c.to_lane), parts);
        }
        FcdOutput {
            lanes,
            vias,
            begin_s: sim.time_s(),
            ..FcdOutput::default()
        }
    }

    /// The lane that position `at` of `place` lies on (on a connection, the internal lane it has reached) and the
    /// position on it.
    fn locate(&self, place: LaneRef, at: f64) -> Option<(&Drawn, f64)> {
        match place {
            LaneRef::Road { road, lane } => Some((self.lanes.get(&(road, lane))?, at)),
            LaneRef::Via { from, to } => {
                let parts = self.vias.get(&(from.0, from.1, to.0, to.1))?;
                let (start, drawn) = parts
                    .iter()
                    .rev()
                    .find(|(start, _)| *start <= at)
                    .or(parts.first())?;
                Some((drawn, at - start))
            }
        }
    }

    /// The geometry of lane `lane` of road `road`.
    pub fn lane_geometry(&self, road: RoadId, lane: u8) -> Option<&LaneGeometry> {
        self.lanes.get(&(road, lane)).map(|d| &d.geometry)
    }

    /// The geometry of the internal lane written as SUMO lane `name`.
    pub fn via_geometry(&self, name: &str) -> Option<&LaneGeometry> {
        self.vias
            .values()
            .flatten()
            .find(|(_, d)| d.name == name)
            .map(|(_, d)| &d.geometry)
    }

    /// The file's start: SUMO's XML declaration and root element.
    pub fn start(&self, out: &mut impl Write) -> std::io::Result<()> {
        writeln!(out, "<?xml version=\"1.0\" encoding=\"UTF-8\"?>\n")?;
        writeln!(
            out,
            "<fcd-export xmlns:xsi=\"http://www.w3.org/2001/XMLSchema-instance\" \
             xsi:noNamespaceSchemaLocation=\"http://sumo.dlr.de/xsd/fcd_file.xsd\">"
        )
    }

    /// The step `sim` just made: the vehicles on the network after it, stamped with the step's begin on SUMO's
    /// clock (as SUMO stamps the state after a step).
    pub fn observe(&mut self, sim: &Simulation, out: &mut impl Write) -> std::io::Result<()> {
        let stamp = sim.time_s() - self.begin_s - sim.step_s() + sim.spec().clock_begin_s;
        for &id in sim.arrived_last_step() {
            self.names.remove(&id);
        }
        self.rows.clear();
        for id in sim.active_ids() {
            let Some(v) = sim.vehicle(id) else { continue };
            let Some((drawn, pos)) = self.locate(v.place, v.pos_m) else {
                continue;
            };
            let Some(front) = drawn.geometry.point_at(pos) else {
                continue;
            };
            // the back: on its lane, else where the route says it lies behind (SUMO's farthest lane behind), else
            // the lane's start (SUMO's, where the back reaches out of the network)
            let back_at = if v.pos_m >= v.length {
                Some((v.place, v.pos_m - v.length))
            } else {
                sim.back_place(id)
            };
            let back = back_at
                .and_then(|(place, at)| self.locate(place, at))
                .and_then(|(d, at)| d.geometry.point_at(at))
                .or_else(|| drawn.geometry.point_at(0.0))
                .unwrap_or(front);
            let [x, y] = front;
            let angle = drawn.geometry.heading(pos, front, back);
            let lane = xml_escape(&drawn.name);
            let name = self
                .names
                .entry(id)
                .or_insert_with(|| vehicle_name(sim, id))
                .clone();
            let row = format!(
                "        <vehicle id=\"{}\" x=\"{x:.2}\" y=\"{y:.2}\" angle=\"{angle:.2}\" type=\"{}\" speed=\"{:.2}\" \
                 pos=\"{:.2}\" lane=\"{}\" slope=\"0.00\"/>",
                xml_escape(&name),
                xml_escape(v.vehicle_type),
                v.speed,
                pos,
                lane,
            );
            self.rows.push((name, row));
        }
        // SUMO's vehicle table is ordered by id
        self.rows.sort_unstable_by(|a, b| a.0.cmp(&b.0));
        if self.rows.is_empty() {
            return writeln!(out, "    <timestep time=\"{stamp:.2}\"/>");
        }
        writeln!(out, "    <timestep time=\"{stamp:.2}\">")?;
        for (_, row) in &self.rows {
            writeln!(out, "{row}")?;
        }
        writeln!(out, "    </timestep>")
    }

    /// The file's end.
    pub fn finish(&self, out: &mut impl Write) -> std::io::Result<()> {
        writeln!(out, "</fcd-export>")
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_lane_position_is_scaled_to_the_shape_as_sumo_scales_it() {
        // highway_ramp's M1_0: 192.91 m of lane drawn 185.70 m long; SUMO 1.8's FCD has pos 4.60 at x 104.43
        let m1 = LaneGeometry::new(vec![[100.0, 95.2], [285.7, 95.2]], 192.91);
        let ([x, y], angle) = m1.place(4.60, 5.0).unwrap();
        assert_eq!(format!("{x:.2} {y:.2} {angle:.2}"), "104.43 95.20 90.00");
        // its on-ramp onr_0 climbs at 26.57 degrees: SUMO's x 104.80, y 0.61, angle 63.43
        let onr = LaneGeometry::new(vec![[100.72, -1.43], [285.90, 91.16]], 208.89);
        let ([x, y], angle) = onr.place(4.60, 5.0).unwrap();
        assert_eq!(format!("{x:.2} {y:.2} {angle:.2}"), "104.80 0.61 63.43");
    }

    #[test]
    fn beyond_the_end_is_the_last_point_and_before_the_start_is_none() {
        let g = LaneGeometry::new(vec![[0.0, 0.0], [10.0, 0.0], [10.0, 10.0]], 20.0);
        assert_eq!(g.point_at(25.0), Some([10.0, 10.0]));
        assert_eq!(g.point_at(15.0), Some([10.0, 5.0]));
        assert_eq!(g.point_at(-0.1), None);
        // a vehicle straddling the corner points from its back on the first leg to its front on the second
        let (front, angle) = g.place(15.0, 10.0).unwrap();
        assert_eq!(front, [10.0, 5.0]);
        assert!((angle - 45.0).abs() < 1e-9, "{angle}");
    }

    #[test]
    fn navigation_degrees_turn_clockwise_from_north() {
        assert_eq!(navi_degree(std::f64::consts::FRAC_PI_2), 0.0);
        assert_eq!(navi_degree(0.0), 90.0);
        assert_eq!(navi_degree(std::f64::consts::PI), 270.0);
        assert_eq!(navi_degree(-std::f64::consts::FRAC_PI_2), 180.0);
    }
}
