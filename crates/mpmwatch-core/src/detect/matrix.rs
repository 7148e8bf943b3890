//! The MI matrix: for every dither i and residual j, the norm of MI over the lag range with its
//! surrogate threshold, the same for the joint embedding of two consecutive dither lags, and
//! the linear baselines (cross-correlation and Pearson) beside it.

use rayon::prelude::*;
use serde::Serialize;

use crate::info::correlation::{ccf, ccf_limit, family_wise_z, pearson};
use crate::info::significance::test_prepared;
use crate::info::{InfoError, LaggedPair, Lags, MiOptions, SurrogateOptions, Threshold, auto_tmax};

use super::partial::partial_out;
use super::verdict::{Channel, localise};
use super::whiten::ArWhitener;

/// A named series.
#[derive(Debug, Clone, Copy)]
pub struct Signal<'a> {
    /// The name shown in reports (a CSV column or tag).
    pub name: &'a str,
    /// The samples.
    pub values: &'a [f64],
}

/// How the lag range is chosen.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum LagChoice {
    /// `min..=max` for every element.
    Fixed(Lags),
    /// `1..=tmax` with tmax the first minimum of each residual's auto-MI, searched up to `max`.
    Auto {
        /// Largest tmax considered.
        max: usize,
    },
}

/// Options of the matrix.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct MatrixOptions {
    /// Lag range.
    pub lags: LagChoice,
    /// Estimator options.
    pub mi: MiOptions,
    /// Surrogate options (count, z, seed). Element (j, i) uses seed `seed + 1000·j + i` so that
    /// elements are independent and the whole matrix is reproducible from one seed.
    pub surrogates: SurrogateOptions,
    /// Also test the embedding of two consecutive dither lags (catches `u(t−1)·u(t−2)`).
    pub joint_embedding: bool,
    /// Family-wise false-alarm rate of the CCF baseline over an element's lags (Bonferroni);
    /// the Pearson limit uses the same rate for its single test. Default 0.05.
    pub ccf_alpha: f64,
    /// Before testing dither i against residual j, subtract from the residual what the other
    /// excited dithers explain linearly over lags 0..=tmax (see [`super::partial_out`]).
    pub partial_out: bool,
    /// Pre-whiten each residual with an AR model of at most this order (AIC) before every
    /// statistic, MI and CCF alike; `None` analyses the raw residuals as the paper does.
    /// See [`super::ArWhitener`] for why this keeps the test's level and raises its power.
    pub whiten: Option<usize>,
}

impl Default for MatrixOptions {
    fn default() -> Self {
        Self {
            lags: LagChoice::Fixed(Lags { min: 1, max: 20 }),
            mi: MiOptions::default(),
            surrogates: SurrogateOptions::default(),
            joint_embedding: true,
            ccf_alpha: 0.05,
            partial_out: true,
            whiten: Some(10),
        }
    }
}

/// One lagged MI test as reported: the profile against lag, per-lag critical values, the norm
/// and its threshold. Values in nats.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct ElementTest {
    /// Lags of the profile.
    pub lags: Vec<usize>,
    /// MI against lag, nats.
    pub profile: Vec<f64>,
    /// Per-lag critical values, nats.
    pub lag_critical: Vec<f64>,
    /// Norm of MI (eq 19), nats.
    pub norm: f64,
    /// Surrogate statistics of the norm.
    pub threshold: Threshold,
    /// Empirical p-value of the norm.
    pub p_value: f64,
    /// Norm above its critical value.
    pub norm_significant: bool,
    /// The lag whose MI exceeds its own critical value by the most, if any does.
    pub peak_lag: Option<usize>,
    /// Norm above its critical value, or MI above the per-lag critical value at some lag.
    pub significant: bool,
    /// Surrogate method used.
    pub method: crate::info::SurrogateMethod,
    /// Surrogate seed.
    pub seed: u64,
}

impl ElementTest {
    /// The norm of MI averages over the lag range, so an effect confined to one lag of twenty
    /// is diluted twentyfold and can stay under the norm's critical value while towering over
    /// its own lag's (measured: 0.146 nats at lag 2 against a per-lag critical value of 0.08,
    /// norm 0.032 against 0.040). The paper reads its figures the same way, by violations of
    /// the per-lag limit, so an element is significant on either count. With z = 6 the extra
    /// per-lag tests add a negligible false-alarm probability.
    fn from(t: crate::info::LaggedTest) -> Self {
        let peak_lag = t
            .profile
            .nats
            .iter()
            .zip(&t.lag_critical)
            .zip(&t.profile.lags)
            .filter(|((v, c), _)| v > c)
            .max_by(|a, b| (a.0.0 - a.0.1).total_cmp(&(b.0.0 - b.0.1)))
            .map(|(_, &lag)| lag);
        Self {
            norm_significant: t.significant,
            peak_lag,
            significant: t.significant || peak_lag.is_some(),
            lags: t.profile.lags,
            profile: t.profile.nats,
            lag_critical: t.lag_critical,
            norm: t.norm,
            threshold: t.threshold,
            p_value: t.p_value,
            method: t.method,
            seed: t.seed,
        }
    }
}

