//! Krauss against cases worked by hand from SUMO 1.8's formulas (step 1 s, decel 4.5, tau 1 unless said).

use super::*;

fn krauss(dt: f64) -> Krauss {
    Krauss {
        accel: 2.6,
        decel: 4.5,
        emergency_decel: 9.0,
        tau: 1.0,
        sigma: 0.5,
        max_speed: 55.55,
        dt,
    }
}

fn close(a: f64, b: f64, tol: f64) -> bool {
    (a - b).abs() <= tol
}

#[test]
fn brake_gap_is_the_discrete_sum_plus_the_reaction() {
    // n = floor(13.89 / 4.5) = 3 steps: 3 * 13.89 - 4.5 * 3 * 4 / 2 = 14.67, plus 13.89 m of reaction
    assert!(close(
        kinematics::brake_gap(1.0, 13.89, 4.5, 0.0),
        14.67,
        1e-9
    ));
    assert!(close(
        kinematics::brake_gap(1.0, 13.89, 4.5, 1.0),
        28.56,
        1e-9
    ));
}

#[test]
fn safe_stop_speed_with_a_reaction_time() {
    let k = krauss(1.0);
    // n = floor(1/2 + (sqrt(1 + 4 (2 g / 4.5 - 1 + 1)) / 2 - 1)), v = n 4.5 + (g - h) / (n + 1), g = gap - 0.001
    for (gap, v) in [
        (5.0, 4.7495),
        (10.0, 7.2495),
        (20.0, 11.1663),
        (50.0, 18.9998),
    ] {
        let got = k.maximum_safe_stop_speed(gap, 1.0);
        assert!(close(got, v, 1e-4), "gap {gap}: {got} against {v}");
    }
    assert_eq!(k.maximum_safe_stop_speed(0.0005, 1.0), 0.0);
}

#[test]
fn following_stops_within_the_gap_plus_the_leaders_braking() {
    let k = krauss(1.0);
    // leader at 10 m/s brakes in 2 steps over 6.5 m; stop within 26.5 m after 1 s: 9 + 12.999 / 3 = 13.333
    let x = k.maximum_safe_follow_speed(20.0, 13.0, 10.0, false);
    assert!(close(x, 13.3330, 1e-3), "{x}");
    // capped by one step of acceleration
    assert!(close(k.follow_speed(20.0, 10.0, 10.0, 30.0), 12.6, 1e-12));
}

#[test]
fn emergency_braking_brakes_only_as_hard_as_needed() {
    let k = krauss(1.0);
    // 20 m/s, 5 m behind a standing leader: the emergency deceleration (20^2 / 10 = 40, amplified) exceeds what
    // the safe stop speed asks, which stays
    let plain = k.maximum_safe_stop_speed(5.0, 1.0);
    assert!(close(
        k.maximum_safe_follow_speed(5.0, 20.0, 0.0, false),
        plain,
        1e-12
    ));
    // everywhere: never harder than the plain rule nor than needed, and off on insertion; somewhere it relents
    let mut relents = 0;
    for speed in (0..60).map(|i| i as f64 * 0.5) {
        for leader in (0..60).map(|i| i as f64 * 0.5) {
            for gap in (1..80).map(|i| i as f64 * 0.5) {
                let lb = kinematics::brake_gap(1.0, leader, 4.5, 0.0);
                let plain = k.maximum_safe_stop_speed(gap + lb, 1.0);
                let x = k.maximum_safe_follow_speed(gap, speed, leader, false);
                assert!(x >= plain - 1e-12, "{speed} {leader} {gap}: {x} < {plain}");
                if x > plain {
                    relents += 1;
                    // braking at least the comfortable deceleration, one step
                    assert!(x <= speed - 4.5 + 1e-9, "{speed} {leader} {gap}: {x}");
                }
                assert_eq!(k.maximum_safe_follow_speed(gap, speed, leader, true), plain);
            }
        }
    }
    assert!(relents > 100, "{relents}");
}

#[test]
fn stop_speed_reacts_within_one_step() {
    let k = krauss(1.0);
    assert!(close(
        k.stop_speed(20.0, 30.0, 30.0),
        k.maximum_safe_stop_speed(20.0, 1.0),
        1e-12
    ));
    assert!(close(k.stop_speed(1000.0, 10.0, 30.0), 12.6, 1e-12));
}

