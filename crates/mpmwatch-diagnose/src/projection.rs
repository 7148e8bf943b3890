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
//! and third power, before and after the channel's dynamics, and to its product with its own
//! previous sample before them (see [`features`]). The statistic is the fraction of
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
//! probability 6·10⁻⁴, which promised a 3×3 plant's nine elements together a false alarm below
//! 0.6 % (the Gaussian z = 4 would promise 3·10⁻⁵ per element; the χ² is right-skewed). The
//! surrogates (not the χ²) set μ and σ, so an imperfectly whitened residual does not break the
//! level; but 40 surrogates estimate them with an error that raises it. Measured
//! (`projection_null_study`, figures in docs/diagnose.md): about twice to three times the χ²
//! figure per element, so over a 3×3 plant's nine elements about 1 to 2 % per record.
//!
//! Pure and seeded: the m-th surrogate of element (i, j) takes the m-th shift drawn from
//! ChaCha8 seeded with `seed + 1000·j + i`.

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
/// channel, `G0(ud²)`, `G0(ud·ud(t−1))`, `G0(ud³)`, `s²`, `s³`, `G0(s³)` with `s = G0(ud)` (`ud`
/// centred). The square and the lag-one product are the diagonal and the first off-diagonal of a
/// second-order Volterra kernel in front of the channel: a product of the input at two
/// neighbouring instants (a bilinear term) is uncorrelated with every single dither lag and,
/// where the dither-driven part is white (an independent dither through a fast loop), with the
/// square too: in general only a column of its own carries it.
fn features(d: &[f64], ud: &[f64], model: &NominalArx, i: usize, has_channel: bool) -> Vec<Vec<f64>> {
    let mut z: Vec<Vec<f64>> = (0..=LAGS).map(|l| delayed(d, l)).collect();
    if has_channel {
        let uc = minus_mean(ud);
        let sc = minus_mean(&model.channel(i, &uc));
        let pow = |x: &[f64], p: i32| -> Vec<f64> { x.iter().map(|v| v.powi(p)).collect() };
        z.push(model.channel(i, &pow(&uc, 2)));
        let product: Vec<f64> = uc.iter().zip(delayed(&uc, 1)).map(|(a, b)| a * b).collect();
        z.push(model.channel(i, &product));
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

#[cfg(test)]
mod tests {
    use super::*;
    use mpmwatch_core::model::Arx;
    use rand::Rng;
    use rand_distr::{Distribution, StandardNormal};

    /// A first-order channel of unit gain and pole 0.8, the nominal of every element here.
    fn first_order() -> NominalArx {
        let arx = Arx::new(vec![1.0, -0.8], vec![vec![0.2]], vec![0]).unwrap();
        NominalArx { arx, fit_pct: 100.0, score: 0.0 }
    }

    /// One element on `n` rows from `seed`: a dither (binary and held 1–4 samples, or uniform),
    /// a residual `effect(ud) + v` with `v` a slow AR(2) disturbance (poles 0.97 and 0.6,
    /// innovation 0.3) independent of the dither, and an input that is the dither plus moves
    /// the dither does not drive: coloured noise and, with `feedback`, a proportional answer to
    /// the last disturbance (as a controller's moves carry the disturbance into the input that
    /// the driven map is fitted on). The data's generator is seeded apart from the surrogates'
    /// shifts. Returns the element's test.
    fn element(
        n: usize,
        seed: u64,
        feedback: bool,
        effect: impl Fn(&NominalArx, &[f64]) -> Vec<f64>,
    ) -> ProjectionTest {
        let mut rng = ChaCha8Rng::seed_from_u64(seed ^ (1 << 40));
        let binary = seed.is_multiple_of(2);
        let mut d = Vec::with_capacity(n);
        while d.len() < n {
            let level = if binary {
                if rng.random::<bool>() { 1.0 } else { -1.0 }
            } else {
                rng.random_range(-1.0..1.0)
            };
            let hold = if binary { rng.random_range(1..=4) } else { 1 };
            d.extend(std::iter::repeat_n(level, hold));
        }
        d.truncate(n);
        let mut gauss = || -> f64 { StandardNormal.sample(&mut rng) };
        let (mut v1, mut v2) = (0.0, 0.0);
        let v: Vec<f64> = (0..n)
            .map(|_| {
                let next = 1.57 * v1 - 0.582 * v2 + 0.3 * gauss();
                v2 = v1;
                v1 = next;
                next
            })
            .collect();
        let gain = if feedback { 0.5 } else { 0.0 };
        let mut m = 0.0;
        let u: Vec<f64> = (0..n)
            .map(|t| {
                m = 0.9 * m + 0.3 * gauss();
                d[t] + m - gain * if t > 0 { v[t - 1] } else { 0.0 }
            })
            .collect();
        let model = first_order();
        let map = DrivenMap::fit(&[&u], &[&d], 0..n);
        let ud = map.apply(0, &[&d]);
        let r: Vec<f64> = effect(&model, &ud).iter().zip(&v).map(|(a, b)| a + b).collect();
        let opts = ProjectionOptions { seed, ..ProjectionOptions::default() };
        let t = projection_tests(&[&d], &map, &[&r], &[&model], &[vec![true]], 0..n, &opts);
        t.into_iter().next().expect("one element tested")
    }

    fn no_effect(_: &NominalArx, ud: &[f64]) -> Vec<f64> {
        vec![0.0; ud.len()]
    }

    /// How many of `count` independent null elements (seeds `seed..seed + count`) the test flags.
    fn null_alarms(n: usize, seed: u64, count: u64, feedback: bool) -> usize {
        (seed..seed + count).filter(|&s| element(n, s, feedback, no_effect).significant).count()
    }

    /// The level on residuals that share nothing with the dither: a slow AR(2) disturbance,
    /// binary and uniform dithers, 1500 rows, thirty elements without feedback and thirty with.
    /// At the measured level, 0.1 to 0.2 % per element (docs/diagnose.md; the release study
    /// below: `PROJ_COUNT=4000 cargo test --release -p mpmwatch-diagnose --lib
    /// projection_null_study -- --ignored --nocapture`), three alarms in sixty have probability
    /// under 3·10⁻⁴; at 5 % per element, a test far off its level, 58 %. A coarse guard in the
    /// suite; the figure is the study's.
    #[test]
    fn the_projection_test_holds_its_level_on_a_residual_the_dither_does_not_reach() {
        let alarms = null_alarms(1500, 1, 30, false) + null_alarms(1500, 31, 30, true);
        assert!(alarms <= 2, "{alarms} of 60 null elements flagged");
    }

    /// The same null, many elements, without and with feedback, for the level's figure.
    #[test]
    #[ignore]
    fn projection_null_study() {
        let count: u64 = std::env::var("PROJ_COUNT").ok().and_then(|v| v.parse().ok()).unwrap_or(4000);
        let n: usize = std::env::var("PROJ_N").ok().and_then(|v| v.parse().ok()).unwrap_or(1500);
        for feedback in [false, true] {
            let seed = if feedback { 2_000_000 } else { 1_000_000 };
            let alarms = null_alarms(n, seed, count, feedback);
            eprintln!(
                "feedback {feedback}: {alarms} of {count} null elements flagged at {n} rows (seeds {seed}..{})",
                seed + count
            );
        }
    }

    /// Power: a square law after the channel (a sensor's bend), `(G0 ud)²` centred and scaled to
    /// half the disturbance's innovation (0.15 against 0.3), which no dither lag carries
    /// linearly. The whitening filter, fitted to the slow disturbance, passes a slow effect
    /// less than the innovation: it explains a tenth to a fifth of the whitened residual, two to
    /// five times the null's critical value near 0.05 at these 1500 rows. (The effect is one
    /// of the test's own features: this checks that the test can fire, not its reach.)
    #[test]
    fn the_projection_test_finds_a_square_law_after_the_channel() {
        let square = |m: &NominalArx, ud: &[f64]| -> Vec<f64> {
            let s = minus_mean(&m.channel(0, &minus_mean(ud)));
            let sq = minus_mean(&s.iter().map(|x| x * x).collect::<Vec<_>>());
            let sd = (sq.iter().map(|x| x * x).sum::<f64>() / sq.len() as f64).sqrt();
            sq.iter().map(|x| 0.15 * x / sd).collect()
        };
        for seed in 1..=4 {
            let t = element(1500, seed, false, square);
            assert!(t.significant, "seed {seed}: R² {} against {}", t.r2, t.threshold.critical);
        }
    }

    /// Power against a bilinear term in front of the channel, `G0(ud(t)·ud(t−1))` centred and
    /// scaled as the square law above (0.15 against the innovation's 0.3), with feedback. Its
    /// R² at seeds 1–4 is 0.08 to 0.14 against critical values near 0.045; with the product's
    /// column removed from the features (checked once, by hand) seeds 1–3 gave 0.055, 0.091 and
    /// 0.044, seed 3 below its critical value, so the seeds tell the two feature sets apart. Like the
    /// square law, one of the test's features: this checks that the column works.
    #[test]
    fn the_projection_test_finds_a_product_of_neighbouring_inputs() {
        let product = |m: &NominalArx, ud: &[f64]| -> Vec<f64> {
            let uc = minus_mean(ud);
            let p: Vec<f64> = uc.iter().zip(delayed(&uc, 1)).map(|(a, b)| a * b).collect();
            let s = minus_mean(&m.channel(0, &p));
            let sd = (s.iter().map(|x| x * x).sum::<f64>() / s.len() as f64).sqrt();
            s.iter().map(|x| 0.15 * x / sd).collect()
        };
        for seed in 1..=4 {
            let t = element(1500, seed, true, product);
            assert!(t.significant, "seed {seed}: R² {} against {}", t.r2, t.threshold.critical);
        }
    }
}
