//! Removing the other dithers' contribution from a residual before testing one dither.
//!
//! In a MIMO loop one wrong channel can dominate a residual: in the paper's Hammerstein case the
//! changed g21 (driven by MV2) swamps e1, and the equally real change of g31 (MV3 → CV1) drowns
//! in it. The other dithers are independent of the dither under test by design, so subtracting
//! what they explain — a least-squares fit on their lags 0..=L — cannot create dependence on the
//! tested dither where there was none: the test keeps its level. What it removes is variance
//! that is noise for this element, so the test gains power. This is the linear, lagged form of
//! the partial correlation the paper cites (Badwe et al.) applied on the dither side.

use crate::numerics::least_squares;

/// `e` minus its least-squares projection on a constant and `others[k](t − l)`, l = 0..=`max_lag`.
/// The first `max_lag` samples have no full regressor row and are dropped: output sample `s` is
/// input sample `s + max_lag`. Returns `e[max_lag..]` unchanged when there are no other dithers,
/// too few samples for the fit, or a value that is not finite.
pub fn partial_out(e: &[f64], others: &[&[f64]], max_lag: usize) -> Vec<f64> {
    let n = e.len();
    let cols = 1 + others.len() * (max_lag + 1);
    let rows = n.saturating_sub(max_lag);
    if others.is_empty() || rows < 4 * cols {
        return e[max_lag.min(n)..].to_vec();
    }
    let y = &e[max_lag..];
    let ones = vec![1.0; rows];
    let mut x: Vec<&[f64]> = vec![&ones];
    for o in others {
        x.extend((0..=max_lag).map(|l| &o[max_lag - l..max_lag - l + rows]));
    }
    // Collinear regressors (two dithers that are shifted copies within the lag window) get the
    // minimum-norm solution, which gives the same projection.
    let Some(beta) = least_squares(&x, y, 0..rows) else { return y.to_vec() };
    (0..rows).map(|t| y[t] - x.iter().zip(&beta).map(|(c, b)| c[t] * b).sum::<f64>()).collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn removes_a_lagged_linear_contribution_exactly() {
        let n = 600;
        let d2: Vec<f64> = (0..n).map(|t| if (t * 7 + t / 3) % 5 < 2 { 1.0 } else { -1.0 }).collect();
        let small: Vec<f64> = (0..n).map(|t| ((t * 7919) % 101) as f64 / 1000.0).collect();
        let e: Vec<f64> = (0..n).map(|t| small[t] + if t >= 2 { 3.0 * d2[t - 2] } else { 0.0 }).collect();
        let out = partial_out(&e, &[&d2], 4);
        assert_eq!(out.len(), n - 4);
        let var = |v: &[f64]| {
            let m = v.iter().sum::<f64>() / v.len() as f64;
            v.iter().map(|a| (a - m).powi(2)).sum::<f64>() / v.len() as f64
        };
        // What remains is the small part (plus what d2's lags happen to explain of it).
        assert!(var(&out) <= var(&small[4..]) + 1e-12, "{} vs {}", var(&out), var(&small[4..]));
        assert!(var(&e[4..]) > 8.0);
    }

    #[test]
    fn no_others_is_the_identity_after_the_cut() {
        let e = [1.0, 2.0, 3.0, 4.0];
        assert_eq!(partial_out(&e, &[], 1), vec![2.0, 3.0, 4.0]);
    }
}
