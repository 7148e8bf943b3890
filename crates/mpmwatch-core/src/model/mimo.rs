//! MIMO models: a matrix of Hammerstein (or linear) channels, `yⱼ = Σᵢ gⱼᵢ(fⱼᵢ(uᵢ))`.

use super::error::ModelError;
use super::hammerstein::{Hammerstein, HammersteinFilter};
use super::transfer::DiscreteTf;

/// An `ny × nu` matrix of channels; `None` is a zero channel.
#[derive(Debug, Clone, PartialEq)]
pub struct MimoModel {
    ny: usize,
    nu: usize,
    channels: Vec<Option<Hammerstein>>,
}

impl MimoModel {
    /// Builds the model from its rows (one row per output, one entry per input).
    pub fn new(rows: Vec<Vec<Option<Hammerstein>>>) -> Result<Self, ModelError> {
        let ny = rows.len();
        let nu = rows.first().map_or(0, Vec::len);
        for (j, row) in rows.iter().enumerate() {
            if row.len() != nu {
                return Err(ModelError::Dimension {
                    what: format!("channels in row {} (output y{})", j, j + 1),
                    expected: nu,
                    found: row.len(),
                });
            }
        }
        Ok(Self { ny, nu, channels: rows.into_iter().flatten().collect() })
    }

    /// Number of outputs.
    pub fn outputs(&self) -> usize {
        self.ny
    }

    /// Number of inputs.
    pub fn inputs(&self) -> usize {
        self.nu
    }

    /// The channel from input `i` to output `j` (0-based).
    pub fn channel(&self, j: usize, i: usize) -> Option<&Hammerstein> {
        if j >= self.ny || i >= self.nu {
            return None;
        }
        self.channels[j * self.nu + i].as_ref()
    }

    /// Replaces one channel (how the cases inject a mismatch).
    pub fn set_channel(
        &mut self,
        j: usize,
        i: usize,
        channel: Option<Hammerstein>,
    ) -> Result<(), ModelError> {
        if j >= self.ny {
            return Err(ModelError::Dimension {
                what: "output index (0-based, must be below)".into(),
                expected: self.ny,
                found: j,
            });
        }
        if i >= self.nu {
            return Err(ModelError::Dimension {
                what: "input index (0-based, must be below)".into(),
                expected: self.nu,
                found: i,
            });
        }
        self.channels[j * self.nu + i] = channel;
        Ok(())
    }

    /// True when no output depends on the current input, so a loop can read `y(t)` first.
    pub fn is_strictly_proper(&self) -> bool {
        self.channels.iter().flatten().all(|c| c.tf.is_strictly_proper())
    }

    /// True when every channel is linear (identity map).
    pub fn is_linear(&self) -> bool {
        self.channels.iter().flatten().all(|c| c.map.is_identity())
    }

    /// The model linearised at the constant input `u_op`, in deviations from it: every static
    /// map `f` is replaced by its slope `f'(u_op)` as a gain in front of the same linear dynamics
    /// (what MATLAB's `linearize` gives for a Hammerstein channel).
    pub fn linearised(&self, u_op: &[f64]) -> Result<MimoModel, ModelError> {
        if u_op.len() != self.nu {
            return Err(ModelError::Dimension {
                what: "operating point".into(),
                expected: self.nu,
                found: u_op.len(),
            });
        }
        let channels = self
            .channels
            .iter()
            .enumerate()
            .map(|(k, c)| {
                c.as_ref()
                    .map(|c| {
                        let slope = c.map.slope(u_op[k % self.nu]);
                        let b = c.tf.numerator().iter().map(|v| v * slope).collect();
                        DiscreteTf::new(b, c.tf.denominator().to_vec(), c.tf.delay()).map(Hammerstein::linear)
                    })
                    .transpose()
            })
            .collect::<Result<Vec<_>, _>>()?;
        Ok(MimoModel { ny: self.ny, nu: self.nu, channels })
    }

    /// A fresh state with zero initial conditions.
    pub fn state(&self) -> MimoState {
        MimoState {
            nu: self.nu,
            ny: self.ny,
            filters: self.channels.iter().map(|c| c.as_ref().map(Hammerstein::filter)).collect(),
        }
    }

