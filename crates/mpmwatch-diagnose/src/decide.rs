//! The residual-correction path's decision for one output: the best-scored hypothesis must
//! beat no correction, then pass the honesty gate (its plain FIT gain on the training part's
//! folds); otherwise the finding is `unexplained`, with what was tried and how it scored.

use std::collections::BTreeMap;

use crate::candidates::{ActsOn, OutputCtx, Physics};
use crate::fitness::fit_pct;
use crate::input::{DiagnoseInput, DiagnoseOptions};
use crate::report::{Finding, Tried};
use crate::select::{self, Split};
use crate::{describe, simulate};

/// From the ranked hypotheses of one output to its finding and correction.
#[allow(clippy::too_many_arguments)]
pub(crate) fn decide(
    ctx: &OutputCtx,
    inst: &OutputCtx,
    r: &[f64],
    ranked: &[select::Scored],
    flagged: &[usize],
    split: &Split,
    opts: &DiagnoseOptions,
    ts: f64,
    input: &DiagnoseInput<'_>,
    j: usize,
) -> (Finding, Option<Vec<f64>>) {
    let y = input.outputs[j].values;
    let null_score = ranked.iter().find(|s| s.fitted.is_none()).map_or(f64::INFINITY, |s| s.score);
    // Per class: its best score against the null, and its cross-validated FIT gain. A class
    // whose refit fails on a fold has no gain to show and is left out of `tried`.
    let mut tried: Vec<Tried> = Vec::new();
    let mut seen: Vec<Physics> = Vec::new();
    // The cross-validated gain of the best-ranked fitted hypothesis (`None`: its refit failed).
    let mut top_gain: Option<Option<CvGain>> = None;
    for s in ranked {
        let Some(f) = &s.fitted else { continue };
        let ph = f.term.physics();
        if seen.contains(&ph) {
            continue;
        }
        seen.push(ph);
        let g = cv_gain(y, ctx, inst, r, f, s.grid.as_ref(), split);
        top_gain.get_or_insert(g);
        if let Some(g) = g {
            tried.push(Tried {
                physics: ph,
                score_vs_null: Some(s.score - null_score),
                validation_gain_pct: g.mean,
            });
        }
    }
    let best = ranked.first().filter(|s| s.fitted.is_some() && s.score < null_score);
    // The honesty gate: the winner must also raise the plain FIT (what the held-out FIT
    // measures) on the training part's blocks by a margin on average, as on the grey-box path.
    // A closed loop has its own margin (larger by default) and no block is required to gain: there the plain
    // FIT is a weak witness (the nominal error partly cancels the disturbance through feedback),
    // so small average gains are noise, while large ones that lost on one block held up on the
    // held-out tail (docs/diagnose.md, "The closed loop's margin").
    let margin = if split.closed_loop { opts.closed_loop_min_gain_pct } else { opts.min_gain_pct };
    let passes = |g: &CvGain| g.mean >= margin;
    let top_gain = top_gain.flatten();
    let best = best.filter(|_| top_gain.is_some_and(|g| passes(&g)));
    let out_name = input.outputs[j].name;
    if let Some((f, grid)) = best.and_then(|b| b.fitted.clone().map(|f| (f, b.grid.clone()))) {
        // Refit the chosen hypothesis on the whole training part (its grid values fixed, or
        // refined afresh from its grid term).
        let train: Vec<usize> = split.train.clone().collect();
        let refit =
            crate::fit::fit_hypothesis(ctx, inst, r, &f, grid.as_ref(), &train, split.whiten).unwrap_or(f);
        if let Some(c) = simulate::correction(ctx, &refit) {
            let in_name = input.inputs[refit.input].name;
            let (summary, parameters) = describe::describe(ctx, &refit, in_name, out_name, ts);
            let finding = Finding {
                input: in_name.to_string(),
                output: out_name.to_string(),
                physics: refit.term.physics(),
                acts_on: refit.term.acts_on(),
                summary,
                parameters,
                fit_before_pct: f64::NAN,
                fit_after_pct: f64::NAN,
                tried,
            };
            return (finding, Some(c));
        }
    }
    let names: Vec<&str> = flagged.iter().map(|&i| input.inputs[i].name).collect();
    let classes: Vec<&str> = tried.iter().map(|t| t.physics.name()).collect();
    let best_candidate = ranked
        .first()
        .and_then(|s| s.fitted.as_ref())
        .zip(top_gain)
        .map(|(f, g)| {
            format!(
                "; the best-scored candidate, {}, changes the cross-validated FIT by {:+.1} points on average and {:+.1} on its worst block (a finding needs {:+.1} on average)",
                f.term.physics().name(),
                g.mean,
                g.min,
                margin,
            )
        })
        .unwrap_or_default();
    let finding = Finding {
        input: names.first().copied().unwrap_or("").to_string(),
        output: out_name.to_string(),
        physics: Physics::Unexplained,
        acts_on: ActsOn::Input,
        summary: format!(
            "{out_name}'s residual carries information about {} but no candidate explains it better than no correction on held-back training data (tried: {}){best_candidate}",
            names.join(", "),
            classes.join(", ")
        ),
        parameters: BTreeMap::new(),
        fit_before_pct: f64::NAN,
        fit_after_pct: f64::NAN,
        tried,
    };
    (finding, None)
}

/// A hypothesis' plain FIT gain over no correction, in points, on each block of the training
/// part's folds (fitted on the other two): the mean and the smallest.
#[derive(Debug, Clone, Copy)]
struct CvGain {
    mean: f64,
    min: f64,
}

fn cv_gain(
    y: &[f64],
    ctx: &OutputCtx,
    inst: &OutputCtx,
    r: &[f64],
    f: &simulate::FittedTerm,
    grid: Option<&crate::candidates::Term>,
    split: &Split,
) -> Option<CvGain> {
    let mut gains = Vec::with_capacity(split.folds.len());
    for (fit_rows, val) in &split.folds {
        let g = crate::fit::fit_hypothesis(ctx, inst, r, f, grid, fit_rows, split.whiten)?;
        let c = simulate::correction(ctx, &g)?;
        let yv = &y[val.clone()];
        let before: Vec<f64> = val.clone().map(|t| ctx.s[t]).collect();
        let after: Vec<f64> = val.clone().map(|t| ctx.s[t] + c[t]).collect();
        gains.push(fit_pct(yv, &after) - fit_pct(yv, &before));
    }
    let mean = gains.iter().sum::<f64>() / gains.len().max(1) as f64;
    let min = gains.iter().copied().fold(f64::INFINITY, f64::min);
    (mean.is_finite() && !gains.is_empty()).then_some(CvGain { mean, min })
}
