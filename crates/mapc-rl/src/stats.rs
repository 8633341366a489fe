//! Welch's t-test (unequal variances) for comparing a policy with the human baseline.

use serde::{Deserialize, Serialize};
use statrs::distribution::{ContinuousCDF, StudentsT};

/// Result of a two-sided Welch t-test of `mean(a) - mean(b)`.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct WelchTest {
    pub t: f64,
    pub df: f64,
    pub p_value: f64,
}

fn mean_var(x: &[f64]) -> (f64, f64) {
    let n = x.len() as f64;
    let m = x.iter().sum::<f64>() / n;
    let v = x.iter().map(|v| (v - m).powi(2)).sum::<f64>() / (n - 1.0);
    (m, v)
}

/// Welch's t-test; `None` with fewer than two samples on a side or zero variance on both.
pub fn welch_t_test(a: &[f64], b: &[f64]) -> Option<WelchTest> {
    if a.len() < 2 || b.len() < 2 {
        return None;
    }
    let (ma, va) = mean_var(a);
    let (mb, vb) = mean_var(b);
    let (na, nb) = (a.len() as f64, b.len() as f64);
    let se2 = va / na + vb / nb;
    if se2 <= 0.0 {
        return None;
    }
    let t = (ma - mb) / se2.sqrt();
    let df = se2 * se2 / ((va / na).powi(2) / (na - 1.0) + (vb / nb).powi(2) / (nb - 1.0));
    let dist = StudentsT::new(0.0, 1.0, df).ok()?;
    let p_value = 2.0 * (1.0 - dist.cdf(t.abs()));
    Some(WelchTest { t, df, p_value })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn welch_by_hand() {
        // a: mean 2, var 1; b: mean 5, var 10/3 (n 3 and 4).
        // se2 = 1/3 + 10/12 = 1.166667; t = -3 / 1.080123 = -2.777460.
        // df = 1.361111 / ((1/3)^2/2 + (5/6)^2/3) = 1.361111 / 0.287037 = 4.741935.
        let w = welch_t_test(&[1.0, 2.0, 3.0], &[3.0, 4.0, 6.0, 7.0]).unwrap();
        assert!((w.t + 2.777460).abs() < 1e-5, "{w:?}");
        assert!((w.df - 4.741935).abs() < 1e-5, "{w:?}");
        // t = 2.776 is the 0.05 two-sided point at 4 df; with 4.74 df p is a little lower.
        assert!(w.p_value > 0.035 && w.p_value < 0.05, "{w:?}");
    }
}
