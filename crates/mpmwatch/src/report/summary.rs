//! The flat per-channel summary printed by `analyze` and reused by diagnosis reports
//! (DESIGN.md §4.5 `channels`): names, norm of MI and threshold in bits, verdict.

use serde::Serialize;

use mpmwatch_core::detect::{Evidence, MatrixResult, Verdict};
use mpmwatch_core::info::Units;

/// One MV→CV channel, in the units of DESIGN.md §4.5.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct ChannelSummary {
    /// Dither (input) name.
    pub input: String,
    /// Residual (output) name.
    pub output: String,
    /// Pairwise norm of MI, bits.
    pub norm_mi_bits: f64,
    /// Its critical value, bits.
    pub threshold_bits: f64,
    /// Joint-lag norm and critical value, bits, when computed.
    pub joint_mi_bits: Option<f64>,
    /// Joint-lag critical value, bits.
    pub joint_threshold_bits: Option<f64>,
    /// Significant on the norm, on any lag, or jointly.
    pub significant: bool,
    /// Lag with the largest exceedance, if any.
    pub peak_lag: Option<usize>,
    /// The element's p-value (DESIGN.md §4.2): of the family-wise maximum, or of the norm
    /// under `--method paper`.
    pub p_value: f64,
    /// The statistic that decided, or the strongest when none did.
    pub evidence: Evidence,
    /// Verdict.
    pub verdict: Verdict,
    /// One-line reason.
    pub reason: String,
    /// Whether the CCF baseline crossed its limit.
    pub ccf_significant: bool,
}

/// The per-channel summary of a matrix.
pub fn summarise(m: &MatrixResult) -> Vec<ChannelSummary> {
    let bits = |v: f64| Units::Bits.from_nats(v);
    m.channels
        .iter()
        .filter_map(|ch| {
            let c = m.cell(ch.mv_index, ch.cv_index)?;
            Some(ChannelSummary {
                input: ch.mv.clone(),
                output: ch.cv.clone(),
                norm_mi_bits: bits(c.pairwise.norm),
                threshold_bits: bits(c.pairwise.threshold.critical),
                joint_mi_bits: c.joint.as_ref().map(|j| bits(j.norm)),
                joint_threshold_bits: c.joint.as_ref().map(|j| bits(j.threshold.critical)),
                significant: c.significant,
                peak_lag: c.pairwise.peak_lag.or(c.joint.as_ref().and_then(|j| j.peak_lag)),
                p_value: c.decision.p_value,
                evidence: c.decision.evidence,
                verdict: ch.verdict,
                reason: ch.reason.clone(),
                ccf_significant: c.ccf.significant,
            })
        })
        .collect()
}
