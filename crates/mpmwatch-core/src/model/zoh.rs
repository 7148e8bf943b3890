//! Continuous transfer functions and their zero-order-hold discretisation.

use super::error::{ModelError, check_poly};
use super::state_space::{Mat, StateSpace};
use super::transfer::DiscreteTf;

/// `G(s) = e^(−θs) · N(s)/D(s)`, polynomials in descending powers of s.
#[derive(Debug, Clone, PartialEq)]
pub struct ContinuousTf {
    num: Vec<f64>,
    den: Vec<f64>,
    delay_s: f64,
}

impl ContinuousTf {
    /// Builds `N(s)/D(s)` with a dead time of `delay_s` seconds; rejects improper or empty
    /// polynomials, a zero leading denominator coefficient and non-finite values.
    pub fn new(num: Vec<f64>, den: Vec<f64>, delay_s: f64) -> Result<Self, ModelError> {
        check_poly("numerator", &num)?;
        check_poly("denominator", &den)?;
        if den[0] == 0.0 {
            return Err(ModelError::ZeroLeading { what: format!("denominator {den:?}") });
        }
        let num: Vec<f64> = {
            let first = num.iter().position(|v| *v != 0.0).unwrap_or(num.len() - 1);
            num[first..].to_vec()
        };
        if num.len() > den.len() {
            return Err(ModelError::Improper {
                what: format!("{num:?}/{den:?}"),
                num: num.len() - 1,
                den: den.len() - 1,
            });
        }
        if !(delay_s.is_finite() && delay_s >= 0.0) {
            return Err(ModelError::NotFinite { what: "dead time".into(), index: 0, value: delay_s });
        }
        Ok(Self { num, den, delay_s })
    }

    /// A controllable-canonical realisation `(A, B, C, D)` of the rational part.
    pub fn realisation(&self) -> (Mat, Mat, Mat, Mat) {
        let n = self.den.len() - 1;
        let d0 = self.den[0];
        let den: Vec<f64> = self.den.iter().map(|v| v / d0).collect();
        let mut num = vec![0.0; n + 1 - self.num.len()];
        num.extend(self.num.iter().map(|v| v / d0));
        let dd = num[0];
        let mut a = Mat::zeros(n, n);
        let mut b = Mat::zeros(n, 1);
        let mut c = Mat::zeros(1, n);
        for j in 0..n {
            a[(0, j)] = -den[j + 1];
            c[(0, j)] = num[j + 1] - dd * den[j + 1];
        }
        for i in 1..n {
            a[(i, i - 1)] = 1.0;
        }
        if n > 0 {
            b[(0, 0)] = 1.0;
        }
        let mut d = Mat::zeros(1, 1);
        d[(0, 0)] = dd;
        (a, b, c, d)
    }

    /// Zero-order-hold discretisation at sample period `t` seconds.
    ///
    /// Exact for piecewise-constant inputs: `Ad = e^(AT)`, `Bd = ∫₀ᵀ e^(Aτ) dτ B` from one matrix
    /// exponential of the augmented matrix. The discrete denominator is the characteristic
    /// polynomial of `Ad` (Faddeev–LeVerrier) and the numerator follows from the Markov
    /// parameters, so no pole/zero bookkeeping is needed for repeated or complex poles. The dead
    /// time must be a whole number of samples.
    pub fn discretise(&self, t: f64) -> Result<DiscreteTf, ModelError> {
        if !(t.is_finite() && t > 0.0) {
            return Err(ModelError::BadSamplePeriod(t));
        }
        let samples = self.delay_s / t;
        if (samples - samples.round()).abs() > 1e-9 * samples.max(1.0) {
            return Err(ModelError::FractionalDelay {
                what: format!("{:?}/{:?}", self.num, self.den),
                delay: self.delay_s,
                period: t,
            });
        }
        let delay = samples.round() as usize;
        let (a, b, c, d) = self.realisation();
        let ss = StateSpace::zoh(&a, &b, &c, &d, t)?;
        let n = a.nrows();
        let ad = ss.a();
        let char_poly = characteristic_polynomial(ad);
        // Markov parameters h0 = D, hk = C Ad^(k-1) Bd
        let mut h = vec![d[(0, 0)]];
        let mut x = ss.b().clone();
        for _ in 0..n {
            h.push((&c * &x)[(0, 0)]);
            x = ad * &x;
        }
        let num: Vec<f64> = (0..=n).map(|k| (0..=k).map(|i| char_poly[i] * h[k - i]).sum()).collect();
        DiscreteTf::new(num, char_poly, delay)
    }
}

/// `det(zI − A) = z^n + p1 z^(n−1) + … + pn`, returned as `[1, p1, …, pn]` (Faddeev–LeVerrier).
pub(crate) fn characteristic_polynomial(a: &Mat) -> Vec<f64> {
    let n = a.nrows();
    let mut p = vec![1.0];
    let mut m = Mat::identity(n, n);
    for k in 1..=n {
        let am = a * &m;
        let pk = -am.trace() / k as f64;
        p.push(pk);
        m = am + Mat::identity(n, n) * pk;
    }
    p
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn first_order_lag_matches_closed_form() {
        for t in [0.1, 0.5, 1.0, 2.0] {
            let g = ContinuousTf::new(vec![1.0], vec![1.0, 1.0], 0.0).unwrap().discretise(t).unwrap();
            let p = (-t).exp();
            assert!((g.denominator()[1] + p).abs() < 1e-12, "pole at T={t}");
            assert!(g.numerator()[0].abs() < 1e-12);
            assert!((g.numerator()[1] - (1.0 - p)).abs() < 1e-12);
        }
    }

    #[test]
    fn second_order_step_matches_continuous_step_at_samples() {
        // (s+2)/(s+1)^2 has step response 2 − (2 + t)e^(−t)... check: L⁻¹{(s+2)/(s(s+1)²)}
        // = 2 − 2e^(−t) − t e^(−t).
        let t = 0.3;
        let g = ContinuousTf::new(vec![1.0, 2.0], vec![1.0, 2.0, 1.0], 0.0).unwrap().discretise(t).unwrap();
        let s = g.step_response(40);
        for (k, v) in s.iter().enumerate() {
            let tk = k as f64 * t;
            let exact = 2.0 - 2.0 * (-tk).exp() - tk * (-tk).exp();
            assert!((v - exact).abs() < 1e-10, "k={k}: {v} vs {exact}");
        }
    }

    #[test]
    fn dead_time_becomes_whole_samples_or_an_error() {
        let g = ContinuousTf::new(vec![1.0], vec![2.0, 1.0], 1.5).unwrap();
        assert_eq!(g.discretise(0.5).unwrap().delay(), 3);
        assert!(matches!(g.discretise(0.4), Err(ModelError::FractionalDelay { .. })));
        assert!(matches!(g.discretise(0.0), Err(ModelError::BadSamplePeriod(_))));
        assert!(matches!(
            ContinuousTf::new(vec![1.0, 0.0, 0.0], vec![1.0, 1.0], 0.0),
            Err(ModelError::Improper { .. })
        ));
    }
}