    /// Simulates a whole record; `u[i]` is input i's series, the result has one series per output.
    pub fn simulate(&self, u: &[Vec<f64>]) -> Result<Vec<Vec<f64>>, ModelError> {
        if u.len() != self.nu {
            return Err(ModelError::Dimension {
                what: "MIMO model inputs".into(),
                expected: self.nu,
                found: u.len(),
            });
        }
        let n = u.first().map_or(0, Vec::len);
        if let Some(bad) = u.iter().find(|ui| ui.len() != n) {
            return Err(ModelError::Dimension {
                what: "MIMO input length".into(),
                expected: n,
                found: bad.len(),
            });
        }
        let mut s = self.state();
        let mut y = vec![Vec::with_capacity(n); self.ny];
        let mut ut = vec![0.0; self.nu];
        for t in 0..n {
            for (i, ui) in u.iter().enumerate() {
                ut[i] = ui[t];
            }
            for (j, v) in s.step(&ut)?.into_iter().enumerate() {
                y[j].push(v);
            }
        }
        Ok(y)
    }
}

/// The step-by-step state of a [`MimoModel`]. Cloning it forks a prediction.
#[derive(Debug, Clone)]
pub struct MimoState {
    nu: usize,
    ny: usize,
    filters: Vec<Option<HammersteinFilter>>,
}

impl MimoState {
    /// The outputs at the current sample before the current input acts (the outputs themselves
    /// for a strictly proper model).
    pub fn peek(&self) -> Vec<f64> {
        (0..self.ny)
            .map(|j| {
                self.filters[j * self.nu..(j + 1) * self.nu]
                    .iter()
                    .flatten()
                    .map(HammersteinFilter::peek)
                    .sum()
            })
            .collect()
    }

    /// Feeds `u(t)`, returns `y(t)`.
    pub fn step(&mut self, u: &[f64]) -> Result<Vec<f64>, ModelError> {
        if u.len() != self.nu {
            return Err(ModelError::Dimension {
                what: "MIMO input vector".into(),
                expected: self.nu,
                found: u.len(),
            });
        }
        let mut y = vec![0.0; self.ny];
        for (k, f) in self.filters.iter_mut().enumerate() {
            if let Some(f) = f {
                y[k / self.nu] += f.step(u[k % self.nu]);
            }
        }
        Ok(y)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::model::{DiscreteTf, StaticMap};

    #[test]
    fn two_by_two_superposes_channels() {
        let g11 = DiscreteTf::new(vec![0.0, 1.0], vec![1.0, -0.5], 0).unwrap();
        let g21 = DiscreteTf::new(vec![3.0], vec![1.0], 2).unwrap();
        let g22 = DiscreteTf::new(vec![0.0, 1.0], vec![1.0], 0).unwrap();
        let m = MimoModel::new(vec![
            vec![Some(Hammerstein::linear(g11)), None],
            vec![Some(Hammerstein::linear(g21)), Some(Hammerstein::new(StaticMap::Square, g22).unwrap())],
        ])
        .unwrap();
        assert!(m.is_strictly_proper());
        let y = m.simulate(&[vec![1.0, 0.0, 0.0, 0.0], vec![2.0, 0.0, 0.0, 0.0]]).unwrap();
        assert_eq!(y[0], vec![0.0, 1.0, 0.5, 0.25]);
        assert_eq!(y[1], vec![0.0, 4.0, 3.0, 0.0]);
        assert!(MimoModel::new(vec![vec![None, None], vec![None]]).is_err());
        assert!(m.state().step(&[1.0]).is_err());

        // linearised at u2 = 1.5: the square law becomes a gain of 3 on the same dynamics
        let lin = m.linearised(&[0.0, 1.5]).unwrap();
        assert!(lin.is_linear());
        let y = lin.simulate(&[vec![0.0; 4], vec![1.0, 0.0, 0.0, 0.0]]).unwrap();
        assert_eq!(y[1], vec![0.0, 3.0, 0.0, 0.0]);
        assert!(m.linearised(&[0.0]).is_err());
        let mut m2 = m.clone();
        assert!(m2.set_channel(2, 0, None).is_err());
        m2.set_channel(1, 0, None).unwrap();
        assert!(m2.channel(1, 0).is_none() && m2.channel(5, 5).is_none());
    }
}
