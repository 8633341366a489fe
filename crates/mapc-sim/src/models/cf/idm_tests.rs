//! IDM as SUMO 1.8 computes it, against a reference implementation and by hand:
//! the next speed (one call and four at once), sub-steps, following, stop, brake gap, arrival and insertion speeds.

use super::*;
use crate::models::cf::kinematics;

fn paper() -> IdmParams {
    IdmParams::new(2.6, 4.5, 9.0, 1.0, 2.5, 4.0, 0.5)
}

/// `next_speed` as first written (a division by the sub-step count every time).
fn next_speed_reference(
    p: &IdmParams,
    gap: f64,
    speed: f64,
    leader: f64,
    des: f64,
    mg: bool,
) -> f64 {
    let n = p.iterations as f64;
    let two_sqrt_ab = 2.0 * (p.accel * p.decel).sqrt();
    let des = des.max(NUMERICAL_EPS);
    let mut v = speed;
    let mut g = if mg { gap + p.min_gap } else { gap };
    for _ in 0..p.iterations {
        let dv = v - leader;
        let mut s = (v * p.tau + v * dv / two_sqrt_ab).max(0.0);
        if mg {
            s += p.min_gap;
        }
        g = g.max(NUMERICAL_EPS);
        let acc = p.accel * (1.0 - p.speed_ratio_pow(v / des) - (s * s) / (g * g));
        v = (v + acc * p.dt / n).max(0.0);
        g -= ((v - leader) * p.dt / n).max(0.0);
    }
    v.max(0.0)
}

/// A deterministic stream of uniform numbers in [0, 1) (xorshift), for the bit-for-bit comparisons.
fn uniform_stream(mut state: u64) -> impl FnMut() -> f64 {
    move || {
        state ^= state << 13;
        state ^= state >> 7;
        state ^= state << 17;
        (state >> 11) as f64 / (1u64 << 53) as f64
    }
}

#[test]
fn next_speed_is_bit_identical_to_the_reference() {
    let mut unit = uniform_stream(0x2545_f491_4f6c_dd1d);
    for dt in [0.1, 0.5, 0.75, 1.0, 1.5, 2.0] {
        let p = IdmParams::new(2.6, 4.5, 9.0, 1.0, 2.5, 4.0, dt);
        for _ in 0..20_000 {
            let (gap, v, l, des) = (
                unit() * 200.0 - 5.0,
                unit() * 35.0,
                unit() * 35.0,
                unit() * 40.0,
            );
            for mg in [false, true] {
                assert_eq!(
                    p.next_speed(gap, v, l, des, mg).to_bits(),
                    next_speed_reference(&p, gap, v, l, des, mg).to_bits(),
                    "dt {dt} gap {gap} v {v} l {l} des {des}"
                );
            }
        }
    }
}

#[test]
fn four_calls_at_once_are_four_calls_bit_for_bit() {
    let mut unit = uniform_stream(0x1234_5678_9abc_def1);
    // 0.5 s (two sub-steps), 0.25, 1.0, an odd count (scalar path) and delta != 4 (scalar path)
    let mut params: Vec<IdmParams> = [0.25, 0.5, 0.75, 1.0]
        .iter()
        .map(|&dt| IdmParams::new(2.6, 4.5, 9.0, 1.0, 2.5, 4.0, dt))
        .collect();
    params.push(IdmParams::new(1.0, 1.5, 9.0, 1.5, 2.0, 3.0, 0.5));
    for p in params {
        for _ in 0..20_000 {
            let speed = unit() * 35.0;
            let des = unit() * 40.0 - 1.0;
            let mut gap = [0.0; 4];
            let mut leader = [0.0; 4];
            let mut mg = [false; 4];
            for i in 0..4 {
                gap[i] = match (unit() * 4.0) as u32 {
                    0 => 1e6,
                    1 => -unit() * 3.0,
                    _ => unit() * 200.0,
                };
                leader[i] = unit() * 35.0;
                mg[i] = unit() < 0.5;
            }
            let got = p.next_speed_x4(gap, speed, leader, des, mg);
            for i in 0..4 {
                let want = p.next_speed(gap[i], speed, leader[i], des, mg[i]);
                assert_eq!(
                    got[i].to_bits(),
                    want.to_bits(),
                    "lane {i}: gap {} v {speed} l {} des {des} mg {}",
                    gap[i],
                    leader[i],
                    mg[i]
                );
            }
        }
    }
}

