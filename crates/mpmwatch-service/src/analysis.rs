//! One analysis run on a window snapshot, and the report it produces (what `/matrix`, the zenoh
//! `matrix` key and the status page show). Synchronous and CPU-bound: the scheduler calls it in
//! the blocking pool.

use std::f64::consts::LN_2;
use std::sync::Arc;

use serde::Serialize;

use mpmwatch_core::detect::{
    self, Cell, Evidence, LagChoice, MatrixOptions, MatrixResult, Method, Signal, Verdict,
};
use mpmwatch_core::info::{Lags, MiOptions, Statistic, SurrogateOptions};

use super::config::ControllerConfig;
use super::window::{Insufficient, Snapshot};

/// Outcome of a run.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum RunStatus {
    /// Analysed.
    Ok,
    /// Not enough contiguous data: not analysed.
    InsufficientData,
    /// The estimator refused the data (e.g. a constant residual); the message says why.
    Error,
}

impl RunStatus {
    /// The metric label.
    pub fn as_str(self) -> &'static str {
        match self {
            Self::Ok => "ok",
            Self::InsufficientData => "insufficient_data",
            Self::Error => "error",
        }
    }
}

/// One channel of the matrix, in bits.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct ChannelSummary {
    /// MV tag.
    pub mv: String,
    /// Dither tag.
    pub dither: String,
    /// CV tag.
    pub cv: String,
    /// MV index.
    pub mv_index: usize,
    /// CV index.
    pub cv_index: usize,
    /// Norm of MI (eq 19), bits.
    pub norm_bits: f64,
    /// Its critical value μ + zσ, bits.
    pub critical_bits: f64,
    /// The matrix element (eq 21): the statistic when significant, else 0; bits.
    pub value_bits: f64,
    /// Significant on the norm, on one lag, or on the joint embedding.
    pub significant: bool,
    /// The statistic that decided, or the strongest when none did (`norm_mi`, `lag_mi`,
    /// `joint_mi`, `ccf`).
    pub statistic: String,
    /// Its value: bits for MI statistics, the absolute correlation for `ccf`.
    pub statistic_bits: f64,
    /// Its critical value, same units.
    pub statistic_critical_bits: f64,
    /// The lag of the deciding statistic, when significant.
    pub peak_lag: Option<usize>,
    /// The element's p-value: of the family-wise maximum, or of the norm (method `paper`).
    pub p_value: f64,
    /// `mismatch`, `clean` or `implicated_by_feedback`.
    pub verdict: String,
    /// Why, in one line.
    pub reason: String,
}

/// The result of one run.
#[derive(Debug, Clone, Serialize)]
pub struct RunReport {
    /// Controller id.
    pub controller: String,
    /// Outcome.
    pub status: RunStatus,
    /// Why it is not `ok`.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub message: Option<String>,
    /// Wall-clock time of the run, RFC 3339.
    pub time: String,
    /// Wall time the run took, seconds.
    pub duration_s: f64,
    /// Samples analysed (or available, when insufficient).
    pub n: usize,
    /// Samples needed.
    pub needed: usize,
    /// Source time of the first and last samples analysed, seconds.
    pub first_time: Option<f64>,
    /// See `first_time`.
    pub last_time: Option<f64>,
    /// Stretches without a gap analysed together (pairs never straddle a gap); 0 when not
    /// analysed.
    pub segments: usize,
    /// Any channel significant (Proposition 1).
    pub mismatch: bool,
    /// MV tags.
    pub mv: Vec<String>,
    /// Dither tags.
    pub dither: Vec<String>,
    /// CV tags.
    pub cv: Vec<String>,
    /// Surrogates per element and the σ multiplier.
    pub surrogates: usize,
    /// σ multiplier (method `paper`).
    pub sigma: f64,
    /// Decision rule.
    pub method: Method,
    /// False-alarm rate per element (method `family`).
    pub alpha: f64,
    /// Channels, row-major (cv, then mv).
    pub channels: Vec<ChannelSummary>,
    /// The full result (profiles), for `/profile`.
    #[serde(skip)]
    pub result: Option<Arc<MatrixResult>>,
}

/// The matrix options of a controller.
pub fn options(c: &ControllerConfig) -> MatrixOptions {
    MatrixOptions {
        method: c.method,
        alpha: c.alpha,
        lags: LagChoice::Fixed(Lags { min: c.lag_min, max: c.lag_max }),
        mi: MiOptions::with_k(c.k),
        surrogates: SurrogateOptions {
            count: c.surrogates,
            z: c.sigma,
            seed: c.seed,
            ..SurrogateOptions::default()
        },
        joint_embedding: c.joint_embedding,
        // Pre-whitening, partialling out the other dithers and the CCF's family-wise limits
        // keep the defaults of `analyze`, so the monitor and the offline verb agree.
        ..MatrixOptions::default()
    }
}

