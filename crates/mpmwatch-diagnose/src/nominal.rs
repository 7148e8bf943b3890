//! The nominal model as the simulation shows it. `diagnose` receives only the simulated outputs,
//! not the model, yet every physics hypothesis is stated against that model ("the gain of the
//! u1→y2 channel is 30 % higher", "u1 passes through a dead zone before the model's dynamics").
//! A simulation driven by the recorded inputs is a noise-free input–output record of the model,
//! so a MISO ARX model fitted to it by least squares recovers a linear nominal model exactly and
//! a nonlinear one approximately; each channel's filter `B_i/A` then carries any signal through
//! "the model's dynamics of channel i→j".

use mpmwatch_core::model::{Arx, ArxOrders, DiscreteTf};
use mpmwatch_core::numerics::{median, minus_median, rms};

use super::fitness::fit_pct;

/// A MISO ARX model `A(q⁻¹) s(t) = Σ_i B_i(q⁻¹) u_i(t) + c` of one simulated output.
#[derive(Debug, Clone, PartialEq)]
pub struct NominalArx {
    /// The identified model (no dead times: leading zero coefficients of `B_i` carry them).
    pub arx: Arx,
    /// FIT% of the ARX simulation against the given simulated output (100 for a linear model).
    pub fit_pct: f64,
    /// The order search's criterion for this model (lower is better; +∞ for the zero model
    /// returned when no order could be fitted), which [`identify_polynomial`] must beat.
    pub score: f64,
}

impl NominalArx {
    /// Input i's transfer function `B_i/A`.
    pub fn tf(&self, i: usize) -> DiscreteTf {
        self.arx.channel(i).unwrap_or_else(|_| unreachable_channel())
    }

    /// Input i's contribution to the output (no constant): the channel's filter applied to `x`,
    /// started in steady state at `x(0)`.
    pub fn channel(&self, i: usize, x: &[f64]) -> Vec<f64> {
        self.tf(i).simulate_from_rest(x)
    }

    /// Whether input i reaches this output at all in the model: its contribution to `u` is
    /// below 1e-6 of the whole simulated output's spread.
    pub fn has_channel(&self, i: usize, u: &[f64], s: &[f64]) -> bool {
        let c = self.channel(i, &minus_median(u));
        rms(&c) > 1e-6 * rms(&minus_median(s)).max(1e-300)
    }

    /// DC gain of channel i.
    pub fn dc_gain(&self, i: usize) -> f64 {
        self.tf(i).dc_gain().unwrap_or(f64::NAN)
    }

    /// Dominant pole of channel i ([`dominant_pole`]).
    pub fn dominant_pole(&self, i: usize, n: usize) -> f64 {
        dominant_pole(&self.tf(i), n)
    }

    /// Pure delay of channel i in samples ([`delay`]).
    pub fn delay(&self, i: usize) -> usize {
        delay(&self.tf(i))
    }

    /// Simulates the model from the inputs, started in steady state.
    pub fn simulate(&self, u: &[&[f64]]) -> Vec<f64> {
        let u0: Vec<f64> = u.iter().map(|x| x.first().copied().unwrap_or(0.0)).collect();
        let rest = self.arx.rest_output(&u0);
        let y0 = if rest.is_finite() { rest } else { 0.0 };
        self.arx.simulate_from(u, y0).unwrap_or_else(|_| vec![f64::NAN; u.first().map_or(0, |x| x.len())])
    }
}