/// The linear baselines of one element.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct CcfBaseline {
    /// Lags of the CCF (the same range as the MI profile).
    pub lags: Vec<usize>,
    /// Cross-correlation of dither(t) with residual(t+τ).
    pub values: Vec<f64>,
    /// ± control limit z/√N, z family-wise over the lags (Bonferroni).
    pub limit: f64,
    /// The z of that limit.
    pub z: f64,
    /// Any |CCF| above the limit.
    pub significant: bool,
    /// Pearson r at lag 0.
    pub pearson_r: f64,
    /// Its Fisher-transform limit.
    pub pearson_limit: f64,
}

/// Element (j, i) of the matrix: dither i against residual j.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Cell {
    /// Dither (MV) index.
    pub mv: usize,
    /// Residual (CV) index.
    pub cv: usize,
    /// Pairwise lagged test.
    pub pairwise: ElementTest,
    /// Joint embedding of two consecutive dither lags, when enabled.
    pub joint: Option<ElementTest>,
    /// Linear baselines.
    pub ccf: CcfBaseline,
    /// True when the pairwise or the joint statistic exceeds its critical value.
    pub significant: bool,
    /// The element of eq 21: the pairwise norm when significant, else 0 (nats). When only the
    /// joint statistic is significant, the joint norm.
    pub value: f64,
}

/// The whole analysis.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct MatrixResult {
    /// Dither names, by MV index.
    pub dithers: Vec<String>,
    /// Residual names, by CV index.
    pub residuals: Vec<String>,
    /// Whether each dither carries any excitation (not constant).
    pub excited: Vec<bool>,
    /// Cells in row-major order (cv, then mv), excited dithers only.
    pub cells: Vec<Cell>,
    /// One verdict per tested channel.
    pub channels: Vec<Channel>,
    /// True when any element is significant (Proposition 1: ΔG ≠ 0).
    pub mismatch: bool,
    /// Sample count.
    pub n: usize,
    /// Surrogates per element.
    pub surrogates: usize,
    /// z of the MI critical values.
    pub z: f64,
    /// Base seed.
    pub seed: u64,
    /// Per residual: the whitening AR model (order 0 and ratio 1 when whitening is off).
    pub whitening: Vec<ArWhitener>,
}

impl MatrixResult {
    /// The cell of dither `mv` against residual `cv`, if that dither was excited.
    pub fn cell(&self, mv: usize, cv: usize) -> Option<&Cell> {
        self.cells.iter().find(|c| c.mv == mv && c.cv == cv)
    }
}

