//! Least squares and instrumental variables by SVD: one solver for every regression in the
//! project (partialling out dithers, ARX identification, hypothesis fits, projection tests).

use nalgebra::{DMatrix, DVector};

/// Singular values below this fraction of the largest are treated as zero: collinear columns
/// (an over-parameterised model, a constant regressor, two dithers that are shifted copies within
/// a lag window) give the minimum-norm solution instead of noise amplified by 1e16.
const RCOND: f64 = 1e-10;

/// The Euclidean norm of each column of `x`, taken on the column divided by its largest
/// magnitude so that squares neither overflow nor underflow (1 for a column of zeros or of
/// non-finite values). Every solver divides the columns by it before the SVD and the coefficients after,
/// so [`RCOND`] compares directions, not units: unscaled, a column a trillion times smaller
/// than another (an input in m³/s beside an output in Pa) falls below the cut-off and its
/// coefficient is set to zero.
fn column_scales(x: &DMatrix<f64>) -> DVector<f64> {
    DVector::from_iterator(
        x.ncols(),
        x.column_iter().map(|c| {
            let m = c.amax();
            let n = if m > 0.0 { m * (c / m).norm() } else { 0.0 };
            if n > 0.0 && n.is_finite() { n } else { 1.0 }
        }),
    )
}

/// A thin singular-value decomposition `X = U Σ Vᵀ`, computed by faer. nalgebra's own SVD
/// returns wrong singular values and vectors on some matrices, exactly rank-deficient ones
/// among them (dimforge/nalgebra#1172, open). On the designs of the test
/// `svd_of_collinear_designs_recomposes` (duplicated and constant columns, where the
/// minimum-norm solution matters) nalgebra's missed 78 of 1998 (docs/estimators.md); the test
/// checks this one.
struct Svd {
    u: DMatrix<f64>,
    s: DVector<f64>,
    v: DMatrix<f64>,
}

impl Svd {
    /// `None` when faer's iteration does not converge or a value is not finite.
    fn new(x: &DMatrix<f64>) -> Option<Self> {
        if x.iter().any(|v| !v.is_finite()) {
            return None;
        }
        let m = faer::Mat::<f64>::from_fn(x.nrows(), x.ncols(), |i, j| x[(i, j)]);
        let d = m.thin_svd().ok()?;
        let (u, s, v) = (d.U(), d.S().column_vector(), d.V());
        let k = s.nrows();
        Some(Self {
            u: DMatrix::from_fn(x.nrows(), k, |i, j| u[(i, j)]),
            s: DVector::from_fn(k, |i, _| s[i]),
            v: DMatrix::from_fn(x.ncols(), k, |i, j| v[(i, j)]),
        })
    }

    /// The largest singular value (0 for an empty matrix).
    fn max(&self) -> f64 {
        self.s.iter().copied().fold(0.0, f64::max)
    }

    /// The minimum-norm solution of `min ‖X θ − b‖`, singular values at or below `cut` taken as
    /// zero.
    fn solve(&self, b: &DVector<f64>, cut: f64) -> DVector<f64> {
        let utb = self.u.transpose() * b;
        let w = DVector::from_fn(self.s.len(), |k, _| if self.s[k] > cut { utb[k] / self.s[k] } else { 0.0 });
        &self.v * w
    }
}

/// `x` with column `k` divided by `s[k]`.
fn equilibrated(mut x: DMatrix<f64>, s: &DVector<f64>) -> DMatrix<f64> {
    for (mut c, v) in x.column_iter_mut().zip(s.iter()) {
        c /= *v;
    }
    x
}

