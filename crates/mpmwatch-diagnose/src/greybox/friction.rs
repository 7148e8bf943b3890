//! Coulomb friction: a constant force against the direction of motion, fed back into the
//! dynamics, that holds a body at rest until the drive beats it (stick–slip). The output is the
//! velocity (`sign(x − v0)`) or a position (`sign(Δx)`).

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
    /// Stick–slip: a body at rest moves only when the drive (the step without the friction,
    /// measured from rest) beats the friction, and a step that carries the motion through rest
    /// is taken again from rest, so the friction alone stops a motion but never reverses it,
    /// while a drive stronger than the friction reverses it. Without this the simulated body
    /// chatters about rest under any drive weaker than the friction, where a real Coulomb
    /// contact sticks. A fitted force along the motion (`γ ≥ 0`) is no friction and is left
    /// as it is.
    fn constrain(&self, p: &[f64], gamma: &[f64], free: f64, forced: f64, x1: f64, x2: f64) -> f64 {
        let g = gamma[0];
        if g.is_nan() || g >= 0.0 {
            return forced;
        }
        let (rest, motion) = if self.on_change { (x1, x1 - x2) } else { (p[0], x1 - p[0]) };
        if motion != 0.0 && (forced - rest) * motion > 0.0 {
            return forced;
        }
        let drive = free - rest;
        if drive.abs() <= -g { rest } else { free + g * drive.signum() }
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

#[cfg(test)]
mod tests {
    use super::super::{Fitted, Model, Orders, fit};
    use super::*;

    /// A noise-free friction-loaded velocity, `x(t) = 0.8 x(t−1) + 0.5 u(t−1) − 0.1 sign(x(t−1))`
    /// with the sticking rule, on a staircase of 41 levels in [−1, 1]: a level within ±0.2
    /// cannot start the body from rest, and the record sticks on a tenth of its rows or more.
    /// The record is the structure's own simulation at the truth, where the simulation error is
    /// zero, so the fit from the element's start must return to the truth; 1e-3 leaves room for
    /// the forward-difference Jacobian, as in the other elements' recovery tests.
    #[test]
    fn a_noise_free_sticking_friction_is_recovered() {
        let u: Vec<f64> = (0..1500).map(|t| ((t / 23 * 7919) % 41) as f64 / 20.0 - 1.0).collect();
        let c = Coulomb { on_change: false };
        let m = Model {
            element: &c,
            input: 0,
            orders: Orders { na: 1, nb: 1, nk: vec![1], trend: false, reading: None },
        };
        let truth = Fitted { p: vec![0.0], theta: vec![0.8, 0.5, -0.1, 0.0], noise: Vec::new() };
        let y = m.simulate(&truth, &[&u], &vec![0.0; u.len()]).unwrap();
        let stuck = (1..u.len()).filter(|&t| y[t] == 0.0 && y[t - 1] == 0.0 && u[t - 1] != 0.0).count();
        assert!(stuck > 150, "the body must stick: {stuck} rows");
        let d = Data { u: vec![&u], y: &y, train: 0..1500, nominal: None, noise_order: 0 };
        let rows: Vec<usize> = (10..1500).collect();
        let f = fit(&m, &d, &rows).unwrap();
        let want = [0.8, 0.5, -0.1];
        assert!(f.theta.iter().zip(want).all(|(a, b)| (a - b).abs() < 1e-3), "{f:?}");
        assert!(f.p[0].abs() < 1e-3 && f.theta[3].abs() < 1e-3, "{f:?}");
    }

    /// The sticking rule on a velocity at rest at 0.1, friction γ = −0.3 per sample: a drive
    /// of 0.2 from rest stays at rest, one of 0.5 moves by what beats the friction (0.2); a
    /// motion the friction would reverse stops at rest, one it only slows goes on, one a
    /// drive stronger than the friction reverses is reversed (taken again from rest); a fitted
    /// force along the motion is left as it is.
    #[test]
    fn friction_sticks_at_rest_and_alone_never_reverses_a_motion() {
        let c = Coulomb { on_change: false };
        let (p, g) = ([0.1], [-0.3]);
        let at_rest = |free: f64| c.constrain(&p, &g, free, free, 0.1, 0.1);
        assert_eq!(at_rest(0.3), 0.1);
        assert_eq!(at_rest(-0.1), 0.1);
        assert!((at_rest(0.6) - 0.3).abs() < 1e-12);
        assert!((at_rest(-0.4) - (-0.1)).abs() < 1e-12);
        // Moving up (x1 = 0.2): friction pulls the prediction 0.25 down to −0.05, past rest.
        assert_eq!(c.constrain(&p, &g, 0.25, -0.05, 0.2, 0.15), 0.1);
        assert_eq!(c.constrain(&p, &g, 0.55, 0.25, 0.2, 0.15), 0.25);
        // The drive itself reverses it: free −0.5 is 0.6 below rest, 0.3 beyond the friction;
        // a reversing drive of 0.1, within the friction, leaves it at rest.
        assert!((c.constrain(&p, &g, -0.5, -0.8, 0.2, 0.15) - (-0.2)).abs() < 1e-12);
        assert_eq!(c.constrain(&p, &g, 0.0, -0.3, 0.2, 0.15), 0.1);
        // Moving down (x1 = −0.1): the mirror image.
        assert_eq!(c.constrain(&p, &g, -0.05, 0.25, -0.1, -0.05), 0.1);
        assert_eq!(c.constrain(&p, &g, -0.5, -0.2, -0.1, -0.05), -0.2);
        assert_eq!(c.constrain(&p, &[0.3], 0.25, -0.05, 0.2, 0.15), -0.05);
        // A position: at rest when it did not change; the rest is where it stands.
        let c = Coulomb { on_change: true };
        assert_eq!(c.constrain(&[], &g, 2.2, 2.2, 2.0, 2.0), 2.0);
        assert!((c.constrain(&[], &g, 2.5, 2.5, 2.0, 2.0) - 2.2).abs() < 1e-12);
        assert_eq!(c.constrain(&[], &g, 2.1, 1.9, 2.0, 1.8), 2.0);
    }
}
