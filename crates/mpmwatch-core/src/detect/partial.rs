//! Removing the other dithers' contribution from a residual before testing one dither.
//!
//! In a MIMO loop one wrong channel can dominate a residual: in the paper's Hammerstein case the
//! changed g21 (driven by MV2) swamps e1, and the equally real change of g31 (MV3 → CV1) drowns
//! in it. The other dithers are independent of the dither under test by design, so subtracting
//! what they explain — a least-squares fit on their lags 0..=L — cannot create dependence on the
//! tested dither where there was none: the test keeps its level. What it removes is variance
//! that is noise for this element, so the test gains power. This is the linear, lagged form of
//! the partial correlation the paper cites (Badwe et al.) applied on the dither side.

use crate::numerics::{BlockLeastSquares, least_squares};

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

/// [`partial_out`] for every element of a matrix, planned once per lag window: one regression
/// of each residual on a constant and every excited dither's lags, from which the fit without
/// any one dither follows exactly ([`BlockLeastSquares`]). A 20×40 matrix then costs one
/// decomposition instead of 800. Designs that are rank-deficient fall back to [`partial_out`].
#[derive(Debug)]
pub struct PartialPlan<'a> {
    dithers: Vec<&'a [f64]>,
    excited: Vec<bool>,
    max_lag: usize,
    ls: Option<BlockLeastSquares>,
    block_of: Vec<Option<usize>>,
}

impl<'a> PartialPlan<'a> {
    /// Plans the partialling-out of `dithers` (those marked `excited`) over lags 0..=`max_lag`.
    pub fn new(dithers: &[&'a [f64]], excited: &[bool], max_lag: usize) -> Self {
        let n = dithers.first().map_or(0, |d| d.len());
        let rows = n.saturating_sub(max_lag);
        let active: Vec<usize> = (0..dithers.len()).filter(|&k| excited[k]).collect();
        let ones = vec![1.0; n];
        let mut cols: Vec<&[f64]> = vec![&ones[max_lag.min(n)..]];
        let mut blocks = Vec::new();
        let mut block_of = vec![None; dithers.len()];
        for &k in &active {
            block_of[k] = Some(blocks.len());
            blocks.push(cols.len()..cols.len() + max_lag + 1);
            cols.extend((0..=max_lag).map(|l| &dithers[k][max_lag - l..max_lag - l + rows]));
        }
        let ls =
            if active.len() > 1 && rows > 0 { BlockLeastSquares::new(&cols, blocks, 0..rows) } else { None };
        Self { dithers: dithers.to_vec(), excited: excited.to_vec(), max_lag, ls, block_of }
    }

    /// The full-design coefficients of residual `e`, shared by its elements; `None` when the
    /// plan fell back.
    pub fn fit(&self, e: &[f64]) -> Option<Vec<f64>> {
        self.ls.as_ref().map(|ls| ls.solve(&e[self.max_lag..]))
    }

    /// `partial_out(e, others, max_lag)` with `others` every excited dither but `i`; `full` is
    /// [`Self::fit`] of `e`.
    pub fn partial_out(&self, e: &[f64], full: Option<&[f64]>, i: usize) -> Vec<f64> {
        let others: Vec<&[f64]> =
            (0..self.dithers.len()).filter(|&k| k != i && self.excited[k]).map(|k| self.dithers[k]).collect();
        let rows = e.len().saturating_sub(self.max_lag);
        let cols = 1 + others.len() * (self.max_lag + 1);
        if others.is_empty() || rows < 4 * cols {
            return e[self.max_lag.min(e.len())..].to_vec();
        }
        match (&self.ls, full, self.block_of.get(i).copied().flatten()) {
            (Some(ls), Some(full), Some(block)) => {
                let (_, fitted) = ls.without(full, block);
                e[self.max_lag..].iter().zip(&fitted).map(|(y, f)| y - f).collect()
            }
            _ => partial_out(e, &others, self.max_lag),
        }
    }
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
    fn the_plan_gives_the_same_residual_as_the_direct_fit() {
        let n = 400;
        let bin = |k: usize| -> Vec<f64> {
            (0..n).map(|t| if (t * (31 + 6 * k) + t / (3 + k) + k) % 7 < 3 { 1.0 } else { -1.0 }).collect()
        };
        let d: Vec<Vec<f64>> = (0..4).map(bin).collect();
        let e: Vec<f64> = (0..n)
            .map(|t| {
                ((t * 7919) % 101) as f64 / 50.0 + if t >= 2 { d[1][t - 2] - 0.5 * d[3][t - 1] } else { 0.0 }
            })
            .collect();
        let refs: Vec<&[f64]> = d.iter().map(Vec::as_slice).collect();
        let excited = [true, true, false, true];
        let plan = PartialPlan::new(&refs, &excited, 3);
        let full = plan.fit(&e);
        assert!(full.is_some(), "a full-rank design is planned");
        for i in [0, 1, 3] {
            let others: Vec<&[f64]> = [0, 1, 3].iter().filter(|&&k| k != i).map(|&k| refs[k]).collect();
            let direct = partial_out(&e, &others, 3);
            let planned = plan.partial_out(&e, full.as_deref(), i);
            assert_eq!(direct.len(), planned.len());
            assert!(direct.iter().zip(&planned).all(|(a, b)| (a - b).abs() < 1e-9), "dither {i}");
        }
    }

    #[test]
    fn no_others_is_the_identity_after_the_cut() {
        let e = [1.0, 2.0, 3.0, 4.0];
        assert_eq!(partial_out(&e, &[], 1), vec![2.0, 3.0, 4.0]);
    }
}
