//! A curved sensor characteristic (a Wiener model): the output is read through
//! `ŷ = x + c·sd·z²`, `z = (x − m)/sd`, a square-law bend about the output's training median
//! (a differential-pressure flow reading without its square-root extraction, a thermocouple
//! or level transmitter read with a linear calibration). Unlike a quadratic on an input, the
//! bend follows the output, whatever drove it there.

use crate::describe::num;
use std::collections::BTreeMap;

use super::polynomial::{centring_of, centring_on, power};
use super::{Data, Element};
use crate::candidates::{ActsOn, Physics};
use mpmwatch_core::numerics::median;

/// Parameters `[m, sd, lo, hi, c]`: the output's median, standard deviation and range on the
/// rows fitted (kept by the fit, [`Element::fixed`], [`Element::fixed_on`]), and the curvature
/// `c`, the bend at one standard deviation from the median in standard deviations. Where the
/// true value leaves the range the readings visited on those rows, the bend goes on along its
/// tangent at the edge (as [`super::polynomial::Polynomial`]'s powers do): a curve fitted on a
/// range is not known outside it. A bend above about 0.25 puts the parabola's vertex within two
/// standard deviations, a reading that turns back: the fit allows it and the description says
/// so.
pub struct SensorPolynomial;

/// Curvatures the fit starts from: a bend of a fifth of a standard deviation at one standard
/// deviation, either way (the start at zero is the linear re-fit, which competes anyway).
const CURVATURES: [f64; 2] = [-0.2, 0.2];

/// The fixed parameters of the output on the training rows: `[median, sd, min, max]`.
fn centring(d: &Data<'_>) -> Vec<f64> {
    let mut p = centring_of(&d.y[d.train.clone()]);
    p[0] = d.y_median();
    p
}

/// The true value `x` whose reading is `y` under curvature `c` (the root on the branch
/// through the median; at the parabola's vertex where `y` lies beyond it), ignoring the
/// clamp at the training range: a stand-in for `x` at the start, not part of the model.
fn inverse(p: &[f64], c: f64, y: f64) -> f64 {
    let (m, sd) = (p[0], p[1]);
    let r = (y - m) / sd;
    let z = if c.abs() < 1e-12 {
        r
    } else {
        let disc = 1.0 + 4.0 * c * r;
        if disc <= 0.0 { -1.0 / (2.0 * c) } else { (disc.sqrt() - 1.0) / (2.0 * c) }
    };
    m + sd * z
}

impl Element for SensorPolynomial {
    fn physics(&self) -> Physics {
        Physics::Quadratic
    }
    fn acts_on(&self) -> ActsOn {
        ActsOn::Output
    }
    fn starts(&self, d: &Data<'_>, _i: usize) -> Vec<Vec<f64>> {
        let p = centring(d);
        CURVATURES.iter().map(|&c| p.iter().copied().chain([c]).collect()).collect()
    }
    fn fixed(&self) -> usize {
        4
    }
    fn fixed_on(&self, d: &Data<'_>, _i: usize, rows: &[usize]) -> Option<Vec<f64>> {
        let mut p = centring_on(d.y, rows)?;
        p[0] = median(&rows.iter().filter_map(|&t| d.y.get(t).copied()).collect::<Vec<f64>>());
        Some(p)
    }
    /// The recorded output read back through the start's curve.
    fn stand_ins(&self, d: &Data<'_>, _i: usize, p: &[f64]) -> Vec<Vec<f64>> {
        vec![d.y.iter().map(|&y| inverse(p, p[4], y)).collect()]
    }
    fn output(&self, p: &[f64], x: f64) -> f64 {
        x + p[4] * p[1] * power(p, x, 2)
    }
    fn map_at(&self, p: &[f64], _gamma: &[f64], v: f64) -> Option<f64> {
        Some(self.output(p, v))
    }
    fn describe(&self, p: &[f64], _input: &str, output: &str) -> (String, BTreeMap<String, f64>) {
        // The parabola's vertex, where the reading turns back.
        let vertex = p[0] - p[1] / (2.0 * p[4]);
        let turns = if (p[2]..=p[3]).contains(&vertex) {
            format!(
                "; the curve turns back at a true value of {}, within the range the readings visit, so readings near it are ambiguous",
                num(vertex)
            )
        } else {
            String::new()
        };
        (
            format!(
                "{output}'s sensor reads through a curved characteristic: x {} {}·(x {} {})²/{} (a square-law bend of {} standard deviations at one standard deviation from the median){turns}",
                if p[4] < 0.0 { "−" } else { "+" },
                num(p[4].abs()),
                if p[0] < 0.0 { "+" } else { "−" },
                num(p[0].abs()),
                num(p[1]),
                num(p[4])
            ),
            BTreeMap::from([("curvature".into(), p[4]), ("centre".into(), p[0]), ("scale".into(), p[1])]),
        )
    }
}