impl RunReport {
    fn empty(c: &ControllerConfig, status: RunStatus, time: String) -> Self {
        Self {
            controller: c.id.clone(),
            status,
            message: None,
            time,
            duration_s: 0.0,
            n: 0,
            needed: c.min_samples,
            first_time: None,
            last_time: None,
            segments: 0,
            mismatch: false,
            mv: c.mv.clone(),
            dither: c.dither.clone(),
            cv: c.cv.clone(),
            surrogates: c.surrogates,
            sigma: c.sigma,
            method: c.method,
            alpha: c.alpha,
            channels: Vec::new(),
            result: None,
        }
    }

    /// The report of a window that cannot be analysed.
    pub fn insufficient(c: &ControllerConfig, why: Insufficient, time: String) -> Self {
        Self {
            message: Some(format!(
                "{} usable samples (in stretches without a gap of at least {} samples), {} needed: not analysed",
                why.usable,
                min_segment(c),
                why.needed
            )),
            n: why.usable,
            ..Self::empty(c, RunStatus::InsufficientData, time)
        }
    }

    /// The channel of MV (or dither) tag `mv` and CV tag `cv`.
    pub fn channel(&self, mv: &str, cv: &str) -> Option<&ChannelSummary> {
        self.channels.iter().find(|ch| (ch.mv == mv || ch.dither == mv) && ch.cv == cv)
    }

    /// The detect cell behind a channel.
    pub fn cell(&self, ch: &ChannelSummary) -> Option<&Cell> {
        self.result.as_ref()?.cell(ch.mv_index, ch.cv_index)
    }
}

/// The shortest stretch without a gap worth analysing: each loses `lag_max` rows to the
/// partialling-out, up to 10 to the whitening and `lag_max` to the lags, and should keep at
/// least 16 pairs beyond that.
pub fn min_segment(c: &ControllerConfig) -> usize {
    2 * c.lag_max + 10 + 16
}

/// Analyses a snapshot. Never panics on data: estimator errors become `status: error`.
pub fn run(c: &ControllerConfig, snap: &Snapshot, time: String) -> RunReport {
    let dithers: Vec<Signal<'_>> =
        c.dither.iter().zip(&snap.dither).map(|(name, v)| Signal { name, values: v }).collect();
    let residuals: Vec<Signal<'_>> =
        c.cv.iter().zip(&snap.residual).map(|(name, v)| Signal { name, values: v }).collect();
    let base = RunReport {
        n: snap.dither.first().map_or(0, Vec::len),
        first_time: Some(snap.first_slot as f64 * c.period),
        last_time: Some(snap.last_slot as f64 * c.period),
        segments: snap.segments.len(),
        ..RunReport::empty(c, RunStatus::Ok, time)
    };
    match detect::analyze_segments(&dithers, &residuals, &snap.segments, &options(c)) {
        Ok(result) => RunReport {
            mismatch: result.mismatch,
            channels: summarise(c, &result),
            result: Some(Arc::new(result)),
            ..base
        },
        Err(e) => RunReport { status: RunStatus::Error, message: Some(e.to_string()), ..base },
    }
}

fn bits(nats: f64) -> f64 {
    nats / LN_2
}

fn verdict_name(v: Verdict) -> &'static str {
    match v {
        Verdict::Mismatch => "mismatch",
        Verdict::Clean => "clean",
        Verdict::ImplicatedByFeedback => "implicated_by_feedback",
    }
}

fn summarise(c: &ControllerConfig, r: &MatrixResult) -> Vec<ChannelSummary> {
    r.cells
        .iter()
        .map(|cell| {
            let p = &cell.pairwise;
            let ch = r.channels.iter().find(|ch| ch.mv_index == cell.mv && ch.cv_index == cell.cv);
            let d = &cell.decision;
            let (statistic, in_bits) = match d.evidence {
                Evidence::NormMi => ("norm_mi", true),
                Evidence::LagMi => ("lag_mi", true),
                Evidence::JointMi => ("joint_mi", true),
                Evidence::Ccf => ("ccf", false),
            };
            let unit = |v: f64| if in_bits { bits(v) } else { v };
            ChannelSummary {
                mv: c.mv[cell.mv].clone(),
                dither: c.dither[cell.mv].clone(),
                cv: c.cv[cell.cv].clone(),
                mv_index: cell.mv,
                cv_index: cell.cv,
                norm_bits: bits(p.norm),
                critical_bits: bits(p.threshold.critical),
                value_bits: bits(cell.value),
                significant: cell.significant,
                statistic: statistic.into(),
                statistic_bits: unit(d.value),
                statistic_critical_bits: unit(d.critical),
                peak_lag: d.significant.then_some(d.lag).flatten(),
                p_value: d.p_value,
                verdict: ch.map_or("clean", |ch| verdict_name(ch.verdict)).into(),
                reason: ch.map(|ch| ch.reason.clone()).unwrap_or_default(),
            }
        })
        .collect()
}

