//! The data every estimator timing draws (the criterion bench and `examples/estimate_time.rs`),
//! so that their figures describe the same estimates.

use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use rand_distr::{Distribution, StandardNormal};

fn ar1(rng: &mut ChaCha8Rng, n: usize, a: f64) -> Vec<f64> {
    let mut prev = 0.0;
    (0..n)
        .map(|_| {
            let e: f64 = StandardNormal.sample(rng);
            prev = a * prev + e;
            prev
        })
        .collect()
}

/// A ±1 dither, an AR(1) residual (pole 0.7) and a continuous AR(1) input (pole 0.5), `n` samples
/// each from seed 1, and the generator after them (for surrogates).
pub fn estimator_data(n: usize) -> (Vec<f64>, Vec<f64>, Vec<f64>, ChaCha8Rng) {
    let mut rng = ChaCha8Rng::seed_from_u64(1);
    let dither: Vec<f64> = (0..n).map(|_| if rng.random::<bool>() { 1.0 } else { -1.0 }).collect();
    let residual = ar1(&mut rng, n, 0.7);
    let continuous = ar1(&mut rng, n, 0.5);
    (dither, residual, continuous, rng)
}
