//! Discrete transfer functions `q^-d · B(q⁻¹) / A(q⁻¹)` and their step-by-step filter.

use std::collections::VecDeque;

use super::error::{ModelError, check_poly};

/// `y(t) = q^-delay · (b0 + b1 q⁻¹ + …) / (1 + a1 q⁻¹ + …) · u(t)`.
///
/// The denominator is stored monic (`a[0] == 1`); [`DiscreteTf::new`] divides both polynomials
/// by the given `a[0]`.
#[derive(Debug, Clone, PartialEq)]
pub struct DiscreteTf {
    b: Vec<f64>,
    a: Vec<f64>,
    delay: usize,
}

impl DiscreteTf {
    /// Builds `q^-delay B/A` from coefficients in ascending powers of q⁻¹.
    pub fn new(b: Vec<f64>, a: Vec<f64>, delay: usize) -> Result<Self, ModelError> {
        check_poly("numerator", &b)?;
        check_poly("denominator", &a)?;
        let a0 = a[0];
        if a0 == 0.0 {
            return Err(ModelError::ZeroLeading { what: format!("denominator {a:?}") });
        }
        Ok(Self { b: b.iter().map(|v| v / a0).collect(), a: a.iter().map(|v| v / a0).collect(), delay })
    }

    /// A static gain `k` (no dynamics).
    pub fn gain(k: f64) -> Result<Self, ModelError> {
        Self::new(vec![k], vec![1.0], 0)
    }

    /// The numerator coefficients (ascending powers of q⁻¹, after normalisation).
    pub fn numerator(&self) -> &[f64] {
        &self.b
    }

    /// The monic denominator coefficients.
    pub fn denominator(&self) -> &[f64] {
        &self.a
    }

    /// The dead time in samples.
    pub fn delay(&self) -> usize {
        self.delay
    }

    /// True when `y(t)` does not depend on `u(t)`, so a loop can read `y(t)` before choosing `u(t)`.
    pub fn is_strictly_proper(&self) -> bool {
        self.delay > 0 || self.b[0] == 0.0
    }

    /// Steady-state gain `B(1)/A(1)`, `None` for an integrator.
    pub fn dc_gain(&self) -> Option<f64> {
        let a1: f64 = self.a.iter().sum();
        (a1.abs() > 1e-12).then(|| self.b.iter().sum::<f64>() / a1)
    }

    /// True when every pole lies strictly inside the unit circle (Schur–Cohn step-down test).
    pub fn is_stable(&self) -> bool {
        is_schur(&self.a)
    }

    /// An error naming `what` when the denominator is not stable.
    pub fn require_stable(&self, what: &str) -> Result<(), ModelError> {
        if self.is_stable() {
            Ok(())
        } else {
            Err(ModelError::Unstable { what: what.to_string(), coefficients: self.a.clone() })
        }
    }

    /// The series connection `self · other`.
    pub fn series(&self, other: &DiscreteTf) -> DiscreteTf {
        DiscreteTf {
            b: poly_mul(&self.b, &other.b),
            a: poly_mul(&self.a, &other.a),
            delay: self.delay + other.delay,
        }
    }

    /// A fresh filter with zero initial conditions.
    pub fn filter(&self) -> TfFilter {
        TfFilter::new(self.clone())
    }

    /// Simulates the whole record from zero initial conditions.
    pub fn simulate(&self, u: &[f64]) -> Vec<f64> {
        let mut f = self.filter();
        u.iter().map(|&x| f.step(x)).collect()
    }

    /// Simulates the whole record started in steady state at the first input value: before the
    /// record the input was `u(0)` and the output its DC response, as a simulation started at an
    /// operating point is (an integrator starts at zero).
    pub fn simulate_from_rest(&self, u: &[f64]) -> Vec<f64> {
        let Some(&u0) = u.first() else { return Vec::new() };
        let den = 1.0 + self.a[1..].iter().sum::<f64>();
        let y0 = if den.abs() > 1e-12 { self.b.iter().sum::<f64>() * u0 / den } else { 0.0 };
        let mut f = TfFilter {
            u_past: VecDeque::from(vec![u0; self.delay + self.b.len()]),
            y_past: VecDeque::from(vec![y0; self.a.len() - 1]),
            tf: self.clone(),
        };
        u.iter().map(|&x| f.step(x)).collect()
    }

    /// The first `n` impulse-response samples `h(0), h(1), …`.
    pub fn impulse_response(&self, n: usize) -> Vec<f64> {
        let mut u = vec![0.0; n];
        if n > 0 {
            u[0] = 1.0;
        }
        self.simulate(&u)
    }

    /// The first `n` unit-step-response samples.
    pub fn step_response(&self, n: usize) -> Vec<f64> {
        self.simulate(&vec![1.0; n])
    }
}

/// Polynomial product (coefficient convolution).
pub(crate) fn poly_mul(p: &[f64], q: &[f64]) -> Vec<f64> {
    let mut out = vec![0.0; p.len() + q.len() - 1];
    for (i, a) in p.iter().enumerate() {
        for (j, b) in q.iter().enumerate() {
            out[i + j] += a * b;
        }
    }
    out
}

/// Schur–Cohn (Jury) step-down: `1 + a1 z⁻¹ + … + an z⁻ⁿ` has all roots inside the unit circle
/// iff every reflection coefficient has magnitude below one.
pub(crate) fn is_schur(a: &[f64]) -> bool {
    let mut c: Vec<f64> = a.to_vec();
    while c.len() > 1 && *c.last().unwrap() == 0.0 {
        c.pop();
    }
    while c.len() > 1 {
        let n = c.len() - 1;
        let k = c[n] / c[0];
        if k.abs() >= 1.0 || k.is_nan() {
            return false;
        }
        let den = 1.0 - k * k;
        c = (0..n).map(|i| (c[i] - k * c[n - i]) / den).collect();
    }
    true
}

