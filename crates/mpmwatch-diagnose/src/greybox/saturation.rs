//! An actuator limit: the input acts only within `[lo, hi]`.

use crate::describe::num;
use std::collections::BTreeMap;

use super::{Data, Element, map_input};
use crate::candidates::{ActsOn, Physics};

/// `clamp(u, lo, hi)`, parameters `[lo, hi]` (a limit outside the input's range is inactive).
pub struct InputSaturation;

impl Element for InputSaturation {
    fn physics(&self) -> Physics {
        Physics::Saturation
    }
    fn acts_on(&self) -> ActsOn {
        ActsOn::Input
    }
    /// Upper, lower and two-sided limits at the 70th–90th (10th–30th) percentiles, the other
    /// side a range beyond the data.
    fn starts(&self, d: &Data<'_>, i: usize) -> Vec<Vec<f64>> {
        let (lo, hi) = (d.u_quantile(i, 0.0), d.u_quantile(i, 1.0));
        let r = (hi - lo).max(f64::MIN_POSITIVE);
        let mut out = Vec::new();
        for q in [0.7, 0.8, 0.9] {
            out.push(vec![lo - r, d.u_quantile(i, q)]);
            out.push(vec![d.u_quantile(i, 1.0 - q), hi + r]);
        }
        out.push(vec![d.u_quantile(i, 0.15), d.u_quantile(i, 0.85)]);
        out
    }
    fn signals(&self, p: &[f64], u: &[&[f64]], i: usize) -> Vec<Vec<f64>> {
        let (lo, hi) = (p[0].min(p[1]), p[0].max(p[1]));
        map_input(u, i, |x| x.iter().map(|v| v.clamp(lo, hi)).collect())
    }
    fn map_at(&self, p: &[f64], _gamma: &[f64], v: f64) -> Option<f64> {
        Some(v.clamp(p[0].min(p[1]), p[0].max(p[1])))
    }
    /// Where the input is beyond a limit.
    fn acting(&self, p: &[f64], u: &[&[f64]], i: usize, _yhat: &[f64]) -> Option<Vec<bool>> {
        let (lo, hi) = (p[0].min(p[1]), p[0].max(p[1]));
        Some(u[i].iter().map(|&v| v < lo || v > hi).collect())
    }
    fn describe(&self, p: &[f64], input: &str, output: &str) -> (String, BTreeMap<String, f64>) {
        let (lo, hi) = (p[0].min(p[1]), p[0].max(p[1]));
        (
            format!("{input} acts on {output} only within [{}, {}] (an actuator limit)", num(lo), num(hi)),
            BTreeMap::from([("lower".into(), lo), ("upper".into(), hi)]),
        )
    }
}