/// Dominant pole of a channel: the real pole of a first-order fit of its step response over `n`
/// samples, clamped to (0, 0.999). The fit reads the time constant where the response reaches
/// 63 % of its final value, counted from the sample before its first move, with the crossing
/// placed between samples on `ln(1 − y/y∞)`: that logarithm is linear in time for a first-order
/// lag, `(t − t₀)·ln a`, so a first-order channel with any pure delay gives back its own pole
/// (while the last of the `n` samples is its final value: for poles up to 0.99 at `n` = 2000).
/// A whole-sample count would read a channel of 2.4 samples as 2 (a pole of 0.61 for 0.65), and
/// a time-constant hypothesis built on that pole cannot cancel the nominal's own.
pub fn dominant_pole(tf: &DiscreteTf, n: usize) -> f64 {
    let mut x = vec![1.0; n.max(20)];
    x[0] = 0.0;
    let step = tf.simulate_from_rest(&x);
    let fin = *step.last().unwrap_or(&0.0);
    if fin.abs() < 1e-300 {
        return 0.5;
    }
    let start = step.iter().position(|v| (v / fin).abs() > 1e-9).unwrap_or(0);
    let t63 = step.iter().position(|v| v / fin >= 1.0 - (-1.0f64).exp()).unwrap_or(step.len() - 1);
    let log_rest = |t: usize| (1.0 - step[t] / fin).max(1e-300).ln();
    // The step is applied at sample 1 from rest, so `step[0]` is 0 and `1 ≤ start ≤ t63` (the
    // crossing is a move): the sample before it exists, and the one before the first move has
    // `ln(1 − y/y∞) = 0`.
    let (a, b) = (log_rest(t63 - 1), log_rest(t63));
    let frac = if b < a { ((-1.0 - a) / (b - a)).clamp(0.0, 1.0) } else { 1.0 };
    let tau = (t63 - start) as f64 + frac;
    (-1.0 / tau.max(0.3)).exp().clamp(1e-3, 0.999)
}

/// Pure delay of a channel in samples: its leading numerator coefficients below 1e-6 of the
/// largest, plus the filter's own delay.
pub fn delay(tf: &DiscreteTf) -> usize {
    let b = tf.numerator();
    let m = b.iter().fold(0.0f64, |a, v| a.max(v.abs()));
    tf.delay() + b.iter().position(|v| v.abs() > 1e-6 * m).unwrap_or(0)
}

/// The identified models have one numerator per input by construction.
fn unreachable_channel() -> DiscreteTf {
    DiscreteTf::gain(0.0).expect("a zero gain is a valid transfer function")
}

/// Fits the nominal model of one simulated output `s` from the inputs `u`, over orders
/// `na ≤ 4`, `nb ≤ 12`, choosing by simulation-mode error with a BIC penalty on `rows`.
pub fn identify(u: &[&[f64]], s: &[f64], rows: std::ops::Range<usize>) -> NominalArx {
    search(u, s, rows).map(|b| b.1).unwrap_or_else(|| NominalArx {
        arx: Arx::new(vec![1.0], vec![vec![0.0]; u.len()], vec![0; u.len()])
            .expect("a zero model is a valid ARX model"),
        fit_pct: f64::NAN,
        score: f64::INFINITY,
    })
}

/// The order search of [`identify`] on the regressors `u`: the best model and its score.
fn search(u: &[&[f64]], s: &[f64], rows: std::ops::Range<usize>) -> Option<(f64, NominalArx)> {
    let mut best: Option<(f64, NominalArx)> = None;
    let scale = rms(&minus_median(&s[rows.clone()])).max(1e-300);
    for na in 0..=4usize {
        for nb in [1usize, 2, 3, 4, 6, 8, 10, 12] {
            let lag = na.max(nb);
            if rows.len() < 4 * (na + nb * u.len() + 1) + lag {
                continue;
            }
            let orders = ArxOrders { na, nb, delays: Vec::new() };
            let Some(arx) = Arx::fit(s, u, &orders, (rows.start + lag)..rows.end) else { continue };
            if !stable(arx.denominator()) {
                continue;
            }
            let m = NominalArx { arx, fit_pct: 0.0, score: f64::INFINITY };
            let sim = m.simulate(u);
            let err: f64 = rows.clone().map(|t| (s[t] - sim[t]).powi(2)).sum::<f64>() / rows.len() as f64;
            let p = (na + nb * u.len() + 1) as f64;
            // Relative error floored at 1e-12: an exact fit stops the search for higher orders.
            let score =
                rows.len() as f64 * (err / (scale * scale)).max(1e-12).ln() + p * (rows.len() as f64).ln();
            if best.as_ref().is_none_or(|b| score < b.0) {
                best = Some((
                    score,
                    NominalArx { fit_pct: fit_pct(&s[rows.clone()], &sim[rows.clone()]), score, ..m },
                ));
            }
        }
    }
    best
}

