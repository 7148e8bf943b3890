//! ARX models `A(q⁻¹) y(t) = Σᵢ q^-nkᵢ Bᵢ(q⁻¹) uᵢ(t) + e(t)` (multi-input, single output).

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
            return Err(ModelError::ZeroLeading {
                what: "ARX A polynomial".into(),
            });
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
            b: b.iter()
                .map(|bi| bi.iter().map(|v| v / a0).collect())
                .collect(),
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
        assert_eq!(
            m.channel(0).unwrap().impulse_response(4),
            vec![0.0, 2.0, 1.0, 0.5]
        );
    }

    #[test]
    fn wrong_input_count_is_an_error() {
        let m = Arx::new(vec![1.0], vec![vec![1.0], vec![1.0]], vec![0, 0]).unwrap();
        assert!(m.simulate(&[vec![1.0]]).is_err());
        assert!(Arx::new(vec![1.0], vec![vec![1.0]], vec![]).is_err());
    }
}
