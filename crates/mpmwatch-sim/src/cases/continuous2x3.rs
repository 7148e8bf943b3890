//! `continuous2x3` (paper §4.1, eqs 25–26): a continuous nonlinear plant with three inputs and
//! two outputs, sampled at [`PERIOD`] by zero-order hold, under a linear MPC designed on the
//! model linearised at the operating point.
//!
//! Our reading of the garbled eq 25 (see `docs/plants.md` for what is certain and why):
//!
//! ```text
//! ⎡y1⎤   ⎡ a/(s+1)           ⎤       ⎡ 0              0          ⎤ ⎡u2⎤
//! ⎣y2⎦ = ⎣ a(s+2)/(s²+2s+1)  ⎦ u1² + ⎣ (s+2)/(s²+2s+3) 1/(s²+s+1) ⎦ ⎣u3⎦ + v
//! ```
//!
//! with `a = 0.2` nominal and `0.8` in the mismatched plant (only u1's column changes), and the
//! coloured noise of eq 26 `v = diag(1/(40s+1), 1/(20s+1)) e`, `Σe = diag(0.1, 0.1)`, realised at
//! the sample period as the monic AR(1) filters `1/(1 − e^(−T/τ) q⁻¹)` driven by white noise of
//! variance 0.1 (the paper says the disturbance contributes 0.1 to the prediction error, i.e. the
//! innovation variance, and quotes 1.03 for y2's disturbance variance; `0.1/(1 − e^(−2/20)) = 1.05`
//! agrees at T = 1 s).
//!
//! The closed loop: operating point `u = (1, 0, 0)` (at u1 = 0 the linearised gain of u1² is zero
//! and u1 would drop out of the MPC), set points the nominal mean steady outputs there under
//! the dither (`(0.4, 0.8)` for a ±1 PRBS, see [`super::dithered_set_point`]),
//! ±1 PRBS dithers on all three MVs. The nominal prediction `yhat` is the nonlinear nominal model
//! `G0` (a = 0.2) on the total MVs; the MPC's own model is the linearisation.
//!
//! Columns: `time, u1..u3, ud1..ud3, y1, y2, yhat1, yhat2, e1, e2`.

use super::{CaseOptions, CaseOutput, DITHER_STREAM, NOISE_STREAM, stream};
use crate::closed_loop::ClosedLoop;
use crate::error::SimError;
use crate::mpc::{LinearMpc, MpcConfig};
use crate::noise::coloured_noise;
use mpmwatch_core::model::{ContinuousTf, DiscreteTf, Hammerstein, MimoModel, StaticMap};

/// Sample period in seconds.
pub const PERIOD: f64 = 1.0;
/// Nominal value of the parameter `a`.
pub const NOMINAL_A: f64 = 0.2;
/// The mismatched plant's `a`.
pub const MISMATCH_A: f64 = 0.8;
/// Operating input at which the MPC model is linearised.
pub const U_OP: [f64; 3] = [1.0, 0.0, 0.0];
/// Variance of each white noise source of eq 26.
pub const NOISE_VARIANCE: f64 = 0.1;
/// Time constants of the noise filters of eq 26 (seconds).
pub const NOISE_TAU: [f64; 2] = [40.0, 20.0];
const WARM_UP: usize = 100;

fn zoh(num: &[f64], den: &[f64]) -> Result<DiscreteTf, SimError> {
    Ok(ContinuousTf::new(num.to_vec(), den.to_vec(), 0.0)?.discretise(PERIOD)?)
}

/// The u2, u3 → y2 channels (certain to be linear and independent of `a`).
fn linear_part() -> Result<(DiscreteTf, DiscreteTf), SimError> {
    Ok((zoh(&[1.0, 2.0], &[1.0, 2.0, 3.0])?, zoh(&[1.0], &[1.0, 1.0, 1.0])?))
}