/// The step-by-step state of a [`DiscreteTf`]: past inputs and outputs.
#[derive(Debug, Clone)]
pub struct TfFilter {
    tf: DiscreteTf,
    /// `u(t-1), u(t-2), …` (most recent first).
    u_past: VecDeque<f64>,
    /// `y(t-1), y(t-2), …` (most recent first).
    y_past: VecDeque<f64>,
}

impl TfFilter {
    fn new(tf: DiscreteTf) -> Self {
        let nu = tf.delay + tf.b.len();
        let ny = tf.a.len() - 1;
        Self { u_past: VecDeque::from(vec![0.0; nu]), y_past: VecDeque::from(vec![0.0; ny]), tf }
    }

    /// The transfer function this filter runs.
    pub fn tf(&self) -> &DiscreteTf {
        &self.tf
    }

    fn output(&self, u: f64) -> f64 {
        let mut y = 0.0;
        for (i, b) in self.tf.b.iter().enumerate() {
            let lag = self.tf.delay + i;
            y += b * if lag == 0 { u } else { self.u_past[lag - 1] };
        }
        for (i, a) in self.tf.a.iter().enumerate().skip(1) {
            y -= a * self.y_past[i - 1];
        }
        y
    }

    /// The output at the current sample if the current input were zero: for a strictly proper
    /// transfer function, the output itself, known before the input is chosen.
    pub fn peek(&self) -> f64 {
        self.output(0.0)
    }

    /// Feeds `u(t)`, returns `y(t)` and advances one sample.
    pub fn step(&mut self, u: f64) -> f64 {
        let y = self.output(u);
        self.u_past.push_front(u);
        self.u_past.pop_back();
        if !self.y_past.is_empty() {
            self.y_past.push_front(y);
            self.y_past.pop_back();
        }
        y
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn first_order_step_response_by_hand() {
        // y(t) = 0.5 y(t-1) + u(t-1): step response 0, 1, 1.5, 1.75, 1.875
        let g = DiscreteTf::new(vec![0.0, 1.0], vec![1.0, -0.5], 0).unwrap();
        assert_eq!(g.step_response(5), vec![0.0, 1.0, 1.5, 1.75, 1.875]);
        assert_eq!(g.dc_gain(), Some(2.0));
        assert!(g.is_strictly_proper());
    }

    #[test]
    fn from_rest_starts_at_the_dc_response_and_stays_there() {
        // y(t) = 0.5 y(t-1) + u(t-1), DC gain 2: a constant input of 3 gives 6 throughout; a step
        // from 3 to 4 at t = 2 shows one sample later: 6, 6, 6, 7, 7.5, 7.75.
        let g = DiscreteTf::new(vec![0.0, 1.0], vec![1.0, -0.5], 0).unwrap();
        assert_eq!(g.simulate_from_rest(&[3.0; 4]), vec![6.0; 4]);
        assert_eq!(
            g.simulate_from_rest(&[3.0, 3.0, 4.0, 4.0, 4.0, 4.0]),
            vec![6.0, 6.0, 6.0, 7.0, 7.5, 7.75]
        );
        assert!(g.simulate_from_rest(&[]).is_empty());
    }

    #[test]
    fn dead_time_shifts_the_response() {
        let g = DiscreteTf::new(vec![2.0], vec![1.0], 3).unwrap();
        assert_eq!(g.impulse_response(6), vec![0.0, 0.0, 0.0, 2.0, 0.0, 0.0]);
    }

    #[test]
    fn denominator_is_normalised() {
        let g = DiscreteTf::new(vec![2.0], vec![2.0, -1.0], 0).unwrap();
        assert_eq!(g.denominator(), &[1.0, -0.5]);
        assert_eq!(g.numerator(), &[1.0]);
        assert!(!g.is_strictly_proper());
    }

    #[test]
    fn schur_test_separates_stable_from_unstable() {
        assert!(is_schur(&[1.0, -1.2, 0.35])); // poles 0.7, 0.5
        assert!(is_schur(&[1.0, -1.6, 0.8])); // |poles| = 0.894
        assert!(!is_schur(&[1.0, -1.5])); // pole 1.5
        assert!(!is_schur(&[1.0, -2.0, 1.0])); // double pole at 1
        assert!(!is_schur(&[1.0, 0.0, 1.21])); // poles ±1.1j
    }

    #[test]
    fn bad_coefficients_are_errors() {
        assert!(matches!(DiscreteTf::new(vec![1.0], vec![0.0, 1.0], 0), Err(ModelError::ZeroLeading { .. })));
        assert!(matches!(DiscreteTf::new(vec![], vec![1.0], 0), Err(ModelError::Empty { .. })));
        assert!(matches!(DiscreteTf::new(vec![f64::NAN], vec![1.0], 0), Err(ModelError::NotFinite { .. })));
        let g = DiscreteTf::new(vec![1.0], vec![1.0, -1.1], 0).unwrap();
        assert!(g.require_stable("test plant").unwrap_err().to_string().contains("test plant"));
    }

    #[test]
    fn peek_equals_step_for_strictly_proper() {
        let g = DiscreteTf::new(vec![0.0, 0.3, 0.2], vec![1.0, -1.2, 0.35], 1).unwrap();
        let mut f = g.filter();
        for k in 0..20 {
            let before = f.peek();
            let y = f.step((k as f64).sin());
            assert_eq!(before, y);
        }
    }
}
