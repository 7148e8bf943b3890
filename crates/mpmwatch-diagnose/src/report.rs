//! The diagnosis report of DESIGN.md §4.5, as serde structs.

use std::collections::BTreeMap;

use serde::{Deserialize, Serialize};

use super::candidates::{ActsOn, Physics};

/// The whole report.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct DiagnosisReport {
    /// True when the MI matrix, the projection or the state-limit test finds a significant
    /// element, or (open-loop records) a named physics improves the fit out of sample.
    pub mismatch: bool,
    /// One entry per tested input→output channel.
    pub channels: Vec<ChannelReport>,
    /// What physics was left out, per output with a flagged channel (on an open-loop record,
    /// also per output whose grey-box explanation won out of sample).
    pub findings: Vec<Finding>,
    /// FIT% on the held-out tail, before and after the correction.
    pub holdout: Holdout,
    /// How the diagnosis was made (seed, surrogates, split, penalty): for reproduction.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub settings: Option<Settings>,
    /// With a physical nominal model: the locating test of its state limits, per output
    /// ([`super::physical`]).
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub states: Vec<StateReport>,
}

/// The state-limit locating test of one output.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct StateReport {
    /// Output name.
    pub output: String,
    /// The physical model's states that were tried.
    pub states: Vec<String>,
    /// Number of limit hypotheses.
    pub hypotheses: usize,
    /// The largest fraction of the whitened residual's variance one hypothesis explains.
    pub r2: f64,
    /// Its surrogate critical value.
    pub critical: f64,
    /// Above the critical value: the limits are fitted.
    pub significant: bool,
}

/// One MV→CV channel of the MI matrix.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct ChannelReport {
    /// Input name.
    pub input: String,
    /// Output name.
    pub output: String,
    /// Norm of MI (eq 19), bits (the joint-lag norm when only that one is significant).
    pub norm_mi_bits: f64,
    /// Its critical value, bits.
    pub threshold_bits: f64,
    /// Above the critical value (norm or any lag, pairwise or joint).
    pub significant: bool,
    /// `mismatch`, `clean` or `implicated_by_feedback`.
    pub verdict: String,
    /// Whether the linear cross-correlation baseline also sees this channel (any lag beyond the
    /// family-wise, Bonferroni, limit over the lag range).
    #[serde(default)]
    pub ccf_significant: bool,
    /// The dither-projection test of this channel ([`super::projection`]): the fraction of the
    /// whitened residual's variance explained by functions of the dither.
    #[serde(default)]
    pub projection_r2: f64,
    /// Its surrogate critical value.
    #[serde(default)]
    pub projection_critical: f64,
    /// The projection test is significant: the channel is fitted even when the MI is not.
    #[serde(default)]
    pub projection_significant: bool,
}

/// One named piece of left-out physics.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Finding {
    /// Input name.
    pub input: String,
    /// Output name.
    pub output: String,
    /// The vocabulary class.
    pub physics: Physics,
    /// Where it acts.
    pub acts_on: ActsOn,
    /// One sentence for a person.
    pub summary: String,
    /// Parameters in engineering units (names say the unit: `_s` seconds; others in the units
    /// of the input or output they refer to).
    pub parameters: BTreeMap<String, f64>,
    /// FIT% of the nominal simulation over the whole record.
    pub fit_before_pct: f64,
    /// FIT% of the corrected simulation over the whole record.
    pub fit_after_pct: f64,
    /// The classes tried and their validation scores relative to the null hypothesis (lower is
    /// better), best first; for `unexplained`, the evidence that nothing fitted.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub tried: Vec<Tried>,
}

/// One class tried on a channel.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Tried {
    /// The class.
    pub physics: Physics,
    /// Its best penalised score minus the null hypothesis' (negative: better than no
    /// correction), on the path that scores residual models (closed loop, physical models);
    /// absent on the grey-box path, which measures only the validation gain.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub score_vs_null: Option<f64>,
    /// FIT% gain on held-back training data, points: the mean over the three blocks of the
    /// training part, each predicted by a fit on the other two; on the residual path over the
    /// better of the nominal and the null hypothesis (the residual's mean on those rows), on the
    /// grey-box path over the nominal, each block's FIT against the block's own mean.
    pub validation_gain_pct: f64,
}

/// Held-out comparison.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Holdout {
    /// First row of the held-out tail.
    pub start_index: usize,
    /// FIT% of the nominal simulation per output.
    pub fit_before_pct: BTreeMap<String, f64>,
    /// FIT% of the corrected simulation per output.
    pub fit_after_pct: BTreeMap<String, f64>,
    /// The inputs and outputs whose held-out values leave the range the training part visited
    /// (none: the tail stays within it).
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub beyond_training: Vec<BeyondTraining>,
}

/// A signal whose held-out tail leaves the range of its training part
/// ([`BeyondTraining::of`]). Every correction was fitted on the training range; beyond it a
/// fitted limit, polynomial or gain is extrapolated, and a held-out FIT that falls there may
/// be an extrapolation's failure rather than the correction's where it was fitted.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct BeyondTraining {
    /// Signal name.
    pub signal: String,
    /// Smallest and largest value over the training part.
    pub training: [f64; 2],
    /// Smallest and largest value over the held-out tail.
    pub holdout: [f64; 2],
    /// Share of the held-out rows outside the training range, percent.
    pub share_pct: f64,
    /// How far the farthest held-out value lies outside the training range, percent of that
    /// range's width (absent when the training part is constant: it has no width).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub excess_pct: Option<f64>,
}

/// The settings a report was made with.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Settings {
    /// Fraction of the record held out.
    pub holdout_fraction: f64,
    /// Surrogates per MI element.
    pub surrogates: usize,
    /// Seed of the surrogates.
    pub seed: u64,
    /// Lags of the MI profile.
    pub lags: [usize; 2],
    /// Penalty multiplier (1 = BIC).
    pub penalty: f64,
    /// Sample time, seconds.
    pub sample_time_s: f64,
    /// Closed-loop scoring criterion (`prediction`, `shifted` or `projected`; `none` for an
    /// open-loop record, scored by the plain validation error).
    #[serde(default)]
    pub scoring: String,
    /// The honesty gate's margin: smallest FIT gain on held-back training data, in points, for a
    /// finding to be reported (open loop, and the grey-box path in a closed loop).
    #[serde(default)]
    pub min_gain_pct: f64,
    /// The same margin for the residual corrections of a dithered closed-loop record (0 in a
    /// report written before it was recorded).
    #[serde(default)]
    pub closed_loop_min_gain_pct: f64,
    /// Open loop: what a drift term must add to the re-fitted linear model's cross-validated FIT
    /// for every structure to carry one, in points (`null`: never, or a report written
    /// before it was recorded).
    #[serde(default)]
    pub drift_min_gain_pct: Option<f64>,
    /// The MI matrix's decision rule in the locating step (`family` or `paper`; empty in a
    /// report written before the rule was recorded).
    #[serde(default)]
    pub locate: String,
    /// Under the `family` rule: the false-alarm rate per record, split evenly over its elements.
    #[serde(default)]
    pub alpha: f64,
}
