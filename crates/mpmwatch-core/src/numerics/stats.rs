//! Order statistics and moments of a series: what "centred", "typical level" and "spread" mean
//! everywhere in the project.

/// The arithmetic mean; 0 for an empty series.
pub fn mean(x: &[f64]) -> f64 {
    x.iter().sum::<f64>() / x.len().max(1) as f64
}

/// The upper median (the middle value, the upper one of the two middle values for an even
/// length: always a sample of `x`, never an average); 0 for an empty series.
pub fn median(x: &[f64]) -> f64 {
    if x.is_empty() {
        return 0.0;
    }
    let mut v = x.to_vec();
    v.sort_by(f64::total_cmp);
    v[v.len() / 2]
}

/// The `q`-quantile by nearest rank (`q` clamped to [0, 1]); 0 for an empty series.
pub fn quantile(x: &[f64], q: f64) -> f64 {
    let mut v: Vec<f64> = x.to_vec();
    v.sort_by(f64::total_cmp);
    if v.is_empty() {
        return 0.0;
    }
    v[((v.len() - 1) as f64 * q.clamp(0.0, 1.0)).round() as usize]
}

/// Standard deviation with `ddof` degrees of freedom removed from the count (0: the
/// population form, 1: the sample form); 0 when `len ≤ ddof`.
pub fn std_dev(x: &[f64], ddof: usize) -> f64 {
    if x.len() <= ddof {
        return 0.0;
    }
    let m = mean(x);
    (x.iter().map(|v| (v - m).powi(2)).sum::<f64>() / (x.len() - ddof) as f64).sqrt()
}

/// Root mean square about zero; 0 for an empty series.
pub fn rms(x: &[f64]) -> f64 {
    (x.iter().map(|v| v * v).sum::<f64>() / x.len().max(1) as f64).sqrt()
}

/// `x` minus its mean (a level that moves with every sample).
pub fn minus_mean(x: &[f64]) -> Vec<f64> {
    let m = mean(x);
    x.iter().map(|v| v - m).collect()
}

/// `x` minus its [`median`] (a level a few outliers or a two-valued dither do not move).
pub fn minus_median(x: &[f64]) -> Vec<f64> {
    let m = median(x);
    x.iter().map(|v| v - m).collect()
}

/// `x(t − d)`, with the first value repeated before the record starts (a record that begins at
/// an operating point).
pub fn lagged(x: &[f64], d: usize) -> Vec<f64> {
    (0..x.len()).map(|t| if t >= d { x[t - d] } else { x[0] }).collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn std_dev_of_a_known_series() {
        // 2, 4, 4, 4, 5, 5, 7, 9: mean 5, squared deviations sum to 32.
        let x = [2.0, 4.0, 4.0, 4.0, 5.0, 5.0, 7.0, 9.0];
        assert!((std_dev(&x, 0) - 2.0).abs() < 1e-15);
        assert!((std_dev(&x, 1) - (32.0f64 / 7.0).sqrt()).abs() < 1e-15);
        assert_eq!(std_dev(&[3.0], 1), 0.0);
    }

    #[test]
    fn closed_forms() {
        let x = [3.0, 1.0, 4.0, 1.0, 5.0, 9.0];
        assert_eq!(mean(&x), 23.0 / 6.0);
        assert_eq!(median(&x), 4.0);
        assert_eq!(median(&[2.0, 1.0, 3.0]), 2.0);
        assert_eq!(quantile(&x, 0.0), 1.0);
        assert_eq!(quantile(&x, 1.0), 9.0);
        assert_eq!(quantile(&x, 0.5), 4.0);
        assert_eq!(rms(&[3.0, -4.0]), (12.5f64).sqrt());
        assert_eq!(minus_mean(&[1.0, 2.0, 6.0]), vec![-2.0, -1.0, 3.0]);
        assert_eq!(minus_median(&[1.0, 2.0, 6.0]), vec![-1.0, 0.0, 4.0]);
        assert_eq!(lagged(&[1.0, 2.0, 3.0], 2), vec![1.0, 1.0, 1.0]);
        assert_eq!(lagged(&[1.0, 2.0, 3.0, 4.0], 1), vec![1.0, 1.0, 2.0, 3.0]);
        assert_eq!((mean(&[]), median(&[]), quantile(&[], 0.3), rms(&[])), (0.0, 0.0, 0.0, 0.0));
    }
}
