//! The plant behind `mpmwatch demo`: the `continuous2x3` case (paper §4.1) under its linear MPC,
//! stepped one sample at a time so it can publish in (accelerated) real time, with the plant's
//! parameter `a` switchable while it runs (0.2 = the nominal model, 0.8 = the paper's mismatch).
//!
//! Both plants run side by side on the same inputs from the start and the switch only chooses
//! which one is measured, so after the switch the loop sees the mismatched plant exactly as if it
//! had always been there (no artificial initial-condition jump beyond the gain change itself).

use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;

use mpmwatch_core::model::{MimoModel, MimoState};
use mpmwatch_sim::cases::continuous2x3 as case;
use mpmwatch_sim::{Controller, Excitation, LinearMpc, SimError, coloured_noise};

/// Warm-up samples at the operating point (as the case's closed loop does).
const WARM_UP: usize = 100;

/// One published sample of every signal.
#[derive(Debug, Clone, PartialEq)]
pub struct DemoSample {
    /// Sample index.
    pub k: usize,
    /// Total MVs `u = uc + ud`.
    pub u: Vec<f64>,
    /// Dithers.
    pub ud: Vec<f64>,
    /// Measured CVs.
    pub y: Vec<f64>,
    /// The MPC's nominal predictions `G0(u)` (a = 0.2).
    pub yhat: Vec<f64>,
}

/// The closed loop, one step at a time.
pub struct DemoPlant {
    nominal_plant: MimoState,
    mismatched_plant: MimoState,
    model: MimoState,
    mpc: LinearMpc,
    dither: Vec<Vec<f64>>,
    noise: Vec<Vec<f64>>,
    setpoint: Vec<f64>,
    /// Measure the mismatched plant (a = 0.8) instead of the nominal one.
    pub mismatched: bool,
    k: usize,
}

impl DemoPlant {
    /// A loop able to run `n` samples (dithers and noise are drawn up front from `seed`).
    pub fn new(n: usize, seed: u64) -> Result<Self, SimError> {
        let nominal: MimoModel = case::plant(case::NOMINAL_A)?;
        let mismatched = case::plant(case::MISMATCH_A)?;
        let mut rng = ChaCha8Rng::seed_from_u64(seed);
        let dither = Excitation::Prbs.generate_many(n, 3, 1.0, &mut rng)?;
        let noise = case::noise_filters()
            .iter()
            .map(|h| coloured_noise(h, n, case::NOISE_VARIANCE, 500, &mut rng))
            .collect::<Result<Vec<_>, _>>()?;
        let setpoint = mpmwatch_sim::cases::dithered_set_point(&nominal, &case::U_OP, &dither)?;
        let mut mpc = LinearMpc::new(
            &case::linearised(case::NOMINAL_A)?,
            case::U_OP.to_vec(),
            case::U_OP.to_vec(),
            case::mpc_config(),
        )?;
        let (mut p0, mut p1, mut m) = (nominal.state(), mismatched.state(), nominal.state());
        for _ in 0..WARM_UP {
            p0.step(&case::U_OP)?;
            p1.step(&case::U_OP)?;
            m.step(&case::U_OP)?;
            mpc.apply(&case::U_OP)?;
        }
        Ok(Self {
            nominal_plant: p0,
            mismatched_plant: p1,
            model: m,
            mpc,
            dither,
            noise,
            setpoint,
            mismatched: false,
            k: 0,
        })
    }

    /// Samples left.
    pub fn remaining(&self) -> usize {
        self.dither[0].len() - self.k
    }

    /// Advances one sample; `None` when the drawn record is used up.
    pub fn step(&mut self) -> Result<Option<DemoSample>, SimError> {
        let k = self.k;
        if k >= self.dither[0].len() {
            return Ok(None);
        }
        let plant = if self.mismatched { &self.mismatched_plant } else { &self.nominal_plant };
        let y: Vec<f64> = plant.peek().iter().enumerate().map(|(j, v)| v + self.noise[j][k]).collect();
        let yhat = self.model.peek();
        let uc = self.mpc.control(&y, &self.setpoint)?;
        let ud: Vec<f64> = self.dither.iter().map(|d| d[k]).collect();
        let u: Vec<f64> = uc.iter().zip(&ud).map(|(a, b)| a + b).collect();
        self.nominal_plant.step(&u)?;
        self.mismatched_plant.step(&u)?;
        self.model.step(&u)?;
        self.mpc.apply(&u)?;
        self.k += 1;
        Ok(Some(DemoSample { k, u, ud, y, yhat }))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn nominal_plant_has_zero_mean_noise_residuals_and_the_switch_changes_y() {
        let mut p = DemoPlant::new(400, 7).unwrap();
        let mut e = Vec::new();
        for _ in 0..200 {
            let s = p.step().unwrap().unwrap();
            e.push(s.y[0] - s.yhat[0]);
        }
        // y1's residual is only the coloured noise while the plant is nominal
        let mean = e.iter().sum::<f64>() / e.len() as f64;
        assert!(mean.abs() < 1.0, "{mean}");
        p.mismatched = true;
        let s = p.step().unwrap().unwrap();
        assert!((s.y[0] - s.yhat[0]).abs() > 0.1);
        assert_eq!(p.remaining(), 199);
    }
}
