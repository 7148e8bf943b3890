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

/// The z that keeps the family-wise false-alarm rate of `lags` two-sided tests at `alpha`
/// (Bonferroni): `Φ⁻¹(1 − alpha / (2·lags))`. With pointwise 95 % limits, 20 lags of pure noise
/// cross a limit somewhere 64 % of the time, which makes a CCF "detection" meaningless.
pub fn family_wise_z(alpha: f64, lags: usize) -> f64 {
    normal_quantile(1.0 - alpha / (2.0 * lags.max(1) as f64))
}

/// The standard normal quantile Φ⁻¹(p), 0 < p < 1, by Acklam's rational approximation
/// (relative error below 1.2·10⁻⁹), ample for control limits.
pub fn normal_quantile(p: f64) -> f64 {
    const A: [f64; 6] = [
        -3.969683028665376e1,
        2.209460984245205e2,
        -2.759285104469687e2,
        1.383_577_518_672_69e2,
        -3.066479806614716e1,
        2.506628277459239,
    ];
    const B: [f64; 5] = [
        -5.447609879822406e1,
        1.615858368580409e2,
        -1.556989798598866e2,
        6.680131188771972e1,
        -1.328068155288572e1,
    ];
    const C: [f64; 6] = [
        -7.784894002430293e-3,
        -3.223964580411365e-1,
        -2.400758277161838,
        -2.549732539343734,
        4.374664141464968,
        2.938163982698783,
    ];
    const D: [f64; 4] = [7.784695709041462e-3, 3.224671290700398e-1, 2.445134137142996, 3.754408661907416];
    if !(p > 0.0 && p < 1.0) {
        return if p <= 0.0 { f64::NEG_INFINITY } else { f64::INFINITY };
    }
    let tail = |q: f64| {
        (((((C[0] * q + C[1]) * q + C[2]) * q + C[3]) * q + C[4]) * q + C[5])
            / ((((D[0] * q + D[1]) * q + D[2]) * q + D[3]) * q + 1.0)
    };
    if p < 0.02425 {
        tail((-2.0 * p.ln()).sqrt())
    } else if p > 1.0 - 0.02425 {
        -tail((-2.0 * (1.0 - p).ln()).sqrt())
    } else {
        let q = p - 0.5;
        let r = q * q;
        (((((A[0] * r + A[1]) * r + A[2]) * r + A[3]) * r + A[4]) * r + A[5]) * q
            / (((((B[0] * r + B[1]) * r + B[2]) * r + B[3]) * r + B[4]) * r + 1.0)
    }
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
    fn normal_quantiles_match_scipy() {
        // scipy.stats.norm.ppf; Acklam's approximation is good to about 1e-9 relative.
        for (p, want) in [
            (0.5, 0.0),
            (0.975, 1.959963984540054),
            (1.0 - 0.05 / 40.0, 3.023341439739154),
            (0.999, 3.090232306167813),
            (0.01, -2.3263478740408408),
            (1e-6, -4.753424308822899),
        ] {
            let got = normal_quantile(p);
            assert!((got - want).abs() <= 2e-9 * want.abs().max(1.0), "p = {p}: {got} vs {want}");
        }
        assert!((family_wise_z(0.05, 20) - 3.023341439739154).abs() < 1e-8);
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
