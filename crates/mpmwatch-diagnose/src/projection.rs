//! A second locating statistic beside the MI matrix: the **dither-projection test**.
//!
//! The pairwise MI of one dither lag against the residual has little power against an effect
//! that acts on the output (an |·| sensor, Coulomb friction or a spring fed back from the
//! output) or that a whole filter of dither lags drives: such an effect depends on the dither
//! through the plant's *output*, a sum over many dither lags, and each single lag carries only a
//! small share of it (measured on the casebook: none of the two friction, the two |x| sensor, the
//! output spring and the 3×3 saturation cases was flagged by the MI matrix).
//!
//! The test regresses the residual of output j on features that are functions of dither i
//! alone: dither i at lags 0..=30, and the model's response to the *dither-driven part* of
//! input i (its projection on the dithers, see [`crate::plan::dither_driven`]) raised to the second
//! and third power, before and after the channel's dynamics. The statistic is the fraction of
//! the (pre-whitened) residual's variance these features explain. Under the null hypothesis the
//! residual is independent of the dithers — in a closed loop the disturbance reaches the inputs
//! through feedback, but never the dithers — so the same statistic computed with the dithers
//! circularly shifted (every dither by the same shift, which keeps their joint structure and
//! each one's autocorrelation, and keeps the residual as it is) samples the null distribution
//! exactly; features fitted on raw inputs would not have this property. The critical value is
//! `μ + zσ` of the surrogate statistics.
//!
//! The choice of z: with p ≈ 37 features and a white residual, `n·R²` is close to χ²(p), whose
//! mean is p and standard deviation √(2p) ≈ 8.6; μ + 4σ is then χ²(37) = 71.4, exceeded with
//! probability 6·10⁻⁴, so a 3×3 plant's nine elements together raise a false alarm with
//! probability below 0.6 % (Bonferroni). The χ² is right-skewed, so the Gaussian z = 4 would
//! promise 3·10⁻⁵ per element; the χ² tail is the honest figure. The surrogates (not the χ²)
//! set μ and σ, so an imperfectly whitened residual does not break the level.
//!
//! Pure and seeded: surrogate m of element (i, j) draws its shift from ChaCha8 stream
//! `seed + 1000·j + i`, stream m.

use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use serde::Serialize;

use super::nominal::NominalArx;
use mpmwatch_core::detect::ArWhitener;
use mpmwatch_core::info::Threshold;
use mpmwatch_core::info::{draw_shift, shift_bounds};
use mpmwatch_core::numerics::{lagged as delayed, least_squares, minus_mean, r_squared};

/// Lags of the dither in the features (the same window as the dither-driven projection).
pub const LAGS: usize = 30;

/// Options of the projection test.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ProjectionOptions {
    /// Surrogates per element.
    pub surrogates: usize,
    /// z of the critical value μ + zσ (see the module documentation for why 4).
    pub z: f64,
    /// Seed of the shifts.
    pub seed: u64,
    /// Largest AR order of the whitening model.
    pub whiten: usize,
}

impl Default for ProjectionOptions {
    fn default() -> Self {
        Self { surrogates: 40, z: 4.0, seed: 1, whiten: 10 }
    }
}

/// The test of one element: dither `input` against the residual of `output`.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct ProjectionTest {
    /// Input (dither) index.
    pub input: usize,
    /// Output index (into the outputs passed in).
    pub output: usize,
    /// Fraction of the whitened residual's variance explained by the features.
    pub r2: f64,
    /// Surrogate statistics of `r2`.
    pub threshold: Threshold,
    /// `r2` above the critical value.
    pub significant: bool,
    /// Number of feature columns.
    pub features: usize,
}

/// How each input follows the dithers: least-squares coefficients on a constant and every
/// dither at lags 0..=[`LAGS`] (in the order constant, dither 0 lags, dither 1 lags, …).
#[derive(Debug, Clone, PartialEq)]
pub struct DrivenMap {
    coefs: Vec<Vec<f64>>,
}

impl DrivenMap {
    /// Fits the map of every input on `rows`. An input whose fit fails maps to its mean.
    pub fn fit(u: &[&[f64]], exc: &[&[f64]], rows: std::ops::Range<usize>) -> Self {
        let ones = vec![1.0; exc.first().map_or(0, |e| e.len())];
        let cols: Vec<Vec<f64>> = exc.iter().flat_map(|e| (0..=LAGS).map(|l| delayed(e, l))).collect();
        let mut refs: Vec<&[f64]> = vec![&ones];
        refs.extend(cols.iter().map(|c| c.as_slice()));
        let coefs = u
            .iter()
            .map(|x| {
                least_squares(&refs, x, rows.clone()).unwrap_or_else(|| {
                    let mut c = vec![0.0; refs.len()];
                    c[0] = x[rows.clone()].iter().sum::<f64>() / rows.len().max(1) as f64;
                    c
                })
            })
            .collect();
        Self { coefs }
    }