/// Least squares `min ‖X θ − y‖` over the rows `rows` of the columns `cols` (each a full-length
/// series). Collinear columns get the minimum-norm solution of the design with unit-norm
/// columns, so the split between them does not depend on their units. Returns `None` when a
/// value is not finite, when there are no rows, or when a row is past the end of `y` or of a
/// column.
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
    if n == 0 || rows.iter().any(|&r| r >= y.len() || cols.iter().any(|c| r >= c.len())) {
        return None;
    }
    let x = DMatrix::from_fn(n, p, |r, c| cols[c][rows[r]]);
    let b = DVector::from_fn(n, |r, _| y[rows[r]]);
    let s = column_scales(&x);
    let svd = Svd::new(&equilibrated(x, &s))?;
    let theta = svd.solve(&b, svd.max() * RCOND);
    let out: Vec<f64> = theta.iter().zip(s.iter()).map(|(t, s)| t / s).collect();
    out.iter().all(|v| v.is_finite()).then_some(out)
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
    let len = cols.iter().chain(inst).map(|c| c.len()).min().unwrap_or(0).min(y.len());
    if n == 0 || rows.iter().any(|&r| r >= len) {
        return None;
    }
    let x = DMatrix::from_fn(n, p, |r, c| cols[c][rows[r]]);
    let z = DMatrix::from_fn(n, p, |r, c| inst[c][rows[r]]);
    let b = DVector::from_fn(n, |r, _| y[rows[r]]);
    let (sx, sz) = (column_scales(&x), column_scales(&z));
    let (x, z) = (equilibrated(x, &sx), equilibrated(z, &sz));
    let zx = z.transpose() * &x;
    let zy = z.transpose() * b;
    let svd = Svd::new(&zx)?;
    let smax = svd.max();
    if smax == 0.0 {
        return None;
    }
    // The p×p cross-moment matrix squares the condition number of X: a looser cut-off.
    let theta = svd.solve(&zy, smax * RCOND * 10.0);
    let out: Vec<f64> = theta.iter().zip(sx.iter()).map(|(t, s)| t / s).collect();
    out.iter().all(|v| v.is_finite()).then_some(out)
}

/// R² of `y` on the columns plus a constant (all of the same length): the share of `y`'s
/// variance the least-squares fit explains, in [0, 1]; 0 when `y` is constant, when there are
/// fewer than two rows per coefficient, or when the fit fails. Columns are standardised first
/// (constant ones dropped), so the singular-value cut-off does not depend on their units: a
/// feature a million times larger than another cannot push the smaller one below it.
pub fn r_squared(y: &[f64], cols: &[Vec<f64>]) -> f64 {
    let n = y.len();
    if n < 2 * (cols.len() + 1) {
        return 0.0;
    }
    let my = y.iter().sum::<f64>() / n as f64;
    let sst: f64 = y.iter().map(|v| (v - my) * (v - my)).sum();
    if sst <= 0.0 {
        return 0.0;
    }
    let std_cols: Vec<Vec<f64>> = cols
        .iter()
        .filter_map(|c| {
            let m = c.iter().sum::<f64>() / n as f64;
            let s = (c.iter().map(|v| (v - m).powi(2)).sum::<f64>() / n as f64).sqrt();
            (s > 1e-12 * m.abs()).then(|| c.iter().map(|v| (v - m) / s).collect())
        })
        .collect();
    let ones = vec![1.0; n];
    let mut refs: Vec<&[f64]> = std_cols.iter().map(Vec::as_slice).collect();
    refs.push(&ones);
    let Some(theta) = least_squares(&refs, y, 0..n) else { return 0.0 };
    let sse: f64 = (0..n)
        .map(|t| {
            let fit: f64 = refs.iter().zip(&theta).map(|(c, th)| c[t] * th).sum();
            (y[t] - fit).powi(2)
        })
        .sum();
    (1.0 - sse / sst).clamp(0.0, 1.0)
}

/// Least squares on a design whose columns come in blocks, solved once and then re-solved
/// without any one block at the cost of a block-sized system: the partialling-out of a 20×40
/// matrix regresses each residual on every other dither, 800 regressions of about 400 columns
/// that differ only by which block is left out. With `H = (XᵀX)⁻¹` and the full solution `b`,
/// the solution without block B is `b − H[:,B] H[B,B]⁻¹ b[B]` (the partitioned inverse), which
/// is exact when X has full column rank; rank-deficient designs are refused, so the caller can
/// fall back to [`least_squares`] and its minimum-norm solution.
#[derive(Debug, Clone)]
pub struct BlockLeastSquares {
    x: DMatrix<f64>,
    pinv: DMatrix<f64>,
    h: DMatrix<f64>,
    blocks: Vec<std::ops::Range<usize>>,
}

