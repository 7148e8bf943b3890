//! Linear baselines shown beside MI: the cross-correlation function and Pearson's correlation,
//! with their control limits (the paper's Figures 2, 9, 11, 17).

use serde::Serialize;

use super::{InfoError, validate};

/// Sample cross-correlation `r_xy(τ) = Σ_t (x(t) − x̄)(y(t+τ) − ȳ) / (N s_x s_y)` for
/// τ in `lags` (negative lags allowed: y leading x). The biased (1/N) form keeps |r| ≤ 1 and
/// is the one whose ±z/√N limits are standard (Box and Jenkins).
pub fn ccf(x: &[f64], y: &[f64], lags: std::ops::RangeInclusive<i64>) -> Result<Vec<f64>, InfoError> {
    validate::same_length("x", x.len(), "y", y.len())?;
    validate::finite("x", x)?;
    validate::finite("y", y)?;
    validate::not_constant("x", x)?;
    validate::not_constant("y", y)?;
    let n = x.len();
    let mx = x.iter().sum::<f64>() / n as f64;
    let my = y.iter().sum::<f64>() / n as f64;
    let sx = (x.iter().map(|v| (v - mx).powi(2)).sum::<f64>() / n as f64).sqrt();
    let sy = (y.iter().map(|v| (v - my).powi(2)).sum::<f64>() / n as f64).sqrt();
    Ok(lags
        .map(|tau| {
            let (xs, ys) = if tau >= 0 {
                let t = (tau as usize).min(n);
                (&x[..n - t], &y[t..])
            } else {
                let t = (tau.unsigned_abs() as usize).min(n);
                (&x[t..], &y[..n - t])
            };
            let s: f64 = xs.iter().zip(ys).map(|(a, b)| (a - mx) * (b - my)).sum();
            s / (n as f64 * sx * sy)
        })
        .collect())
}

/// The ±limit of a sample cross-correlation under independence (one series white): `z/√N`.
pub fn ccf_limit(n: usize, z: f64) -> f64 {
    z / (n as f64).sqrt()
}

/// Pearson's correlation of paired samples with the critical |r| at two-sided level given by
/// `z` (1.96 for 95 %) from Fisher's transform, `tanh(z / √(N − 3))`.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct Pearson {
    /// The correlation coefficient.
    pub r: f64,
    /// The critical |r|.
    pub limit: f64,
    /// True when |r| exceeds the limit.
    pub significant: bool,
}

/// Pearson's r with its Fisher-transform limit.
pub fn pearson(x: &[f64], y: &[f64], z: f64) -> Result<Pearson, InfoError> {
    if x.len() < 4 {
        return Err(InfoError::TooFewSamples { what: "Pearson correlation".into(), n: x.len(), needed: 4 });
    }
    let r = ccf(x, y, 0..=0)?[0];
    let limit = (z / ((x.len() - 3) as f64).sqrt()).tanh();
    Ok(Pearson { r, limit, significant: r.abs() > limit })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn ccf_finds_a_delayed_copy() {
        let x: Vec<f64> = (0..500).map(|i| ((i * 7919) % 1009) as f64).collect();
        let y: Vec<f64> = (0..500).map(|t| if t >= 3 { x[t - 3] } else { 0.0 }).collect();
        let r = ccf(&x, &y, -5..=5).unwrap();
        let best = r.iter().enumerate().max_by(|a, b| a.1.total_cmp(b.1)).unwrap().0 as i64 - 5;
        assert_eq!(best, 3);
        assert!(r[8] > 0.95 && r[8] <= 1.0, "{}", r[8]);
    }

    #[test]
    fn pearson_of_exact_line_is_one() {
        let x: Vec<f64> = (0..50).map(f64::from).collect();
        let y: Vec<f64> = x.iter().map(|v| -2.0 * v + 1.0).collect();
        let p = pearson(&x, &y, 1.96).unwrap();
        assert!((p.r + 1.0).abs() < 1e-12 && p.significant);
        assert!((p.limit - (1.96 / 47f64.sqrt()).tanh()).abs() < 1e-15);
    }
}
