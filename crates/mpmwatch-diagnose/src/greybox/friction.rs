//! Coulomb friction: a constant force against the direction of motion, fed back into the
//! dynamics. The output is the velocity (`sign(x − v0)`) or a position (`sign(Δx)`).

use std::collections::BTreeMap;

use super::{Data, Element};
use crate::candidates::{ActsOn, Physics};

/// `sign(x(t−1) − v0)` (parameter `[v0]`, the output's reading at rest) or
/// `sign(x(t−1) − x(t−2))` (no parameter).
pub struct Coulomb {
    /// The output is a position: motion is its change.
    pub on_change: bool,
}

impl Element for Coulomb {
    fn physics(&self) -> Physics {
        Physics::CoulombFriction
    }
    fn acts_on(&self) -> ActsOn {
        ActsOn::Output
    }
    /// At rest the velocity reads zero, or the output's median when zero is outside its range.
    fn starts(&self, d: &Data<'_>, _i: usize) -> Vec<Vec<f64>> {
        if self.on_change {
            return vec![Vec::new()];
        }
        let (lo, hi) = (d.y_quantile(0.02), d.y_quantile(0.98));
        if lo < 0.0 && hi > 0.0 { vec![vec![0.0]] } else { vec![vec![d.y_median()]] }
    }
    fn feedback(&self, p: &[f64], x1: f64, x2: f64, out: &mut Vec<f64>) {
        let m = if self.on_change { x1 - x2 } else { x1 - p[0] };
        out.push(if m == 0.0 { 0.0 } else { m.signum() });
    }
    fn feedbacks(&self) -> usize {
        1
    }
    fn map_at(&self, p: &[f64], gamma: &[f64], v: f64) -> Option<f64> {
        let m = if self.on_change { v } else { v - p[0] };
        Some(gamma[0] * if m == 0.0 { 0.0 } else { m.signum() })
    }
    /// Against the motion: the output's change per sample, or the output itself.
    fn map_axes(&self, d: &Data<'_>, _i: usize, _input: &str, output: &str) -> (String, (f64, f64), String) {
        let force = "friction force fed back (per sample)".to_string();
        if self.on_change {
            let y = &d.y[d.train.clone()];
            let m = y.windows(2).map(|w| (w[1] - w[0]).abs()).fold(0.0f64, f64::max);
            (format!("change of {output} per sample"), (-m, m), force)
        } else {
            (output.to_string(), (d.y_quantile(0.0), d.y_quantile(1.0)), force)
        }
    }
    fn describe(&self, _p: &[f64], _input: &str, output: &str) -> (String, BTreeMap<String, f64>) {
        let what = if self.on_change { "the change of" } else { "the sign of" };
        (format!("a constant force against {what} {output} (Coulomb friction)"), BTreeMap::new())
    }
}
