//! Hammerstein blocks: a static nonlinearity followed by linear dynamics, `y = G(q) f(u)`.

use super::error::ModelError;
use super::transfer::{DiscreteTf, TfFilter};

/// The static input nonlinearity of a Hammerstein block.
#[derive(Debug, Clone, PartialEq)]
pub enum StaticMap {
    /// `f(u) = u`.
    Identity,
    /// `f(u) = u²` (a parabola: even, so linear correlation cannot see it).
    Square,
    /// `f(u) = sin(u)`.
    Sine,
    /// `f(u) = Σ cₖ uᵏ`, coefficients in ascending powers.
    Polynomial(Vec<f64>),
}

impl StaticMap {
    /// `f(u)`.
    pub fn value(&self, u: f64) -> f64 {
        match self {
            Self::Identity => u,
            Self::Square => u * u,
            Self::Sine => u.sin(),
            Self::Polynomial(c) => c.iter().rev().fold(0.0, |acc, ck| acc * u + ck),
        }
    }

    /// `f'(u)`, used to linearise the block around a trajectory.
    pub fn slope(&self, u: f64) -> f64 {
        match self {
            Self::Identity => 1.0,
            Self::Square => 2.0 * u,
            Self::Sine => u.cos(),
            Self::Polynomial(c) => {
                c.iter().enumerate().skip(1).rev().fold(0.0, |acc, (k, ck)| acc * u + k as f64 * ck)
            }
        }
    }

    /// True for the identity map.
    pub fn is_identity(&self) -> bool {
        matches!(self, Self::Identity)
    }

    /// Rejects a polynomial with no or non-finite coefficients.
    pub fn validate(&self) -> Result<(), ModelError> {
        match self {
            Self::Polynomial(c) if c.is_empty() || c.iter().any(|v| !v.is_finite()) => {
                Err(ModelError::BadMap(format!("polynomial coefficients {c:?} must be finite and non-empty")))
            }
            _ => Ok(()),
        }
    }
}

/// A Hammerstein block `y(t) = G(q) f(u(t))`; a linear channel is the identity map.
#[derive(Debug, Clone, PartialEq)]
pub struct Hammerstein {
    /// The static nonlinearity.
    pub map: StaticMap,
    /// The linear dynamics after it.
    pub tf: DiscreteTf,
}

impl Hammerstein {
    /// A block with a map and linear dynamics.
    pub fn new(map: StaticMap, tf: DiscreteTf) -> Result<Self, ModelError> {
        map.validate()?;
        Ok(Self { map, tf })
    }

    /// A linear block (identity map).
    pub fn linear(tf: DiscreteTf) -> Self {
        Self { map: StaticMap::Identity, tf }
    }

    /// A fresh filter with zero initial conditions.
    pub fn filter(&self) -> HammersteinFilter {
        HammersteinFilter { map: self.map.clone(), filter: self.tf.filter() }
    }

    /// Simulates a whole record.
    pub fn simulate(&self, u: &[f64]) -> Vec<f64> {
        let mut f = self.filter();
        u.iter().map(|&x| f.step(x)).collect()
    }
}

/// The step-by-step state of a [`Hammerstein`] block.
#[derive(Debug, Clone)]
pub struct HammersteinFilter {
    map: StaticMap,
    filter: TfFilter,
}

impl HammersteinFilter {
    /// The output if the current input's direct feed-through were absent (see [`TfFilter::peek`]).
    pub fn peek(&self) -> f64 {
        self.filter.peek()
    }

    /// Feeds `u(t)`, returns `y(t)`.
    pub fn step(&mut self, u: f64) -> f64 {
        self.filter.step(self.map.value(u))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn maps_and_slopes() {
        let p = StaticMap::Polynomial(vec![1.0, 2.0, 3.0]); // 1 + 2u + 3u²
        assert_eq!(p.value(2.0), 17.0);
        assert_eq!(p.slope(2.0), 14.0);
        assert_eq!(StaticMap::Square.slope(-1.5), -3.0);
        assert!((StaticMap::Sine.slope(0.3) - 0.3f64.cos()).abs() < 1e-15);
        assert!(StaticMap::Polynomial(vec![]).validate().is_err());
    }

    #[test]
    fn square_then_first_order_by_hand() {
        // y(t) = 0.5 y(t-1) + u(t-1)²
        let g = DiscreteTf::new(vec![0.0, 1.0], vec![1.0, -0.5], 0).unwrap();
        let h = Hammerstein::new(StaticMap::Square, g).unwrap();
        assert_eq!(h.simulate(&[2.0, -1.0, 0.0, 0.0]), vec![0.0, 4.0, 3.0, 1.5]);
    }
}
