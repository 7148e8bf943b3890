//! One named structure fitted on a chosen estimation part and simulated anywhere: how the
//! physics a diagnosis names is carried to a benchmark's own test split.

use std::collections::BTreeMap;
use std::ops::Range;

use super::{Data, Element, Fitted, Model, Orders, abs_sensor, clip_sensor, fit, friction, stiffness};
use crate::error::DiagnoseError;

/// The structures a caller can ask for by name.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Structure {
    /// Linear dynamics only.
    Linear,
    /// A force in the cube of the output fed back (a Duffing spring).
    CubicStiffness,
    /// A clip of the output to `[lo, hi]`.
    ClipSensor,
    /// A sensor of the magnitude only.
    AbsSensor,
    /// Coulomb friction against the sign of the output's change.
    CoulombFriction,
}

impl Structure {
    fn element(self) -> Box<dyn Element> {
        match self {
            Structure::Linear => Box::new(super::Linear),
            Structure::CubicStiffness => Box::new(stiffness::CubicStiffness),
            Structure::ClipSensor => Box::new(clip_sensor::ClipSensor { range: None }),
            Structure::AbsSensor => Box::new(abs_sensor::AbsSensor),
            Structure::CoulombFriction => Box::new(friction::Coulomb { on_change: true }),
        }
    }
}

/// An unfitted grey-box model: a structure on linear orders `na` poles, `nb` taps, dead time
/// `nk` per input.
#[derive(Debug, Clone)]
pub struct GreyBox {
    /// The physics element.
    pub structure: Structure,
    /// Poles.
    pub na: usize,
    /// Numerator taps per input.
    pub nb: usize,
    /// Dead time per input, samples.
    pub nk: Vec<usize>,
}

/// A grey-box model fitted by simulation error.
pub struct FittedGreyBox {
    element: Box<dyn Element>,
    orders: Orders,
    fitted: Fitted,
}

impl GreyBox {
    /// Fits on the rows `rows` of the record (`u` per input, `y` the output) by simulation
    /// error from the element's starts (the whole record is simulated; only `rows` are scored).
    pub fn fit(&self, u: &[&[f64]], y: &[f64], rows: Range<usize>) -> Result<FittedGreyBox, DiagnoseError> {
        if u.is_empty() || u.iter().any(|x| x.len() != y.len()) || self.nk.len() != u.len() {
            return Err(DiagnoseError::invalid(
                "grey-box record",
                format!("it needs inputs as long as the output ({}) and one dead time per input", y.len()),
            ));
        }
        if rows.end > y.len() || rows.len() < 10 * (self.na + self.nb * u.len() + 4) {
            return Err(DiagnoseError::invalid(
                "estimation rows",
                format!("{rows:?} are outside the record of {} samples or too few for the orders", y.len()),
            ));
        }
        let element = self.structure.element();
        let orders = Orders { na: self.na, nb: self.nb, nk: self.nk.clone(), trend: false, reading: None };
        let d = Data { u: u.to_vec(), y, train: rows.clone(), nominal: None, noise_order: 0 };
        let model = Model { element: element.as_ref(), input: 0, orders: orders.clone() };
        let idx: Vec<usize> = rows.collect();
        let fitted = fit(&model, &d, &idx).ok_or_else(|| {
            DiagnoseError::invalid(
                format!("{:?} structure", self.structure),
                "no start gives a stable simulation on the estimation rows",
            )
        })?;
        Ok(FittedGreyBox { element, orders, fitted })
    }
}

impl FittedGreyBox {
    /// Simulation over a record: `u` per input, `y` whose first samples start the simulation
    /// (only as many as the orders need). `None` when it diverges, or when the inputs are not
    /// the fitted model's (their count) or not as long as `y`.
    pub fn simulate(&self, u: &[&[f64]], y: &[f64]) -> Option<Vec<f64>> {
        if u.len() != self.orders.nk.len() || u.iter().any(|x| x.len() != y.len()) {
            return None;
        }
        let model = Model { element: self.element.as_ref(), input: 0, orders: self.orders.clone() };
        model.simulate(&self.fitted, u, y)
    }

    /// A sentence and the element's parameters.
    pub fn describe(&self, input: &str, output: &str) -> (String, BTreeMap<String, f64>) {
        self.element.describe(&self.fitted.p, input, output)
    }
}
