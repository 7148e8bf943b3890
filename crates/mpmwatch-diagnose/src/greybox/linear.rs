//! The linear re-fit: the record's own linear dynamics, no physics element. It competes with
//! every element; what it changes against the nominal (a gain, a time constant, a dead time)
//! is read by the caller.

use std::collections::BTreeMap;

use super::{Data, Element};
use crate::candidates::{ActsOn, Physics};

/// No element: the inputs drive the linear dynamics directly.
pub struct Linear;

impl Element for Linear {
    fn physics(&self) -> Physics {
        Physics::Gain
    }
    fn acts_on(&self) -> ActsOn {
        ActsOn::Input
    }
    fn starts(&self, _d: &Data<'_>, _i: usize) -> Vec<Vec<f64>> {
        vec![Vec::new()]
    }
    fn describe(&self, _p: &[f64], input: &str, output: &str) -> (String, BTreeMap<String, f64>) {
        (format!("the linear dynamics of {input}→{output} differ from the model's"), BTreeMap::new())
    }
}