#[test]
fn free_speed_brakes_towards_a_lower_limit_ahead() {
    let k = krauss(1.0);
    // 30 m to a 5 m/s limit: y = 2.38, two full steps of 4.5, 1.5 m left over three steps: 14.5
    assert!(close(k.free_speed(20.0, 30.0, 5.0, 30.0), 14.5, 1e-9));
    // closer than one step at the limit: the limit itself
    assert_eq!(k.free_speed(20.0, 4.0, 5.0, 30.0), 5.0);
}

#[test]
fn secure_gap_is_own_braking_with_reaction_less_the_leaders() {
    let k = krauss(1.0);
    let g = k.secure_gap(13.89, 10.0);
    assert!(close(g, 28.56 - 6.5, 1e-9), "{g}");
    assert_eq!(k.secure_gap(0.0, 20.0), 0.0);
}

#[test]
fn dawdling_takes_up_to_sigma_of_one_steps_acceleration() {
    let k = krauss(0.5);
    // fast: 20 - 0.5 * 2.6 * 0.5 * r
    assert!(close(k.dawdled(20.0, 0.0), 20.0, 0.0));
    assert!(close(
        k.dawdled(20.0, 0.999),
        20.0 - 0.5 * 2.6 * 0.999 * 0.5,
        1e-12
    ));
    // below the acceleration (as numbers): a share of the speed itself, so a starting driver still starts
    assert!(close(
        k.dawdled(2.0, 0.5),
        2.0 - 0.5 * 2.0 * 0.5 * 0.5,
        1e-12
    ));
    // never below the lower bound of the step
    assert_eq!(k.dawdle(19.9, 20.0, 0.999), 19.9);
    let mut no_sigma = k;
    no_sigma.sigma = 0.0;
    assert_eq!(no_sigma.dawdled(20.0, 0.7), 20.0);
}

/// SUMO's formulas as written, with their divisions: the fast paths must give the same bits.
fn reference_follow_speed(k: &Krauss, gap: f64, speed: f64, leader_speed: f64, lc: bool) -> f64 {
    let brake_gap = |v: f64, decel: f64| {
        let red = decel * k.dt;
        let n = (v / red).floor();
        k.dt * (n * v - red * n * (n + 1.0) / 2.0)
    };
    let stop = |gap: f64| {
        let g = gap - NUMERICAL_EPS;
        if g <= 0.0 {
            return 0.0;
        }
        let (b, t, s) = (k.decel * k.dt, k.tau, k.dt);
        let n = (0.5 - (t + ((s * s) + 4.0 * ((s * (2.0 * g / b - t)) + t * t)).sqrt() * -0.5) / s)
            .floor();
        let h = 0.5 * n * (n - 1.0) * b * s + n * b * t;
        n * b + (g - h) / (n * s + t)
    };
    let mut x = stop(gap + brake_gap(leader_speed, k.decel));
    if !lc {
        let orig = (speed - x) / k.dt;
        if orig > k.decel + NUMERICAL_EPS {
            let lb = 0.5 * leader_speed * leader_speed / k.decel;
            let b1 = 0.5 * speed * speed / (gap + lb);
            let em = if b1 <= k.decel {
                b1
            } else if gap <= 0.0 {
                -(k.emergency_decel * k.dt)
            } else {
                0.5 * (speed * speed - leader_speed * leader_speed) / gap
            };
            x = (speed - (1.2 * em).max(k.decel).min(orig) * k.dt).max(0.0);
        }
    }
    x.min((speed + k.accel * k.dt).min(k.max_speed))
}

#[test]
fn fast_paths_give_the_formulas_bits() {
    let mut s = 0x9E37_79B9_7F4A_7C15u64;
    let mut next = || {
        s ^= s << 13;
        s ^= s >> 7;
        s ^= s << 17;
        (s >> 11) as f64 / (1u64 << 53) as f64
    };
    for dt in [1.0, 0.5, 0.1, 0.2] {
        let k = krauss(dt);
        for _ in 0..100_000 {
            let speed = next() * 35.0;
            let leader = if next() < 0.2 { 0.0 } else { next() * 35.0 };
            // gaps from overlapping to far, and speeds on the brake steps' boundaries
            let gap = next() * next() * 300.0 - 5.0;
            let leader = if next() < 0.1 {
                (leader / (k.decel * dt)).floor() * k.decel * dt
            } else {
                leader
            };
            for lc in [false, true] {
                let fast = if lc {
                    k.follow_speed_lc(gap, speed, leader, 30.0)
                } else {
                    k.follow_speed(gap, speed, leader, 30.0)
                };
                let reference = reference_follow_speed(&k, gap, speed, leader, lc);
                assert_eq!(
                    fast.to_bits(),
                    reference.to_bits(),
                    "gap {gap} speed {speed} leader {leader} dt {dt} lc {lc}"
                );
            }
        }
    }
}

