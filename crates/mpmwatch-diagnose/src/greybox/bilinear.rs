//! A bilinear input: the input acts through its product with its own previous sample as well
//! as linearly (a flow that goes with a command times a valve position that follows the
//! command one sample late; a rate times a concentration). Unlike a static square, the product
//! of two successive samples sees how fast the input moves: on a held input it is the square,
//! on a changing one it is not.

use std::collections::BTreeMap;

use super::{Data, Element, polynomial};
use crate::candidates::{ActsOn, Physics};

/// The inputs and `z(t)·z(t−1)`, `z` the input standardised about its training mean and held at
/// its training range's edges as the polynomial's powers are (same parameters, kept by the
/// fit). Linear in its coefficients.
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
                "{output} responds to the product of {input}'s deviation with its previous sample's, not only to {input} (a bilinear input term, fitted for {input} in [{lo:.4}, {hi:.4}] and held at that range's edges beyond it)"
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
}
