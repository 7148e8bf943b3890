//! ARX models `A(q⁻¹) y(t) = Σᵢ q^-nkᵢ Bᵢ(q⁻¹) uᵢ(t) + e(t)` (multi-input, single output).

use std::collections::VecDeque;

use super::error::{ModelError, check_poly};
use super::transfer::DiscreteTf;

/// A MISO ARX model; `a` is monic after construction. An identified model may carry a constant
/// `c` on the right-hand side (`A y = Σ B u + c`, the operating point); a built one has none.
#[derive(Debug, Clone, PartialEq)]
pub struct Arx {
    a: Vec<f64>,
    b: Vec<Vec<f64>>,
    delays: Vec<usize>,
    offset: f64,
}

/// The structure of an ARX model to identify: `na` past outputs, and per input `nb` numerator
/// coefficients after its dead time.
#[derive(Debug, Clone, PartialEq)]
pub struct ArxOrders {
    /// Number of past outputs (`A`'s degree).
    pub na: usize,
    /// Numerator length per input.
    pub nb: usize,
    /// Dead time per input, samples (empty: none).
    pub delays: Vec<usize>,
}

impl Arx {
    /// Builds the model: `a = [1, a1, …]`, one numerator and one dead time per input.
    pub fn new(a: Vec<f64>, b: Vec<Vec<f64>>, delays: Vec<usize>) -> Result<Self, ModelError> {
        check_poly("ARX A polynomial", &a)?;
        if a[0] == 0.0 {
            return Err(ModelError::ZeroLeading { what: "ARX A polynomial".into() });
        }
        if b.len() != delays.len() {
            return Err(ModelError::Dimension {
                what: "ARX dead times (one per input)".into(),
                expected: b.len(),
                found: delays.len(),
            });
        }
        for (i, bi) in b.iter().enumerate() {
            check_poly(&format!("ARX B polynomial of input {}", i + 1), bi)?;
        }
        let a0 = a[0];
        Ok(Self {
            a: a.iter().map(|v| v / a0).collect(),
            b: b.iter().map(|bi| bi.iter().map(|v| v / a0).collect()).collect(),
            delays,
            offset: 0.0,
        })
    }

    /// Identifies `y(t) = −a₁y(t−1) − … + Σᵢ Σₖ bᵢₖ uᵢ(t−dᵢ−k) + c` by least squares on `rows`
    /// (rows before the longest lag are skipped, so every regressor is inside the record).
    /// `None` when the fit cannot be made: `nb` = 0, a dead-time list of the wrong length, an
    /// input or output shorter than `rows`, no row left after the lags, or a value that is not
    /// finite.
    pub fn fit(y: &[f64], u: &[&[f64]], orders: &ArxOrders, rows: std::ops::Range<usize>) -> Option<Self> {
        use crate::numerics::{lagged, least_squares};
        let delays: Vec<usize> =
            if orders.delays.is_empty() { vec![0; u.len()] } else { orders.delays.clone() };
        if orders.nb == 0
            || delays.len() != u.len()
            || y.len() < rows.end
            || u.iter().any(|x| x.len() < rows.end)
        {
            return None;
        }
        let ones = vec![1.0; y.len()];
        let mut cols: Vec<Vec<f64>> = (1..=orders.na).map(|l| lagged(y, l)).collect();
        for (ui, d) in u.iter().zip(&delays) {
            cols.extend((*d..d + orders.nb).map(|k| lagged(ui, k)));
        }
        let mut refs: Vec<&[f64]> = cols.iter().map(Vec::as_slice).collect();
        refs.push(&ones);
        let lag = delays.iter().map(|d| (d + orders.nb).saturating_sub(1)).max().unwrap_or(0).max(orders.na);
        let first = rows.start.max(lag);
        if first >= rows.end {
            return None;
        }
        let th = least_squares(&refs, y, first..rows.end)?;
        let mut a = vec![1.0];
        a.extend(th[..orders.na].iter().map(|v| -v));
        let b = (0..u.len())
            .map(|i| th[orders.na + i * orders.nb..orders.na + (i + 1) * orders.nb].to_vec())
            .collect();
        Some(Self { a, b, delays, offset: th[th.len() - 1] })
    }

