//! Statistics over the finished runs: percentiles, mean and standard deviation, and the
//! `summary.json` they go into.

/// The percentiles `summary.json` reports, in percent.
pub const PERCENTILES: [f64; 5] = [1.0, 5.0, 50.0, 95.0, 99.0];

/// The `p`-th percentile (`0 <= p <= 100`) of `sorted` (ascending, finite, non-empty), by
/// linear interpolation between the closest ranks: rank `h = (n - 1) p / 100`, value
/// `x[floor h] + (h - floor h) (x[floor h + 1] - x[floor h])` (NumPy's default, Hyndman and
/// Fan's type 7).
pub fn percentile(sorted: &[f64], p: f64) -> f64 {
    debug_assert!(!sorted.is_empty());
    let h = (sorted.len() - 1) as f64 * p / 100.0;
    let lo = h.floor() as usize;
    let hi = (lo + 1).min(sorted.len() - 1);
    let f = h - lo as f64;
    if f == 0.0 {
        sorted[lo]
    } else {
        sorted[lo] + f * (sorted[hi] - sorted[lo])
    }
}

/// One column's statistics over the finished runs.
#[derive(Clone, Debug, PartialEq)]
pub struct ColumnStats {
    /// p1, p5, p50, p95, p99 ([`PERCENTILES`]).
    pub percentiles: [f64; 5],
    /// Arithmetic mean.
    pub mean: f64,
    /// Sample standard deviation (divisor `n - 1`; 0 for one run).
    pub std: f64,
}

/// The statistics of `values` (finite), or `None` when empty. The sums run in the order
/// given (runs sorted by `k`), so the result does not depend on threads or shards.
pub fn column_stats(values: &[f64]) -> Option<ColumnStats> {
    if values.is_empty() {
        return None;
    }
    let n = values.len() as f64;
    let mean = values.iter().sum::<f64>() / n;
    let std = if values.len() > 1 {
        (values.iter().map(|x| (x - mean) * (x - mean)).sum::<f64>() / (n - 1.0)).sqrt()
    } else {
        0.0
    };
    let mut sorted = values.to_vec();
    sorted.sort_by(f64::total_cmp);
    Some(ColumnStats {
        percentiles: PERCENTILES.map(|p| percentile(&sorted, p)),
        mean,
        std,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn percentiles_interpolate_between_ranks() {
        let x = [1.0, 2.0, 3.0, 4.0, 5.0];
        assert_eq!(percentile(&x, 0.0), 1.0);
        assert_eq!(percentile(&x, 50.0), 3.0);
        assert_eq!(percentile(&x, 100.0), 5.0);
        assert_eq!(percentile(&x, 25.0), 2.0);
        assert!((percentile(&x, 10.0) - 1.4).abs() < 1e-15);
        assert_eq!(percentile(&[7.0], 99.0), 7.0);
    }

    #[test]
    fn mean_and_sample_std() {
        let s = column_stats(&[2.0, 4.0, 4.0, 4.0, 5.0, 5.0, 7.0, 9.0]).unwrap();
        assert_eq!(s.mean, 5.0);
        // Sum of squared deviations 32, n - 1 = 7.
        assert!((s.std - (32.0f64 / 7.0).sqrt()).abs() < 1e-15);
        assert_eq!(s.percentiles[2], 4.5);
        assert_eq!(column_stats(&[3.0]).unwrap().std, 0.0);
        assert!(column_stats(&[]).is_none());
    }
}
