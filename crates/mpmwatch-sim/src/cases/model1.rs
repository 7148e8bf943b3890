//! `model1` (paper §3.1, eqs 12–14): a SISO nonlinear system driven open loop by the excitation,
//!
//! `y(t) = −0.8 y(t−1) + 0.08 (y²(t−1) + 4.5 u(t−1) + u(t−1) u(t−2)) + d(t)`,
//! `d(t) = e(t) / (1 − 1.6 q⁻¹ + 0.8 q⁻²)`, `e` white with variance 0.01,
//!
//! and four candidate residuals (eq 13):
//! `ε1 = 0.7 d(t−1) + d(t)` (no input information), `ε2 = 0.06 u(t−1) u(t−2) + d(t)`,
//! `ε3 = 0.2 y(t−1) + d(t)`, `ε4 = 0.03 y²(t−1) + d(t)`.
//!
//! Columns: `time, u, y, e1, e2, e3, e4` (time = sample index, period 1 s).

use super::{CaseOptions, CaseOutput, DITHER_STREAM, NOISE_STREAM, stream};
use crate::error::SimError;
use crate::noise::coloured_noise;
use mpmwatch_core::io::Table;
use mpmwatch_core::model::DiscreteTf;

/// Variance of the white noise driving the ARIMA(2,0,0) disturbance (eq 14).
pub const NOISE_VARIANCE: f64 = 0.01;
/// Samples of the disturbance discarded before the record (its poles have modulus 0.89).
const BURN_IN: usize = 500;

/// The disturbance filter of eq 14, `1/(1 − 1.6 q⁻¹ + 0.8 q⁻²)`.
pub fn disturbance_filter() -> DiscreteTf {
    DiscreteTf::new(vec![1.0], vec![1.0, -1.6, 0.8], 0).expect("constant coefficients")
}

/// The signals of one run.
#[derive(Debug, Clone, PartialEq)]
pub struct Model1Record {
    /// Input.
    pub u: Vec<f64>,
    /// Output.
    pub y: Vec<f64>,
    /// Disturbance `d`.
    pub d: Vec<f64>,
    /// Residuals ε1..ε4.
    pub e: [Vec<f64>; 4],
}

/// Simulates eq 12 for the given input and disturbance.
pub fn simulate(u: &[f64], d: &[f64]) -> Result<Model1Record, SimError> {
    let n = u.len();
    if d.len() != n {
        return Err(SimError::parameter(
            "model1 disturbance length",
            d.len(),
            &format!("must equal the input length {n}"),
        ));
    }
    let past = |s: &[f64], t: usize, k: usize| if t >= k { s[t - k] } else { 0.0 };
    let mut y = vec![0.0; n];
    for t in 0..n {
        let y1 = past(&y, t, 1);
        let (u1, u2) = (past(u, t, 1), past(u, t, 2));
        y[t] = -0.8 * y1 + 0.08 * (y1 * y1 + 4.5 * u1 + u1 * u2) + d[t];
        if y[t].abs() >= 1e6 || y[t].is_nan() {
            return Err(SimError::Diverged { sample: t, signal: "y".into(), value: y[t] });
        }
    }
    let e = [
        (0..n).map(|t| 0.7 * past(d, t, 1) + d[t]).collect(),
        (0..n).map(|t| 0.06 * past(u, t, 1) * past(u, t, 2) + d[t]).collect(),
        (0..n).map(|t| 0.2 * past(&y, t, 1) + d[t]).collect(),
        (0..n).map(|t| 0.03 * past(&y, t, 1).powi(2) + d[t]).collect(),
    ];
    Ok(Model1Record { u: u.to_vec(), y, d: d.to_vec(), e })
}

fn std_dev(x: &[f64]) -> f64 {
    let m = x.iter().sum::<f64>() / x.len() as f64;
    (x.iter().map(|v| (v - m).powi(2)).sum::<f64>() / x.len() as f64).sqrt()
}

/// Runs the case: input from the excitation, disturbance from the seed.
pub(crate) fn run(n: usize, opts: &CaseOptions) -> Result<CaseOutput, SimError> {
    if let Some(m) = &opts.mismatch {
        return Err(SimError::Mismatch {
            case: "model1".into(),
            given: m.clone(),
            accepted: "none (model1's four residuals ε1..ε4 are its scenarios)".into(),
        });
    }
    let u = opts.excitation.generate(n, opts.dither_std, &mut stream(opts.seed, DITHER_STREAM))?;
    let variance = NOISE_VARIANCE * opts.noise_scale * opts.noise_scale;
    let mut d =
        coloured_noise(&disturbance_filter(), n, variance, BURN_IN, &mut stream(opts.seed, NOISE_STREAM))?;
    let mut summary = format!(
        "model1: eq 12, {:?} input (std {}), disturbance variance of e = {variance}",
        opts.excitation, opts.dither_std
    );
    if let Some(ratio) = opts.noise_ratio {
        if !(ratio.is_finite() && ratio >= 0.0) {
            return Err(SimError::parameter("noise ratio", ratio, "must be finite and non-negative"));
        }
        // Figure 5: std(d) / std(signal part of ε2)
        let signal: Vec<f64> = (2..n).map(|t| 0.06 * u[t - 1] * u[t - 2]).collect();
        let scale = ratio * std_dev(&signal) / std_dev(&d).max(f64::MIN_POSITIVE);
        d.iter_mut().for_each(|v| *v *= scale);
        summary = format!(
            "model1: eq 12, {:?} input, disturbance scaled to std(d)/std(0.06·u(t−1)u(t−2)) = {ratio}",
            opts.excitation
        );
    }
    let rec = simulate(&u, &d)?;
    let mut table = Table::new((0..n).map(|k| k as f64).collect());
    table.push_column("u", rec.u)?;
    table.push_column("y", rec.y)?;
    for (i, e) in rec.e.into_iter().enumerate() {
        table.push_column(format!("e{}", i + 1), e)?;
    }
    Ok(CaseOutput { table, controller: None, summary })
}