/// Highest power of an input in [`PolyChannels`].
const POLY_DEGREE: usize = 3;

/// FIT% above which the linear nominal is taken as exact: an exactly linear model is recovered
/// far above it (`recovers_a_two_input_model_exactly`), so [`identify_polynomial`] leaves every
/// linear nominal alone without a search.
const LINEAR_EXACT_PCT: f64 = 99.9;

/// The channels of a simulated output that is not linear in its inputs (a square law, a
/// Hammerstein model's static maps): a MISO ARX on the powers 1 to [`POLY_DEGREE`] of every
/// input about its operating point, `A(q⁻¹) s = Σ_i Σ_k B_ik(q⁻¹) z_iᵏ + c` with
/// `z_i = (u_i − c_i)/d_i` (median and RMS deviation on the rows fitted). Centred and scaled, the
/// powers stay apart for an input far from zero (a temperature at 350 ± 5: the raw powers of
/// 345–355 are collinear to a part in 10⁵, and the least-squares cut-off would drop the
/// curvature). Input i's contribution is then what the model
/// itself does with that input, so that a change of the channel's gain or time constant is
/// stated against it: measured against the linear nominal's approximation instead, a gain change
/// of a square-law channel (the paper's continuous 2×3 plant) is as much a `quadratic` as a gain.
#[derive(Debug, Clone, PartialEq)]
pub struct PolyChannels {
    arx: Arx,
    /// Per input: its centre `c_i` and scale `d_i`.
    centre: Vec<f64>,
    scale: Vec<f64>,
}

impl PolyChannels {
    /// Input i's contribution for the input `x` (in the record's units) relative to the input
    /// held at `at`: `Σ_k B_ik/A (z(x)ᵏ − z(at)ᵏ)`, started in steady state.
    pub fn response(&self, i: usize, x: &[f64], at: f64) -> Vec<f64> {
        let z = |v: f64| (v - self.centre[i]) / self.scale[i];
        let mut out = vec![0.0; x.len()];
        for k in 1..=POLY_DEGREE {
            let Ok(tf) = self.arx.channel(i * POLY_DEGREE + k - 1) else { continue };
            let p: Vec<f64> = x.iter().map(|&v| z(v).powi(k as i32) - z(at).powi(k as i32)).collect();
            out.iter_mut().zip(tf.simulate_from_rest(&p)).for_each(|(o, r)| *o += r);
        }
        out
    }

    /// Input i's channel linearised at the input `at`: `Σ_k k·z(at)^(k−1)/d_i · B_ik / A`, the
    /// response to a small move from there per unit of the move. Its gain and dead time are the
    /// model's as an engineer reads them at the operating point; the linear ARX fitted to the
    /// whole simulation averages the channel's slope over the record's range.
    pub fn linearised(&self, i: usize, at: f64) -> Option<DiscreteTf> {
        let z = (at - self.centre[i]) / self.scale[i];
        let a = self.arx.denominator().to_vec();
        let mut b: Vec<f64> = Vec::new();
        for k in 1..=POLY_DEGREE {
            let tf = self.arx.channel(i * POLY_DEGREE + k - 1).ok()?;
            let w = k as f64 * z.powi(k as i32 - 1) / self.scale[i];
            let bk = tf.numerator();
            let lead = tf.delay();
            if b.len() < lead + bk.len() {
                b.resize(lead + bk.len(), 0.0);
            }
            bk.iter().enumerate().for_each(|(j, v)| b[lead + j] += w * v);
        }
        DiscreteTf::new(b, a, 0).ok()
    }
}

