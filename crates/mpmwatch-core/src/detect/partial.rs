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
    let rows: Vec<usize> = (max_lag.min(e.len())..e.len()).collect();
    partial_out_rows(e, others, max_lag, &rows)
}

/// [`partial_out`] over the regression rows `rows` (each at least `max_lag`): `e[rows]` minus
/// its projection.
fn partial_out_rows(e: &[f64], others: &[&[f64]], max_lag: usize, rows: &[usize]) -> Vec<f64> {
    let y: Vec<f64> = rows.iter().map(|&t| e[t]).collect();
    let cols = 1 + others.len() * (max_lag + 1);
    if others.is_empty() || rows.len() < 4 * cols {
        return y;
    }
    let design = design(others, max_lag, rows);
    let refs: Vec<&[f64]> = design.iter().map(Vec::as_slice).collect();
    // Collinear regressors (two dithers that are shifted copies within the lag window) get the
    // minimum-norm solution, which gives the same projection.
    let Some(beta) = least_squares(&refs, &y, 0..rows.len()) else { return y };
    (0..rows.len()).map(|r| y[r] - refs.iter().zip(&beta).map(|(c, b)| c[r] * b).sum::<f64>()).collect()
}

/// The regressors on `rows`: a constant, then each dither at lags 0..=`max_lag`.
fn design(dithers: &[&[f64]], max_lag: usize, rows: &[usize]) -> Vec<Vec<f64>> {
    let mut cols = vec![vec![1.0; rows.len()]];
    for d in dithers {
        cols.extend((0..=max_lag).map(|l| rows.iter().map(|&t| d[t - l]).collect()));
    }
    cols
}

/// The regression rows of a record in segments (lengths `segments`, laid end to end): the
/// times with at least `max_lag` earlier samples in their own segment.
fn rows_within(segments: &[usize], max_lag: usize) -> Vec<usize> {
    super::whiten::segment_starts(segments)
        .iter()
        .zip(segments)
        .flat_map(|(&s, &len)| s + max_lag.min(len)..s + len)
        .collect()
}

/// [`partial_out`] for every element of a matrix, planned once per lag window: one regression
/// of each residual on a constant and every excited dither's lags, from which the fit without
/// any one dither follows exactly ([`BlockLeastSquares`]). A 20×40 matrix then costs one
/// decomposition instead of 800. Designs that are rank-deficient fall back to [`partial_out`].
/// A record in segments regresses only rows whose lags stay inside their segment.
#[derive(Debug)]
pub struct PartialPlan<'a> {
    dithers: Vec<&'a [f64]>,
    excited: Vec<bool>,
    max_lag: usize,
    rows: Vec<usize>,
    segments: Vec<usize>,
    ls: Option<BlockLeastSquares>,
    block_of: Vec<Option<usize>>,
}

impl<'a> PartialPlan<'a> {
    /// Plans the partialling-out of `dithers` (those marked `excited`) over lags 0..=`max_lag`,
    /// on a record of contiguous segments of lengths `segments`.
    pub fn new(dithers: &[&'a [f64]], excited: &[bool], max_lag: usize, segments: &[usize]) -> Self {
        let rows = rows_within(segments, max_lag);
        let active: Vec<usize> = (0..dithers.len()).filter(|&k| excited[k]).collect();
        let active_dithers: Vec<&[f64]> = active.iter().map(|&k| dithers[k]).collect();
        let mut block_of = vec![None; dithers.len()];
        let blocks: Vec<std::ops::Range<usize>> = active
            .iter()
            .enumerate()
            .map(|(b, &k)| {
                block_of[k] = Some(b);
                1 + b * (max_lag + 1)..1 + (b + 1) * (max_lag + 1)
            })
            .collect();
        let ls = if active.len() > 1 && !rows.is_empty() {
            let cols = design(&active_dithers, max_lag, &rows);
            let refs: Vec<&[f64]> = cols.iter().map(Vec::as_slice).collect();
            BlockLeastSquares::new(&refs, blocks, 0..rows.len())
        } else {
            None
        };
        let segments = segments.iter().filter(|&&len| len > max_lag).map(|len| len - max_lag).collect();
        Self { dithers: dithers.to_vec(), excited: excited.to_vec(), max_lag, rows, segments, ls, block_of }
    }

    /// The segment lengths of the partialled-out residual (each segment loses `max_lag`).
    pub fn segments(&self) -> &[usize] {
        &self.segments
    }

    /// `x` on the regression rows, which is what the partialled-out residual lines up with.
    pub fn on_rows(&self, x: &[f64]) -> Vec<f64> {
        self.rows.iter().map(|&t| x[t]).collect()
    }

    /// The full-design coefficients of residual `e`, shared by its elements; `None` when the
    /// plan fell back.
    pub fn fit(&self, e: &[f64]) -> Option<Vec<f64>> {
        self.ls.as_ref().map(|ls| ls.solve(&self.on_rows(e)))
    }

    /// `e` on the regression rows minus what every excited dither but `i` explains; `full` is
    /// [`Self::fit`] of `e`.
    pub fn partial_out(&self, e: &[f64], full: Option<&[f64]>, i: usize) -> Vec<f64> {
        let others: Vec<&[f64]> =
            (0..self.dithers.len()).filter(|&k| k != i && self.excited[k]).map(|k| self.dithers[k]).collect();
        let cols = 1 + others.len() * (self.max_lag + 1);
        if others.is_empty() || self.rows.len() < 4 * cols {
            return self.on_rows(e);
        }
        match (&self.ls, full, self.block_of.get(i).copied().flatten()) {
            (Some(ls), Some(full), Some(block)) => {
                let (_, fitted) = ls.without(full, block);
                self.rows.iter().zip(&fitted).map(|(&t, f)| e[t] - f).collect()
            }
            _ => partial_out_rows(e, &others, self.max_lag, &self.rows),
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
        let plan = PartialPlan::new(&refs, &excited, 3, &[n]);
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
    fn in_segments_each_one_loses_its_head_and_no_row_reaches_across() {
        let n = 400;
        let bin = |k: usize| -> Vec<f64> {
            (0..n).map(|t| if (t * (31 + 6 * k) + t / (3 + k) + k) % 7 < 3 { 1.0 } else { -1.0 }).collect()
        };
        let d: Vec<Vec<f64>> = (0..2).map(bin).collect();
        let e: Vec<f64> = (0..n)
            .map(|t| ((t * 7919) % 101) as f64 / 50.0 + if t >= 1 { d[1][t - 1] } else { 0.0 })
            .collect();
        let refs: Vec<&[f64]> = d.iter().map(Vec::as_slice).collect();
        let plan = PartialPlan::new(&refs, &[true, true], 2, &[250, 150]);
        assert_eq!(plan.segments(), &[248, 148]);
        let out = plan.partial_out(&e, plan.fit(&e).as_deref(), 0);
        assert_eq!(out.len(), 396);
        // The same as regressing the rows 2..250 and 252..400 directly.
        let rows: Vec<usize> = (2..250).chain(252..400).collect();
        let direct = partial_out_rows(&e, &[&d[1]], 2, &rows);
        assert!(out.iter().zip(&direct).all(|(a, b)| (a - b).abs() < 1e-9));
        assert_eq!(plan.on_rows(&d[0]).len(), 396);
    }

    #[test]
    fn no_others_is_the_identity_after_the_cut() {
        let e = [1.0, 2.0, 3.0, 4.0];
        assert_eq!(partial_out(&e, &[], 1), vec![2.0, 3.0, 4.0]);
    }
}
