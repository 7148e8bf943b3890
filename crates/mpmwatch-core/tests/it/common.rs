//! Seeded signal generators shared by the integration tests.
#![allow(dead_code)]

use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use rand_distr::{Distribution, StandardNormal};

/// A seeded RNG.
pub fn rng(seed: u64) -> ChaCha8Rng {
    ChaCha8Rng::seed_from_u64(seed)
}

/// n standard normal draws.
pub fn normal(rng: &mut ChaCha8Rng, n: usize) -> Vec<f64> {
    (0..n).map(|_| StandardNormal.sample(rng)).collect()
}

/// n i.i.d. ±1 draws (a random binary dither).
pub fn binary(rng: &mut ChaCha8Rng, n: usize) -> Vec<f64> {
    (0..n).map(|_| if rng.random::<bool>() { 1.0 } else { -1.0 }).collect()
}

/// AR(1) series with coefficient `a` driven by unit normal noise.
pub fn ar1(rng: &mut ChaCha8Rng, n: usize, a: f64) -> Vec<f64> {
    let e = normal(rng, n + 100);
    let mut y = vec![0.0; n + 100];
    for t in 1..n + 100 {
        y[t] = a * y[t - 1] + e[t];
    }
    y.split_off(100)
}

/// Bivariate Gaussian pair with correlation rho.
pub fn gaussian_pair(rng: &mut ChaCha8Rng, n: usize, rho: f64) -> (Vec<f64>, Vec<f64>) {
    let x = normal(rng, n);
    let z = normal(rng, n);
    let y = x.iter().zip(&z).map(|(a, b)| rho * a + (1.0 - rho * rho).sqrt() * b).collect();
    (x, y)
}