    /// The monic denominator `[1, a₁, …]`.
    pub fn denominator(&self) -> &[f64] {
        &self.a
    }

    /// Input `i`'s numerator (after its dead time).
    pub fn numerator(&self, i: usize) -> &[f64] {
        &self.b[i]
    }

    /// The constant `c` (0 for a model built with [`Arx::new`]).
    pub fn offset(&self) -> f64 {
        self.offset
    }

    /// The steady-state output for constant inputs `u0`, one per input (NaN for an integrator
    /// or a wrong count of inputs).
    pub fn rest_output(&self, u0: &[f64]) -> f64 {
        if u0.len() != self.b.len() {
            return f64::NAN;
        }
        let den: f64 = self.a.iter().sum();
        let num: f64 =
            self.offset + self.b.iter().zip(u0).map(|(bi, u)| bi.iter().sum::<f64>() * u).sum::<f64>();
        if den.abs() > 1e-12 { num / den } else { f64::NAN }
    }

    /// Simulation started from the past: before the record each input held its first value and
    /// the output was `y0`. With `y0` = [`Arx::rest_output`] of the first inputs the model starts
    /// in steady state. Inputs of unequal length or of the wrong count give an error.
    pub fn simulate_from(&self, u: &[&[f64]], y0: f64) -> Result<Vec<f64>, ModelError> {
        let n = u.first().map_or(0, |x| x.len());
        if u.len() != self.b.len() || u.iter().any(|x| x.len() != n) {
            return Err(ModelError::Dimension {
                what: "ARX inputs".into(),
                expected: self.b.len(),
                found: u.len(),
            });
        }
        let mut y = vec![y0; n];
        for t in 0..n {
            let mut v = self.offset;
            for ((bi, nk), ui) in self.b.iter().zip(&self.delays).zip(u) {
                for (k, b) in bi.iter().enumerate() {
                    let kk = nk + k;
                    v += b * if t >= kk { ui[t - kk] } else { ui[0] };
                }
            }
            for (l, a) in self.a.iter().enumerate().skip(1) {
                v -= a * if t >= l { y[t - l] } else { y0 };
            }
            y[t] = v;
        }
        Ok(y)
    }

    /// Number of inputs.
    pub fn inputs(&self) -> usize {
        self.b.len()
    }

    /// Input `i`'s channel as a transfer function `q^-nk B/A`.
    pub fn channel(&self, i: usize) -> Result<DiscreteTf, ModelError> {
        let b = self.b.get(i).ok_or(ModelError::Dimension {
            what: "ARX input index".into(),
            expected: self.b.len(),
            found: i,
        })?;
        DiscreteTf::new(b.clone(), self.a.clone(), self.delays[i])
    }

    fn check(&self, u: &[Vec<f64>], n: usize) -> Result<(), ModelError> {
        if u.len() != self.b.len() {
            return Err(ModelError::Dimension {
                what: "ARX inputs".into(),
                expected: self.b.len(),
                found: u.len(),
            });
        }
        if let Some(bad) = u.iter().find(|ui| ui.len() != n) {
            return Err(ModelError::Dimension {
                what: "ARX input length".into(),
                expected: n,
                found: bad.len(),
            });
        }
        Ok(())
    }

    fn exogenous(&self, u: &[Vec<f64>], t: usize) -> f64 {
        let mut s = self.offset;
        for ((bi, nk), ui) in self.b.iter().zip(&self.delays).zip(u) {
            for (j, b) in bi.iter().enumerate() {
                if let Some(idx) = t.checked_sub(nk + j) {
                    s += b * ui[idx];
                }
            }
        }
        s
    }

