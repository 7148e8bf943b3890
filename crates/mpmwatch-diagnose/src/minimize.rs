//! The one nonlinear least-squares solver of the diagnosis: Levenberg–Marquardt
//! (`levenberg-marquardt`) on a residual given as a function of the parameters, with a
//! forward-difference Jacobian. Every simulation-error fit (the grey-box hypotheses, a physical
//! model's calibration) goes through [`minimize`], or [`minimize_from`] for several starts.

use levenberg_marquardt::{LeastSquaresProblem, LevenbergMarquardt};
use nalgebra::{DMatrix, DVector, Dyn, Owned};

/// Minimises `Σ r(x)²` from `x0` and returns the parameters reached. `residual` returns `None`
/// where the model cannot be evaluated (a diverging simulation); those points are given a
/// residual of `blowup` in every entry, large and finite, so a step into them is rejected
/// rather than aborting the search. `len` is the length of every residual vector.
pub fn minimize(
    residual: &dyn Fn(&[f64]) -> Option<Vec<f64>>,
    x0: &[f64],
    len: usize,
    blowup: f64,
) -> Vec<f64> {
    let floor = x0.iter().map(|v| if *v != 0.0 { 1e-3 * v.abs() } else { 1e-3 }).collect();
    let problem = Problem { residual, len, blowup, x: DVector::from_column_slice(x0), floor };
    let (solved, _) = LevenbergMarquardt::new().with_patience(30).minimize(problem);
    solved.x.as_slice().to_vec()
}

/// [`minimize`] from each of `starts`; the parameters with the least `Σ r(x)²` (a point that
/// cannot be evaluated, or whose sum is not finite, never wins). `None` without starts. For
/// fits with local minima, where one start stops in a poor one.
pub fn minimize_from(
    residual: &dyn Fn(&[f64]) -> Option<Vec<f64>>,
    starts: &[Vec<f64>],
    len: usize,
    blowup: f64,
) -> Option<Vec<f64>> {
    let cost = |x: &[f64]| {
        let c: f64 = residual(x).map_or(f64::INFINITY, |r| r.iter().map(|e| e * e).sum());
        if c.is_finite() { c } else { f64::INFINITY }
    };
    let mut best: Option<(f64, Vec<f64>)> = None;
    for x0 in starts {
        let x = minimize(residual, x0, len, blowup);
        let c = cost(&x);
        if best.as_ref().is_none_or(|b| c < b.0) {
            best = Some((c, x));
        }
    }
    best.map(|b| b.1)
}

struct Problem<'a> {
    residual: &'a dyn Fn(&[f64]) -> Option<Vec<f64>>,
    len: usize,
    blowup: f64,
    x: DVector<f64>,
    /// The least magnitude a difference step is taken relative to, per parameter.
    floor: Vec<f64>,
}

impl Problem<'_> {
    fn residual_at(&self, x: &DVector<f64>) -> DVector<f64> {
        match (self.residual)(x.as_slice()) {
            Some(r) if r.len() == self.len && r.iter().all(|v| v.is_finite()) => DVector::from_vec(r),
            _ => DVector::from_element(self.len, self.blowup),
        }
    }
}

impl LeastSquaresProblem<f64, Dyn, Dyn> for Problem<'_> {
    type ResidualStorage = Owned<f64, Dyn>;
    type JacobianStorage = Owned<f64, Dyn, Dyn>;
    type ParameterStorage = Owned<f64, Dyn>;

    fn set_params(&mut self, x: &DVector<f64>) {
        self.x.copy_from(x);
    }

    fn params(&self) -> DVector<f64> {
        self.x.clone()
    }

    fn residuals(&self) -> Option<DVector<f64>> {
        Some(self.residual_at(&self.x))
    }

    /// Forward differences, one evaluation per parameter (the crate's own numerical derivative
    /// re-evaluates once per residual entry, which for a simulation is quadratic in the
    /// record's length). The step is a millionth of the parameter, or of a thousandth of its
    /// start when it comes near zero (of 1e-3 for a start at zero): a step fixed in absolute
    /// terms would cross the whole range of a parameter in small units (a dead zone in m³/s).
    fn jacobian(&self) -> Option<DMatrix<f64>> {
        let r0 = self.residual_at(&self.x);
        let mut j = DMatrix::zeros(r0.len(), self.x.len());
        for k in 0..self.x.len() {
            let mut x = self.x.clone();
            let h = 1e-6 * self.x[k].abs().max(self.floor[k]);
            x[k] += h;
            let r = self.residual_at(&x);
            j.set_column(k, &((r - &r0) / h));
        }
        Some(j)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Rosenbrock's function as residuals `[10(y − x²), 1 − x]`: its one minimum is (1, 1),
    /// reached from the textbook start (−1.2, 1).
    #[test]
    fn finds_the_rosenbrock_minimum() {
        let r = |x: &[f64]| Some(vec![10.0 * (x[1] - x[0] * x[0]), 1.0 - x[0]]);
        let x = minimize(&r, &[-1.2, 1.0], 2, 1e3);
        assert!((x[0] - 1.0).abs() < 1e-6 && (x[1] - 1.0).abs() < 1e-6, "{x:?}");
    }

    /// Of two starts either side of a double well `r = x² − 1 + 0.1·x` (minima near −1.05 and
    /// 0.95, both roots, so both reach zero cost), the one that cannot be evaluated loses and
    /// the other's root wins; without starts there is nothing.
    #[test]
    fn the_best_start_wins_and_refused_ones_lose() {
        let r = |x: &[f64]| (x[0] > -0.5).then(|| vec![x[0] * x[0] - 1.0 + 0.1 * x[0]]);
        let x = minimize_from(&r, &[vec![-2.0], vec![2.0]], 1, 1e3).unwrap();
        let root = (-0.1 + (0.01f64 + 4.0).sqrt()) / 2.0;
        assert!((x[0] - root).abs() < 1e-6, "{x:?}");
        assert!(minimize_from(&r, &[], 1, 1e3).is_none());
    }

    /// A region where the model cannot be evaluated is stepped around, not into: an exponential
    /// decay fitted with its rate kept positive by refusing negative rates, from a start (rate
    /// 3 against 0.05) whose first steps land on negative rates.
    #[test]
    fn steps_around_points_that_cannot_be_evaluated() {
        let t: Vec<f64> = (0..50).map(|k| k as f64 * 0.1).collect();
        let y: Vec<f64> = t.iter().map(|t| 2.0 * (-0.05 * t).exp()).collect();
        let refused = std::cell::Cell::new(0);
        let r = |x: &[f64]| {
            if x[1] <= 0.0 {
                refused.set(refused.get() + 1);
                return None;
            }
            Some(t.iter().zip(&y).map(|(t, y)| x[0] * (-x[1] * t).exp() - y).collect())
        };
        let x = minimize(&r, &[1.0, 3.0], t.len(), 1e3);
        assert!((x[0] - 2.0).abs() < 1e-6 && (x[1] - 0.05).abs() < 1e-6, "{x:?}");
        assert!(refused.get() > 0, "no refused point was tried, so the test shows nothing");
    }
}
