//! An actuator dead zone: the input has no effect within ±w of its centre, and acts by its
//! excess beyond.

use crate::describe::num;
use std::collections::BTreeMap;

use super::{Data, Element, map_input};
use crate::candidates::{ActsOn, Physics};

/// `dz(u) = sign(u − c)·max(|u − c| − w, 0)`, parameters `[c, w]`.
pub struct DeadZone;

fn map(u: f64, c: f64, w: f64) -> f64 {
    let e = u - c;
    e.signum() * (e.abs() - w.abs()).max(0.0)
}

impl Element for DeadZone {
    fn physics(&self) -> Physics {
        Physics::DeadZone
    }
    fn acts_on(&self) -> ActsOn {
        ActsOn::Input
    }
    /// Centred on the input's median, or on zero when zero is inside the input's range (an
    /// actuator's dead zone sits around its rest); widths of 10–40 % of the half-range.
    fn starts(&self, d: &Data<'_>, i: usize) -> Vec<Vec<f64>> {
        let (lo, hi) = (d.u_quantile(i, 0.05), d.u_quantile(i, 0.95));
        let half = 0.5 * (hi - lo);
        let mut centres = vec![d.u_quantile(i, 0.5)];
        if lo < 0.0 && hi > 0.0 {
            centres.push(0.0);
        }
        centres.iter().flat_map(|&c| [0.1, 0.25, 0.4].map(|f| vec![c, f * half])).collect()
    }
    fn signals(&self, p: &[f64], u: &[&[f64]], i: usize) -> Vec<Vec<f64>> {
        map_input(u, i, |x| x.iter().map(|&v| map(v, p[0], p[1])).collect())
    }
    fn map_at(&self, p: &[f64], _gamma: &[f64], v: f64) -> Option<f64> {
        Some(map(v, p[0], p[1]))
    }
    /// Where the input is inside the zone.
    fn acting(&self, p: &[f64], u: &[&[f64]], i: usize, _yhat: &[f64]) -> Option<Vec<bool>> {
        Some(u[i].iter().map(|&v| (v - p[0]).abs() < p[1].abs()).collect())
    }
    fn describe(&self, p: &[f64], input: &str, output: &str) -> (String, BTreeMap<String, f64>) {
        (
            format!(
                "{input} has no effect on {output} within ±{} of {} (a dead zone)",
                num(p[1].abs()),
                num(p[0])
            ),
            BTreeMap::from([("width".into(), p[1].abs()), ("centre".into(), p[0])]),
        )
    }
}
