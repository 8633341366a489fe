//! The floating-car data's positions against SUMO 1.8's own: each of SUMO's recorded (lane, position) is placed
//! with mapc's lane geometry and compared with SUMO's x, y and angle, on a SUMO user's network with real curves
//! (eccles_interchange) and on one whose left turn crosses an internal junction (RESCO's ingolstadt1).

use mapc_scenario::ResolvedScenario;
use mapc_sim::{Simulation, spec_from_scenario};
use mapc_sumo::fcd::FcdOutput;

/// What SUMO's rows of `sample` (lane, pos, x, y, angle, and the lane before where the back reaches it; vehicles
/// `length` long) come to with mapc's geometry of `cfg`: the largest distance to SUMO's point on lanes and on
/// internal lanes, the largest angle difference (the back on the same lane, or at its place on the lane before),
/// and the rows of each kind (on lanes, on internal lanes, with an angle, with the back on the lane before).
fn against_sumo(cfg: &str, sample: &str, length: f64) -> (f64, f64, f64, [usize; 4]) {
    let root = concat!(env!("CARGO_MANIFEST_DIR"), "/../..");
    let rs = ResolvedScenario::load(&format!("{root}/scenarios/sumo/{cfg}")).unwrap();
    let mut sim = Simulation::from_spec(spec_from_scenario(&rs).unwrap(), 0).unwrap();
    let fcd = FcdOutput::new(&mut sim);
    let g = &sim.spec().graph;
    let geometry_of = |lane: &str| {
        if lane.starts_with(':') {
            return fcd
                .via_geometry(lane)
                .unwrap_or_else(|| panic!("no internal lane {lane}"));
        }
        let (edge, index) = lane.rsplit_once('_').unwrap();
        let road = g
            .roads
            .iter()
            .find(|r| r.provenance.sumo_ids.first().map(String::as_str) == Some(edge))
            .unwrap_or_else(|| panic!("no road for edge {edge}"));
        let k = road.lane_of_sumo_index(index.parse().unwrap()).unwrap();
        fcd.lane_geometry(road.id, k).unwrap()
    };
    let (mut lane_err, mut angle_err, mut via_err) = (Vec::new(), Vec::new(), Vec::new());
    let mut behind_rows = 0;
    for line in sample.lines().filter(|l| !l.starts_with('#')).skip(1) {
        let f: Vec<&str> = line.split(',').collect();
        let num = |i: usize| -> f64 { f[i].parse().unwrap() };
        let (lane, pos, x, y, angle) = (f[0], num(1), num(2), num(3), num(4));
        let geometry = geometry_of(lane);
        let ([gx, gy], gangle) = geometry.place(pos, length).unwrap();
        let err = (gx - x).hypot(gy - y);
        let behind = f.get(5).copied().unwrap_or("");
        // a back on the lane before (SUMO's further lane): the angle from there
        let gangle = if pos < length && !behind.is_empty() {
            let before = geometry_of(behind);
            let at = before.length_m() - (length - pos);
            // (only a lane that ends where this one starts: in a step of 1 s a driver may cross a short internal
            // lane whole, and its back is then on that one)
            let joined = match (before.point_at(before.length_m()), geometry.point_at(0.0)) {
                (Some(a), Some(b)) => (a[0] - b[0]).hypot(a[1] - b[1]) < 0.1,
                _ => false,
            };
            match before.point_at(at) {
                Some(back) if at >= 0.0 && joined => {
                    behind_rows += 1;
                    mapc_sumo::fcd::navi_degree((gy - back[1]).atan2(gx - back[0]))
                }
                _ => f64::NAN,
            }
        } else if pos < length {
            f64::NAN
        } else {
            gangle
        };
        if lane.starts_with(':') {
            via_err.push(err);
        } else {
            lane_err.push(err);
        }
        if gangle.is_finite() {
            let d = (gangle - angle).rem_euclid(360.0);
            angle_err.push(d.min(360.0 - d));
        }
    }
    let largest = |xs: &[f64]| xs.iter().copied().fold(0.0, f64::max);
    (
        largest(&lane_err),
        largest(&via_err),
        largest(&angle_err),
        [lane_err.len(), via_err.len(), angle_err.len(), behind_rows],
    )
}

#[test]
fn positions_on_eccles_interchange_lie_where_sumo_puts_them() {
    let (lane_max, via_max, angle_max, rows) = against_sumo(
        "eccles_interchange/interchangeSim.cfg",
        include_str!("data/eccles_fcd_sample.csv"),
        5.0,
    );
    assert!(
        rows[0] > 900 && rows[1] > 100 && rows[2] > 1100 && rows[3] > 250,
        "{rows:?}"
    );
    // SUMO writes two decimals: half a centimetre on each axis
    assert!(lane_max < 0.015 && via_max < 0.015, "{lane_max} {via_max}");
    // (and its angles two decimals of degrees; a back on the lane before lies at most 5 m behind the front)
    assert!(angle_max < 0.05, "{angle_max}");
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
