//! A hardening (or softening) spring: a force in the cube of the output's deviation fed back
//! into the dynamics (a Duffing oscillator).

use crate::describe::num;
use std::collections::BTreeMap;

use super::{Data, Element};
use crate::candidates::{ActsOn, Physics};

/// Feeds back `(x(t−1) − level)³`; parameter `[level]`.
pub struct CubicStiffness;

impl Element for CubicStiffness {
    fn physics(&self) -> Physics {
        Physics::Cubic
    }
    fn acts_on(&self) -> ActsOn {
        ActsOn::Output
    }
    fn starts(&self, d: &Data<'_>, _i: usize) -> Vec<Vec<f64>> {
        vec![vec![d.y_median()]]
    }
    fn feedback(&self, p: &[f64], x1: f64, _x2: f64, out: &mut Vec<f64>) {
        out.push((x1 - p[0]).powi(3));
    }
    fn feedbacks(&self) -> usize {
        1
    }
    fn map_at(&self, p: &[f64], gamma: &[f64], v: f64) -> Option<f64> {
        Some(gamma[0] * (v - p[0]).powi(3))
    }
    fn map_axes(&self, d: &Data<'_>, _i: usize, _input: &str, output: &str) -> (String, (f64, f64), String) {
        (
            output.to_string(),
            (d.y_quantile(0.0), d.y_quantile(1.0)),
            "spring force fed back (per sample)".into(),
        )
    }
    fn describe(&self, p: &[f64], _input: &str, output: &str) -> (String, BTreeMap<String, f64>) {
        (
            format!("a force in the cube of {output}'s deviation from {} (a stiffening spring)", num(p[0])),
            BTreeMap::from([("level".into(), p[0])]),
        )
    }
}