/// Krauss models over steps, decelerations and headways: the grid the bounds' tests run over.
fn model_grid(taus: &[f64]) -> Vec<Krauss> {
    let mut out = Vec::new();
    for &dt in &[0.1, 0.5, 1.0] {
        for &decel in &[1.0, 3.5, 4.5, 7.5] {
            for &tau in taus {
                out.push(Krauss {
                    accel: 2.6,
                    decel,
                    emergency_decel: 9.0,
                    tau,
                    sigma: 0.5,
                    max_speed: 50.0,
                    dt,
                });
            }
        }
    }
    out
}

/// The stopping bound's promise (`kinematics::surely_stops_within`): where it says a driver surely stops, the
/// safe stop speed of that gap is at least its speed; and it decides most of the cases the exact speed allows
/// (it is not a bound that never fires).
#[test]
fn surely_stops_within_never_overstates_and_mostly_fires() {
    let (mut fired, mut truly) = (0u64, 0u64);
    for k in model_grid(&[0.0, 0.5, 1.0, 1.6]) {
        for si in 0..=120 {
            let speed = si as f64 * 0.37;
            for gi in 0..=400 {
                let gap = gi as f64 * 0.61;
                let safe = k.maximum_safe_stop_speed(gap, k.tau);
                truly += (safe >= speed) as u64;
                if super::kinematics::surely_stops_within(k.tau, k.decel, gap, speed) {
                    fired += 1;
                    assert!(safe >= speed, "{k:?} v {speed} gap {gap}: {safe}");
                }
            }
        }
    }
    // (the cases it leaves to the exact computation lie within about a metre of the braking distance)
    assert!(fired * 10 >= truly * 9, "fired {fired} of {truly}");
}

/// The open minor link's shortcut (`CarFollowModel::stop_speed_at_least`, read by the moves before they compute
/// the stop speed at the line): where it says the stop speed is at least `v`, the stop speed is; and it decides
/// most of the cases where the stop speed is.
#[test]
fn stop_speed_at_least_never_overstates_and_mostly_fires() {
    let (mut fired, mut truly) = (0u64, 0u64);
    for k in model_grid(&[1.0]) {
        for si in 0..=60 {
            let speed = si as f64 * 0.53;
            for gi in 0..=200 {
                let gap = gi as f64 * 0.83;
                let stop = k.stop_speed(gap, speed, 30.0);
                for vi in 0..=20 {
                    let v = vi as f64 * 1.1;
                    truly += (stop >= v) as u64;
                    if k.stop_speed_at_least(gap, speed, v) {
                        fired += 1;
                        assert!(stop >= v, "{k:?} speed {speed} gap {gap} v {v}: {stop}");
                    }
                }
            }
        }
    }
    assert!(fired * 10 >= truly * 7, "fired {fired} of {truly}");
}

/// The secure gap's bound never calls a gap secure that the exact check blocks, over speeds, decelerations,
/// headways, steps and safety factors; and it decides every gap beyond its slack.
#[test]
fn surely_secure_never_passes_a_blocked_gap() {
    let (mut decided, mut beyond) = (0u64, 0u64);
    for k in model_grid(&[0.0, 1.0, 1.6]) {
        for si in 0..=40 {
            let speed = si as f64 * 1.07;
            for li in 0..=40 {
                let leader = li as f64 * 1.07;
                for &factor in &[0.5, 1.0, 2.0] {
                    let secure = k.secure_gap(speed, leader) * factor;
                    for gi in 0..=150 {
                        let gap = gi as f64 * 1.3;
                        let sure = k.surely_secure(gap, speed, leader, factor);
                        assert!(
                            !sure || gap >= secure,
                            "{k:?} v {speed} leader {leader} factor {factor} gap {gap}: secure {secure}"
                        );
                        let slack = 0.5 * k.dt * (2.0 * k.decel * k.dt + speed + leader);
                        if gap > secure + factor * slack + 1e-3 {
                            beyond += 1;
                            decided += sure as u64;
                        }
                    }
                }
            }
        }
    }
    assert_eq!(
        decided, beyond,
        "gaps beyond the bound's slack left to the exact check"
    );
}

