//! The numerical fitting tools: least squares (SVD, nalgebra), FROLS term selection, and the
//! causal linear filters the candidate terms are built from.

use nalgebra::{DMatrix, DVector};

/// Least squares `min ‖X θ − y‖` over the rows `rows` of the columns `cols` (each a full-length
/// series). Solved by SVD with a relative singular-value cut-off, so collinear columns (an
/// over-parameterised model, a constant regressor) give the minimum-norm solution instead of
/// garbage. Returns `None` when a value is not finite.
pub fn least_squares(cols: &[&[f64]], y: &[f64], rows: std::ops::Range<usize>) -> Option<Vec<f64>> {
    least_squares_rows(cols, y, &rows.collect::<Vec<_>>())
}

/// [`least_squares`] over any set of rows.
pub fn least_squares_rows(cols: &[&[f64]], y: &[f64], rows: &[usize]) -> Option<Vec<f64>> {
    let p = cols.len();
    if p == 0 {
        return Some(Vec::new());
    }
    let n = rows.len();
    let x = DMatrix::from_fn(n, p, |r, c| cols[c][rows[r]]);
    let b = DVector::from_fn(n, |r, _| y[rows[r]]);
    let svd = x.svd(true, true);
    let smax = svd.singular_values.max();
    if !smax.is_finite() {
        return None;
    }
    let theta = svd.solve(&b, smax * 1e-10).ok()?;
    let out: Vec<f64> = theta.iter().copied().collect();
    out.iter().all(|v| v.is_finite()).then_some(out)
}

/// Forward regression with orthogonal least squares (FROLS, Billings 2013 §3.5): repeatedly
/// picks the candidate column whose part orthogonal to the already chosen ones explains the most
/// of `y` (the error reduction ratio, ERR), until `max_terms` are chosen or the best ERR falls
/// below `min_err`. Returns the chosen indices with their ERR, in order of choice.
pub fn frols(
    cands: &[Vec<f64>],
    y: &[f64],
    rows: &[usize],
    max_terms: usize,
    min_err: f64,
) -> Vec<(usize, f64)> {
    let pick = |c: &[f64]| -> Vec<f64> { rows.iter().map(|&t| c[t]).collect() };
    let yy: Vec<f64> = pick(y);
    let sigma = dot(&yy, &yy);
    if sigma == 0.0 {
        return Vec::new();
    }
    let mut basis: Vec<Vec<f64>> = Vec::new();
    let mut chosen: Vec<(usize, f64)> = Vec::new();
    for _ in 0..max_terms {
        let mut best: Option<(usize, f64, Vec<f64>)> = None;
        for (m, c) in cands.iter().enumerate() {
            if chosen.iter().any(|&(k, _)| k == m) {
                continue;
            }
            let cr = pick(c);
            let mut w: Vec<f64> = cr.clone();
            for q in &basis {
                let a = dot(q, &w) / dot(q, q);
                w.iter_mut().zip(q).for_each(|(wi, qi)| *wi -= a * qi);
            }
            let ww = dot(&w, &w);
            if ww <= 1e-12 * dot(&cr, &cr).max(f64::MIN_POSITIVE) {
                continue;
            }
            let g = dot(&w, &yy);
            let err = g * g / (ww * sigma);
            if best.as_ref().is_none_or(|b| err > b.1) {
                best = Some((m, err, w));
            }
        }
        match best {
            Some((m, err, w)) if err >= min_err => {
                chosen.push((m, err));
                basis.push(w);
            }
            _ => break,
        }
    }
    chosen
}

fn dot(a: &[f64], b: &[f64]) -> f64 {
    a.iter().zip(b).map(|(x, y)| x * y).sum()
}

