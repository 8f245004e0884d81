//! Statistics over runs.

/// Nearest-rank quantile `q` in (0, 1] of values already sorted (NaN when empty).
pub fn quantile(sorted: &[f64], q: f64) -> f64 {
    if sorted.is_empty() {
        return f64::NAN;
    }
    let k = ((q * sorted.len() as f64).ceil() as usize).clamp(1, sorted.len()) - 1;
    sorted[k]
}

/// Nearest-rank quantile of `values`, sorting them in place.
pub fn quantile_of(values: &mut [f64], q: f64) -> f64 {
    values.sort_by(f64::total_cmp);
    quantile(values, q)
}

/// The Wilson score interval at 95 % (z = 1.96) of a fraction of `passed` successes in `n`
/// trials: (low, high), within [0, 1]; (0, 1) when there are no trials.
pub fn wilson(passed: u64, n: u64) -> (f64, f64) {
    if n == 0 {
        return (0.0, 1.0);
    }
    let (z, n) = (1.959_963_984_540_054, n as f64);
    let p = passed as f64 / n;
    let centre = p + z * z / (2.0 * n);
    let half = z * (p * (1.0 - p) / n + z * z / (4.0 * n * n)).sqrt();
    let d = 1.0 + z * z / n;
    // (None passed: 0 exactly; all: 1, not 1 − 1e-17.)
    let lo = if passed == 0 { 0.0 } else { ((centre - half) / d).clamp(0.0, 1.0) };
    let hi = if passed as f64 == n { 1.0 } else { ((centre + half) / d).clamp(0.0, 1.0) };
    (lo, hi)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn wilson_intervals() {
        // Known values: 0 of 10 → (0, 0.2775); 10 of 10 → (0.7225, 1); 50 of 100 → (0.4038, 0.5962).
        let close = |a: (f64, f64), b: (f64, f64)| (a.0 - b.0).abs() < 1e-4 && (a.1 - b.1).abs() < 1e-4;
        assert!(close(wilson(0, 10), (0.0, 0.2775)), "{:?}", wilson(0, 10));
        assert!(close(wilson(10, 10), (0.7225, 1.0)), "{:?}", wilson(10, 10));
        assert!(close(wilson(50, 100), (0.4038, 0.5962)), "{:?}", wilson(50, 100));
        assert_eq!(wilson(0, 0), (0.0, 1.0));
    }

    #[test]
    fn nearest_rank() {
        let mut v: Vec<f64> = (1..=100).rev().map(f64::from).collect();
        assert_eq!(quantile_of(&mut v, 0.99), 99.0);
        assert_eq!(quantile(&v, 0.5), 50.0);
        assert_eq!(quantile(&v, 0.05), 5.0);
        assert_eq!(quantile(&[3.0], 0.99), 3.0);
        assert!(quantile(&[], 0.5).is_nan());
    }
}