fn check_signals(kind: &str, s: &[Signal<'_>], n: usize) -> Result<(), InfoError> {
    if s.is_empty() {
        return Err(InfoError::InvalidParameter {
            name: "signals",
            value: kind.to_string(),
            reason: "at least one is needed",
        });
    }
    for sig in s {
        crate::info::validate::same_length(sig.name, sig.values.len(), "the first dither", n)?;
        crate::info::validate::finite(sig.name, sig.values)?;
    }
    Ok(())
}

/// Computes the MI matrix, its thresholds, the baselines and the verdicts.
pub fn analyze(
    dithers: &[Signal<'_>],
    residuals: &[Signal<'_>],
    opts: &MatrixOptions,
) -> Result<MatrixResult, InfoError> {
    let n = dithers.first().map_or(0, |d| d.values.len());
    check_signals("dithers", dithers, n)?;
    check_signals("residuals", residuals, n)?;
    for r in residuals {
        crate::info::validate::not_constant(r.name, r.values)?;
    }
    let excited: Vec<bool> =
        dithers.iter().map(|d| crate::info::validate::not_constant(d.name, d.values).is_ok()).collect();
    if !excited.iter().any(|&e| e) {
        return Err(InfoError::Constant { series: "every dither".into(), value: dithers[0].values[0] });
    }
    let whitening: Vec<ArWhitener> = residuals
        .iter()
        .map(|r| match opts.whiten {
            Some(max) => ArWhitener::fit(r.values, max),
            None => ArWhitener { coefficients: Vec::new(), variance_ratio: 1.0 },
        })
        .collect();
    // The automatic tmax reads the memory of the raw residual (Abarbanel's rule on what the
    // dither drives); whitening spreads an effect over `order` further lags, so they are added.
    let lags: Vec<Lags> = residuals
        .iter()
        .zip(&whitening)
        .map(|(r, w)| match opts.lags {
            LagChoice::Fixed(l) => Ok(l),
            LagChoice::Auto { max } => {
                Lags::new(1, (auto_tmax(r.values, max, opts.mi.k)? + w.order()).min(max))
            }
        })
        .collect::<Result<_, _>>()?;
    let pairs: Vec<(usize, usize)> = (0..residuals.len())
        .flat_map(|j| (0..dithers.len()).map(move |i| (j, i)))
        .filter(|&(_, i)| excited[i])
        .collect();
    let cells = pairs
        .par_iter()
        .map(|&(j, i)| {
            // Partial out the other dithers, then whiten what is left with an AR model fitted
            // to it (the per-residual whitener is reported; the per-element refit differs only
            // by the removed dither-driven part).
            let others: Vec<&[f64]> =
                (0..dithers.len()).filter(|&k| k != i && excited[k]).map(|k| dithers[k].values).collect();
            let cut = if opts.partial_out && !others.is_empty() { lags[j].max } else { 0 };
            let cleaned = if cut > 0 {
                partial_out(residuals[j].values, &others, cut)
            } else {
                residuals[j].values.to_vec()
            };
            let w = match opts.whiten {
                Some(max) => ArWhitener::fit(&cleaned, max),
                None => ArWhitener { coefficients: Vec::new(), variance_ratio: 1.0 },
            };
            let white = w.apply(&cleaned);
            let d = Signal { name: dithers[i].name, values: &dithers[i].values[cut + w.order()..] };
            let r = Signal { name: residuals[j].name, values: &white };
            cell(&d, &r, i, j, lags[j], opts)
        })
        .collect::<Result<Vec<_>, _>>()?;
    let channels = localise(&cells, &excited, dithers, residuals);
    Ok(MatrixResult {
        dithers: dithers.iter().map(|d| d.name.to_string()).collect(),
        residuals: residuals.iter().map(|r| r.name.to_string()).collect(),
        mismatch: cells.iter().any(|c| c.significant),
        excited,
        cells,
        channels,
        n,
        surrogates: opts.surrogates.count,
        z: opts.surrogates.z,
        seed: opts.surrogates.seed,
        whitening,
    })
}

fn cell(
    d: &Signal<'_>,
    r: &Signal<'_>,
    mv: usize,
    cv: usize,
    lags: Lags,
    opts: &MatrixOptions,
) -> Result<Cell, InfoError> {
    let sur =
        SurrogateOptions { seed: opts.surrogates.seed + 1000 * cv as u64 + mv as u64, ..opts.surrogates };
    let pair = LaggedPair::new(d.values, r.values, lags, 1, &opts.mi)?;
    let pairwise = ElementTest::from(test_prepared(&pair, &sur)?);
    let joint = if opts.joint_embedding {
        let pair2 = LaggedPair::new(d.values, r.values, lags, 2, &opts.mi)?;
        Some(ElementTest::from(test_prepared(&pair2, &SurrogateOptions { seed: sur.seed ^ 0x5eed, ..sur })?))
    } else {
        None
    };
    let ccf_values = ccf(d.values, r.values, lags.min as i64..=lags.max as i64)?;
    let z = family_wise_z(opts.ccf_alpha, lags.len());
    let limit = ccf_limit(d.values.len(), z);
    let p = pearson(d.values, r.values, family_wise_z(opts.ccf_alpha, 1))?;
    let ccf = CcfBaseline {
        lags: lags.iter().collect(),
        significant: ccf_values.iter().any(|v| v.abs() > limit),
        values: ccf_values,
        limit,
        z,
        pearson_r: p.r,
        pearson_limit: p.limit,
    };
    let joint_sig = joint.as_ref().is_some_and(|j| j.significant);
    let significant = pairwise.significant || joint_sig;
    let value = if pairwise.significant {
        pairwise.norm
    } else if joint_sig {
        joint.as_ref().map_or(0.0, |j| j.norm)
    } else {
        0.0
    };
    Ok(Cell { mv, cv, pairwise, joint, ccf, significant, value })
}