impl BlockLeastSquares {
    /// The design of columns `cols` over `rows`, with `blocks` naming column ranges. `None` when
    /// a value is not finite, a block is out of range, there are fewer rows than columns, or the
    /// columns are collinear to within [`RCOND`].
    pub fn new(
        cols: &[&[f64]],
        blocks: Vec<std::ops::Range<usize>>,
        rows: std::ops::Range<usize>,
    ) -> Option<Self> {
        let (n, p) = (rows.len(), cols.len());
        if p == 0 || n < p || cols.iter().any(|c| c.len() < rows.end) || blocks.iter().any(|b| b.end > p) {
            return None;
        }
        let x = DMatrix::from_fn(n, p, |r, c| cols[c][rows.start + r]);
        if x.iter().any(|v| !v.is_finite()) {
            return None;
        }
        let scales = column_scales(&x);
        let Svd { u, s, v } = Svd::new(&equilibrated(x.clone(), &scales))?;
        let (smax, smin) = (s.max(), s.min());
        if !(smax.is_finite() && smin > smax * RCOND) {
            return None;
        }
        // With X = X̃ S (S the column scales): X⁺ = S⁻¹ X̃⁺ and (XᵀX)⁻¹ = S⁻¹ (X̃ᵀX̃)⁻¹ S⁻¹.
        let unscale = DMatrix::from_diagonal(&scales.map(|v| 1.0 / v));
        let v_scaled = unscale * v * DMatrix::from_diagonal(&s.map(|v| 1.0 / v));
        let pinv = &v_scaled * u.transpose();
        let h = &v_scaled * v_scaled.transpose();
        Some(Self { x, pinv, h, blocks })
    }

    /// The full least-squares coefficients for `y` given on the design's rows.
    pub fn solve(&self, y: &[f64]) -> Vec<f64> {
        (&self.pinv * DVector::from_column_slice(y)).as_slice().to_vec()
    }

    /// From the full coefficients `full`, the coefficients of the fit without block `block`
    /// (zero on that block), and the fitted values of that fit on the design's rows.
    pub fn without(&self, full: &[f64], block: usize) -> (Vec<f64>, Vec<f64>) {
        let b = DVector::from_column_slice(full);
        let r = self.blocks[block].clone();
        let hbb = self.h.view((r.start, r.start), (r.len(), r.len())).into_owned();
        let rhs = b.rows(r.start, r.len()).into_owned();
        let w = match hbb.clone().cholesky() {
            Some(ch) => ch.solve(&rhs),
            None => Svd::new(&hbb)
                .map_or_else(|| DVector::zeros(r.len()), |svd| svd.solve(&rhs, svd.max() * RCOND)),
        };
        let mut beta = b - self.h.columns(r.start, r.len()) * w;
        beta.rows_mut(r.start, r.len()).fill(0.0);
        let fitted = &self.x * &beta;
        (beta.as_slice().to_vec(), fitted.as_slice().to_vec())
    }
}

/// The orthogonal projection on the span of some feature columns over a block of rows.
#[derive(Debug, Clone)]
pub struct Projector {
    q: DMatrix<f64>,
}

impl Projector {
    /// An orthonormal basis of the features on `rows` (thin SVD of the features scaled to unit
    /// norm; directions with singular values below 1e-8 of the largest are dropped, so collinear
    /// features cost nothing, whatever their units). No features,
    /// no rows or features shorter than `rows` give the projection on nothing (every `P x` = 0).
    pub fn new(features: &[Vec<f64>], rows: std::ops::Range<usize>) -> Self {
        let n = rows.len();
        if n == 0 || features.is_empty() || features.iter().any(|f| f.len() < rows.end) {
            return Self { q: DMatrix::zeros(n, 0) };
        }
        let x = DMatrix::from_fn(n, features.len(), |r, c| features[c][rows.start + r]);
        let Some(svd) = Svd::new(&equilibrated(x.clone(), &column_scales(&x))) else {
            return Self { q: DMatrix::zeros(n, 0) };
        };
        let (u, smax) = (&svd.u, svd.max());
        let keep: Vec<usize> = (0..svd.s.len()).filter(|&k| svd.s[k] > 1e-8 * smax).collect();
        let q = DMatrix::from_fn(n, keep.len(), |r, c| u[(r, keep[c])]);
        Self { q }
    }

