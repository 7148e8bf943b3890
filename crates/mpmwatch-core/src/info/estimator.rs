//! The public mutual-information entry points: input checks, choice between the continuous
//! (KSG1) and discrete-X (Ross) paths, units.

use serde::Serialize;

use super::discrete::{Levels, ross};
use super::ksg::{MAX_X_DIM, ksg1};
use super::{InfoError, validate};

/// How to treat X.
#[derive(
    Debug, Clone, Copy, PartialEq, Eq, Serialize, strum::EnumString, strum::Display, strum::VariantNames,
)]
#[serde(rename_all = "snake_case")]
#[strum(serialize_all = "snake_case")]
pub enum XKind {
    /// Discrete when X has few distinct values (see [`MiOptions::max_levels`]), else continuous.
    Auto,
    /// Always the continuous KSG1 estimator.
    Continuous,
    /// Always the discrete-X (Ross) estimator; fails if X has more than `max_levels` values.
    Discrete,
}

/// Which estimator produced a number.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Estimator {
    /// KSG algorithm 1, max-norm, kd-tree joint search.
    Ksg1,
    /// Ross (2014): KSG1 specialised to a discrete X.
    Ross,
}

/// Units of an information quantity. Estimators work in nats; the paper reports bits.
#[derive(
    Debug,
    Clone,
    Copy,
    PartialEq,
    Eq,
    Default,
    Serialize,
    strum::EnumString,
    strum::Display,
    strum::VariantNames,
)]
#[serde(rename_all = "snake_case")]
#[strum(serialize_all = "snake_case")]
pub enum Units {
    /// Natural logarithm.
    #[default]
    Nats,
    /// Base-2 logarithm, as in the paper.
    Bits,
}

impl Units {
    /// Converts a value in nats to these units.
    pub fn from_nats(self, nats: f64) -> f64 {
        match self {
            Units::Nats => nats,
            Units::Bits => nats / std::f64::consts::LN_2,
        }
    }
}

/// Options of a single mutual-information estimate.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct MiOptions {
    /// Number of nearest neighbours. Kraskov et al. recommend 2–4; larger k lowers variance and
    /// raises bias. Default 4.
    pub k: usize,
    /// How to treat X.
    pub x_kind: XKind,
    /// In `Auto` mode, X is discrete when it has at most this many distinct values and at
    /// least 2(k + 1) samples per level on average. Default 16 (a multilevel PRBS has a few).
    pub max_levels: usize,
    /// Divide continuous variables by their standard deviation before the KSG1 search, as
    /// scikit-learn's `mutual_info_regression` does. The max-norm joint neighbourhood depends
    /// on the relative scale of X and Y at finite N, and a dither in % against a residual in
    /// engineering units would otherwise bias the estimate. Default true. The discrete-X path
    /// is scale-free and ignores this.
    pub standardize: bool,
}

impl Default for MiOptions {
    fn default() -> Self {
        Self { k: 4, x_kind: XKind::Auto, max_levels: 16, standardize: true }
    }
}

impl MiOptions {
    /// Options with `k` neighbours and the other fields at their defaults.
    pub fn with_k(k: usize) -> Self {
        Self { k, ..Self::default() }
    }

    /// The levels of `x` if this configuration treats it as discrete. Errors when the caller
    /// forced `Discrete` on a series with too many levels.
    pub fn discrete_levels(&self, x: &[f64]) -> Result<Option<Levels>, InfoError> {
        match self.x_kind {
            XKind::Continuous => Ok(None),
            XKind::Discrete => match Levels::of(x, self.max_levels) {
                Some(l) => Ok(Some(l)),
                None => Err(InfoError::TooManyLevels {
                    series: "x".into(),
                    levels: count_distinct(x),
                    max: self.max_levels,
                }),
            },
            XKind::Auto => {
                let cap = self.max_levels.min(x.len() / (2 * (self.k + 1))).max(2);
                Ok(Levels::of(x, cap))
            }
        }
    }
}

fn count_distinct(x: &[f64]) -> usize {
    let mut v = x.to_vec();
    v.sort_unstable_by(f64::total_cmp);
    v.dedup();
    v.len()
}