/// Identifies [`PolyChannels`] of `s` on `rows` when the linear nominal `linear` (from
/// [`identify`] on the same rows) leaves part of it unexplained (FIT below [`LINEAR_EXACT_PCT`])
/// and the polynomial model scores better under the same order search and penalty (its extra
/// coefficients must pay for themselves); `None` otherwise.
pub fn identify_polynomial(
    u: &[&[f64]],
    s: &[f64],
    rows: std::ops::Range<usize>,
    linear: &NominalArx,
) -> Option<PolyChannels> {
    if linear.fit_pct.is_nan() || linear.fit_pct >= LINEAR_EXACT_PCT {
        return None;
    }
    let centre: Vec<f64> = u.iter().map(|x| median(&x[rows.clone()])).collect();
    // A constant input has no powers to speak of: scale 1 keeps them finite (all zero).
    let scale: Vec<f64> = u
        .iter()
        .map(|x| rms(&minus_median(&x[rows.clone()])))
        .map(|d| if d > 0.0 && d.is_finite() { d } else { 1.0 })
        .collect();
    let powers: Vec<Vec<f64>> = u
        .iter()
        .zip(centre.iter().zip(&scale))
        .flat_map(|(x, (c, d))| {
            (1..=POLY_DEGREE).map(move |k| x.iter().map(|v| ((v - c) / d).powi(k as i32)).collect())
        })
        .collect();
    let refs: Vec<&[f64]> = powers.iter().map(Vec::as_slice).collect();
    let (score, poly) = search(&refs, s, rows)?;
    (score < linear.score).then_some(PolyChannels { arx: poly.arx, centre, scale })
}

