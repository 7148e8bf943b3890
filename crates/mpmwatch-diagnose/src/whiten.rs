//! The whitening filter of the diagnosis' fits: an AR model of an error series fitted by least
//! squares, and the one-step prediction error it leaves. Used by the grey-box path's
//! prediction-error fit, by the correction path's prefiltered coefficients and refined grid
//! values, and (its rows only) by the closed loop's fold score, whose AR model has a constant.
//! The locating step whitens with core's `ArWhitener` instead (Yule–Walker on the training
//! part of a residual). Every whitening here uses only rows whose predecessors are rows too, so a
//! validation block left out of a fit is never reached.

use mpmwatch_core::numerics::least_squares_rows;

/// The rows of `rows` whose `p` predecessors are rows too: where a whitening filter of order
/// `p` reaches no excluded block.
pub(crate) fn whitenable(rows: &[usize], p: usize) -> Vec<usize> {
    let inside: std::collections::HashSet<usize> = rows.iter().copied().collect();
    rows.iter().copied().filter(|&t| t >= p && (1..=p).all(|k| inside.contains(&(t - k)))).collect()
}

/// The AR(`p`) model `e(t) = Σ_k a_k e(t−k) + ε(t)` of `e` by least squares on `rows` (each
/// with its `p` predecessors); `None` when too few rows or the fit fails, empty for `p = 0`.
pub(crate) fn ar_fit(e: &[f64], rows: &[usize], p: usize) -> Option<Vec<f64>> {
    if p == 0 {
        return Some(Vec::new());
    }
    let used = whitenable(rows, p);
    if used.len() < 10 * p {
        return None;
    }
    let lagged: Vec<Vec<f64>> =
        (1..=p).map(|k| (0..e.len()).map(|t| if t >= k { e[t - k] } else { 0.0 }).collect()).collect();
    let refs: Vec<&[f64]> = lagged.iter().map(Vec::as_slice).collect();
    least_squares_rows(&refs, e, &used)
}

/// The one-step prediction error at `t` of a simulation error `e` under the AR noise model `a`
/// (`t` must have `a.len()` predecessors).
pub(crate) fn whitened(e: &[f64], a: &[f64], t: usize) -> f64 {
    e[t] - a.iter().enumerate().map(|(k, ak)| ak * e[t - k - 1]).sum::<f64>()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Two blocks of rows with a gap: a row is whitenable when its `p` predecessors are rows,
    /// so the first `p` rows after the gap (and of the record) are not.
    #[test]
    fn whitening_reaches_no_excluded_block() {
        let rows: Vec<usize> = (0..10).chain(20..30).collect();
        let expected: Vec<usize> = (2..10).chain(22..30).collect();
        assert_eq!(whitenable(&rows, 2), expected);
        assert_eq!(whitenable(&rows, 0), rows);
    }

    /// An exact AR(2) series `e(t) = 1.2 e(t−1) − 0.5 e(t−2)` with garbage (1000) in an
    /// excluded block: the least-squares AR(2) on the remaining rows recovers the coefficients
    /// exactly (every equation it uses holds exactly). The rows just after the block (150 and
    /// 151) are rows, but their predecessors are garbage: were they used, two equations with
    /// regressors near 1000 and targets below 1 would pull the fit far off.
    #[test]
    fn an_ar_fit_skips_an_excluded_block() {
        let n = 300;
        let mut e = vec![0.0; n];
        e[0] = 1.0;
        e[1] = 0.3;
        for t in 2..n {
            // Restarted after every 40 samples so the series does not decay to zero.
            e[t] = if t % 40 < 2 {
                ((t * 7919) % 13) as f64 / 6.0 - 1.0
            } else {
                1.2 * e[t - 1] - 0.5 * e[t - 2]
            };
        }
        // A restart's own row does not follow the recursion, so it is excluded as an equation.
        for v in &mut e[100..150] {
            *v = 1e3;
        }
        let rows: Vec<usize> = (0..n).filter(|t| !(100..150).contains(t) && t % 40 >= 2).collect();
        let a = ar_fit(&e, &rows, 2).unwrap();
        assert!((a[0] - 1.2).abs() < 1e-9 && (a[1] + 0.5).abs() < 1e-9, "{a:?}");
        assert_eq!(ar_fit(&e, &rows, 0), Some(Vec::new()));
        assert_eq!(ar_fit(&e, &rows[..15], 2), None);
        // `whitened` is the one-step prediction error: zero under the exact model on every row
        // it may use.
        for t in whitenable(&rows, 2) {
            assert!(whitened(&e, &a, t).abs() < 1e-9, "row {t}");
        }
    }
}