#[cfg(test)]
mod tests {
    use super::super::{Model, Orders, fit};
    use super::*;

    /// The description says where the curve turns back when that lies in the readings' range
    /// (vertex `m − sd/(2c)`: −0.9 for a bend of 0.5 about 0.1 with unit scale), not otherwise;
    /// signs are written out, not as `+ -`.
    #[test]
    fn the_description_says_where_the_reading_turns_back() {
        let (text, _) = SensorPolynomial.describe(&[0.1, 1.0, -2.0, 2.0, 0.5], "u", "y");
        assert!(text.contains("turns back at a true value of -0.9000,"), "{text}");
        assert!(text.contains("x + 0.5000·(x − 0.1000)²/1.000"), "{text}");
        let (text, _) = SensorPolynomial.describe(&[0.1, 1.0, -2.0, 2.0, -0.1], "u", "y");
        assert!(!text.contains("turns back"), "{text}");
        assert!(text.contains("x − 0.1000·(x − 0.1000)²/1.000"), "{text}");
        let (text, _) = SensorPolynomial.describe(&[-0.1, 1.0, -2.0, 2.0, 0.1], "u", "y");
        assert!(text.contains("x + 0.1000·(x + 0.1000)²/1.000"), "{text}");
    }

    /// The stand-in inverts the curve inside the training range, to rounding.
    #[test]
    fn the_stand_in_inverts_the_curve() {
        let p = [1.0, 2.0, -10.0, 10.0, 0.3];
        for x in [-2.0, -0.5, 0.0, 1.0, 3.5, 6.0] {
            let y = SensorPolynomial.output(&p, x);
            assert!((inverse(&p, p[4], y) - x).abs() < 1e-9, "{x}: {}", inverse(&p, p[4], y));
        }
    }

    /// A noise-free first-order plant `x(t) = 0.8 x(t−1) + 0.4 u(t−1)` read through a sensor of
    /// curvature 0.3 about the reading's own median and scale: the fit recovers the curvature
    /// and the dynamics (the simulation error is zero at the truth; the tolerance leaves room
    /// for the forward-difference Jacobian, as in the other elements' recovery tests). The
    /// truth uses the fixed parameters the fit takes from the readings, so it is in the class.
    #[test]
    fn a_noise_free_curved_sensor_is_recovered() {
        let n = 1500;
        let u: Vec<f64> = (0..n).map(|t| ((t / 29 * 7919) % 41) as f64 / 20.0 - 1.0).collect();
        let mut x = vec![0.0; n];
        for t in 1..n {
            x[t] = 0.8 * x[t - 1] + 0.4 * u[t - 1];
        }
        // The fixed parameters are the fitted readings' (rows 60 on, the training part here), so
        // the readings are generated by fixed-point iteration: the curve about those readings'
        // median and scale, which depend on the curve.
        let mut y = x.clone();
        for _ in 0..50 {
            let d = Data { u: vec![&u], y: &y, train: 60..n, nominal: None, noise_order: 0 };
            let p: Vec<f64> = centring(&d).into_iter().chain([0.3]).collect();
            y = x.iter().map(|&v| SensorPolynomial.output(&p, v)).collect();
        }
        let d = Data { u: vec![&u], y: &y, train: 60..n, nominal: None, noise_order: 0 };
        let truth: Vec<f64> = centring(&d).into_iter().chain([0.3]).collect();
        let err = x
            .iter()
            .zip(&y)
            .map(|(&v, &r)| (SensorPolynomial.output(&truth, v) - r).abs())
            .fold(0.0, f64::max);
        assert!(err < 1e-9, "the readings are the curve of the plant's output to {err}");
        let m = Model {
            element: &SensorPolynomial,
            input: 0,
            orders: Orders { na: 1, nb: 1, nk: vec![1], trend: false, reading: None },
        };
        // From row 60 the start of the simulation (the first readings taken as true values) has
        // decayed to 0.8^60 ≈ 2e-6 of the readings' bend.
        let rows: Vec<usize> = (60..n).collect();
        let f = fit(&m, &d, &rows).unwrap();
        assert!((f.p[4] - 0.3).abs() < 1e-3, "{f:?}");
        assert!((f.theta[0] - 0.8).abs() < 1e-3 && (f.theta[1] - 0.4).abs() < 1e-3, "{f:?}");
    }
}