/// Stable when the impulse response of `1/A` decays (checked over a long horizon; cheap and
/// exact enough for the orders used here).
fn stable(a: &[f64]) -> bool {
    if a.len() <= 1 {
        return true;
    }
    let mut x = vec![0.0; 4000];
    x[0] = 1.0;
    let Ok(tf) = DiscreteTf::new(vec![1.0], a.to_vec(), 0) else { return false };
    let h = tf.simulate_from_rest(&x);
    let tail = h[3000..].iter().fold(0.0f64, |m, v| m.max(v.abs()));
    tail.is_finite() && tail < 1e-3
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn recovers_a_two_input_model_exactly() {
        let u1: Vec<f64> = (0..400).map(|t| ((t * 7919) % 13) as f64 - 6.0).collect();
        let u2: Vec<f64> = (0..400).map(|t| ((t * 104729) % 7) as f64 - 3.0).collect();
        let y1 = DiscreteTf::new(vec![0.0, 0.0, 0.2], vec![1.0, -0.8], 0).unwrap().simulate_from_rest(&u1);
        let y2 = DiscreteTf::new(vec![0.0, 0.5], vec![1.0, -0.5], 0).unwrap().simulate_from_rest(&u2);
        let s: Vec<f64> = y1.iter().zip(&y2).map(|(a, b)| a + b + 1.0).collect();
        let m = identify(&[&u1, &u2], &s, 0..400);
        assert!(m.fit_pct > 99.9, "{m:?}");
        assert!((m.dc_gain(0) - 1.0).abs() < 1e-6 && (m.dc_gain(1) - 1.0).abs() < 1e-6, "{m:?}");
        assert_eq!(m.delay(0), 2);
    }

    /// A first-order lag `k(1 − a)/(1 − a·q⁻¹)` behind a pure delay gives back its own pole,
    /// whatever the delay and however fast the lag (the 63 % crossing falls between samples;
    /// ln of the step's remainder is exactly linear in time, so only rounding is left: 1e-9);
    /// a second-order channel of two equal poles, whose step is not first-order, reads its 63 %
    /// time, `2.146·τ₁` for the continuous lag, within one sample (this numerator, `q⁻¹` alone,
    /// is not the zero-order hold's, which moves the discrete step by about half a sample).
    #[test]
    fn the_dominant_pole_of_a_first_order_lag_is_its_pole() {
        for a in [0.2f64, 0.45, 0.6545, 0.9, 0.98] {
            for d in [0usize, 1, 3] {
                let mut b = vec![0.0; d + 1];
                b[d] = 0.7 * (1.0 - a);
                let tf = DiscreteTf::new(b, vec![1.0, -a], 0).unwrap();
                let p = dominant_pole(&tf, 2000);
                assert!((p - a).abs() < 1e-9, "a {a} delay {d}: read {p}");
            }
        }
        // Two poles at 0.9 (τ₁ = 9.49 samples): (1 + t/τ₁)·e^(−t/τ₁) = e⁻¹ at t = 2.146·τ₁.
        let p1: f64 = 0.9;
        let tf = DiscreteTf::new(vec![0.0, (1.0 - p1).powi(2)], vec![1.0, -2.0 * p1, p1 * p1], 0).unwrap();
        let tau = -1.0 / dominant_pole(&tf, 2000).ln();
        let want = 2.146 * (-1.0 / p1.ln());
        assert!((tau - want).abs() < 1.0, "second order: τ {tau} against {want}");
    }

    /// A square law on one input and a linear second input, uniform random inputs (seed 11),
    /// noise-free (the paper's continuous
    /// 2×3 plant has `0.2·u1²` through a first-order lag): the polynomial channels reproduce
    /// input 1's contribution about its operating point, `G1(u1² − u0²)`, to 1e-6 of its spread
    /// (the model is in the class searched, so only rounding is left); a linear output gets no
    /// polynomial channels.
    #[test]
    fn polynomial_channels_recover_a_square_law() {
        use rand::{Rng, SeedableRng};
        let n = 600;
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(11);
        let u1: Vec<f64> = (0..n).map(|_| rng.random_range(-0.5..2.5)).collect();
        let u2: Vec<f64> = (0..n).map(|_| rng.random_range(-3.0..3.0)).collect();
        let g1 = DiscreteTf::new(vec![0.0, 0.2 * 0.3], vec![1.0, -0.7], 0).unwrap();
        let g2 = DiscreteTf::new(vec![0.0, 0.5], vec![1.0, -0.7], 0).unwrap();
        let sq: Vec<f64> = u1.iter().map(|v| v * v).collect();
        let (y1, y2) = (g1.simulate_from_rest(&sq), g2.simulate_from_rest(&u2));
        let s: Vec<f64> = y1.iter().zip(&y2).map(|(a, b)| a + b).collect();
        let linear = identify(&[&u1, &u2], &s, 0..n);
        let poly = identify_polynomial(&[&u1, &u2], &s, 0..n, &linear).expect("polynomial channels");
        let at = 1.0;
        let want = g1.simulate_from_rest(&u1.iter().map(|v| v * v - at * at).collect::<Vec<_>>());
        let got = poly.response(0, &u1, at);
        let spread = rms(&minus_median(&want));
        let err = (20..n).map(|t| (got[t] - want[t]).abs()).fold(0.0, f64::max);
        assert!(err < 1e-6 * spread, "largest error {err} against a spread of {spread}");
        // The same law about an operating point far from zero, u1 at 10⁴ (its raw powers are
        // collinear to a part in 10⁸): the same accuracy.
        let far: Vec<f64> = u1.iter().map(|v| v + 1e4).collect();
        let linear = identify(&[&far, &u2], &s, 0..n);
        let poly = identify_polynomial(&[&far, &u2], &s, 0..n, &linear).expect("polynomial channels at 1e4");
        let got = poly.response(0, &far, at + 1e4);
        let err = (20..n).map(|t| (got[t] - want[t]).abs()).fold(0.0, f64::max);
        assert!(err < 1e-6 * spread, "at 1e4: largest error {err} against a spread of {spread}");
        // Linearised at an input, the channel is `d(u²)/du = 2u` times G1: DC gain `2u·G1(1)`.
        // Taken at the median (where the weights of u² and u³ vanish) and at both ends of the
        // range (where they carry the slope). The law is in the class searched, so the
        // coefficients are its own up to the solver's rounding on three centred, scaled powers;
        // 1e-6 relative leaves orders of magnitude for that.
        let g1_dc = g1.dc_gain().expect("a stable channel");
        for x in [at, -0.4, 2.4] {
            let want = 2.0 * x * g1_dc;
            let got = poly.linearised(0, x + 1e4).and_then(|tf| tf.dc_gain()).expect("linearised channel");
            assert!((got - want).abs() < 1e-6 * want.abs(), "linearised DC gain at {x}: {got}, want {want}");
        }
        let linear_only: Vec<f64> = y2.iter().map(|v| 2.0 * v).collect();
        let m = identify(&[&u1, &u2], &linear_only, 0..n);
        assert!(identify_polynomial(&[&u1, &u2], &linear_only, 0..n, &m).is_none());
    }
}
