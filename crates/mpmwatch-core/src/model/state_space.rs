//! Discrete state-space models `x(t+1) = A x(t) + B u(t)`, `y(t) = C x(t) + D u(t)`.

use nalgebra::{DMatrix, DVector};

use super::error::ModelError;

/// A dense real matrix (nalgebra's, dynamically sized).
pub type Mat = DMatrix<f64>;

/// A discrete linear state-space model.
#[derive(Debug, Clone, PartialEq)]
pub struct StateSpace {
    a: Mat,
    b: Mat,
    c: Mat,
    d: Mat,
}

impl StateSpace {
    /// Builds the model; the matrix sizes must agree.
    pub fn new(a: Mat, b: Mat, c: Mat, d: Mat) -> Result<Self, ModelError> {
        let n = a.nrows();
        let dim = |what: &str, expected: usize, found: usize| {
            if expected == found {
                Ok(())
            } else {
                Err(ModelError::Dimension { what: what.into(), expected, found })
            }
        };
        dim("columns of A", n, a.ncols())?;
        dim("rows of B", n, b.nrows())?;
        dim("columns of C", n, c.ncols())?;
        dim("rows of D", c.nrows(), d.nrows())?;
        dim("columns of D", b.ncols(), d.ncols())?;
        Ok(Self { a, b, c, d })
    }

    /// Zero-order-hold discretisation of the continuous model `(A, B, C, D)` at period `t`.
    pub fn zoh(a: &Mat, b: &Mat, c: &Mat, d: &Mat, t: f64) -> Result<Self, ModelError> {
        if !(t.is_finite() && t > 0.0) {
            return Err(ModelError::BadSamplePeriod(t));
        }
        // validates the sizes before they are used as indices
        Self::new(a.clone(), b.clone(), c.clone(), d.clone())?;
        let (n, m) = (a.nrows(), b.ncols());
        // exp([[A, B], [0, 0]]·T) = [[Ad, Bd], [0, I]] (Van Loan)
        let mut aug = Mat::zeros(n + m, n + m);
        aug.view_mut((0, 0), (n, n)).copy_from(&(a * t));
        aug.view_mut((0, n), (n, m)).copy_from(&(b * t));
        let e = aug.exp();
        let ad = e.view((0, 0), (n, n)).into_owned();
        let bd = e.view((0, n), (n, m)).into_owned();
        Self::new(ad, bd, c.clone(), d.clone())
    }

    /// The state matrix.
    pub fn a(&self) -> &Mat {
        &self.a
    }
    /// The input matrix.
    pub fn b(&self) -> &Mat {
        &self.b
    }
    /// The output matrix.
    pub fn c(&self) -> &Mat {
        &self.c
    }
    /// The feed-through matrix.
    pub fn d(&self) -> &Mat {
        &self.d
    }

    /// A fresh state at the origin.
    pub fn state(&self) -> SsState {
        SsState { model: self.clone(), x: DVector::zeros(self.a.nrows()) }
    }

    /// Simulates a whole record; `u[t]` is the input vector at sample t.
    pub fn simulate(&self, u: &[Vec<f64>]) -> Result<Vec<Vec<f64>>, ModelError> {
        let mut s = self.state();
        u.iter().map(|ut| s.step(ut)).collect()
    }
}

/// The step-by-step state of a [`StateSpace`] model.
#[derive(Debug, Clone)]
pub struct SsState {
    model: StateSpace,
    x: DVector<f64>,
}

impl SsState {
    /// The current state vector.
    pub fn x(&self) -> &[f64] {
        self.x.as_slice()
    }

    /// `C x(t)`: the output before the direct feed-through of `u(t)`.
    pub fn peek(&self) -> Vec<f64> {
        (&self.model.c * &self.x).as_slice().to_vec()
    }

    /// Feeds `u(t)`, returns `y(t)` and advances the state.
    pub fn step(&mut self, u: &[f64]) -> Result<Vec<f64>, ModelError> {
        if u.len() != self.model.b.ncols() {
            return Err(ModelError::Dimension {
                what: "state-space input vector".into(),
                expected: self.model.b.ncols(),
                found: u.len(),
            });
        }
        let u = DVector::from_column_slice(u);
        let y = &self.model.c * &self.x + &self.model.d * &u;
        self.x = &self.model.a * &self.x + &self.model.b * &u;
        Ok(y.as_slice().to_vec())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn double_integrator_zoh_by_hand() {
        // x1' = x2, x2' = u: Ad = [[1, T], [0, 1]], Bd = [T²/2, T]
        let a = Mat::from_row_slice(2, 2, &[0.0, 1.0, 0.0, 0.0]);
        let b = Mat::from_row_slice(2, 1, &[0.0, 1.0]);
        let c = Mat::from_row_slice(1, 2, &[1.0, 0.0]);
        let d = Mat::zeros(1, 1);
        let t = 0.4;
        let ss = StateSpace::zoh(&a, &b, &c, &d, t).unwrap();
        assert!((ss.a()[(0, 1)] - t).abs() < 1e-14);
        assert!((ss.b()[(0, 0)] - t * t / 2.0).abs() < 1e-14);
        assert!((ss.b()[(1, 0)] - t).abs() < 1e-14);
        // unit step: position (kT)²/2
        let y = ss.simulate(&vec![vec![1.0]; 6]).unwrap();
        for (k, yk) in y.iter().enumerate() {
            let tk = k as f64 * t;
            assert!((yk[0] - tk * tk / 2.0).abs() < 1e-12);
        }
    }

    #[test]
    fn wrong_sizes_are_errors() {
        let a = Mat::identity(2, 2);
        let b = Mat::zeros(3, 1);
        assert!(StateSpace::new(a, b, Mat::zeros(1, 2), Mat::zeros(1, 1)).is_err());
        let ss = StateSpace::new(Mat::identity(1, 1), Mat::zeros(1, 1), Mat::zeros(1, 1), Mat::zeros(1, 1))
            .unwrap();
        assert!(ss.state().step(&[1.0, 2.0]).is_err());
        let bad_b = Mat::zeros(2, 1);
        assert!(
            StateSpace::zoh(&Mat::identity(1, 1), &bad_b, &Mat::zeros(1, 1), &Mat::zeros(1, 1), 0.1).is_err()
        );
    }
}
