//! Disturbance generators: seeded white Gaussian noise and noise coloured by a transfer function.

use rand::Rng;
use rand_distr::{Distribution, Normal};

use super::error::SimError;
use mpmwatch_core::model::DiscreteTf;

/// `n` samples of N(0, variance).
pub fn white_gaussian(n: usize, variance: f64, rng: &mut impl Rng) -> Result<Vec<f64>, SimError> {
    if !(variance.is_finite() && variance >= 0.0) {
        return Err(SimError::parameter("noise variance", variance, "must be finite and non-negative"));
    }
    if variance == 0.0 {
        return Ok(vec![0.0; n]);
    }
    let d = Normal::new(0.0, variance.sqrt())
        .map_err(|e| SimError::parameter("noise variance", variance, &e.to_string()))?;
    Ok((0..n).map(|_| d.sample(rng)).collect())
}

/// `n` samples of `H(q) e(t)` with `e` white N(0, variance). The filter must be stable, and the
/// first `burn_in` samples are discarded so the record starts near stationarity.
pub fn coloured_noise(
    h: &DiscreteTf,
    n: usize,
    variance: f64,
    burn_in: usize,
    rng: &mut impl Rng,
) -> Result<Vec<f64>, SimError> {
    h.require_stable("noise filter")?;
    let e = white_gaussian(n + burn_in, variance, rng)?;
    Ok(h.simulate(&e).split_off(burn_in))
}
