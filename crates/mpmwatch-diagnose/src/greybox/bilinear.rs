//! A bilinear input: the input acts through its product with its own previous sample as well
//! as linearly (a flow that goes with a command times a valve position that follows the
//! command one sample late; a rate times a concentration). Unlike a static square, the product
//! of two successive samples sees how fast the input moves: on a held input it is the square,
//! on a changing one it is not.

use crate::describe::num;
use std::collections::BTreeMap;

use mpmwatch_core::info::pearson;

use super::{Data, Element, polynomial};
use crate::candidates::{ActsOn, Physics};

/// Largest correlation of the product with the square at which the product is still told apart.
const IDENTIFIABLE_BELOW: f64 = 0.9;

/// The inputs and `z(t)·z(t−1)`, `z` the input standardised about its mean on the rows fitted
/// and held at their range's edges (the polynomial's parameters, kept by the fit): the product
/// of two held samples, not a power with a tangent. Linear in its coefficients.
pub struct Bilinear;

impl Element for Bilinear {
    fn physics(&self) -> Physics {
        Physics::Bilinear
    }
    fn acts_on(&self) -> ActsOn {
        ActsOn::Input
    }
    fn starts(&self, d: &Data<'_>, i: usize) -> Vec<Vec<f64>> {
        vec![polynomial::centring_of(&d.u[i][d.train.clone()])]
    }
    fn fixed(&self) -> usize {
        4
    }
    fn fixed_on(&self, d: &Data<'_>, i: usize, rows: &[usize]) -> Option<Vec<f64>> {
        polynomial::centring_on(d.u[i], rows)
    }
    /// Only where the product carries a fifth of its variance beyond the square: correlation
    /// below 0.9 between `z(t)·z(t−1)` and `z(t)²` on the training rows (1 − 0.9² = 0.19). On a
    /// staircase or a slowly filtered input the two are one regressor, and a bilinear class would
    /// only compete with the quadratic for the same fit; a dithered input moves every sample.
    fn identifiable(&self, d: &Data<'_>, i: usize) -> bool {
        let p = polynomial::centring_of(&d.u[i][d.train.clone()]);
        let z: Vec<f64> = d.u[i][d.train.clone()].iter().map(|&v| polynomial::standardised(&p, v)).collect();
        let prod: Vec<f64> = z.windows(2).map(|w| w[0] * w[1]).collect();
        let sq: Vec<f64> = z.iter().skip(1).map(|v| v * v).collect();
        pearson(&prod, &sq, 1.96).is_ok_and(|c| c.r.abs() < IDENTIFIABLE_BELOW)
    }
    fn signals(&self, p: &[f64], u: &[&[f64]], i: usize) -> Vec<Vec<f64>> {
        let z: Vec<f64> = u[i].iter().map(|&v| polynomial::standardised(p, v)).collect();
        let mut out: Vec<Vec<f64>> = u.iter().map(|x| x.to_vec()).collect();
        out.push((0..z.len()).map(|t| if t > 0 { z[t] * z[t - 1] } else { z[t] * z[t] }).collect());
        out
    }
    fn describe(&self, p: &[f64], input: &str, output: &str) -> (String, BTreeMap<String, f64>) {
        let (lo, hi) = (p.get(2).copied().unwrap_or(f64::NAN), p.get(3).copied().unwrap_or(f64::NAN));
        (
            format!(
                "{output} responds to the product of {input}'s deviation with its previous sample's, not only to {input} (a bilinear input term, fitted for {input} in [{}, {}] and held at that range's edges beyond it)",
                num(lo),
                num(hi)
            ),
            BTreeMap::from([("fitted_range_low".to_string(), lo), ("fitted_range_high".to_string(), hi)]),
        )
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The product term is `z(t)·z(t−1)` of the standardised, range-held input (the first
    /// sample, without a predecessor, its own square); the inputs pass unchanged.
    #[test]
    fn the_product_is_of_successive_standardised_samples() {
        let train = [-1.0, 0.0, 1.0, 2.0];
        let p = polynomial::centring_of(&train);
        let z = |v: f64| (v - 0.5) / 1.25f64.sqrt();
        let u = [0.5, 2.0, 5.0, -4.0];
        let sig = Bilinear.signals(&p, &[&u], 0);
        assert_eq!(sig[0], u.to_vec());
        assert_eq!(sig[1], vec![0.0, 0.0, z(2.0) * z(2.0), z(-1.0) * z(2.0)]);
    }

    /// A staircase held 20 samples per level: the product of successive samples is the square
    /// but at one sample in twenty (correlation 0.92), so the class is not tried; a level held
    /// for one sample each (a dither) leaves them apart. A constant input has no correlation and is not tried.
    #[test]
    fn the_product_must_differ_from_the_square() {
        let levels = |hold: usize| -> Vec<f64> {
            (0..1000).map(|t| ((t / hold * 7919) % 41) as f64 / 20.0 - 1.0).collect()
        };
        let (stairs, moving) = (levels(20), levels(1));
        fn data(u: &[f64]) -> Data<'_> {
            Data { u: vec![u], y: u, train: 0..1000, nominal: None, noise_order: 0 }
        }
        assert!(!Bilinear.identifiable(&data(&stairs), 0));
        assert!(Bilinear.identifiable(&data(&moving), 0));
        assert!(!Bilinear.identifiable(&data(&[1.0; 1000]), 0));
    }
}
