//! Significance of a lagged MI statistic by surrogate data (paper §2.2, eq 11).
//!
//! Under the null hypothesis the dither and the residual are independent. Surrogates of the
//! dither destroy any coupling while keeping its own structure: circular shifts for a discrete
//! dither (iAAFT cannot reproduce a binary series), iAAFT for a continuous one. The statistic
//! of each surrogate gives a mean μ and standard deviation σ; the critical value is μ + zσ with
//! z = 6 by default (the paper's robust choice), and an empirical p-value
//! `(1 + #{I_s ≥ I}) / (M + 1)` is reported beside it.
//!
//! Surrogates run in parallel with rayon. Surrogate m draws from its own ChaCha8 stream
//! `(seed, stream m)`, so the result does not depend on the number of threads.

use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use rayon::prelude::*;
use serde::Serialize;

use super::InfoError;
use super::estimator::MiOptions;
use super::lagged::{LaggedPair, LaggedProfile, Lags, norm_of};
use super::surrogate::{Iaaft, IaaftOptions, draw_shift, end_matched_range, shift_bounds};

/// How surrogates of the dither are made.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum SurrogateMethod {
    /// Circular shifts for a discrete dither, iAAFT for a continuous one.
    Auto,
    /// Random circular shifts (away from zero lag).
    CircularShift,
    /// iAAFT (amplitude distribution and spectrum kept).
    Iaaft,
}

/// Options of the surrogate test.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SurrogateOptions {
    /// Number of surrogates M. Default 100.
    pub count: usize,
    /// Multiplier z of σ in the critical value. Default 6 (eq 11).
    pub z: f64,
    /// Seed of the surrogate streams; report it with the result.
    pub seed: u64,
    /// How surrogates are made.
    pub method: SurrogateMethod,
    /// iAAFT iteration settings.
    pub iaaft: IaaftOptions,
}

impl Default for SurrogateOptions {
    fn default() -> Self {
        Self { count: 100, z: 6.0, seed: 0, method: SurrogateMethod::Auto, iaaft: IaaftOptions::default() }
    }
}

/// Summary of a surrogate distribution against an observed statistic.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct Threshold {
    /// Surrogate mean μ.
    pub mean: f64,
    /// Surrogate standard deviation σ (n − 1 denominator).
    pub std: f64,
    /// Critical value μ + zσ.
    pub critical: f64,
}

impl Threshold {
    /// μ, σ and μ + zσ of a sample of surrogate statistics (at least 2).
    pub fn of(samples: &[f64], z: f64) -> Self {
        let m = samples.len() as f64;
        let mean = samples.iter().sum::<f64>() / m;
        let var = samples.iter().map(|s| (s - mean).powi(2)).sum::<f64>() / (m - 1.0);
        let std = var.sqrt();
        Self { mean, std, critical: mean + z * std }
    }
}

/// Empirical p-value of `observed` against surrogate statistics, `(1 + #{s ≥ observed}) / (M + 1)`.
pub fn empirical_p_value(observed: f64, surrogates: &[f64]) -> f64 {
    let above = surrogates.iter().filter(|&&s| s >= observed).count();
    (1 + above) as f64 / (surrogates.len() + 1) as f64
}

/// The result of a lagged surrogate test for one (dither, residual) pair.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct LaggedTest {
    /// The observed MI against lag.
    pub profile: LaggedProfile,
    /// Per-lag critical values μ_τ + zσ_τ, for plotting beside the profile.
    pub lag_critical: Vec<f64>,
    /// The norm of MI (eq 19), nats.
    pub norm: f64,
    /// Surrogate statistics of the norm.
    pub threshold: Threshold,
    /// Empirical p-value of the norm.
    pub p_value: f64,
    /// True when the norm exceeds its critical value.
    pub significant: bool,
    /// The surrogate norms, in surrogate order.
    pub surrogate_norms: Vec<f64>,
    /// The method actually used.
    pub method: SurrogateMethod,
    /// The seed used.
    pub seed: u64,
    /// The largest iAAFT spectral error among the surrogates (iAAFT only).
    pub worst_spectral_error: Option<f64>,
    /// The sample range analysed (the whole record unless iAAFT end matching trimmed it).
    pub analysed: std::ops::Range<usize>,
}