/// MI and critical value against lag of one channel (`/profile`), bits.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Profile {
    /// Controller id.
    pub controller: String,
    /// MV tag.
    pub mv: String,
    /// Dither tag.
    pub dither: String,
    /// CV tag.
    pub cv: String,
    /// Lags.
    pub lags: Vec<usize>,
    /// MI of dither(t) and residual(t + lag), bits.
    pub mi_bits: Vec<f64>,
    /// Per-lag surrogate critical values, bits.
    pub critical_bits: Vec<f64>,
    /// Norm of MI and its critical value, bits.
    pub norm_bits: f64,
    /// See `norm_bits`.
    pub norm_critical_bits: f64,
    /// Cross-correlation at the same lags, and its ± limit.
    pub ccf: Vec<f64>,
    /// See `ccf`.
    pub ccf_limit: f64,
    /// Under the family rule, the CCF's critical |r| per lag (its calibration surrogates'
    /// `|μ| + z*σ`, z the family's critical standardised value): what decided, rather than
    /// the Bonferroni `ccf_limit` shown beside it.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub ccf_critical: Option<Vec<f64>>,
    /// Under the family rule, the joint-lag MI and its critical values per lag, bits.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub joint_bits: Option<Vec<f64>>,
    /// See `joint_bits`.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub joint_critical_bits: Option<Vec<f64>>,
    /// The rule's p-value of the element and its alpha (family).
    pub p_value: f64,
    /// See `p_value`.
    pub alpha: Option<f64>,
    /// Time of the run.
    pub time: String,
}

/// One channel's decision in one run, for the trend (`/trend`).
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct TrendPoint {
    /// Time of the run, RFC 3339.
    pub time: String,
    /// The element's p-value.
    pub p_value: f64,
    /// Significant in that run.
    pub significant: bool,
    /// The deciding (or strongest) statistic, its value and critical value (see
    /// [`ChannelSummary`]).
    pub statistic: String,
    /// See `statistic`.
    pub value: f64,
    /// See `statistic`.
    pub critical: f64,
}

/// Every channel's trend point of an `ok` run, keyed by (MV index, CV index).
pub fn trend_points(report: &RunReport) -> Vec<((usize, usize), TrendPoint)> {
    if report.status != RunStatus::Ok {
        return Vec::new();
    }
    report
        .channels
        .iter()
        .map(|ch| {
            let point = TrendPoint {
                time: report.time.clone(),
                p_value: ch.p_value,
                significant: ch.significant,
                statistic: ch.statistic.clone(),
                value: ch.statistic_bits,
                critical: ch.statistic_critical_bits,
            };
            ((ch.mv_index, ch.cv_index), point)
        })
        .collect()
}

/// The profile of one channel of a report.
pub fn profile(report: &RunReport, ch: &ChannelSummary) -> Option<Profile> {
    let cell = report.cell(ch)?;
    let p = &cell.pairwise;
    Some(Profile {
        controller: report.controller.clone(),
        mv: ch.mv.clone(),
        dither: ch.dither.clone(),
        cv: ch.cv.clone(),
        lags: p.lags.clone(),
        mi_bits: p.profile.iter().map(|v| bits(*v)).collect(),
        critical_bits: p.lag_critical.iter().map(|v| bits(*v)).collect(),
        norm_bits: bits(p.norm),
        norm_critical_bits: bits(p.threshold.critical),
        ccf: cell.ccf.values.clone(),
        ccf_limit: cell.ccf.limit,
        ccf_critical: cell.family.as_ref().and_then(|t| {
            let c = t.profiles.iter().find(|p| p.statistic == Statistic::Ccf)?;
            Some(c.mean.iter().zip(&c.std).map(|(m, sd)| m.abs() + t.critical_z * sd).collect())
        }),
        joint_bits: cell
            .family
            .as_ref()
            .and(cell.joint.as_ref())
            .map(|j| j.profile.iter().map(|v| bits(*v)).collect()),
        joint_critical_bits: cell
            .family
            .as_ref()
            .and(cell.joint.as_ref())
            .map(|j| j.lag_critical.iter().map(|v| bits(*v)).collect()),
        p_value: cell.decision.p_value,
        alpha: cell.decision.alpha,
        time: report.time.clone(),
    })
}
