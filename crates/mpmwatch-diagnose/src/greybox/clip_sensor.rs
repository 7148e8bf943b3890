//! An output that cannot leave `[lo, hi]`: a sensor at the end of its range, a level at an
//! overflow (a Wiener system's clip).

use crate::describe::num;
use std::collections::BTreeMap;

use super::{Data, Element};
use crate::candidates::{ActsOn, Physics};

/// `ŷ = clamp(x, lo, hi)`, parameters `[lo, hi]`.
pub struct ClipSensor;

impl Element for ClipSensor {
    fn physics(&self) -> Physics {
        Physics::Saturation
    }
    fn acts_on(&self) -> ActsOn {
        ActsOn::Output
    }
    fn starts(&self, d: &Data<'_>, _i: usize) -> Vec<Vec<f64>> {
        let (lo, hi) = (d.y_quantile(0.0), d.y_quantile(1.0));
        let r = (hi - lo).max(f64::MIN_POSITIVE);
        let mut out = Vec::new();
        for q in [0.7, 0.85, 0.95] {
            out.push(vec![lo - r, d.y_quantile(q)]);
            out.push(vec![d.y_quantile(1.0 - q), hi + r]);
        }
        out
    }
    fn output(&self, p: &[f64], x: f64) -> f64 {
        x.clamp(p[0].min(p[1]), p[0].max(p[1]))
    }
    fn invertible(&self, p: &[f64], y: f64) -> bool {
        y > p[0].min(p[1]) && y < p[0].max(p[1])
    }
    fn map_at(&self, p: &[f64], _gamma: &[f64], v: f64) -> Option<f64> {
        Some(self.output(p, v))
    }
    /// Where the simulated reading is held at a limit.
    fn acting(&self, p: &[f64], _u: &[&[f64]], _i: usize, yhat: &[f64]) -> Option<Vec<bool>> {
        let (lo, hi) = (p[0].min(p[1]), p[0].max(p[1]));
        Some(yhat.iter().map(|&v| v <= lo || v >= hi).collect())
    }
    fn describe(&self, p: &[f64], _input: &str, output: &str) -> (String, BTreeMap<String, f64>) {
        let (lo, hi) = (p[0].min(p[1]), p[0].max(p[1]));
        (
            format!("{output} cannot leave [{}, {}] (a clip or overflow on the output)", num(lo), num(hi)),
            BTreeMap::from([("lower".into(), lo), ("upper".into(), hi)]),
        )
    }
}
