//! Diagnosis: when a simulation and the recordings differ, say where (which input→output
//! channel, from the MI matrix of excitations against residuals), what physics the model left
//! out (a fixed vocabulary, see [`Physics`]), fit it, and show the corrected simulation's FIT% on
//! a held-out tail the fit never saw. Pure and synchronous: no files, no printing.
//!
//! [`diagnose`] reads as its three steps, then builds the report:
//! 1. **plan** ([`plan`]): check the input ([`input`]), hold out the record's tail, split the
//!    training part into three cross-validation folds, decide whether the loop is closed, and
//!    identify the nominal model of every output from its simulation (noise-free, [`nominal`])
//!    so every hypothesis can be phrased against the model's own channel dynamics
//!    ([`candidates`]); with a physical model ([`PhysicalModel`], open loop only), its state
//!    limits (an overflow) and the inputs' actuator gains are hypotheses too, each the model
//!    re-run with it ([`physical`]);
//! 2. **locate** ([`locate`]): the MI matrix of the excitations against the residuals
//!    `r = y − s` on the training part (the family rule at a stated false-alarm rate per
//!    record, [`DiagnoseOptions::alpha`]), the dither-projection test ([`projection`]) and,
//!    with a physical model, the state-limit test. In a closed loop only what they flag is
//!    explained: the inputs carry the disturbance back through feedback, and the dither,
//!    independent of the disturbance, is what says a channel is wrong at all, so a
//!    disturbance-only change yields no finding;
//! 3. **explain** ([`explain`]), per output. On an open-loop record without a physical model,
//!    grey-box structures ([`greybox`]), each the nominal's re-fitted linear dynamics with one
//!    physics element, fitted by simulation error and chosen by blocked cross-validation
//!    against the best re-fitted linear model; an output nothing flagged is explained too and
//!    kept only when a finding wins out of sample. Otherwise (a closed loop, or a physical
//!    model) corrections added to the residual of a flagged output, fitted and chosen by
//!    3-fold cross-validation with a BIC penalty (in a closed loop on the one-step prediction
//!    error under an AR noise model, [`select`]); the winner must beat no correction and pass
//!    the honesty gate on its plain FIT gain ([`decide`]). The grey-box path can be asked for
//!    in a closed loop too ([`DiagnoseOptions::greybox_closed_loop`]). Every winner is
//!    refitted on the whole training part and the corrected simulation ([`simulate`]) is
//!    scored on the held-out tail.

#![warn(missing_docs)]

mod candidates;
mod decide;
mod describe;
mod error;
mod explain;
mod extrapolation;
mod fit;
mod fitness;
mod frols;
mod greybox;
mod input;
mod locate;
mod minimize;
mod nominal;
mod physical;
mod plan;
mod projection;
mod report;
mod select;
mod simulate;
mod whiten;

use std::collections::BTreeMap;

pub use candidates::{ActsOn, Physics};
pub use error::DiagnoseError;
pub use fitness::fit_pct;
pub use greybox::{ElementCurve, FittedGreyBox, GreyBox, MIN_ACTING, Reading, Structure, pinned};
pub use input::{DiagnoseInput, DiagnoseOptions};
pub use minimize::{minimize, minimize_from};
pub use mpmwatch_core::detect::Method;
pub use nominal::{NominalArx, identify as identify_nominal};
pub use physical::{LEVEL_QUANTILES, PhysicalModel};
pub use report::{
    BeyondTraining, ChannelReport, DiagnosisReport, Finding, Holdout, Settings, StateReport, Tried,
};
pub use select::Scoring;

use mpmwatch_core::detect::{MatrixResult, Signal};

/// A diagnosis: the report, the corrected simulation of every output over the whole record, and
/// the MI matrix behind the localisation.
#[derive(Debug, Clone)]
pub struct Diagnosis {
    /// The §4.5 report.
    pub report: DiagnosisReport,
    /// Corrected simulation per output (the nominal simulation where nothing was found).
    pub corrected: Vec<Vec<f64>>,
    /// The MI matrix on the training part (`None` when no output is testable: every residual
    /// is constant on the training part).
    pub matrix: Option<MatrixResult>,
    /// Per output, the named physics element's map when the grey-box step fitted one (a dead
    /// zone's input–output map, a friction force against motion), for a figure.
    pub curves: Vec<Option<ElementCurve>>,
}

