//! A sensor that cannot see direction: it measures the magnitude of the signal (a speed from
//! counted pulses, a flow from a differential pressure), `ŷ = |x| + offset`.

use crate::describe::num;
use std::collections::BTreeMap;

use super::{Data, Element};
use crate::candidates::{ActsOn, Physics};

/// `ŷ = |x| + o`, parameter `[o]`.
pub struct AbsSensor;

/// Poles of the low-pass filters whose sign stands in for the direction at the start.
const DIRECTION_POLES: [f64; 3] = [0.5, 0.8, 0.95];

impl Element for AbsSensor {
    fn physics(&self) -> Physics {
        Physics::AbsSensor
    }
    fn acts_on(&self) -> ActsOn {
        ActsOn::Output
    }
    fn starts(&self, d: &Data<'_>, _i: usize) -> Vec<Vec<f64>> {
        vec![vec![d.y_quantile(0.0).min(0.0)]]
    }
    /// The recorded magnitude signed by a direction: the nominal simulation's sign (the user's
    /// model knows which way the input drives), and the sign of the input low-passed at a few
    /// time constants (the input's zero taken as "no drive").
    fn stand_ins(&self, d: &Data<'_>, i: usize, p: &[f64]) -> Vec<Vec<f64>> {
        let by_nominal = d.nominal.map(|s| {
            s.iter().zip(d.y).map(|(&s, &y)| (y - p[0]).abs() * if s < 0.0 { -1.0 } else { 1.0 }).collect()
        });
        let by_input = DIRECTION_POLES.iter().map(|&a| {
            let mut lp = 0.0;
            d.u[i]
                .iter()
                .zip(d.y)
                .map(|(&u, &y)| {
                    lp = a * lp + (1.0 - a) * u;
                    (y - p[0]).abs() * if lp < 0.0 { -1.0 } else { 1.0 }
                })
                .collect()
        });
        by_nominal.into_iter().chain(by_input).collect()
    }
    fn output(&self, p: &[f64], x: f64) -> f64 {
        x.abs() + p[0]
    }
    fn map_at(&self, p: &[f64], _gamma: &[f64], v: f64) -> Option<f64> {
        Some(self.output(p, v))
    }
    /// A true value of either sign, as far as the reading goes.
    fn map_axes(&self, d: &Data<'_>, _i: usize, _input: &str, output: &str) -> (String, (f64, f64), String) {
        let m = d.y_quantile(0.0).abs().max(d.y_quantile(1.0).abs());
        (format!("true {output} (signed)"), (-m, m), format!("{output} as measured"))
    }
    fn describe(&self, p: &[f64], _input: &str, output: &str) -> (String, BTreeMap<String, f64>) {
        (
            format!(
                "{output}'s sensor sees the magnitude only, not the direction (|x| with a zero offset of {})",
                num(p[0])
            ),
            BTreeMap::from([("zero_offset".into(), p[0])]),
        )
    }
}
