//! A polynomial static map on an input (a Hammerstein model): power, flow or torque that goes
//! with the square or the cube of the command (a heater driven by a voltage, a valve).

use std::collections::BTreeMap;

use super::{Data, Element};
use crate::candidates::{ActsOn, Physics};

/// The input and its powers up to `degree` about the input's mean, each through its own
/// numerator. No parameters of its own: the map is linear in its coefficients.
pub struct Polynomial {
    /// 2 (quadratic) or 3 (cubic).
    pub degree: i32,
}

/// The input's mean and standard deviation, about which its powers are taken.
fn centre_and_scale(x: &[f64]) -> (f64, f64) {
    let n = x.len().max(1) as f64;
    let m = x.iter().sum::<f64>() / n;
    let sd = (x.iter().map(|v| (v - m).powi(2)).sum::<f64>() / n).sqrt().max(1e-12);
    (m, sd)
}

impl Element for Polynomial {
    fn physics(&self) -> Physics {
        if self.degree == 2 { Physics::Quadratic } else { Physics::Cubic }
    }
    fn acts_on(&self) -> ActsOn {
        ActsOn::Input
    }
    fn starts(&self, _d: &Data<'_>, _i: usize) -> Vec<Vec<f64>> {
        vec![Vec::new()]
    }
    fn signals(&self, _p: &[f64], u: &[&[f64]], i: usize) -> Vec<Vec<f64>> {
        let x = u[i];
        let (m, sd) = centre_and_scale(x);
        let mut out: Vec<Vec<f64>> = u.iter().map(|x| x.to_vec()).collect();
        for k in 2..=self.degree {
            out.push(x.iter().map(|v| ((v - m) / sd).powi(k)).collect());
        }
        out
    }
    /// What the dynamics see of an input `v`, in the input's units: `v` plus each power's
    /// steady-state contribution over the input's own gain (`None` when that gain is zero).
    fn map_from_gains(&self, dc: &[f64], u: &[f64], i: usize, v: f64) -> Option<f64> {
        let powers = (self.degree - 1) as usize;
        let first = dc.len().checked_sub(powers)?;
        let gain = dc[i];
        if gain.abs() < 1e-12 || !gain.is_finite() {
            return None;
        }
        let (m, sd) = centre_and_scale(u);
        let z = (v - m) / sd;
        Some(v + (2..=self.degree).zip(&dc[first..]).map(|(k, g)| g / gain * z.powi(k)).sum::<f64>())
    }
    fn describe(&self, _p: &[f64], input: &str, output: &str) -> (String, BTreeMap<String, f64>) {
        let what = if self.degree == 2 { "square" } else { "cube" };
        (
            format!(
                "{output} responds to the {what} of {input}'s deviation, not only to {input} (a static polynomial map on the input)"
            ),
            BTreeMap::new(),
        )
    }
}
