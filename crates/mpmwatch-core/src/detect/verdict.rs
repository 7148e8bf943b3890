//! Localisation (paper §3.4): from the zero pattern of the MI matrix to a verdict per channel.
//!
//! * Proposition 1: a non-zero matrix means ΔG ≠ 0.
//! * Proposition 2: an all-zero column i means MV i's submodels are right.
//! * Proposition 3: an all-zero row j means CV j's submodels are right.
//! * Proposition 4: with only MV i excited (the others held constant), a non-zero (j, i) means
//!   Δg_ji ≠ 0.
//!
//! Feedback can make an element non-zero although its own submodel is right: dither i reaches
//! a wrong channel (j', i), the controller reacts to residual j', and its moves reach residual
//! j through another wrong submodel (j, k). That path needs another significant element in
//! column i *and* another in row j. When both exist, the element is only
//! `implicated_by_feedback`; when either is missing, feedback cannot explain it and it is a
//! `mismatch`.

use serde::Serialize;

use super::matrix::{Cell, Signal};

/// Verdict on one MV→CV channel.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Verdict {
    /// The submodel is wrong.
    Mismatch,
    /// No evidence against the submodel.
    Clean,
    /// Significant, but the information may have travelled through the controller from other
    /// wrong channels; re-test with only this MV excited (Proposition 4) to decide.
    ImplicatedByFeedback,
}

/// The verdict on one channel with its one-line reason.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Channel {
    /// Dither (MV) name.
    pub mv: String,
    /// Residual (CV) name.
    pub cv: String,
    /// MV index.
    pub mv_index: usize,
    /// CV index.
    pub cv_index: usize,
    /// The verdict.
    pub verdict: Verdict,
    /// Why, in one line.
    pub reason: String,
}

/// Applies Propositions 1–4 to the cells.
pub fn localise(
    cells: &[Cell],
    excited: &[bool],
    dithers: &[Signal<'_>],
    residuals: &[Signal<'_>],
) -> Vec<Channel> {
    let n_excited = excited.iter().filter(|&&e| e).count();
    let sig = |mv: usize, cv: usize| cells.iter().any(|c| c.mv == mv && c.cv == cv && c.significant);
    cells
        .iter()
        .map(|c| {
            let (i, j) = (c.mv, c.cv);
            let (mv, cv) = (dithers[i].name, residuals[j].name);
            let col_others: Vec<&str> =
                (0..residuals.len()).filter(|&jj| jj != j && sig(i, jj)).map(|jj| residuals[jj].name).collect();
            let row_others: Vec<&str> =
                (0..dithers.len()).filter(|&ii| ii != i && sig(ii, j)).map(|ii| dithers[ii].name).collect();
            let stat = match (c.decision.evidence, c.decision.lag) {
                (super::Evidence::NormMi, _) => "norm of MI".to_string(),
                (super::Evidence::LagMi, Some(l)) => format!("MI at lag {l}"),
                (super::Evidence::JointMi, Some(l)) => format!("joint-lag MI at lags {l}, {}", l + 1),
                (super::Evidence::Ccf, Some(l)) => format!("cross-correlation at lag {l}"),
                (e, None) => format!("{e:?}"),
            };
            let stat = match c.decision.alpha {
                Some(a) => format!("{stat} (p = {:.2e}, alpha {a})", c.decision.p_value),
                None => stat,
            };
            let (verdict, reason) = if !c.significant {
                let why = if col_others.is_empty() {
                    format!("no residual carries information about {mv} (Proposition 2)")
                } else if row_others.is_empty() {
                    format!("{cv} carries information about no dither (Proposition 3)")
                } else {
                    format!("MI of {mv} and {cv} stays below its surrogate critical value")
                };
                (Verdict::Clean, why)
            } else if n_excited == 1 {
                (
                    Verdict::Mismatch,
                    format!("{mv} is the only excited MV and {cv} carries its information (Proposition 4)"),
                )
            } else if !col_others.is_empty() && !row_others.is_empty() {
                (
                    Verdict::ImplicatedByFeedback,
                    format!(
                        "significant, but {mv} also reaches {} and {cv} is also reached by {}: the information may \
                         come through the controller; excite {mv} alone to decide",
                        col_others.join(", "),
                        row_others.join(", ")
                    ),
                )
            } else {
                (
                    Verdict::Mismatch,
                    format!(
                        "{stat} above its critical value and no feedback path explains it (no other {})",
                        if col_others.is_empty() { format!("residual reached by {mv}") } else { format!("dither reaching {cv}") }
                    ),
                )
            };
            Channel { mv: mv.to_string(), cv: cv.to_string(), mv_index: i, cv_index: j, verdict, reason }
        })
        .collect()
}