/// Lagged MI profile of (x, y), its norm, and their surrogate thresholds.
///
/// When the surrogates are iAAFT, both series are first cut to the end-matched range of x
/// ([`end_matched_range`], at most a tenth trimmed) and `analysed` says which range that was.
pub fn lagged_test(
    x: &[f64],
    y: &[f64],
    lags: Lags,
    width: usize,
    mi: &MiOptions,
    sur: &SurrogateOptions,
) -> Result<LaggedTest, InfoError> {
    let pair = LaggedPair::new(x, y, lags, width, mi)?;
    let iaaft = match sur.method {
        SurrogateMethod::Auto => !pair.is_discrete(),
        m => m == SurrogateMethod::Iaaft,
    };
    if !iaaft {
        return test_prepared(&pair, sur);
    }
    let range = end_matched_range(x, 0.1);
    let pair = LaggedPair::new(&x[range.clone()], &y[range.clone()], lags, width, mi)?;
    let mut test = test_prepared(&pair, sur)?;
    test.analysed = range;
    Ok(test)
}

/// [`lagged_test`] on an already prepared pair.
pub fn test_prepared(pair: &LaggedPair<'_>, sur: &SurrogateOptions) -> Result<LaggedTest, InfoError> {
    if sur.count < 2 {
        return Err(InfoError::InvalidParameter {
            name: "surrogates",
            value: sur.count.to_string(),
            reason: "at least 2 surrogates are needed for a standard deviation",
        });
    }
    if !(sur.z.is_finite() && sur.z > 0.0) {
        return Err(InfoError::InvalidParameter {
            name: "z",
            value: sur.z.to_string(),
            reason: "must be positive",
        });
    }
    let method = match sur.method {
        SurrogateMethod::Auto if pair.is_discrete() => SurrogateMethod::CircularShift,
        SurrogateMethod::Auto => SurrogateMethod::Iaaft,
        m => m,
    };
    let profile = pair.profile();
    let x = pair.x();
    let (profiles, errors): (Vec<Vec<f64>>, Vec<f64>) = match method {
        SurrogateMethod::CircularShift => {
            let bounds = shift_bounds(pair.len(), pair.lags().max, profile.embedding)?;
            (0..sur.count)
                .into_par_iter()
                .map(|m| {
                    let mut rng = stream(sur.seed, m);
                    let s = draw_shift(x, bounds, &mut rng);
                    (pair.profile_shifted(s), 0.0)
                })
                .unzip()
        }
        SurrogateMethod::Iaaft => {
            if pair.is_discrete() {
                return Err(InfoError::InvalidParameter {
                    name: "surrogate method",
                    value: "iaaft".into(),
                    reason: "iAAFT does not converge on a discrete dither; use circular shifts",
                });
            }
            let generator = Iaaft::new(x, sur.iaaft)?;
            (0..sur.count)
                .into_par_iter()
                .map(|m| {
                    let mut rng = stream(sur.seed, m);
                    let (xs, rep) = generator.generate(&mut rng);
                    (pair.profile_with_x(&xs), rep.spectral_error)
                })
                .unzip()
        }
        SurrogateMethod::Auto => unreachable!("resolved above"),
    };
    let surrogate_norms: Vec<f64> = profiles.iter().map(|p| norm_of(p)).collect();
    let lag_critical = (0..profile.lags.len())
        .map(|l| {
            let col: Vec<f64> = profiles.iter().map(|p| p[l]).collect();
            Threshold::of(&col, sur.z).critical
        })
        .collect();
    let norm = profile.norm();
    let threshold = Threshold::of(&surrogate_norms, sur.z);
    let worst = (method == SurrogateMethod::Iaaft).then(|| errors.iter().cloned().fold(0.0, f64::max));
    Ok(LaggedTest {
        lag_critical,
        norm,
        p_value: empirical_p_value(norm, &surrogate_norms),
        significant: norm > threshold.critical,
        threshold,
        surrogate_norms,
        method,
        seed: sur.seed,
        worst_spectral_error: worst,
        analysed: 0..pair.len(),
        profile,
    })
}

/// The RNG of surrogate `m`: an independent ChaCha stream per surrogate.
pub fn stream(seed: u64, m: usize) -> ChaCha8Rng {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    rng.set_stream(m as u64);
    rng
}
