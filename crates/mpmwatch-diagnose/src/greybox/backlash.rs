//! Backlash (play): the actuator does not move until the command reverses by more than the
//! gap.

use crate::describe::num;
use std::collections::BTreeMap;

use super::{Data, Element, map_input};
use crate::candidates::{ActsOn, Physics};

/// The play operator of total width `w`; parameter `[w]`.
pub struct Backlash;

fn play(u: &[f64], w: f64) -> Vec<f64> {
    let h = 0.5 * w.abs();
    let mut out = u.first().copied().unwrap_or(0.0);
    u.iter()
        .map(|&v| {
            if v > out + h {
                out = v - h;
            } else if v < out - h {
                out = v + h;
            }
            out
        })
        .collect()
}

impl Element for Backlash {
    fn physics(&self) -> Physics {
        Physics::Backlash
    }
    fn acts_on(&self) -> ActsOn {
        ActsOn::Input
    }
    fn starts(&self, d: &Data<'_>, i: usize) -> Vec<Vec<f64>> {
        let r = d.u_quantile(i, 0.95) - d.u_quantile(i, 0.05);
        [0.05, 0.15, 0.3].iter().map(|f| vec![f * r]).collect()
    }
    fn signals(&self, p: &[f64], u: &[&[f64]], i: usize) -> Vec<Vec<f64>> {
        map_input(u, i, |x| play(x, p[0]))
    }
    fn trace(&self, p: &[f64], sweep: &[f64]) -> Option<Vec<f64>> {
        Some(play(sweep, p[0]))
    }
    fn describe(&self, p: &[f64], input: &str, output: &str) -> (String, BTreeMap<String, f64>) {
        (
            format!("{input} reaches {output} through play of width {} (backlash)", num(p[0].abs())),
            BTreeMap::from([("width".into(), p[0].abs())]),
        )
    }
}
