//! A discrete PI controller in velocity form with output limits.

use super::closed_loop::Controller;
use super::error::SimError;

/// `Δu(t) = Kp (e(t) − e(t−1)) + Kp·T/Ti · e(t)`, clamped to `[u_min, u_max]`.
///
/// The velocity form needs no separate anti-windup: a clamped output simply stops integrating.
#[derive(Debug, Clone, PartialEq)]
pub struct Pi {
    kp: f64,
    ki: f64,
    u_min: f64,
    u_max: f64,
    u: f64,
    e_prev: f64,
}

impl Pi {
    /// Gain `kp`, integral time `ti` in samples (> 0), limits and initial output.
    pub fn new(kp: f64, ti: f64, u_min: f64, u_max: f64, u_init: f64) -> Result<Self, SimError> {
        if !(kp.is_finite() && ti.is_finite() && ti > 0.0) {
            return Err(SimError::parameter(
                "PI tuning",
                format!("kp={kp}, ti={ti}"),
                "kp finite, ti positive",
            ));
        }
        if !(u_min <= u_init && u_init <= u_max) {
            return Err(SimError::parameter(
                "PI limits",
                format!("[{u_min}, {u_max}] with u0={u_init}"),
                "need u_min ≤ u0 ≤ u_max",
            ));
        }
        Ok(Self { kp, ki: kp / ti, u_min, u_max, u: u_init, e_prev: 0.0 })
    }

    /// One sample: set point `r`, measurement `y`; returns the new output.
    pub fn update(&mut self, r: f64, y: f64) -> f64 {
        let e = r - y;
        self.u = (self.u + self.kp * (e - self.e_prev) + self.ki * e).clamp(self.u_min, self.u_max);
        self.e_prev = e;
        self.u
    }
}

impl Controller for Pi {
    fn control(&mut self, y: &[f64], r: &[f64]) -> Result<Vec<f64>, SimError> {
        Ok(vec![self.update(r[0], y[0])])
    }

    fn apply(&mut self, _u: &[f64]) -> Result<(), SimError> {
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use mpmwatch_core::model::DiscreteTf;

    #[test]
    fn removes_offset_on_a_first_order_plant() {
        let plant = DiscreteTf::new(vec![0.0, 0.5], vec![1.0, -0.8], 0).unwrap();
        let mut f = plant.filter();
        let mut pi = Pi::new(0.5, 3.0, -10.0, 10.0, 0.0).unwrap();
        let mut y = 0.0;
        for _ in 0..200 {
            let u = pi.update(1.0, y);
            f.step(u);
            y = f.peek();
        }
        assert!((y - 1.0).abs() < 1e-6, "y = {y}");
    }

    #[test]
    fn output_stays_inside_limits() {
        let mut pi = Pi::new(100.0, 1.0, -1.0, 2.0, 0.0).unwrap();
        for k in 0..50 {
            let u = pi.update(if k < 25 { 100.0 } else { -100.0 }, 0.0);
            assert!((-1.0..=2.0).contains(&u));
        }
        assert!(Pi::new(1.0, 0.0, -1.0, 1.0, 0.0).is_err());
    }
}