    /// `P x` for `x` given on the projector's rows.
    pub fn project(&self, x: &[f64]) -> Vec<f64> {
        let v = DVector::from_column_slice(x);
        let coef = self.q.transpose() * v;
        (&self.q * coef).as_slice().to_vec()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    #[test]
    fn least_squares_recovers_exact_coefficients() {
        let x1: Vec<f64> = (0..50).map(|t| (t as f64 * 0.3).sin()).collect();
        let x2: Vec<f64> = (0..50).map(|t| (t as f64 * 0.7).cos()).collect();
        let y: Vec<f64> = x1.iter().zip(&x2).map(|(a, b)| 2.0 * a - 0.5 * b).collect();
        let th = least_squares(&[&x1, &x2], &y, 0..50).unwrap();
        assert!((th[0] - 2.0).abs() < 1e-10 && (th[1] + 0.5).abs() < 1e-10);
    }

    #[test]
    fn collinear_columns_get_the_minimum_norm_solution() {
        // y = x and two identical columns: the minimum-norm split is one half each.
        let x: Vec<f64> = (0..40).map(|t| (t as f64 * 0.4).sin()).collect();
        let th = least_squares(&[&x, &x], &x, 0..40).unwrap();
        assert!((th[0] - 0.5).abs() < 1e-9 && (th[1] - 0.5).abs() < 1e-9, "{th:?}");
    }

    #[test]
    fn instrumental_with_the_regressors_as_instruments_is_least_squares() {
        let x: Vec<f64> = (0..60).map(|t| (t as f64 * 0.21).sin() + 0.1 * (t % 7) as f64).collect();
        let y: Vec<f64> = x.iter().enumerate().map(|(t, v)| 1.5 * v + 0.01 * ((t * 13) % 5) as f64).collect();
        let rows: Vec<usize> = (0..60).collect();
        let a = least_squares_rows(&[&x], &y, &rows).unwrap();
        let b = instrumental(&[&x], &[&x], &y, &rows).unwrap();
        assert!((a[0] - b[0]).abs() < 1e-9);
    }

    #[test]
    fn r_squared_of_an_affine_map_is_one_and_of_a_constant_zero() {
        let x: Vec<f64> = (0..100).map(|t| (t as f64 * 0.37).sin()).collect();
        let y: Vec<f64> = x.iter().map(|v| 3.0 - 2.0 * v).collect();
        assert!((r_squared(&y, std::slice::from_ref(&x)) - 1.0).abs() < 1e-12);
        assert_eq!(r_squared(&[4.0; 100], &[x]), 0.0);
    }

    #[test]
    fn r_squared_does_not_depend_on_the_columns_units() {
        let x: Vec<f64> = (0..200).map(|t| (t as f64 * 0.37).sin()).collect();
        let z: Vec<f64> = (0..200).map(|t| ((t * 7919) % 17) as f64).collect();
        let y: Vec<f64> = x.iter().zip(&z).map(|(a, b)| a + 1e-3 * b + 0.1 * (a * b).cos()).collect();
        let small = r_squared(&y, &[x.clone(), z.clone()]);
        let big = r_squared(&y, &[x, z.iter().map(|v| v * 1e12).collect()]);
        assert!((small - big).abs() < 1e-9, "{small} vs {big}");
        assert!(small > 0.5 && small < 1.0);
    }

    /// The coefficients follow the columns' units exactly: with one column a billion times
    /// smaller and another a billion times larger (a spread of 1e18, beyond the cut-off
    /// unscaled), the coefficients are those of the unit design, rescaled, to rounding. The
    /// same holds for instrumental variables, the block solver and the projection.
    #[test]
    fn solutions_do_not_depend_on_the_columns_units() {
        let n = 200;
        let a: Vec<f64> = (0..n).map(|t| (t as f64 * 0.37).sin()).collect();
        let b: Vec<f64> = (0..n).map(|t| ((t * 7919) % 17) as f64 - 8.0).collect();
        let ones = vec![1.0; n];
        let y: Vec<f64> = (0..n).map(|t| 2.0 * a[t] - 0.25 * b[t] + 1.0 + 0.01 * (t as f64).cos()).collect();
        let (sa, sb) = (1e-9, 1e9);
        let a2: Vec<f64> = a.iter().map(|v| v * sa).collect();
        let b2: Vec<f64> = b.iter().map(|v| v * sb).collect();
        let rows: Vec<usize> = (0..n).collect();
        let close = |x: f64, y: f64| (x - y).abs() <= 1e-9 * x.abs().max(y.abs());
        let unit = least_squares(&[&a, &b, &ones], &y, 0..n).unwrap();
        let scaled = least_squares(&[&a2, &b2, &ones], &y, 0..n).unwrap();
        // Instruments in yet other units than the regressors: the IV solution does not move.
        let (za, zb): (Vec<f64>, Vec<f64>) = a.iter().zip(&b).map(|(u, v)| (u * 1e6, v * 1e-6)).unzip();
        let iv = instrumental(&[&a2, &b2, &ones], &[&za, &zb, &ones], &y, &rows).unwrap();
        let bls = BlockLeastSquares::new(&[&a2, &b2, &ones], vec![0..1, 1..3], 0..n).unwrap();
        let blocked = bls.solve(&y);
        for th in [&scaled, &iv, &blocked] {
            assert!(
                close(th[0] * sa, unit[0]) && close(th[1] * sb, unit[1]) && close(th[2], unit[2]),
                "{th:?} vs {unit:?}"
            );
        }
        let (beta, _) = bls.without(&blocked, 0);
        let direct = least_squares(&[&b, &ones], &y, 0..n).unwrap();
        assert!(close(beta[1] * sb, direct[0]) && close(beta[2], direct[1]), "{beta:?} vs {direct:?}");
        let p = Projector::new(&[a2, b2], 0..n);
        assert_eq!(p.q.ncols(), 2, "the small feature is a direction of its own");
        assert!(close(r_squared(&a, &[a.iter().map(|v| v * 1e-13).collect()]), 1.0));
    }

    /// The SVD recomposes its matrix on designs built like the project's (a constant, lagged
    /// outputs of an AR(1) loop, lagged ±1 inputs), a third of them with an exactly duplicated
    /// column and all with more than four columns holding a second constant: 3000 seeded
    /// designs, each `‖U Σ Vᵀ − X‖ / ‖X‖` below 1e-12 (a backward-stable SVD reaches a small
    /// multiple of machine precision, 2.2e-16). nalgebra's SVD fails this on 78 of them.
    #[test]
    fn svd_of_collinear_designs_recomposes() {
        let mut state = 12345u64;
        let mut rnd = || {
            state ^= state << 13;
            state ^= state >> 7;
            state ^= state << 17;
            (state >> 11) as f64 / (1u64 << 53) as f64 - 0.5
        };
        for trial in 0..3000 {
            let (n, p) = (50 + (trial % 7) * 40, 2 + trial % 9);
            let (mut y, mut u) = (vec![0.0; n + 10], vec![0.0; n + 10]);
            let a = 0.5 + 0.98 * rnd().abs();
            for t in 1..n + 10 {
                u[t] = if rnd() > 0.0 { 1.0 } else { -1.0 };
                y[t] = a * y[t - 1] + u[t - 1] + 0.1 * rnd();
            }
            let x = DMatrix::from_fn(n, p, |r, c| match c % 4 {
                0 => 1.0,
                1 => y[r + 5 - c / 4],
                2 => u[r + 5 - c / 4],
                _ if trial % 3 == 0 => y[r + 5],
                _ => rnd(),
            });
            // Every third design cut to its first p − 1 rows: wide (more columns than rows).
            let x = if trial % 3 == 1 { x.rows(0, p - 1).into_owned() } else { x };
            let svd = Svd::new(&x).unwrap();
            let back = &svd.u * DMatrix::from_diagonal(&svd.s) * svd.v.transpose();
            let err = (back - &x).norm() / x.norm();
            assert!(err < 1e-12, "trial {trial} ({n}×{p}): relative error {err:e}");
            // `solve` needs orthonormal columns in both factors.
            for f in [&svd.u, &svd.v] {
                let off = (f.transpose() * f - DMatrix::identity(f.ncols(), f.ncols())).norm();
                assert!(off < 1e-12, "trial {trial}: ‖FᵀF − I‖ = {off:e}");
            }
        }
    }

    #[test]
    fn degenerate_designs_are_none_not_a_panic() {
        let x = [1.0, 2.0, 3.0];
        assert_eq!(least_squares(&[&x], &x, 0..0), None);
        assert_eq!(least_squares(&[&x], &x, 0..4), None);
        assert_eq!(least_squares(&[&x], &[1.0, f64::NAN, 2.0], 0..3), None);
        assert_eq!(instrumental(&[&x], &[&x], &x, &[]), None);
        assert_eq!(Projector::new(&[], 0..3).project(&x), vec![0.0; 3]);
    }

    #[test]
    fn leaving_a_block_out_matches_the_regression_without_it() {
        let n = 300;
        let col = |k: usize| -> Vec<f64> {
            (0..n).map(|t| (t as f64 * (0.31 + 0.17 * k as f64)).sin() + 0.1 * k as f64).collect()
        };
        let cols: Vec<Vec<f64>> = (0..6).map(col).collect();
        let y: Vec<f64> = (0..n).map(|t| (t as f64 * 0.37).sin() + 0.3 * cols[2][t] - cols[4][t]).collect();
        let refs: Vec<&[f64]> = cols.iter().map(Vec::as_slice).collect();
        let bls = BlockLeastSquares::new(&refs, vec![0..2, 2..4, 4..6], 0..n).unwrap();
        let full = bls.solve(&y);
        assert!(full.iter().zip(&least_squares(&refs, &y, 0..n).unwrap()).all(|(a, b)| (a - b).abs() < 1e-9));
        for (block, keep) in [(0, [2, 3, 4, 5]), (1, [0, 1, 4, 5]), (2, [0, 1, 2, 3])] {
            let (beta, fitted) = bls.without(&full, block);
            let kept: Vec<&[f64]> = keep.iter().map(|&k| refs[k]).collect();
            let direct = least_squares(&kept, &y, 0..n).unwrap();
            for (&k, d) in keep.iter().zip(&direct) {
                assert!((beta[k] - d).abs() < 1e-9, "block {block} column {k}: {} vs {d}", beta[k]);
            }
            let direct_fit: Vec<f64> =
                (0..n).map(|t| kept.iter().zip(&direct).map(|(c, b)| c[t] * b).sum()).collect();
            assert!(fitted.iter().zip(&direct_fit).all(|(a, b)| (a - b).abs() < 1e-9));
        }
    }

    #[test]
    fn block_least_squares_refuses_a_collinear_design() {
        let a: Vec<f64> = (0..30).map(|t| (t as f64 * 0.3).sin()).collect();
        assert!(BlockLeastSquares::new(&[&a, &a], vec![0..1, 1..2], 0..30).is_none());
        assert!(BlockLeastSquares::new(&[&a], std::iter::once(0..1).collect(), 0..0).is_none());
    }

    #[test]
    fn projection_drops_collinear_features() {
        let a: Vec<f64> = (0..30).map(|t| (t as f64 * 0.3).sin()).collect();
        let b: Vec<f64> = a.iter().map(|v| 2.0 * v).collect();
        let p = Projector::new(&[a.clone(), b], 0..30);
        assert_eq!(p.q.ncols(), 1, "two collinear features span one direction");
        let pa = p.project(&a);
        assert!(pa.iter().zip(&a).all(|(u, v)| (u - v).abs() < 1e-9));
    }

    #[test]
    fn projection_is_idempotent_and_keeps_the_span() {
        let f: Vec<Vec<f64>> = vec![(0..30).map(|t| t as f64).collect(), vec![1.0; 30]];
        let p = Projector::new(&f, 0..30);
        let line: Vec<f64> = (0..30).map(|t| 2.0 * t as f64 - 1.0).collect();
        let pl = p.project(&line);
        assert!(pl.iter().zip(&line).all(|(a, b)| (a - b).abs() < 1e-9));
        let noise: Vec<f64> = (0..30).map(|t| ((t * 7919) % 13) as f64).collect();
        let once = p.project(&noise);
        let twice = p.project(&once);
        assert!(once.iter().zip(&twice).all(|(a, b)| (a - b).abs() < 1e-9));
    }
}
