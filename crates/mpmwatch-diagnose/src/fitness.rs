//! FIT% as MATLAB's `compare` reports it: `100·(1 − ‖y − ŷ‖ / ‖y − mean(y)‖)`.

/// FIT% of `yhat` against `y` (100 is perfect, 0 is no better than the mean, negative is worse).
/// A constant `y` gives 100 for an exact `yhat` and −∞ otherwise, as the formula says.
pub fn fit_pct(y: &[f64], yhat: &[f64]) -> f64 {
    let n = y.len().min(yhat.len());
    if n == 0 {
        return f64::NAN;
    }
    let mean = y[..n].iter().sum::<f64>() / n as f64;
    let num: f64 = y[..n].iter().zip(&yhat[..n]).map(|(a, b)| (a - b).powi(2)).sum::<f64>().sqrt();
    let den: f64 = y[..n].iter().map(|a| (a - mean).powi(2)).sum::<f64>().sqrt();
    if den == 0.0 {
        return if num == 0.0 { 100.0 } else { f64::NEG_INFINITY };
    }
    100.0 * (1.0 - num / den)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn closed_forms() {
        let y = [1.0, 2.0, 3.0, 4.0];
        assert_eq!(fit_pct(&y, &y), 100.0);
        assert!(fit_pct(&y, &[2.5; 4]).abs() < 1e-12);
        // Half the deviation left: ‖y − ŷ‖ = ‖y − ȳ‖/2.
        let half: Vec<f64> = y.iter().map(|v| 2.5 + 0.5 * (v - 2.5)).collect();
        assert!((fit_pct(&y, &half) - 50.0).abs() < 1e-12);
    }
}