    /// Simulation: the model runs on the inputs and its own past outputs.
    pub fn simulate(&self, u: &[Vec<f64>]) -> Result<Vec<f64>, ModelError> {
        let n = u.first().map_or(0, Vec::len);
        self.check(u, n)?;
        let mut y = vec![0.0; n];
        for t in 0..n {
            let mut v = self.exogenous(u, t);
            for (j, a) in self.a.iter().enumerate().skip(1) {
                if let Some(idx) = t.checked_sub(j) {
                    v -= a * y[idx];
                }
            }
            y[t] = v;
        }
        Ok(y)
    }

    /// One-step-ahead prediction: past outputs are the measured `y`.
    pub fn predict(&self, u: &[Vec<f64>], y: &[f64]) -> Result<Vec<f64>, ModelError> {
        self.check(u, y.len())?;
        Ok((0..y.len())
            .map(|t| {
                let mut v = self.exogenous(u, t);
                for (j, a) in self.a.iter().enumerate().skip(1) {
                    if let Some(idx) = t.checked_sub(j) {
                        v -= a * y[idx];
                    }
                }
                v
            })
            .collect())
    }
}

impl Arx {
    /// A step-by-step one-step-ahead predictor with empty history (the online form of
    /// [`Arx::predict`]).
    pub fn predictor(&self) -> ArxPredictor {
        let depth = self.b.iter().zip(&self.delays).map(|(b, d)| b.len() + d).max().unwrap_or(0);
        ArxPredictor {
            model: self.clone(),
            u_past: VecDeque::from(vec![vec![0.0; self.b.len()]; depth]),
            y_past: VecDeque::from(vec![0.0; self.a.len() - 1]),
        }
    }
}

/// The state of an online ARX predictor: past inputs and past measured outputs.
#[derive(Debug, Clone)]
pub struct ArxPredictor {
    model: Arx,
    /// `u(t), u(t−1), …` after a step (most recent first; one vector per sample).
    u_past: VecDeque<Vec<f64>>,
    /// Measured `y(t−1), y(t−2), …`.
    y_past: VecDeque<f64>,
}

