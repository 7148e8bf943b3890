//! ARX models `A(q⁻¹) y(t) = Σᵢ q^-nkᵢ Bᵢ(q⁻¹) uᵢ(t) + e(t)` (multi-input, single output).

use std::collections::VecDeque;

use super::error::{ModelError, check_poly};
use super::transfer::DiscreteTf;

/// A MISO ARX model; `a` is monic after construction.
#[derive(Debug, Clone, PartialEq)]
pub struct Arx {
    a: Vec<f64>,
    b: Vec<Vec<f64>>,
    delays: Vec<usize>,
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
        })
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
        let mut s = 0.0;
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
        let mut v = 0.0;
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
    fn wrong_input_count_is_an_error() {
        let m = Arx::new(vec![1.0], vec![vec![1.0], vec![1.0]], vec![0, 0]).unwrap();
        assert!(m.simulate(&[vec![1.0]]).is_err());
        assert!(Arx::new(vec![1.0], vec![vec![1.0]], vec![]).is_err());
    }
}