/// A causal discrete filter `y(t) = Σ a_l y(t−l) + Σ_k b_k x(t−k)` (l from 1, k from 0), started
/// in steady state at the first input value (before the record, x = x(0) and y its DC response),
/// as a simulation started at an operating point is. `a` holds `a_1..a_na` with this sign.
pub fn filter(b: &[f64], a: &[f64], x: &[f64]) -> Vec<f64> {
    let x0 = x.first().copied().unwrap_or(0.0);
    let den = 1.0 - a.iter().sum::<f64>();
    let y0 = if den.abs() > 1e-12 { b.iter().sum::<f64>() * x0 / den } else { 0.0 };
    let mut y = vec![0.0; x.len()];
    for t in 0..x.len() {
        let mut v = 0.0;
        for (k, bk) in b.iter().enumerate() {
            v += bk * if t >= k { x[t - k] } else { x0 };
        }
        for (l, al) in a.iter().enumerate() {
            v += al * if t > l { y[t - l - 1] } else { y0 };
        }
        y[t] = v;
    }
    y
}

/// `x(t − d)`, with the first value repeated before the record starts.
pub fn delayed(x: &[f64], d: usize) -> Vec<f64> {
    (0..x.len()).map(|t| if t >= d { x[t - d] } else { x[0] }).collect()
}

/// Instrumental-variable estimate: solves `Zᵀ X θ = Zᵀ y` over `rows`, with one instrument column
/// per regressor. In a closed loop the regressors (built from the recorded inputs) carry the
/// disturbance back through feedback and least squares is biased; instruments built from the
/// dither-driven part of the inputs are independent of the disturbance, so the estimate is not.
/// With `Z = X` this is least squares.
pub fn instrumental(cols: &[&[f64]], inst: &[&[f64]], y: &[f64], rows: &[usize]) -> Option<Vec<f64>> {
    let p = cols.len();
    if p == 0 || inst.len() != p {
        return None;
    }
    let n = rows.len();
    let x = DMatrix::from_fn(n, p, |r, c| cols[c][rows[r]]);
    let z = DMatrix::from_fn(n, p, |r, c| inst[c][rows[r]]);
    let b = DVector::from_fn(n, |r, _| y[rows[r]]);
    let zx = z.transpose() * &x;
    let zy = z.transpose() * b;
    let svd = zx.svd(true, true);
    let smax = svd.singular_values.max();
    if !smax.is_finite() || smax == 0.0 {
        return None;
    }
    let theta = svd.solve(&zy, smax * 1e-9).ok()?;
    let out: Vec<f64> = theta.iter().copied().collect();
    out.iter().all(|v| v.is_finite()).then_some(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn least_squares_recovers_exact_coefficients() {
        let x1: Vec<f64> = (0..50).map(|t| (t as f64 * 0.37).sin()).collect();
        let x2: Vec<f64> = (0..50).map(|t| (t as f64 * 0.11).cos()).collect();
        let y: Vec<f64> = x1.iter().zip(&x2).map(|(a, b)| 2.0 * a - 0.5 * b).collect();
        let th = least_squares(&[&x1, &x2], &y, 0..50).unwrap();
        assert!((th[0] - 2.0).abs() < 1e-10 && (th[1] + 0.5).abs() < 1e-10, "{th:?}");
    }

    #[test]
    fn frols_picks_the_true_terms_first() {
        let c: Vec<Vec<f64>> =
            (0..5).map(|k| (0..200).map(|t| ((t * (k + 2)) as f64 * 0.7).sin()).collect()).collect();
        let y: Vec<f64> = (0..200).map(|t| 3.0 * c[3][t] + 0.5 * c[1][t]).collect();
        let rows: Vec<usize> = (0..200).collect();
        let chosen = frols(&c, &y, &rows, 4, 1e-6);
        assert_eq!(chosen[0].0, 3);
        assert_eq!(chosen[1].0, 1);
        assert_eq!(chosen.len(), 2);
    }

    #[test]
    fn first_order_filter_step_response() {
        let mut x = vec![1.0; 30];
        x[0] = 0.0;
        let y = filter(&[0.0, 0.5], &[0.5], &x);
        assert!((y[29] - 1.0).abs() < 1e-6 && y[0] == 0.0);
    }
}