/// Diagnoses signals named as `mpmwatch diagnose` names a numbered CSV pair: inputs `u1..`,
/// excitations `d1..` (by position), outputs `y1..` with their simulations, time in samples of
/// one second. The casebook and the scenario tests use it on generated closed-loop records.
pub fn diagnose_numbered(
    u: &[Vec<f64>],
    d: &[Vec<f64>],
    y: &[Vec<f64>],
    s: &[Vec<f64>],
    opts: &DiagnoseOptions,
) -> Result<Diagnosis, DiagnoseError> {
    let n = y.first().map_or(0, Vec::len);
    let time: Vec<f64> = (0..n).map(|k| k as f64).collect();
    let names =
        |prefix: &str, count: usize| -> Vec<String> { (1..=count).map(|i| format!("{prefix}{i}")).collect() };
    let (un, dn, yn) = (names("u", u.len()), names("d", d.len()), names("y", y.len()));
    fn sig<'a>(names: &'a [String], v: &'a [Vec<f64>]) -> Vec<Signal<'a>> {
        names.iter().zip(v).map(|(a, b)| Signal { name: a.as_str(), values: b.as_slice() }).collect()
    }
    let input = DiagnoseInput {
        time: &time,
        inputs: sig(&un, u),
        excitations: Some(sig(&dn, d)),
        outputs: sig(&yn, y),
        simulated: sig(&yn, s),
        physical: Vec::new(),
    };
    diagnose(&input, opts)
}

/// A stage of [`diagnose_with_progress`], reported as it starts: on a long record each can take
/// minutes, and the explaining of an output (fitting every candidate on every fold) most.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Progress<'a> {
    /// The locating tests start on the training part's `rows`.
    Locating {
        /// Training rows.
        rows: usize,
    },
    /// Output `output` is being explained, the `index`-th (from 1) of the `of` outputs tested.
    /// Only the outputs explained are told (in a closed loop, those the locating tests
    /// flagged; in open loop, every one), so an index may be skipped.
    Explaining {
        /// The output's name.
        output: &'a str,
        /// Its place among the tested outputs, from 1.
        index: usize,
        /// How many outputs are tested.
        of: usize,
    },
}

/// Runs the whole diagnosis: plan, locate, explain, and the report.
pub fn diagnose(input: &DiagnoseInput<'_>, opts: &DiagnoseOptions) -> Result<Diagnosis, DiagnoseError> {
    diagnose_with_progress(input, opts, &mut |_| {})
}

/// [`diagnose`], telling `progress` as each stage starts (the command line prints it).
pub fn diagnose_with_progress(
    input: &DiagnoseInput<'_>,
    opts: &DiagnoseOptions,
    progress: &mut dyn FnMut(Progress<'_>),
) -> Result<Diagnosis, DiagnoseError> {
    let plan = plan::plan(input, opts)?;
    progress(Progress::Locating { rows: plan.n_train });
    let located = locate::locate(input, opts, &plan)?;
    let explain::Explained { findings, corrected, curves } =
        explain::explain(input, opts, &plan, &located, progress);
    let (n_train, ts) = (plan.n_train, plan.ts);
    let mismatch = located.any();
    let locate::Located { matrix, states, channels, .. } = located;
    let mut before = BTreeMap::new();
    let mut after = BTreeMap::new();
    for (j, y) in input.outputs.iter().enumerate() {
        before
            .insert(y.name.to_string(), fit_pct(&y.values[n_train..], &input.simulated[j].values[n_train..]));
        after.insert(y.name.to_string(), fit_pct(&y.values[n_train..], &corrected[j][n_train..]));
    }
    let report = DiagnosisReport {
        mismatch: mismatch || findings.iter().any(|f| f.physics != Physics::Unexplained),
        channels,
        findings,
        holdout: Holdout {
            start_index: n_train,
            fit_before_pct: before,
            fit_after_pct: after,
            beyond_training: input
                .inputs
                .iter()
                .chain(&input.outputs)
                .filter_map(|x| BeyondTraining::of(x.name, x.values, n_train))
                .collect(),
        },
        settings: Some(Settings {
            holdout_fraction: opts.holdout_fraction,
            surrogates: opts.surrogates,
            seed: opts.seed,
            lags: [opts.lags.min, opts.lags.max],
            penalty: opts.penalty,
            sample_time_s: ts,
            scoring: match (&input.excitations, opts.scoring) {
                (None, _) => "none",
                (Some(_), Scoring::Prediction) => "prediction",
                (Some(_), Scoring::Shifted) => "shifted",
                (Some(_), Scoring::Projected) => "projected",
            }
            .to_string(),
            min_gain_pct: opts.min_gain_pct,
            closed_loop_min_gain_pct: opts.closed_loop_min_gain_pct,
            drift_min_gain_pct: opts.drift_min_gain_pct.is_finite().then_some(opts.drift_min_gain_pct),
            locate: match opts.locate {
                Method::Family => "family",
                Method::Paper => "paper",
            }
            .to_string(),
            alpha: opts.alpha,
        }),
        states,
    };
    Ok(Diagnosis { report, corrected, matrix, curves })
}