#[test]
fn sub_steps_follow_sumo_rule() {
    assert_eq!(paper().iterations, 2);
    assert_eq!(
        IdmParams::new(2.6, 4.5, 9.0, 1.0, 2.5, 4.0, 0.1).iterations,
        1
    );
    assert_eq!(
        IdmParams::new(2.6, 4.5, 9.0, 1.0, 2.5, 4.0, 1.0).iterations,
        4
    );
}

#[test]
fn free_acceleration_from_standstill_is_accel_times_dt() {
    // v = 0: no interaction term, (v/v0)^4 = 0, so each sub-step adds a * dt / 2.
    let p = paper();
    let v = p.next_speed(1e6, 0.0, 30.0, 30.0, false);
    // second sub-step: v = 0.65, (0.65/30)^4 ~ 2.2e-7 -> acc ~ 2.6
    let expected = 0.65 + 0.25 * 2.6 * (1.0 - (0.65f64 / 30.0).powi(4));
    assert!((v - expected).abs() < 1e-12, "{v} vs {expected}");
}

#[test]
fn following_matches_hand_computation() {
    // v = 10, leader 10, gap 20 (bumper gap minus s0): s* = 2.5 + 10 = 12.5, gap' = 22.5.
    let p = paper();
    let s1: f64 = 12.5;
    let g1: f64 = 22.5;
    let acc1 = 2.6 * (1.0 - (10.0f64 / 30.0).powi(4) - (s1 * s1) / (g1 * g1));
    let v1 = 10.0 + acc1 * 0.25;
    let g2 = g1 - ((v1 - 10.0) * 0.25f64).max(0.0);
    let s2 = 2.5 + (v1 * 1.0 + v1 * (v1 - 10.0) / (2.0 * (2.6f64 * 4.5).sqrt())).max(0.0);
    let acc2 = 2.6 * (1.0 - (v1 / 30.0).powi(4) - (s2 * s2) / (g2 * g2));
    let v2 = v1 + acc2 * 0.25;
    let got = p.follow_speed(20.0, 10.0, 10.0, 30.0);
    assert!((got - v2).abs() < 1e-12, "{got} vs {v2}");
}

#[test]
fn stop_speed_brakes_for_a_near_stop_line_and_is_zero_at_it() {
    let p = paper();
    assert_eq!(p.stop_speed(0.005, 5.0, 30.0), 0.0);
    let v = p.stop_speed(10.0, 10.0, 30.0);
    assert!(v < 10.0 - 2.0, "must brake hard: {v}");
    // from standstill close to the line IDM alone would not move; the kinematic bound lets it creep.
    assert!(p.stop_speed(3.0, 0.0, 30.0) > 0.0);
}

#[test]
fn brake_gap_and_safe_stop_speed_are_consistent() {
    let p = paper();
    // from 9 m/s braking 2.25 m/s per step: 6.75, 4.5, 2.25, 0 -> distance 0.5 * (6.75+4.5+2.25) = 6.75
    assert!((p.brake_gap(9.0, 4.5, 0.0) - 6.75).abs() < 1e-9);
    for gap in [1.0, 5.0, 6.75, 20.0, 100.0] {
        let v = p.maximum_safe_stop_speed(gap, 0.0);
        assert!(p.brake_gap(v, 4.5, 0.0) <= gap + 1e-6, "gap {gap}: v {v}");
        // driving at v now and braking by b per step covers exactly the gap
        let b = 4.5 * 0.5;
        let (mut x, mut d) = (v, 0.0);
        while x > 1e-9 {
            d += x * 0.5;
            x -= b;
        }
        assert!(
            (d - (gap - NUMERICAL_EPS)).abs() < 1e-6,
            "gap {gap}: v {v} covers {d}"
        );
    }
}

#[test]
fn arrival_time_accelerating_and_cruising() {
    let p = paper();
    // at 10 m/s cruising 100 m: 10 s
    assert!(
        (kinematics::minimal_arrival_time(p.accel, p.decel, 100.0, 10.0, 10.0) - 10.0).abs() < 1e-9
    );
    // 0 -> 2.6 m/s takes 1 s and 1.3 m, then 8.7 m at 2.6 m/s
    let t = kinematics::minimal_arrival_time(p.accel, p.decel, 10.0, 0.0, 2.6);
    assert!((t - (1.0 + 8.7 / 2.6)).abs() < 1e-9, "{t}");
}

#[test]
fn insertion_speed_kept_when_gap_suffices() {
    let p = paper();
    assert_eq!(p.insertion_follow_speed(10.0, 50.0, 10.0, 30.0), 10.0);
    assert!(p.insertion_follow_speed(10.0, 5.0, 0.0, 30.0) < 10.0);
}