impl ArxPredictor {
    /// Takes `u(t)` and returns the prediction of `y(t)` from the past measurements, then records
    /// the measured `y(t)` for the next sample.
    pub fn step(&mut self, u: &[f64], y_measured: f64) -> Result<f64, ModelError> {
        let m = &self.model;
        if u.len() != m.b.len() {
            return Err(ModelError::Dimension {
                what: "ARX predictor inputs".into(),
                expected: m.b.len(),
                found: u.len(),
            });
        }
        if !self.u_past.is_empty() {
            self.u_past.pop_back();
            self.u_past.push_front(u.to_vec());
        }
        let mut v = m.offset;
        for (i, (bi, nk)) in m.b.iter().zip(&m.delays).enumerate() {
            for (j, b) in bi.iter().enumerate() {
                v += b * self.u_past[nk + j][i];
            }
        }
        for (j, a) in m.a.iter().enumerate().skip(1) {
            v -= a * self.y_past[j - 1];
        }
        if !self.y_past.is_empty() {
            self.y_past.pop_back();
            self.y_past.push_front(y_measured);
        }
        Ok(v)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn simulation_and_prediction_by_hand() {
        // y(t) = 0.5 y(t-1) + 2 u(t-1)
        let m = Arx::new(vec![1.0, -0.5], vec![vec![2.0]], vec![1]).unwrap();
        let u = vec![vec![1.0, 0.0, 0.0, 0.0]];
        assert_eq!(m.simulate(&u).unwrap(), vec![0.0, 2.0, 1.0, 0.5]);
        let y = [0.0, 1.0, 1.0, 1.0];
        assert_eq!(m.predict(&u, &y).unwrap(), vec![0.0, 2.0, 0.5, 0.5]);
        assert_eq!(m.channel(0).unwrap().impulse_response(4), vec![0.0, 2.0, 1.0, 0.5]);
    }

    #[test]
    fn online_predictor_equals_the_whole_record_prediction() {
        let m = Arx::new(vec![1.0, -1.05, 0.136], vec![vec![0.5, -0.2], vec![1.0]], vec![1, 0]).unwrap();
        let u1: Vec<f64> = (0..25).map(|k| (k as f64 * 0.7).sin()).collect();
        let u2: Vec<f64> = (0..25).map(|k| (k % 3) as f64).collect();
        let y: Vec<f64> = (0..25).map(|k| (k as f64 * 0.3).cos()).collect();
        let whole = m.predict(&[u1.clone(), u2.clone()], &y).unwrap();
        let mut p = m.predictor();
        for k in 0..25 {
            assert!((p.step(&[u1[k], u2[k]], y[k]).unwrap() - whole[k]).abs() < 1e-12, "k={k}");
        }
        assert!(p.step(&[1.0], 0.0).is_err());
    }

    #[test]
    fn identification_recovers_an_exact_model_and_its_offset() {
        // y(t) = 0.6 y(t-1) + 0.5 u(t-2) - 0.2 u(t-3) + 1.5, driven by a deterministic input.
        let u: Vec<f64> = (0..300).map(|t| ((t * 37) % 11) as f64 - 5.0).collect();
        let mut y = vec![0.0; 300];
        for t in 3..300 {
            y[t] = 0.6 * y[t - 1] + 0.5 * u[t - 2] - 0.2 * u[t - 3] + 1.5;
        }
        let orders = ArxOrders { na: 1, nb: 2, delays: vec![2] };
        let m = Arx::fit(&y, &[&u], &orders, 0..300).unwrap();
        assert!((m.denominator()[1] + 0.6).abs() < 1e-10);
        assert!((m.numerator(0)[0] - 0.5).abs() < 1e-10 && (m.numerator(0)[1] + 0.2).abs() < 1e-10);
        assert!((m.offset() - 1.5).abs() < 1e-9);
        let rest = m.rest_output(&[2.0]);
        assert!((rest - (1.5 + 0.3 * 2.0) / 0.4).abs() < 1e-9);
        let flat = m.simulate_from(&[&[2.0; 20]], rest).unwrap();
        assert!(flat.iter().all(|v| (v - rest).abs() < 1e-9));
        // From the past (input 2, output y0 = 10) a step to 4 at t = 1: by hand with
        // y(t) = 0.6 y(t-1) + 0.5 u(t-2) - 0.2 u(t-3) + 1.5.
        let s = m.simulate_from(&[&[2.0, 4.0, 4.0, 4.0, 4.0]], 10.0).unwrap();
        let want = [8.1, 6.96, 6.276, 6.8656, 6.81936];
        assert!(s.iter().zip(want).all(|(a, b)| (a - b).abs() < 1e-9), "{s:?}");
        // The offset is part of every simulation, not only `simulate_from`.
        let sim = m.simulate(&[vec![2.0; 400]]).unwrap();
        assert!((sim[399] - rest).abs() < 1e-9);
        assert!(Arx::fit(&y, &[&u], &ArxOrders { nb: 0, ..orders.clone() }, 0..300).is_none());
        assert!(Arx::fit(&y, &[&u], &orders, 0..301).is_none());
        assert!(Arx::fit(&y, &[&u], &orders, 0..3).is_none());
    }

    #[test]
    fn wrong_input_count_is_an_error() {
        let m = Arx::new(vec![1.0], vec![vec![1.0], vec![1.0]], vec![0, 0]).unwrap();
        assert!(m.simulate(&[vec![1.0]]).is_err());
        assert!(Arx::new(vec![1.0], vec![vec![1.0]], vec![]).is_err());
    }
}
