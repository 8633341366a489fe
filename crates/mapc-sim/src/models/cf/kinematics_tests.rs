use super::*;
use crate::models::cf::Krauss;

/// The bound's promise, over speeds, gaps, headways, decelerations and steps alike: where it says a driver
/// surely stops, the safe stop speed of that gap is at least its speed; and it says so for most gaps more than a
/// few metres beyond the braking distance (it is not a bound that never fires).
#[test]
fn surely_stops_within_never_overstates_and_mostly_fires() {
    let (mut fired, mut truly) = (0u64, 0u64);
    for &dt in &[0.1, 0.5, 1.0] {
        for &decel in &[1.0, 3.5, 4.5, 7.5] {
            for &tau in &[0.0, 0.5, 1.0, 1.6] {
                let k = Krauss {
                    accel: 2.6,
                    decel,
                    emergency_decel: 9.0,
                    tau,
                    sigma: 0.5,
                    max_speed: 50.0,
                    dt,
                };
                for si in 0..=120 {
                    let speed = si as f64 * 0.37;
                    for gi in 0..=400 {
                        let gap = gi as f64 * 0.61;
                        let safe = k.maximum_safe_stop_speed(gap, tau);
                        truly += (safe >= speed) as u64;
                        if surely_stops_within(tau, decel, gap, speed) {
                            fired += 1;
                            assert!(
                                safe >= speed,
                                "dt {dt} decel {decel} tau {tau} v {speed} gap {gap}: {safe}"
                            );
                        }
                    }
                }
            }
        }
    }
    // (the cases it leaves to the exact computation lie within about a metre of the braking distance)
    assert!(fired * 10 >= truly * 9, "fired {fired} of {truly}");
}
