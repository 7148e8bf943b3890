//! Per output, from what the locating tests flagged to a finding. On an open-loop record
//! without a physical model (or on request in a closed loop): the grey-box structures of
//! [`crate::greybox`], each a model re-fitted whole, which also explain an open-loop output
//! nothing flagged. Otherwise (a closed loop, or a physical model): corrections added to the
//! residual of a flagged output ([`crate::select`]), chosen by their one-step prediction error in
//! a closed loop and gated by [`crate::decide`].

use crate::Progress;
use crate::candidates::Physics;
use crate::decide::decide;
use crate::fitness::fit_pct;
use crate::greybox::{self, ElementCurve};
use crate::input::{DiagnoseInput, DiagnoseOptions};
use crate::locate::Located;
use crate::plan::{Plan, instrument_ctx, scoring_ctxs};
use crate::report::Finding;
use crate::select::{self, Scoring};

/// Order of the AR noise model of a grey-box fit on a dithered record
/// ([`DiagnoseOptions::greybox_closed_loop`]): the disturbances of a plant are coloured, often
/// two-pole, and load steps need a pole near one; four poles cover both.
const CLOSED_LOOP_NOISE_ORDER: usize = 4;

/// The findings, and every output's corrected simulation and element curve.
pub(crate) struct Explained {
    /// One finding per output that was explained, in output order.
    pub findings: Vec<Finding>,
    /// Corrected simulation per output over the whole record (the nominal one where nothing was
    /// found).
    pub corrected: Vec<Vec<f64>>,
    /// Per output, the named element's map, for its figure.
    pub curves: Vec<Option<ElementCurve>>,
}

/// Explains every testable output.
pub(crate) fn explain(
    input: &DiagnoseInput<'_>,
    opts: &DiagnoseOptions,
    plan: &Plan<'_>,
    located: &Located,
    progress: &mut dyn FnMut(Progress<'_>),
) -> Explained {
    let mut findings = Vec::new();
    let mut corrected: Vec<Vec<f64>> = input.simulated.iter().map(|s| s.values.to_vec()).collect();
    let mut curves: Vec<Option<ElementCurve>> = vec![None; input.simulated.len()];
    for (cv, &j) in plan.testable.iter().enumerate() {
        let mut flagged = located.flagged(cv, input.inputs.len());
        let limits = located.limits(cv);
        let open_loop = input.excitations.is_none();
        let greybox_path =
            (open_loop || opts.greybox_closed_loop) && input.physical.get(j).copied().flatten().is_none();
        // Without dithers the MI of an input against the residual of a least-squares nominal
        // misses much of what a fit shows (the residual is orthogonal to the regressors), so
        // on the grey-box path an output nothing flagged is still explained, every input a
        // candidate; only a finding that wins out of sample is kept (below), or a correction
        // that won but was withheld, which says the model is wrong.
        let quiet = flagged.is_empty() && !limits;
        if quiet && !(greybox_path && open_loop) {
            continue;
        }
        if flagged.is_empty() {
            // Nothing flagged on the grey-box path: every input is a candidate. Or the
            // state-limit test says the residual depends on the inputs, not that a limit
            // is what it is: a wrong gain or time constant correlates with some limit's
            // correction too. So every input competes with the limits, not just the limits
            // with no correction.
            flagged = (0..input.inputs.len()).collect();
        }
        let s0 = input.simulated[j].values;
        progress(Progress::Explaining {
            output: input.outputs[j].name,
            index: cv + 1,
            of: plan.testable.len(),
        });
        let (mut finding, corrected_j, curve) = if greybox_path {
            let e = by_structures(input, opts, plan, cv, j, &flagged, open_loop);
            if quiet && e.finding.physics == Physics::Unexplained && !e.withheld {
                continue;
            }
            (e.finding, e.corrected, e.curve)
        } else {
            let (finding, c) = by_corrections(input, opts, plan, cv, j, &flagged, limits);
            let c = c.map(|c| s0.iter().zip(&c).map(|(a, b)| a + b).collect());
            (finding, c, None)
        };
        if let Some(c) = corrected_j {
            corrected[j] = c;
        }
        curves[j] = curve;
        let y = input.outputs[j].values;
        finding.fit_before_pct = fit_pct(y, s0);
        finding.fit_after_pct = fit_pct(y, &corrected[j]);
        findings.push(finding);
    }
    Explained { findings, corrected, curves }
}

/// Output `j` (testable output `cv`) explained by grey-box structures, each fitted whole.
fn by_structures(
    input: &DiagnoseInput<'_>,
    opts: &DiagnoseOptions,
    plan: &Plan<'_>,
    cv: usize,
    j: usize,
    flagged: &[usize],
    open_loop: bool,
) -> greybox::Explanation {
    let (y, s0) = (input.outputs[j].values, input.simulated[j].values);
    let noise_order = if open_loop { 0 } else { CLOSED_LOOP_NOISE_ORDER };
    let d =
        greybox::Data { u: plan.u_all.clone(), y, train: 0..plan.n_train, nominal: Some(s0), noise_order };
    let names = greybox::Names {
        inputs: input.inputs.iter().map(|u| u.name).collect(),
        output: input.outputs[j].name,
    };
    let o =
        greybox::Output { d: &d, s: s0, nominal: &plan.ctxs[cv].model, flagged, names: &names, ts: plan.ts };
    let margins = greybox::Margins {
        warmup: opts.warmup,
        min_gain: opts.min_gain_pct,
        drift_min_gain: opts.drift_min_gain_pct,
    };
    greybox::explain(&o, &plan.split.folds, &margins)
}

/// Output `j` (testable output `cv`) explained by a correction added to its residual: the
/// finding, and the correction over the whole record (`None`: none passed).
fn by_corrections(
    input: &DiagnoseInput<'_>,
    opts: &DiagnoseOptions,
    plan: &Plan<'_>,
    cv: usize,
    j: usize,
    flagged: &[usize],
    limits: bool,
) -> (Finding, Option<Vec<f64>>) {
    let ctx = &plan.ctxs[cv];
    let inst = instrument_ctx(ctx, &plan.u_driven);
    let r = &plan.residuals[j];
    let scoring = if opts.scoring == Scoring::Shifted {
        scoring_ctxs(ctx, &plan.u_all, &plan.u_driven)
    } else {
        Vec::new()
    };
    let ranked =
        select::rank(ctx, &inst, &scoring, r, flagged, limits, &plan.split, opts.penalty, opts.scoring);
    decide(ctx, &inst, r, &ranked, flagged, &plan.split, opts, plan.ts, input, j)
}