/// The least braking distance (`kinematics::brake_gap_at_least`) never exceeds Euler's, and the follow speed's
/// shortcut built on it (the gap plus that distance surely long enough to stop from the cap) never skips a case
/// whose exact safe follow speed lies below the cap; it also decides cases the gap alone leaves open (its
/// reason to be).
#[test]
fn the_leaders_least_braking_distance_never_overstates_and_the_shortcut_keeps_the_cap() {
    use super::kinematics::{brake_gap, brake_gap_at_least, surely_stops_within};
    let (mut by_leader, mut checked) = (0u64, 0u64);
    for k in model_grid(&[0.0, 1.0, 1.6]) {
        for li in 0..=60 {
            let leader = li as f64 * 0.83;
            let least = brake_gap_at_least(k.dt, leader, k.decel);
            assert!(
                least <= brake_gap(k.dt, leader, k.decel, 0.0),
                "{k:?} leader {leader}: {least}"
            );
            for si in 0..=40 {
                let speed = si as f64 * 1.09;
                let cap = (speed + k.accel * k.dt).min(k.max_speed);
                for gi in 0..=160 {
                    let gap = gi as f64 * 0.9;
                    if !surely_stops_within(k.tau, k.decel, gap + least, cap) {
                        continue;
                    }
                    checked += 1;
                    by_leader += !surely_stops_within(k.tau, k.decel, gap, cap) as u64;
                    for on_insertion in [false, true] {
                        let exact = k.maximum_safe_follow_speed(gap, speed, leader, on_insertion);
                        assert!(
                            exact >= cap,
                            "{k:?} gap {gap} v {speed} leader {leader}: {exact} < {cap}"
                        );
                    }
                }
            }
        }
    }
    assert!(by_leader * 5 >= checked, "{by_leader} of {checked}");
}

/// The lane changer's kept stop speed gives the plan the follow speed's bits behind the same gap and leader speed,
/// and is never taken for another: a share keyed on the gap alone would give the wrong speed behind a leader of
/// another speed (and fail the comparison below, or the debug check in the read).
#[test]
fn a_kept_stop_speed_is_taken_only_for_its_own_gap_and_leader_speed() {
    let mut kept = 0;
    for m in model_grid(&[0.5, 1.0, 1.5]) {
        for &gap in &[0.3, 2.0, 7.5, 20.0, 45.0] {
            for &leader in &[0.0, 3.0, 9.0, 17.0] {
                for &speed in &[1.0, 8.0, 16.0, 28.0] {
                    let mut share = StopShare::default();
                    let lc = m.follow_speed_sharing(&mut share, true, gap, speed, leader, 0.0);
                    assert_eq!(
                        lc.to_bits(),
                        m.follow_speed_lc(gap, speed, leader, 0.0).to_bits()
                    );
                    kept += share.get(gap, leader).is_some() as usize;
                    // the plan behind the same leader, and behind another leader speed or another gap
                    for (g, l) in [(gap, leader), (gap, leader + 2.0), (gap + 1.0, leader)] {
                        assert_eq!(
                            m.follow_speed_sharing(&mut share.clone(), false, g, speed, l, 0.0)
                                .to_bits(),
                            m.follow_speed(g, speed, l, 0.0).to_bits(),
                            "{m:?} gap {g} leader {l} speed {speed}"
                        );
                    }
                    // a second lane-change question behind the same leader reads it
                    assert_eq!(
                        m.follow_speed_sharing(&mut share, true, gap, speed + 1.0, leader, 0.0)
                            .to_bits(),
                        m.follow_speed_lc(gap, speed + 1.0, leader, 0.0).to_bits()
                    );
                }
            }
        }
    }
    // the exact follow speed ran (and its stop speed was kept) in a good share of the cases
    assert!(kept > 1000, "kept {kept}");
}
