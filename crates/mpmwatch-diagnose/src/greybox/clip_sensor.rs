//! An output that cannot leave `[lo, hi]`: a sensor at the end of its range, a level at an
//! overflow (a Wiener system's clip).

use crate::describe::num;
use std::collections::BTreeMap;

use super::{Data, Element, Reading};
use crate::candidates::{ActsOn, Physics};

/// `ŷ = clamp(x, lo, hi)`: parameters `[lo, hi]` fitted from starts at the output's quantiles,
/// or, when the record shows its instrument's range (`range`, [`super::pinned`]), no
/// parameter: the range as the record shows it (a side it does not show pinned is open).
pub struct ClipSensor {
    /// The range the record shows pinned, when it shows one.
    pub range: Option<Reading>,
}

impl ClipSensor {
    /// The limits under `p`.
    fn limits(&self, p: &[f64]) -> (f64, f64) {
        match self.range {
            Some(r) => (r.lower, r.upper),
            None => (p[0].min(p[1]), p[0].max(p[1])),
        }
    }
}

impl Element for ClipSensor {
    fn physics(&self) -> Physics {
        Physics::Saturation
    }
    fn acts_on(&self) -> ActsOn {
        ActsOn::Output
    }
    fn starts(&self, d: &Data<'_>, _i: usize) -> Vec<Vec<f64>> {
        if self.range.is_some() {
            return vec![Vec::new()];
        }
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
        let (lo, hi) = self.limits(p);
        x.clamp(lo, hi)
    }
    fn invertible(&self, p: &[f64], y: f64) -> bool {
        let (lo, hi) = self.limits(p);
        y > lo && y < hi
    }
    fn map_at(&self, p: &[f64], _gamma: &[f64], v: f64) -> Option<f64> {
        Some(self.output(p, v))
    }
    /// Where the simulated reading is held at a limit.
    fn acting(&self, p: &[f64], _u: &[&[f64]], _i: usize, yhat: &[f64]) -> Option<Vec<bool>> {
        let (lo, hi) = self.limits(p);
        Some(yhat.iter().map(|&v| v <= lo || v >= hi).collect())
    }
    fn describe(&self, p: &[f64], _input: &str, output: &str) -> (String, BTreeMap<String, f64>) {
        let (lo, hi) = self.limits(p);
        let limits = BTreeMap::from([("lower".into(), lo), ("upper".into(), hi)]);
        match self.range {
            Some(r) => (
                format!(
                    "{}, where the model's simulation goes beyond it (a clip on the output: an instrument's range or a hard limit; the linear dynamics re-fitted with it)",
                    r.describe(output)
                ),
                limits.into_iter().filter(|(_, v)| v.is_finite()).collect(),
            ),
            None => (
                format!(
                    "{output} cannot leave [{}, {}] (a clip or overflow on the output)",
                    num(lo),
                    num(hi)
                ),
                limits,
            ),
        }
    }
}