    /// The dither-driven part of input `i` given (possibly shifted) dithers.
    pub fn apply(&self, i: usize, exc: &[&[f64]]) -> Vec<f64> {
        let n = exc.first().map_or(0, |e| e.len());
        let c = &self.coefs[i];
        let mut out = vec![c[0]; n];
        for (k, e) in exc.iter().enumerate() {
            for l in 0..=LAGS {
                let b = c[1 + k * (LAGS + 1) + l];
                if b == 0.0 {
                    continue;
                }
                for t in 0..n {
                    out[t] += b * if t >= l { e[t - l] } else { e[0] };
                }
            }
        }
        out
    }
}

/// The feature columns of element (i, ·): dither `d` at lags 0..=LAGS and, when the model has the
/// channel, `G0(ud²)`, `G0(ud³)`, `s²`, `s³`, `G0(s³)` with `s = G0(ud)` (`ud` centred).
fn features(d: &[f64], ud: &[f64], model: &NominalArx, i: usize, has_channel: bool) -> Vec<Vec<f64>> {
    let mut z: Vec<Vec<f64>> = (0..=LAGS).map(|l| delayed(d, l)).collect();
    if has_channel {
        let uc = minus_mean(ud);
        let sc = minus_mean(&model.channel(i, &uc));
        let pow = |x: &[f64], p: i32| -> Vec<f64> { x.iter().map(|v| v.powi(p)).collect() };
        z.push(model.channel(i, &pow(&uc, 2)));
        z.push(model.channel(i, &pow(&uc, 3)));
        z.push(pow(&sc, 2));
        z.push(pow(&sc, 3));
        z.push(model.channel(i, &pow(&sc, 3)));
    }
    z
}

/// Runs the test on every element. `exc`, `residuals` are the training part (length n); `rows`
/// the rows analysed (after the warm-up); `models[j]`, `has_channel[j][i]` the nominal model of
/// output j and whether it has channel i.
pub fn projection_tests(
    exc: &[&[f64]],
    map: &DrivenMap,
    residuals: &[&[f64]],
    models: &[&NominalArx],
    has_channel: &[Vec<bool>],
    rows: std::ops::Range<usize>,
    opts: &ProjectionOptions,
) -> Vec<ProjectionTest> {
    let n = exc.first().map_or(0, |e| e.len());
    let start = rows.start.max(LAGS + 1);
    let end = rows.end.min(n);
    if end <= start + 200 {
        return Vec::new();
    }
    // Whitening of each residual, applied to the features alike (generalised least squares).
    let whiteners: Vec<ArWhitener> =
        residuals.iter().map(|r| ArWhitener::fit(&r[start..end], opts.whiten)).collect();
    let white_r: Vec<Vec<f64>> =
        residuals.iter().zip(&whiteners).map(|(r, w)| w.apply(&r[start..end])).collect();
    let stat = |exc_s: &[&[f64]], i: usize, j: usize| -> (f64, usize) {
        let ud = map.apply(i, exc_s);
        let cols: Vec<Vec<f64>> = features(exc_s[i], &ud, models[j], i, has_channel[j][i])
            .into_iter()
            .map(|c| whiteners[j].apply(&c[start..end]))
            .collect();
        (r_squared(&white_r[j], &cols), cols.len())
    };
    let bounds = shift_bounds(n, LAGS, 1).ok();
    let mut out = Vec::new();
    for j in 0..residuals.len() {
        for i in 0..exc.len() {
            if mpmwatch_core::info::not_constant("dither", exc[i]).is_err() {
                continue;
            }
            let (r2, p) = stat(exc, i, j);
            let Some(b) = bounds else { continue };
            let mut rng = ChaCha8Rng::seed_from_u64(opts.seed + 1000 * j as u64 + i as u64);
            let sur: Vec<f64> = (0..opts.surrogates)
                .map(|_| {
                    let s = draw_shift(exc[i], b, &mut rng);
                    let shifted: Vec<Vec<f64>> =
                        exc.iter().map(|e| (0..n).map(|t| e[(t + s) % n]).collect()).collect();
                    let refs: Vec<&[f64]> = shifted.iter().map(|v| v.as_slice()).collect();
                    stat(&refs, i, j).0
                })
                .collect();
            let threshold = Threshold::of(&sur, opts.z);
            out.push(ProjectionTest {
                input: i,
                output: j,
                r2,
                significant: r2 > threshold.critical,
                threshold,
                features: p,
            });
        }
    }
    out
}
