//! The floating-car data's positions against SUMO 1.8's own: each of SUMO's recorded (lane, position) is placed
//! with mapc's lane geometry and compared with SUMO's x, y and angle, on a SUMO user's network with real curves
//! (eccles_interchange) and on one whose left turn crosses an internal junction (RESCO's ingolstadt1).

use mapc_scenario::ResolvedScenario;
use mapc_sim::{Simulation, spec_from_scenario};
use mapc_sumo::fcd::FcdOutput;

/// What SUMO's rows of `sample` (lane, pos, x, y, angle; vehicles `length` long) come to with mapc's geometry of
/// `cfg`: the largest distance to SUMO's point on lanes and on internal lanes, the largest angle difference (where
/// the back is on the same lane), and the rows of each kind.
fn against_sumo(cfg: &str, sample: &str, length: f64) -> (f64, f64, f64, [usize; 3]) {
    let root = concat!(env!("CARGO_MANIFEST_DIR"), "/../..");
    let rs = ResolvedScenario::load(&format!("{root}/scenarios/sumo/{cfg}")).unwrap();
    let mut sim = Simulation::from_spec(spec_from_scenario(&rs).unwrap(), 0).unwrap();
    let fcd = FcdOutput::new(&mut sim);
    let g = &sim.spec().graph;
    let (mut lane_err, mut angle_err, mut via_err) = (Vec::new(), Vec::new(), Vec::new());
    for line in sample.lines().filter(|l| !l.starts_with('#')).skip(1) {
        let f: Vec<&str> = line.split(',').collect();
        let num = |i: usize| -> f64 { f[i].parse().unwrap() };
        let (lane, pos, x, y, angle) = (f[0], num(1), num(2), num(3), num(4));
        let geometry = if lane.starts_with(':') {
            fcd.via_geometry(lane)
                .unwrap_or_else(|| panic!("no internal lane {lane}"))
        } else {
            let (edge, index) = lane.rsplit_once('_').unwrap();
            let road = g
                .roads
                .iter()
                .find(|r| r.provenance.sumo_ids.first().map(String::as_str) == Some(edge))
                .unwrap_or_else(|| panic!("no road for edge {edge}"));
            let k = road.lane_of_sumo_index(index.parse().unwrap()).unwrap();
            fcd.lane_geometry(road.id, k).unwrap()
        };
        let ([gx, gy], gangle) = geometry.place(pos, length).unwrap();
        let err = (gx - x).hypot(gy - y);
        if lane.starts_with(':') {
            via_err.push(err);
        } else {
            lane_err.push(err);
            // (behind the lane's start SUMO draws the back on the lane before, mapc at the lane's start)
            if pos >= length {
                let d = (gangle - angle).rem_euclid(360.0);
                angle_err.push(d.min(360.0 - d));
            }
        }
    }
    let largest = |xs: &[f64]| xs.iter().copied().fold(0.0, f64::max);
    (
        largest(&lane_err),
        largest(&via_err),
        largest(&angle_err),
        [lane_err.len(), via_err.len(), angle_err.len()],
    )
}

#[test]
fn positions_on_eccles_interchange_lie_where_sumo_puts_them() {
    let (lane_max, via_max, angle_max, rows) = against_sumo(
        "eccles_interchange/interchangeSim.cfg",
        include_str!("data/eccles_fcd_sample.csv"),
        5.0,
    );
    assert!(rows[0] > 900 && rows[1] > 100 && rows[2] > 800, "{rows:?}");
    // SUMO writes two decimals: half a centimetre on each axis
    assert!(lane_max < 0.015 && via_max < 0.015, "{lane_max} {via_max}");
    assert!(angle_max < 0.02, "{angle_max}");
}

#[test]
fn a_left_turn_across_an_internal_junction_is_on_the_internal_lane_sumo_names() {
    // ingolstadt1's left turn drives two internal lanes (:..._2_0, then :..._8_0 after its internal junction):
    // each of SUMO's rows is found on the lane it names, at its own position there
    let (_, via_max, _, rows) = against_sumo(
        "resco_ingolstadt1/ingolstadt1.sumocfg",
        include_str!("data/ingolstadt1_internal_fcd_sample.csv"),
        5.0,
    );
    assert!(rows[1] > 300, "{rows:?}");
    assert!(via_max < 0.015, "{via_max}");
}
