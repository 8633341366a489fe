//! Bit-for-bit checks of the hot loop's shortcuts.

use super::step::moves::exact_reciprocal;
use super::step::planning::LazyPassSpeed;
use super::*;

#[test]
fn division_by_the_step_is_division_bit_for_bit() {
    let mut state = 0x9e37_79b9_7f4a_7c15u64;
    let mut next = || {
        state ^= state << 13;
        state ^= state >> 7;
        state ^= state << 17;
        state
    };
    let steps = [
        0.5,
        0.25,
        1.0,
        2.0,
        0.125,
        0.1,
        0.3,
        0.75,
        1.5,
        f64::MIN_POSITIVE,
        5e-324,
    ];
    // the shortcut applies to the steps people use, not to the others
    assert!(
        [0.5, 0.25, 1.0, 2.0]
            .iter()
            .all(|&d| exact_reciprocal(d).is_some())
    );
    assert!(
        [0.1, 0.3, 0.75, 5e-324]
            .iter()
            .all(|&d| exact_reciprocal(d).is_none())
    );
    for &dt in &steps {
        for _ in 0..20_000 {
            // any finite f64, subnormals and huge values included, and ordinary gaps
            let raw = f64::from_bits(next());
            let x = if raw.is_finite() { raw } else { 1.0 };
            let gap = (next() >> 11) as f64 / (1u64 << 53) as f64 * 400.0 - 5.0;
            for v in [x, gap, 0.0, -0.0] {
                assert_eq!(
                    exact_reciprocal(dt).map_or(v / dt, |r| v * r).to_bits(),
                    (v / dt).to_bits(),
                    "{v} / {dt}"
                );
            }
        }
    }
}

#[test]
fn lazy_pass_speed_is_the_eager_chain_bit_for_bit() {
    // the eager chain: root, then cap, then every leader, each with fmin; ties and signed zeros included
    let mut rng = StdRng::seed_from_u64(7);
    let pick = |rng: &mut StdRng| -> f64 {
        match rng.random_range(0..6) {
            0 => 0.0,
            1 => -0.0,
            2 => 5.0,
            3 => f64::INFINITY,
            _ => rng.random_range(-1.0..30.0),
        }
    };
    for _ in 0..20_000 {
        let (dist, speed) = (rng.random_range(0.0..200.0), pick(&mut rng).abs());
        let (accel, cap) = (2.6, pick(&mut rng));
        let leaders: Vec<f64> = (0..rng.random_range(0..5))
            .map(|_| pick(&mut rng))
            .collect();
        let mut eager = kinematics::speed_after_distance(dist, speed, accel).fmin(cap);
        let mut lazy = LazyPassSpeed::new(dist, speed, accel, cap);
        for &v in &leaders {
            eager = eager.fmin(v);
            lazy.lower(v);
        }
        assert_eq!(
            lazy.get().to_bits(),
            eager.to_bits(),
            "{dist} {speed} {cap} {leaders:?}"
        );
    }
}

#[test]
fn brake_gap_bound_lies_above_the_exact_gap() {
    for (decel, dt) in [(4.5, 0.5), (4.5, 0.1), (1.0, 1.0), (7.5, 0.2), (3.0, 2.0)] {
        let p = CfModel::idm(IdmParams::new(2.6, decel, 9.0, 1.0, 2.5, 4.0, dt));
        let tc = TypeConsts {
            max_speed: 30.0,
            max_brake_dist: 0.0,
            impatience: 0.5,
            max_arrival_from_visibility: 0.0,
            inv_two_decel: Some(0.5 / p.decel),
        };
        for i in 0..200_000 {
            let v = i as f64 * 0.000_37;
            for h in [0.0, 1.0, 1.6] {
                let exact = p.brake_gap(v, p.decel, h);
                assert!(tc.brake_gap_above(v, h) > exact, "v {v} h {h}: {exact}");
            }
        }
    }
}