/// One estimate of I(X; Y).
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct MiEstimate {
    /// The estimate in nats. May be slightly negative under independence; never clipped, so
    /// surrogate statistics stay unbiased.
    pub nats: f64,
    /// Number of sample pairs used.
    pub n: usize,
    /// The estimator used.
    pub estimator: Estimator,
}

/// Estimates I(X; Y) in nats for paired samples, choosing the discrete-X path when X has few
/// levels (a PRBS dither) and KSG1 otherwise.
///
/// ```
/// use mpmwatch_core::info::{mutual_information, MiOptions};
/// let x: Vec<f64> = (0..500).map(|i| (i as f64 * 0.37).sin()).collect();
/// let y: Vec<f64> = x.iter().enumerate().map(|(i, v)| v + 0.1 * (i as f64 * 1.3).cos()).collect();
/// let est = mutual_information(&x, &y, &MiOptions::default()).unwrap();
/// assert!(est.nats > 1.0);
/// ```
pub fn mutual_information(x: &[f64], y: &[f64], opts: &MiOptions) -> Result<MiEstimate, InfoError> {
    validate::pair(x, y, opts.k)?;
    Ok(match opts.discrete_levels(x)? {
        Some(levels) => MiEstimate { nats: ross(&levels, y, opts.k), n: x.len(), estimator: Estimator::Ross },
        None => {
            let (xs, ys) = (scaled(x, opts.standardize), scaled(y, opts.standardize));
            MiEstimate { nats: ksg1(&[&xs], &ys, opts.k), n: x.len(), estimator: Estimator::Ksg1 }
        }
    })
}

/// The standard deviation of `v`, computed on `v / max|v|` so that neither squares of huge
/// values overflow nor squares of tiny ones underflow; `None` when it is zero or not finite.
pub(crate) fn robust_std(v: &[f64]) -> Option<f64> {
    let m = v.iter().fold(0.0f64, |a, x| a.max(x.abs()));
    if !(m > 0.0 && m.is_finite()) {
        return None;
    }
    let n = v.len() as f64;
    let mean = v.iter().map(|x| x / m).sum::<f64>() / n;
    let sd = (v.iter().map(|x| (x / m - mean).powi(2)).sum::<f64>() / n).sqrt();
    (sd > 0.0).then_some(sd * m).filter(|s| s.is_finite() && *s > 0.0)
}

/// `v` divided by its (population) standard deviation when `on`; `v` itself otherwise.
pub(crate) fn scaled(v: &[f64], on: bool) -> std::borrow::Cow<'_, [f64]> {
    match robust_std(v).filter(|_| on) {
        Some(sd) => std::borrow::Cow::Owned(v.iter().map(|a| a / sd).collect()),
        None => std::borrow::Cow::Borrowed(v),
    }
}

/// KSG1 estimate in nats of I(X; Y) for a multivariate continuous X given as columns (at most
/// 4), e.g. a dither at two consecutive lags. Columns are standardised when `standardize`.
pub fn mutual_information_multi(
    x: &[&[f64]],
    y: &[f64],
    k: usize,
    standardize: bool,
) -> Result<f64, InfoError> {
    if x.is_empty() || x.len() > MAX_X_DIM {
        return Err(InfoError::InvalidParameter {
            name: "x columns",
            value: x.len().to_string(),
            reason: "X must have between 1 and 4 columns",
        });
    }
    validate::neighbours("mutual information", y.len(), k)?;
    validate::finite("y", y)?;
    validate::not_constant("y", y)?;
    for (d, col) in x.iter().enumerate() {
        let name = format!("x[{d}]");
        validate::same_length(&name, col.len(), "y", y.len())?;
        validate::finite(&name, col)?;
    }
    if x.iter().all(|c| validate::not_constant("x", c).is_err()) {
        return Err(InfoError::Constant { series: "x".into(), value: x[0][0] });
    }
    let xs: Vec<_> = x.iter().map(|c| scaled(c, standardize)).collect();
    let cols: Vec<&[f64]> = xs.iter().map(|c| c.as_ref()).collect();
    Ok(ksg1(&cols, &scaled(y, standardize), k))
}