/// The sampled plant (or nominal model) with parameter `a`.
pub fn plant(a: f64) -> Result<MimoModel, SimError> {
    if !a.is_finite() {
        return Err(SimError::parameter("a", a, "must be finite"));
    }
    let (g22, g23) = linear_part()?;
    let g11 = Hammerstein::new(StaticMap::Square, zoh(&[a], &[1.0, 1.0])?)?;
    let g21 = Hammerstein::new(StaticMap::Square, zoh(&[a, 2.0 * a], &[1.0, 2.0, 1.0])?)?;
    Ok(MimoModel::new(vec![
        vec![Some(g11), None, None],
        vec![Some(g21), Some(Hammerstein::linear(g22)), Some(Hammerstein::linear(g23))],
    ])?)
}

/// The nominal model linearised at the operating point (the MPC's model, in deviations from
/// [`U_OP`]): `a·u1²` becomes `2·a·u1_op·Δu1`, the rest is already linear.
pub fn linearised(a: f64) -> Result<MimoModel, SimError> {
    Ok(plant(a)?.linearised(&U_OP)?)
}

/// The noise filters of eq 26 at [`PERIOD`].
pub fn noise_filters() -> Vec<DiscreteTf> {
    NOISE_TAU
        .iter()
        .map(|tau| {
            DiscreteTf::new(vec![1.0], vec![1.0, -(-PERIOD / tau).exp()], 0).expect("constant coefficients")
        })
        .collect()
}

/// The MPC tuning used by the case.
pub fn mpc_config() -> MpcConfig {
    MpcConfig {
        np: 20,
        nc: 4,
        q: vec![1.0, 1.0],
        r: vec![1.0, 1.0, 1.0],
        // u1 stays positive so the sign of its gain (2·a·u1) never flips under the linear MPC
        u_min: vec![0.2, -3.0, -3.0],
        u_max: vec![2.5, 3.0, 3.0],
        du_max: vec![0.3; 3],
    }
}

/// Parses `--mismatch`: `none` (plant a = 0.2) or `a=VALUE`; default `a=0.8`.
pub fn plant_a(spec: Option<&str>) -> Result<f64, SimError> {
    let bad = |given: &str| SimError::Mismatch {
        case: "continuous2x3".into(),
        given: given.into(),
        accepted: "none, a=VALUE (default a=0.8)".into(),
    };
    match spec {
        None => Ok(MISMATCH_A),
        Some("none") => Ok(NOMINAL_A),
        Some(s) => s
            .strip_prefix("a=")
            .and_then(|v| v.parse::<f64>().ok())
            .filter(|v| v.is_finite())
            .ok_or_else(|| bad(s)),
    }
}

/// Runs the case.
pub(crate) fn run(n: usize, opts: &CaseOptions) -> Result<CaseOutput, SimError> {
    let a = plant_a(opts.mismatch.as_deref())?;
    let nominal = plant(NOMINAL_A)?;
    let plant = plant(a)?;
    let dither =
        opts.excitation.generate_many(n, 3, opts.dither_std, &mut stream(opts.seed, DITHER_STREAM))?;
    let mut noise_rng = stream(opts.seed, NOISE_STREAM);
    let variance = NOISE_VARIANCE * opts.noise_scale * opts.noise_scale;
    let noise = noise_filters()
        .iter()
        .map(|h| coloured_noise(h, n, variance, 500, &mut noise_rng))
        .collect::<Result<Vec<_>, _>>()?;
    let setpoint = super::dithered_set_point(&nominal, &U_OP, &dither)?;
    let mut mpc = LinearMpc::new(&linearised(NOMINAL_A)?, U_OP.to_vec(), U_OP.to_vec(), mpc_config())?;
    let rec = ClosedLoop {
        plant: &plant,
        nominal: &nominal,
        dither: &dither,
        noise: &noise,
        setpoint: &setpoint,
        u_start: &U_OP,
        warm_up: WARM_UP,
        bound: 1e3,
    }
    .run(&mut mpc)?;
    Ok(CaseOutput {
        table: rec.to_table(PERIOD)?,
        controller: Some(mpc.stats().clone()),
        summary: format!(
            "continuous2x3: eqs 25–26 at T = {PERIOD} s, plant a = {a}, model a = {NOMINAL_A}, linear MPC, {:?} dithers (std {})",
            opts.excitation, opts.dither_std
        ),
    })
}
