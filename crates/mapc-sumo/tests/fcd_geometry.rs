//! The floating-car data's positions against SUMO 1.8's own on a SUMO user's network with real curves
//! (eccles_interchange): each of SUMO's recorded (lane, position) is placed with mapc's lane geometry and compared
//! with SUMO's x, y and angle.

use mapc_scenario::ResolvedScenario;
use mapc_sim::{Simulation, spec_from_scenario};
use mapc_sumo::fcd::FcdOutput;

fn percentile(mut xs: Vec<f64>, p: f64) -> f64 {
    xs.sort_by(f64::total_cmp);
    xs[((xs.len() - 1) as f64 * p).round() as usize]
}

#[test]
fn positions_on_eccles_interchange_lie_where_sumo_puts_them() {
    let root = concat!(env!("CARGO_MANIFEST_DIR"), "/../..");
    let rs = ResolvedScenario::load(&format!(
        "{root}/scenarios/sumo/eccles_interchange/interchangeSim.cfg"
    ))
    .unwrap();
    let mut sim = Simulation::from_spec(spec_from_scenario(&rs).unwrap(), 0).unwrap();
    let fcd = FcdOutput::new(&mut sim);
    let g = &sim.spec().graph;
    let sample = include_str!("data/eccles_fcd_sample.csv");
    let (mut lane_err, mut angle_err, mut via_err) = (Vec::new(), Vec::new(), Vec::new());
    let mut vias_unnamed = 0;
    for line in sample.lines().filter(|l| !l.starts_with('#')).skip(1) {
        let f: Vec<&str> = line.split(',').collect();
        let (lane, pos): (&str, f64) = (f[0], f[1].parse().unwrap());
        let (x, y, angle): (f64, f64, f64) = (
            f[2].parse().unwrap(),
            f[3].parse().unwrap(),
            f[4].parse().unwrap(),
        );
        let geometry = if lane.starts_with(':') {
            match fcd.via_geometry(lane) {
                Some(geometry) => geometry,
                None => {
                    // (an internal lane after the first of a connection's chain: mapc names the first)
                    vias_unnamed += 1;
                    continue;
                }
            }
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
        let ([gx, gy], gangle) = geometry.place(pos, 5.0).unwrap();
        let err = (gx - x).hypot(gy - y);
        if lane.starts_with(':') {
            via_err.push(err);
        } else {
            lane_err.push(err);
            // (behind the lane's start SUMO draws the back on the lane before, mapc at the lane's start)
            if pos >= 5.0 {
                let d = (gangle - angle).rem_euclid(360.0);
                angle_err.push(d.min(360.0 - d));
            }
        }
    }
    let largest = |xs: &[f64]| xs.iter().copied().fold(0.0, f64::max);
    let (lane_max, angle_max, via_max) =
        (largest(&lane_err), largest(&angle_err), largest(&via_err));
    eprintln!(
        "{} rows on lanes, {} on internal lanes ({vias_unnamed} after a chain's first); largest distance to SUMO's \
         point {lane_max:.4} m on lanes, {via_max:.4} m on internal lanes; largest angle difference {angle_max:.4} \
         degrees (median distance on lanes {:.4} m)",
        lane_err.len(),
        via_err.len(),
        percentile(lane_err.clone(), 0.5),
    );
    assert!(lane_err.len() > 900 && via_err.len() > 100 && angle_err.len() > 800);
    // SUMO writes two decimals: half a centimetre on each axis
    assert!(lane_max < 0.015 && via_max < 0.015, "{lane_max} {via_max}");
    assert!(angle_max < 0.02, "{angle_max}");
}
