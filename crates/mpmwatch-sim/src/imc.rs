//! Internal model control (IMC) with a first-order filter, for SISO discrete models.

use super::closed_loop::Controller;
use super::error::SimError;
use mpmwatch_core::model::{DiscreteTf, ModelError, TfFilter};

/// IMC: the model runs beside the plant, the controller acts on `r − (y − ŷ)` through
/// `Q = F · G0₋⁻¹` with the filter `F = (1−λ)/(1−λq⁻¹)` (unit static gain, so no offset).
///
/// `G0₋⁻¹` inverts `A/B'` where `B'` is the numerator with its leading zeros removed (the dead
/// time cannot be inverted). When `B'` has zeros outside the unit circle its inverse would be
/// unstable; then only its static gain `B'(1)` is inverted, the usual safe fallback.
#[derive(Debug, Clone)]
pub struct Imc {
    model: TfFilter,
    q: TfFilter,
    u_min: f64,
    u_max: f64,
}

impl Imc {
    /// Builds the controller for a stable model `g0`, filter pole `lambda` in [0, 1).
    pub fn new(g0: &DiscreteTf, lambda: f64, u_min: f64, u_max: f64) -> Result<Self, SimError> {
        g0.require_stable("IMC model")?;
        if !(0.0..1.0).contains(&lambda) {
            return Err(SimError::parameter("IMC filter pole", lambda, "must lie in [0, 1)"));
        }
        if u_min >= u_max || u_min.is_nan() || u_max.is_nan() {
            return Err(SimError::parameter(
                "IMC limits",
                format!("[{u_min}, {u_max}]"),
                "need u_min < u_max",
            ));
        }
        let b = g0.numerator();
        let first = b
            .iter()
            .position(|v| *v != 0.0)
            .ok_or(ModelError::Empty { what: "IMC model numerator (all zero)".into() })?;
        let b_inv: Vec<f64> = b[first..].to_vec();
        let invertible = DiscreteTf::new(vec![1.0], b_inv.clone(), 0)?;
        let b_part = if invertible.is_stable() { b_inv } else { vec![b_inv.iter().sum()] };
        if b_part.iter().sum::<f64>() == 0.0 {
            return Err(SimError::parameter("IMC model", format!("{b:?}"), "numerator has zero static gain"));
        }
        let inverse = DiscreteTf::new(g0.denominator().to_vec(), b_part, 0)?;
        let filter = DiscreteTf::new(vec![1.0 - lambda], vec![1.0, -lambda], 0)?;
        Ok(Self { model: g0.filter(), q: inverse.series(&filter).filter(), u_min, u_max })
    }
}

impl Controller for Imc {
    fn control(&mut self, y: &[f64], r: &[f64]) -> Result<Vec<f64>, SimError> {
        let residual = y[0] - self.model.peek();
        Ok(vec![self.q.step(r[0] - residual).clamp(self.u_min, self.u_max)])
    }

    fn apply(&mut self, u: &[f64]) -> Result<(), SimError> {
        self.model.step(u[0]);
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn perfect_model_gives_the_delayed_filter_response() {
        // G0 = q⁻² 0.4/(1 − 0.6 q⁻¹): with plant = model, y = q⁻² F r, step response 1 − λ^k
        let g0 = DiscreteTf::new(vec![0.0, 0.4], vec![1.0, -0.6], 1).unwrap();
        let lambda = 0.7;
        let mut imc = Imc::new(&g0, lambda, -100.0, 100.0).unwrap();
        let mut plant = g0.filter();
        for k in 0..30 {
            let y = plant.peek();
            let expected = if k >= 2 { 1.0 - lambda.powi(k - 1) } else { 0.0 };
            assert!((y - expected).abs() < 1e-12, "k={k}: {y} vs {expected}");
            let u = imc.control(&[y], &[1.0]).unwrap();
            imc.apply(&u).unwrap();
            plant.step(u[0]);
        }
    }

    #[test]
    fn no_offset_under_gain_mismatch() {
        let g0 = DiscreteTf::new(vec![0.0, 0.4], vec![1.0, -0.6], 0).unwrap();
        let g = DiscreteTf::new(vec![0.0, 0.6], vec![1.0, -0.6], 0).unwrap();
        let mut imc = Imc::new(&g0, 0.5, -100.0, 100.0).unwrap();
        let mut plant = g.filter();
        for _ in 0..300 {
            let u = imc.control(&[plant.peek()], &[2.0]).unwrap();
            imc.apply(&u).unwrap();
            plant.step(u[0]);
        }
        assert!((plant.peek() - 2.0).abs() < 1e-8);
    }

    #[test]
    fn unstable_model_is_refused() {
        let g0 = DiscreteTf::new(vec![0.0, 1.0], vec![1.0, -1.2], 0).unwrap();
        assert!(Imc::new(&g0, 0.5, -1.0, 1.0).is_err());
        let g0 = DiscreteTf::new(vec![0.0, 1.0], vec![1.0, -0.2], 0).unwrap();
        assert!(Imc::new(&g0, 1.0, -1.0, 1.0).is_err());
    }
}
