//! The fast helpers against the library, bit for bit.

use super::*;

#[test]
fn fast_min_max_agree_with_the_library() {
    let mut vals = vec![
        0.0,
        -0.0,
        1.0,
        -1.0,
        f64::INFINITY,
        f64::NEG_INFINITY,
        f64::MIN_POSITIVE,
        1e-300,
        30.0,
        NUMERICAL_EPS,
    ];
    let mut x = 0x9E37_79B9_7F4A_7C15u64;
    for _ in 0..2000 {
        x ^= x << 13;
        x ^= x >> 7;
        x ^= x << 17;
        vals.push((x >> 11) as f64 / (1u64 << 53) as f64 * 200.0 - 100.0);
    }
    for &a in &vals {
        for &b in vals.iter().take(200).chain([f64::NAN].iter()) {
            // equal as numbers (zeros of either sign); a NaN on the right is ignored by both
            assert_eq!(a.fmin(b), a.min(b), "min({a}, {b})");
            assert_eq!(a.fmax(b), a.max(b), "max({a}, {b})");
        }
    }
}

#[test]
fn floor_and_ceil_exact_are_the_library_bit_for_bit() {
    let mut xs = vec![
        0.0,
        -0.0,
        0.5,
        -0.5,
        1.0,
        -1.0,
        1.5,
        -1.5,
        2.0 - 1e-16,
        4.4e15,
        -4.4e15,
        1e300,
        -1e300,
    ];
    xs.extend([
        f64::NAN,
        f64::INFINITY,
        f64::NEG_INFINITY,
        f64::MIN_POSITIVE,
        -f64::MIN_POSITIVE,
    ]);
    xs.extend([
        4_503_599_627_370_495.5,
        -4_503_599_627_370_495.5,
        4_503_599_627_370_496.0,
    ]);
    let mut state = 0x9e37_79b9_7f4a_7c15u64;
    for _ in 0..100_000 {
        state ^= state << 13;
        state ^= state >> 7;
        state ^= state << 17;
        xs.push(f64::from_bits(state));
        xs.push((state % 2_000_000) as f64 / 997.0 - 1000.0);
    }
    // both ways, whichever the build takes: the instruction where the target has one, else the truncation
    for x in xs {
        for (floor, ceil) in [
            (floor_exact as fn(f64) -> f64, ceil_exact as fn(f64) -> f64),
            (floor_by_truncation, ceil_by_truncation),
        ] {
            assert_eq!(floor(x).to_bits(), x.floor().to_bits(), "{x:e}");
            assert_eq!(ceil(x).to_bits(), x.ceil().to_bits(), "ceil {x:e}");
            // the probabilities LC2013 rounds up (`x * 100000`), small ones included
            let p = x * 1e-9;
            assert_eq!(ceil(p).to_bits(), p.ceil().to_bits(), "ceil {p:e}");
        }
    }
}

#[test]
fn floor_near_is_the_exact_floor_bit_for_bit() {
    // quotients by a parameter, as the kinematics take them: by the reciprocal, and at and around integers
    let mut x = 0x2545_F491_4F6C_DD1Du64;
    let mut next = || {
        x ^= x << 13;
        x ^= x >> 7;
        x ^= x << 17;
        (x >> 11) as f64 / (1u64 << 53) as f64
    };
    for _ in 0..200_000 {
        let b = [0.45, 0.75, 0.9, 4.5 * 0.1, 2.5, 7.5 * 0.5, 9.0][(next() * 7.0) as usize];
        let a = match (next() * 3.0) as usize {
            0 => next() * 60.0,
            // exact multiples of the divisor and their neighbours
            1 => (next() * 100.0).floor() * b,
            _ => f64::from_bits(((next() * 100.0).floor() * b).to_bits() + 1),
        };
        let exact = (a / b).floor();
        assert_eq!(
            floor_near(a * (1.0 / b), || a / b).to_bits(),
            exact.to_bits(),
            "{a} / {b}"
        );
    }
}

#[test]
fn a_processor_without_x86_64_v2_is_told_what_it_lacks() {
    assert_eq!(cpu_lacks(|_| true), Ok(()));
    let e = cpu_lacks(|f| f != "sse4.1" && f != "popcnt").unwrap_err();
    assert!(e.contains("(sse4.1, popcnt)"), "{e}");
    assert!(e.contains("RUSTFLAGS=\"-C target-cpu=native\""), "{e}");
    // this machine runs the build that tests it
    assert_eq!(check_cpu(), Ok(()));
}
