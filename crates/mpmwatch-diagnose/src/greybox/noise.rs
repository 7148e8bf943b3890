//! The noise model of a fit on a dithered record: the prediction-error refinement that
//! searches an AR model of the simulation error together with the structure's coefficients (the
//! direct method of closed-loop identification), with the whitening of [`crate::whiten`].

use super::{Data, Fitted, Model};
use crate::minimize::minimize;
use crate::whiten::{ar_fit, whitenable, whitened};

/// The prediction-error refinement of an output-error fit `start`: an AR noise model of order
/// `d.noise_order` fitted to its simulation error gives the start of the noise coefficients,
/// then they, every coefficient and the element's free parameters are searched together for
/// the least one-step prediction error on the rows of `rows` the whitening can use
/// ([`whitenable`]: it reaches no excluded block). The start is returned when the refinement
/// cannot simulate.
pub(super) fn prediction_error_fit(
    model: &Model<'_>,
    d: &Data<'_>,
    rows: &[usize],
    start: Fitted,
    scale: f64,
) -> Fitted {
    let p = d.noise_order;
    let used = whitenable(rows, p);
    if used.len() < 3 * (p + start.theta.len()) {
        return start;
    }
    let Some(s0) = model.simulate(&start, &d.u, d.y) else { return start };
    let e0: Vec<f64> = s0.iter().zip(d.y).map(|(a, b)| a - b).collect();
    let Some(ar) = ar_fit(&e0, rows, p) else { return start };
    let (fixed, free) = start.p.split_at(model.element.fixed().min(start.p.len()));
    let (n_p, n_theta) = (free.len(), start.theta.len());
    let fitted = |x: &[f64]| Fitted {
        p: fixed.iter().chain(&x[..n_p]).copied().collect(),
        theta: x[n_p..n_p + n_theta].to_vec(),
        noise: x[n_p + n_theta..].to_vec(),
    };
    let residual = |x: &[f64]| -> Option<Vec<f64>> {
        let s = model.simulate(&fitted(x), &d.u, d.y)?;
        let e: Vec<f64> = s.iter().zip(d.y).map(|(a, b)| a - b).collect();
        Some(used.iter().map(|&t| whitened(&e, &x[n_p + n_theta..], t)).collect())
    };
    let x0: Vec<f64> = free.iter().chain(&start.theta).chain(&ar).copied().collect();
    let x = minimize(&residual, &x0, used.len(), 1e3 * scale);
    if x.iter().any(|v| !v.is_finite()) {
        return start;
    }
    let f = fitted(&x);
    if model.simulate(&f, &d.u, d.y).is_some() { f } else { start }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::greybox::{Linear, Orders, fit};

    /// A closed loop: `x(t) = 0.9 x(t−1) + 0.2 u(t−1)` (pole 0.9, gain 2) measured with an AR(1)
    /// disturbance of pole 0.95, under `u(t) = −0.5 y(t) + d(t)` with a ±1 dither, N = 3000,
    /// seeds 1–4. The recorded input carries the controller's answer to the disturbance, so
    /// the output-error fit, which takes the error for white, lets the dynamics absorb it; the
    /// prediction-error fit with an AR noise model (order 4 ⊇ the true 1) is consistent (the
    /// direct method; Ljung, *System Identification*, §13.4). Over seeds 1–12 the
    /// prediction-error pole scattered with a standard deviation of 0.009 around 0.899 and the
    /// gain with 0.19 around 1.98; the bounds are three of those. The output-error pole was
    /// 0.07–0.17 low on every seed: a bias, not scatter.
    #[test]
    fn a_noise_model_removes_the_closed_loop_bias() {
        use rand::{Rng, SeedableRng};
        let n = 3000;
        for seed in 1..=4 {
            let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(seed);
            let (mut x, mut v) = (0.0, 0.0);
            let (mut u, mut y) = (vec![0.0; n], vec![0.0; n]);
            for t in 0..n {
                let u_prev = if t > 0 { u[t - 1] } else { 0.0 };
                x = 0.9 * x + 0.2 * u_prev;
                let e: f64 = rng.random::<f64>() - 0.5;
                v = 0.95 * v + 0.5 * e;
                y[t] = x + v;
                let dither = if rng.random::<bool>() { 1.0 } else { -1.0 };
                u[t] = -0.5 * y[t] + dither;
            }
            let rows: Vec<usize> = (20..n).collect();
            let m = Model {
                element: &Linear,
                input: 0,
                orders: Orders { na: 1, nb: 1, nk: vec![1], trend: false, reading: None },
            };
            let gain_pole = |noise_order: usize| {
                let d = Data { u: vec![&u], y: &y, train: 0..n, nominal: None, noise_order };
                let f = fit(&m, &d, &rows).unwrap();
                (f.theta[1] / (1.0 - f.theta[0]), f.theta[0])
            };
            let (pe_gain, pe_pole) = gain_pole(4);
            assert!(
                (pe_gain - 2.0).abs() < 0.6 && (pe_pole - 0.9).abs() < 0.03,
                "seed {seed}: {pe_gain} {pe_pole}"
            );
            let (_, oe_pole) = gain_pole(0);
            assert!(oe_pole < 0.85, "seed {seed}: the output-error fit is unbiased here ({oe_pole})");
        }
    }
}
