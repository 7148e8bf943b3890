//! Choosing between hypotheses. Every concrete term is fitted and scored by 3-fold
//! cross-validation within the training part (never on the held-out tail), with a BIC-style
//! penalty per coefficient and per grid value. Open loop: the score is the validation error of
//! the corrected residual. Closed loop: by default the one-step prediction error of the corrected
//! residual under an ARIMA(8, 1, 1) noise model fitted with each hypothesis (the direct
//! prediction-error method, see [`Scoring`] and [`NoiseModel`]). The
//! intercept-only correction is the null hypothesis every term must beat.

use super::candidates::{ActsOn, OutputCtx, Term, grid};
use super::fit::{fit_hypothesis, fit_term, refine};
use super::simulate::{FittedTerm, correction};
use super::whiten::whitenable;
use mpmwatch_core::numerics::{Projector, lagged as delayed, least_squares_rows, minus_mean};
use rayon::prelude::*;

/// How hypotheses are scored in a closed loop (open-loop records always use the plain
/// validation error of the corrected residual).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum Scoring {
    /// One-step prediction error of the corrected residual under a [`NoiseModel`] fitted on the
    /// fit rows (the *direct* prediction-error method of closed-loop identification). The
    /// correction is evaluated on the recorded inputs. Under the true hypothesis the corrected
    /// residual is the disturbance alone, whose innovation is independent of everything before
    /// it, the inputs included (they reach the residual through the plant's delay); so no term
    /// built from the past can lower the expected prediction error below the innovation's, and a
    /// wrong term adds its dither-driven part on top. Raw squared errors lack this property: a
    /// wrong correction of inputs that carry the disturbance back can cancel part of it.
    #[default]
    Prediction,
    /// Validation error with the correction evaluated on the dither-driven part of the inputs
    /// plus circularly shifted copies of their disturbance-driven part (see [`rank`]).
    Shifted,
    /// Validation error projected on dither features (a GMM/IV criterion, see [`Projector`]).
    Projected,
}

/// AR order of the noise model of [`Scoring::Prediction`], and of the one the coefficients are
/// fitted under then ([`Split::whiten`]): enough for the slow, coloured disturbances of process
/// plants (an AR(1) with pole 0.9 needs one lag; a noise model of moderate order costs the same
/// for every hypothesis, so it does not bias the comparison).
pub const PREDICTION_ORDER: usize = 8;

/// The criterion one fold is scored with.
#[derive(Debug, Clone, Copy)]
pub enum Criterion<'a> {
    /// Open loop: validation SSE of the corrected residual.
    Plain,
    /// [`Scoring::Shifted`] with its scoring contexts.
    Shifted(&'a [OutputCtx]),
    /// [`Scoring::Projected`] with the fold's projector.
    Projected(&'a Projector),
    /// [`Scoring::Prediction`] with its noise model.
    Prediction(NoiseModel),
}

/// The noise model of [`Criterion::Prediction`]: ARIMA(`order`, 1, 1) with a constant,
/// `φ(B)·(1 − B)·e(t) = c + (1 − θB)·w(t)`, `w` the innovation.
///
/// The moving-average coefficient θ spans the disturbances of a process plant: θ = 1 cancels
/// the difference and leaves an AR model of the levels (a disturbance that returns to a mean),
/// θ = 0 an AR model of the first differences (one that wanders: load steps, drifts), and in
/// between a level that follows the series with a memory of about `1/(1 − θ)` samples (an AR
/// disturbance with occasional load steps, which neither end predicts: the levels' model misses
/// a step's new level on every row after it, the differences' model cannot undo the unit root
/// that differencing puts into a stationary part).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct NoiseModel {
    /// AR order.
    pub order: usize,
    /// θ, or `None`: the value of [`MA_GRID`] that predicts the fit rows best.
    pub ma: Option<f64>,
}

/// The values of θ a [`NoiseModel`] with `ma: None` chooses from, by the one-step prediction
/// error on its fit rows: the two ends and a local level's memory of 2 to 100 samples.
pub const MA_GRID: [f64; 9] = [0.0, 0.5, 0.7, 0.8, 0.9, 0.95, 0.98, 0.99, 1.0];

/// One scored hypothesis.
#[derive(Debug, Clone, PartialEq)]
pub struct Scored {
    /// The fitted term (`None`: the null hypothesis).
    pub fitted: Option<FittedTerm>,
    /// The criterion's validation sum of squares: of the corrected residual (open loop, shifted),
    /// of its one-step prediction error (prediction) or of its dither-projected part (projected).
    pub sse: f64,
    /// Complexity: coefficients plus grid values.
    pub complexity: usize,
    /// Penalised score (lower is better).
    pub score: f64,
    /// `Some`: the grid term its continuous values were refined from (see [`refine`]); wherever
    /// it is fitted again (each fold, the honesty gate's folds, the final refit) they are refined
    /// afresh from this term, so no fold starts from values fitted on its own validation block.
    pub grid: Option<Term>,
}

/// Splits of the record.
#[derive(Debug, Clone)]
pub struct Split {
    /// Dither features (`None`: open loop). In a closed loop they build the instruments and,
    /// under [`Scoring::Projected`], the projector of the score.
    pub features: Option<Vec<Vec<f64>>>,
    /// Rows used to fit during selection (the first 70 % of the training part; grids and
    /// feature sets are built on them).
    pub fit: std::ops::Range<usize>,
    /// Cross-validation folds within the training part: (fit rows, validation block).
    pub folds: Vec<(Vec<usize>, std::ops::Range<usize>)>,
    /// The whole training part (the final refit).
    pub train: std::ops::Range<usize>,
    /// Some input moves with more than its excitations (a controller acts on it): hypotheses
    /// are then scored by prediction error, and the honesty gate takes the closed loop's margin
    /// (see `decide`). False in open loop, and when the excitations given are the inputs
    /// themselves.
    pub closed_loop: bool,
    /// AR order of the noise model a term's coefficients are fitted under (see [`fit_term`](crate::fit::fit_term)):
    /// set in `plan` to [`PREDICTION_ORDER`] whenever excitations are given and hypotheses are
    /// scored by [`Scoring::Prediction`] (whether or not `closed_loop`), else 0 (plain
    /// instrumental variables; plain least squares in open loop).
    pub whiten: usize,
}

/// Scores a fitted term on the validation rows of one fold: `n·ln(SSE/n)` (−2 log-likelihood up
/// to a constant), with `n` and the complexity `k` the penalty is charged on once over all folds
/// (see [`rank`]).
///
/// `crit` says what SSE is: [`Criterion::Plain`] (open loop), the squared corrected residual;
/// [`Criterion::Prediction`], its one-step prediction error under an AR noise model fitted on
/// `fit_rows` (a wrong correction cannot lower it by cancelling the disturbance that feedback put
/// into the recorded inputs: the disturbance's innovation is independent of the past those
/// inputs are made of); [`Criterion::Shifted`], the squared residual after the correction
/// averaged over contexts with shifted disturbance-driven inputs; [`Criterion::Projected`], the
/// residual's dither-projected part. `n` counts the validation rows the SSE covers.
pub fn score(
    ctx: &OutputCtx,
    crit: Criterion<'_>,
    r: &[f64],
    f: Option<&FittedTerm>,
    fit_rows: &[usize],
    validate: std::ops::Range<usize>,
) -> Option<FoldScore> {
    let (c, complexity) = match f {
        Some(f) => {
            let free = if f.term.fixed_weight() { 0 } else { f.coefs.len() };
            let c = match crit {
                Criterion::Shifted(set) => {
                    // Averaged over the scoring contexts (see `rank`), intercept re-centred on
                    // the fit rows.
                    let mut g = f.clone();
                    g.intercept = 0.0;
                    let mut c0 = vec![0.0; r.len()];
                    for i in set {
                        let ci = correction(i, &g)?;
                        c0.iter_mut().zip(&ci).for_each(|(a, b)| *a += b / set.len() as f64);
                    }
                    g.intercept = fit_rows.iter().map(|&t| r[t] - c0[t]).sum::<f64>() / fit_rows.len() as f64;
                    c0.iter().map(|v| v + g.intercept).collect()
                }
                _ => correction(ctx, f)?,
            };
            (c, 1 + free + f.term.grid_params())
        }
        None => {
            let m = fit_rows.iter().map(|&t| r[t]).sum::<f64>() / fit_rows.len() as f64;
            (vec![m; r.len()], 1)
        }
    };
    let mut n = validate.len() as f64;
    let sse: f64 = match crit {
        // What the dithers explain of the residual after the correction, plus what they cannot
        // explain of the residual itself (common to every hypothesis).
        Criterion::Projected(p) => {
            let e: Vec<f64> = validate.clone().map(|t| r[t] - c[t]).collect();
            let rv: Vec<f64> = validate.clone().map(|t| r[t]).collect();
            let pr = p.project(&rv);
            let orth: f64 = rv.iter().zip(&pr).map(|(a, b)| (a - b).powi(2)).sum();
            let pe = p.project(&e);
            orth + pe.iter().map(|v| v * v).sum::<f64>()
        }
        Criterion::Prediction(noise) => {
            let e: Vec<f64> = r.iter().zip(&c).map(|(a, b)| a - b).collect();
            let (sse, used) = prediction_sse(&e, noise, fit_rows, validate.clone())?;
            n = used as f64;
            sse
        }
        Criterion::Plain | Criterion::Shifted(_) => validate.clone().map(|t| (r[t] - c[t]).powi(2)).sum(),
    };
    if !sse.is_finite() || n < 1.0 {
        return None;
    }
    Some(FoldScore { ll: n * (sse / n).max(1e-300).ln(), sse, rows: n as usize, complexity })
}

/// One fold's [`score`]: the −2 log-likelihood part `n·ln(SSE/n)`, the SSE, the `n` validation
/// rows it covers and the hypothesis' complexity.
#[derive(Debug, Clone, Copy)]
pub struct FoldScore {
    /// `n·ln(SSE/n)`.
    pub ll: f64,
    /// The criterion's sum of squares.
    pub sse: f64,
    /// `n`.
    pub rows: usize,
    /// Coefficients plus grid values.
    pub complexity: usize,
}

/// One-step prediction of `e` under the [`NoiseModel`], fitted by least squares on the rows of
/// `fit_rows` whose past back to `order + 1` samples (`order` for θ = 1) are fit rows too (the
/// folds' fit rows are not contiguous: a row just after the validation block would otherwise
/// regress on validation samples; the moving average's filter restarts at each run of fit rows
/// for the same reason). Returns the squared prediction error summed over the validation rows
/// from `order + 1` on (`order` for θ = 1), and how many rows that sum covers. With θ < 1 a
/// level that differs between the fit rows and the validation block costs its first sample
/// and then decays with the level's memory.
pub fn prediction_sse(
    e: &[f64],
    noise: NoiseModel,
    fit_rows: &[usize],
    validate: std::ops::Range<usize>,
) -> Option<(f64, usize)> {
    let fixed;
    let thetas: &[f64] = match noise.ma {
        Some(theta) => {
            fixed = [theta];
            &fixed
        }
        None => &MA_GRID,
    };
    thetas
        .iter()
        .filter_map(|&theta| arima_sse(e, noise.order, theta, fit_rows, validate.clone()))
        .min_by(|a, b| a.0.total_cmp(&b.0))
        .map(|(_, sse, used)| (sse, used))
}

/// [`prediction_sse`] at one θ: the fit rows' sum of squares, the validation rows' and how many
/// rows the latter covers.
fn arima_sse(
    e: &[f64],
    order: usize,
    theta: f64,
    fit_rows: &[usize],
    validate: std::ops::Range<usize>,
) -> Option<(f64, f64, usize)> {
    let levels = theta >= 1.0;
    let lead = usize::from(!levels);
    // What the AR part predicts: `x = (1 − B)·e / (1 − θB)`, so that `φ(B)·x = c + w`; at θ = 1
    // the levels themselves. Over the whole record in time order for the validation rows (their
    // past is all of the record before them); on the fit rows restarted at each run of
    // contiguous fit rows, so that no fit row's value carries a validation sample.
    let mut is_fit = vec![false; e.len()];
    fit_rows.iter().filter(|&&t| t < e.len()).for_each(|&t| is_fit[t] = true);
    let x_all: Vec<f64> = if levels {
        e.to_vec()
    } else {
        let mut x = vec![0.0; e.len()];
        for t in 1..e.len() {
            x[t] = e[t] - e[t - 1] + theta * x[t - 1];
        }
        x
    };
    let x_fit: Vec<f64> = if levels {
        e.to_vec()
    } else {
        let mut x = vec![0.0; e.len()];
        for t in 1..e.len() {
            // A run's first difference starts the filter from rest (`x[t − 1]` is 0 there).
            if is_fit[t] && is_fit[t - 1] {
                x[t] = e[t] - e[t - 1] + theta * x[t - 1];
            }
        }
        x
    };
    let ones = vec![1.0; e.len()];
    let predict_cols = |x: &[f64]| -> Vec<Vec<f64>> { (1..=order).map(|k| delayed(x, k)).collect() };
    let fit_lags = predict_cols(&x_fit);
    let mut cols: Vec<&[f64]> = vec![&ones];
    cols.extend(fit_lags.iter().map(|c| c.as_slice()));
    let rows: Vec<usize> = whitenable(fit_rows, order + lead).into_iter().filter(|&t| t < e.len()).collect();
    let th = least_squares_rows(&cols, &x_fit, &rows)?;
    let sq = |x: &[f64], cols: &[&[f64]], t: usize| {
        (x[t] - cols.iter().zip(&th).map(|(c, b)| c[t] * b).sum::<f64>()).powi(2)
    };
    let fit_sse: f64 = rows.iter().map(|&t| sq(&x_fit, &cols, t)).sum();
    let all_lags = predict_cols(&x_all);
    let mut cols: Vec<&[f64]> = vec![&ones];
    cols.extend(all_lags.iter().map(|c| c.as_slice()));
    let used: Vec<usize> = validate.filter(|&t| t >= order + lead && t < e.len()).collect();
    let sse = used.iter().map(|&t| sq(&x_all, &cols, t)).sum();
    Some((fit_sse, sse, used.len()))
}

/// Every hypothesis on the given inputs of one output (with a physical model: the actuator gains
/// of those inputs stated through it, and, when `limits`, every state limit), scored, best
/// first.
///
/// Each is scored by 3-fold cross-validation within the training part (see [`score`]).
///
/// Closed loop: the criterion is `scoring_mode`: by default the prediction error (see
/// [`score`]); under [`Scoring::Shifted`] a correction is scored as the average of its
/// evaluations on `scoring`, contexts whose inputs are the dither-driven part plus a circularly
/// shifted copy of the disturbance-driven part (the shift breaks the link to the disturbance in
/// the residual while the inputs keep their full spread); `scoring` is empty otherwise.
#[allow(clippy::too_many_arguments)]
pub fn rank(
    ctx: &OutputCtx,
    inst: &OutputCtx,
    scoring: &[OutputCtx],
    r: &[f64],
    inputs: &[usize],
    limits: bool,
    split: &Split,
    penalty: f64,
    scoring_mode: Scoring,
) -> Vec<Scored> {
    let projected = scoring_mode == Scoring::Projected;
    // Closed loop, projected scoring: the dither features of the split plus, per input, the
    // nonlinear functions of its dither-driven response that the candidate classes produce.
    let projectors: Option<Vec<Projector>> = split.features.as_ref().filter(|_| projected).map(|z| {
        let mut z = z.clone();
        z.extend(nonlinear_dither_features(ctx, inst));
        split.folds.iter().map(|(_, val)| Projector::new(&z, val.clone())).collect()
    });
    // Closed loop, prediction error: each hypothesis is scored under its own noise model,
    // fitted with it on each fold's fit rows, θ included ([`NoiseModel`]). A disturbance that
    // wanders (load steps, drifts) leaves a level that differs between a validation block and
    // its fit rows; under a model of the levels that costs every row of the block, and a wrong
    // correction that follows the level through the controller's moves (which answer the
    // disturbance) gains by it, not by the physics. A model of the differences ignores levels
    // but also the slow part of a correct correction. Until stop 80 each hypothesis kept the
    // better of those two ends on the validation rows, so a wrong correction won wherever it
    // won under either (docs/diagnose-history.md, stop 80).
    let prediction = split.features.is_some() && projectors.is_none() && scoring_mode == Scoring::Prediction;
    // Each hypothesis: fitted and scored on every fold. The folds' validation blocks tile the
    // training part, so their log-likelihoods add up to one of its `N` rows, and the BIC charges
    // `k·ln N` once: charged per fold, each parameter would pay about three times its price and
    // a class with one more (a dead zone's width, a saturation's second limit) would lose to a
    // gain that explains less.
    let fold_score = |f: Option<&FittedTerm>, grid: Option<&Term>| -> Option<(f64, f64, usize)> {
        let (mut ll, mut sse, mut rows, mut complexity) = (0.0, 0.0, 0usize, 0);
        for (k, (fit_rows, val)) in split.folds.iter().enumerate() {
            let fitted = match f {
                Some(f) => Some(fit_hypothesis(ctx, inst, r, f, grid, fit_rows, split.whiten)?),
                None => None,
            };
            let crit = match (&split.features, &projectors) {
                (None, _) => Criterion::Plain,
                (Some(_), Some(p)) => Criterion::Projected(&p[k]),
                (Some(_), None) if prediction => {
                    Criterion::Prediction(NoiseModel { order: PREDICTION_ORDER, ma: None })
                }
                (Some(_), None) => Criterion::Shifted(scoring),
            };
            let s = score(ctx, crit, r, fitted.as_ref(), fit_rows, val.clone())?;
            (ll, sse, rows, complexity) = (ll + s.ll, sse + s.sse, rows + s.rows, s.complexity);
        }
        Some((ll + penalty * complexity as f64 * (rows.max(1) as f64).ln(), sse, complexity))
    };
    let fit_rows: Vec<usize> = split.fit.clone().collect();
    let mut out: Vec<Scored> = Vec::new();
    if let Some((score, sse, complexity)) = fold_score(None, None) {
        out.push(Scored { fitted: None, sse, complexity, score, grid: None });
    }
    // An output-side effect (a sensor map, an output clip, a force fed back from the output) is a
    // property of the output, not of one channel: it is tried once, through the flagged input
    // that is this output's own actuator. When two channels share their dynamics, the data
    // cannot tell through which one a fed-back force enters; trying it on every flagged input
    // would let noise pick.
    let dominant = own_actuator(ctx, inst, r, inputs, split.train.clone());
    for &i in inputs {
        let mut terms = grid(ctx, i, split.fit.clone());
        if dominant.is_some_and(|d| d != i) {
            terms.retain(|t| t.acts_on() == ActsOn::Input);
        }
        if ctx.has_channel[i] {
            terms.push(Term::Bilinear(Vec::new()));
        }
        let from = out.len();
        // Each term is fitted and scored on its own, on every core; they come back in the
        // order listed, so the choice does not depend on the threads.
        out.par_extend(terms.into_par_iter().filter_map(|t| {
            // The bilinear products are chosen once by FROLS on the fit rows, then kept fixed.
            let f = fit_term(ctx, inst, r, i, t, &fit_rows, split.whiten)?;
            let (score, sse, complexity) = fold_score(Some(&f), None)?;
            Some(Scored { fitted: Some(f), sse, complexity, score, grid: None })
        }));
        // Per class and side, its best grid term with continuous values, refined: from the grid
        // term on the fit rows for the term kept, and afresh from it on each fold's fit rows for
        // its score. Only where the score is the prediction error or the plain open-loop error:
        // the other closed-loop scorings have no fitting criterion of their own to refine by.
        let refinable = split.features.is_none() || split.whiten > 0;
        let mut starts: Vec<&Scored> = Vec::new();
        for c in out[from..].iter().filter(|_| refinable) {
            let Some(f) = &c.fitted else { continue };
            if f.term.continuous().is_empty() {
                continue;
            }
            let class = |s: &Scored| s.fitted.as_ref().map(|g| (g.term.physics(), g.term.acts_on()));
            match starts.iter_mut().find(|b| class(b) == class(c)) {
                Some(b) if c.score < b.score => *b = c,
                Some(_) => {}
                None => starts.push(c),
            }
        }
        let starts: Vec<Term> =
            starts.into_iter().filter_map(|s| s.fitted.as_ref().map(|f| f.term.clone())).collect();
        out.par_extend(starts.into_par_iter().filter_map(|g| {
            let f = refine(ctx, inst, r, i, &g, &fit_rows, split.whiten).filter(|f| f.term != g)?;
            let (score, sse, complexity) = fold_score(Some(&f), Some(&g))?;
            Some(Scored { fitted: Some(f), sse, complexity, score, grid: Some(g) })
        }));
    }
    // Hypotheses stated through a physical model: its state limits when their test fired
    // (attributed to the first flagged input, since the model, not a channel, carries them), and
    // the actuator gains of the flagged inputs.
    let first = inputs.first().copied().unwrap_or(0);
    for (t, _) in &ctx.physical_terms {
        let i = match t {
            Term::StateLimit { .. } if limits => first,
            Term::ModelGain { input, .. } if inputs.contains(input) => *input,
            _ => continue,
        };
        let Some(f) = fit_term(ctx, inst, r, i, t.clone(), &fit_rows, split.whiten) else { continue };
        if let Some((score, sse, complexity)) = fold_score(Some(&f), None) {
            out.push(Scored { fitted: Some(f), sse, complexity, score, grid: None });
        }
    }
    out.sort_by(|a, b| a.score.total_cmp(&b.score));
    out
}

/// The output's own actuator among `inputs` (those with a model channel). In a closed loop, the
/// input whose controller move (the input less its dither-driven part) a PI law of this output
/// explains best among the moves that pass [`pi_law_fit`]'s surrogate test: an input without
/// controller moves (in manual, or an open loop) takes no part, nor does a move that fails it.
/// Otherwise (no input's move answers this output: an open loop, or a loop through an input
/// nobody flagged): the input whose dither-driven response carries the most of this output's
/// variance. Under decentralised control the first rule finds the loop's pairing, which the
/// second misses wherever a coupling is stronger than the loop's own channel.
fn own_actuator(
    ctx: &OutputCtx,
    inst: &OutputCtx,
    r: &[f64],
    inputs: &[usize],
    rows: std::ops::Range<usize>,
) -> Option<usize> {
    let with_channel = || inputs.iter().copied().filter(|&i| ctx.has_channel[i]);
    let var_of = |x: &[f64]| {
        let m = x[rows.clone()].iter().sum::<f64>() / rows.len().max(1) as f64;
        x[rows.clone()].iter().map(|v| (v - m).powi(2)).sum::<f64>()
    };
    let y: Vec<f64> = r.iter().zip(&ctx.s).map(|(a, b)| a + b).collect();
    let rows = rows.start.max(2)..rows.end.max(2);
    let paired = with_channel()
        .filter_map(|i| {
            let uc: Vec<f64> = ctx.ut[i].iter().zip(&inst.ut[i]).map(|(a, b)| a - b).collect();
            let duc: Vec<f64> = rows.clone().map(|t| uc[t] - uc[t - 1]).collect();
            let m = duc.iter().sum::<f64>() / duc.len().max(1) as f64;
            let sst: f64 = duc.iter().map(|v| (v - m).powi(2)).sum();
            if sst == 0.0 || sst <= 1e-12 * var_of(&ctx.ut[i]) {
                return None;
            }
            let yr: Vec<f64> = rows.clone().map(|t| y[t]).collect();
            let (y1, y2): (Vec<f64>, Vec<f64>) = rows.clone().map(|t| (y[t - 1], y[t - 2])).unzip();
            pi_law_fit(&duc, [&yr, &y1, &y2]).map(|r2| (i, r2))
        })
        .max_by(|a, b| a.1.total_cmp(&b.1));
    paired.map(|(i, _)| i).or_else(|| {
        with_channel().max_by(|&a, &b| var_of(&inst.s_channel[a]).total_cmp(&var_of(&inst.s_channel[b])))
    })
}

/// Circular shifts of a controller move against the output in [`pi_law_fit`]'s surrogate test:
/// with the move's own alignment, 100 shifts spaced evenly round the record. The move's fit must
/// beat all 99 others: a false-alarm rate of about 1/100 per input.
const PAIRING_SURROGATES: usize = 99;

/// How well a PI law explains a controller move: the R² of the move's increment `du` regressed
/// on the measured output now and one and two samples before (`y`, the span of a PI law's
/// increment and level of the output with one sample of delay) and 1, if it beats the R² of
/// every one of [`PAIRING_SURROGATES`] circular shifts of `du`, spaced evenly round the record.
/// A shift keeps the move's and the output's autocorrelation and breaks only their alignment;
/// with the shifts evenly spaced the true alignment is one of 100 nearly exchangeable ones (for
/// stationary series; not exactly, since a shifted move jumps where it wraps round), so a move
/// that does not answer the output beats the rest with probability about 1 % when the series'
/// correlation times are short against the record (more for very slow series:
/// docs/diagnose-history.md, stop 37). The χ² law of `n·R²`, which assumes independent rows,
/// is passed by chance far more often on autocorrelated process data, and shifts bunched away
/// from the true alignment are too (they behave like fewer surrogates). `None`: the move does
/// not beat every shift, a constant increment, fewer than 100 rows (no distinct shifts), or a
/// failed fit (then no shift counts as beaten).
fn pi_law_fit(du: &[f64], y: [&[f64]; 3]) -> Option<f64> {
    let m = du.len();
    if m < PAIRING_SURROGATES + 1 {
        return None;
    }
    let real = pi_law_r2(du, y)?;
    let shifted = |k: usize| -> Vec<f64> { (0..m).map(|t| du[(t + k) % m]).collect() };
    (1..=PAIRING_SURROGATES)
        .all(|j| pi_law_r2(&shifted(j * m / (PAIRING_SURROGATES + 1)), y).is_some_and(|s| s < real))
        .then_some(real)
}

/// The R² of `du` regressed on `y` (the output now, one and two samples back) and 1 (`None`: a
/// constant `du` or a failed fit).
fn pi_law_r2(du: &[f64], y: [&[f64]; 3]) -> Option<f64> {
    let m = du.len();
    let mean = du.iter().sum::<f64>() / m as f64;
    let sst: f64 = du.iter().map(|v| (v - mean).powi(2)).sum();
    if sst.is_nan() || sst <= 0.0 {
        return None;
    }
    let one = vec![1.0; m];
    let cols: [&[f64]; 4] = [y[0], y[1], y[2], &one];
    let all: Vec<usize> = (0..m).collect();
    let b = least_squares_rows(&cols, du, &all)?;
    let sse: f64 =
        (0..m).map(|t| du[t] - cols.iter().zip(&b).map(|(c, k)| c[t] * k).sum::<f64>()).map(|e| e * e).sum();
    Some(1.0 - sse / sst)
}

/// Per input with a model channel, `G0(ud²)`, `G0(ud³)`, `sd²`, `sd³`, `G0(sd³)` of its
/// dither-driven centred input `ud` and response `sd`; and the square and cube of the whole
/// dither-driven output (what an output-side map makes of the dither).
pub fn nonlinear_dither_features(ctx: &OutputCtx, inst: &OutputCtx) -> Vec<Vec<f64>> {
    let pow = |x: &[f64], p: i32| x.iter().map(|v| v.powi(p)).collect::<Vec<f64>>();
    let mut z = Vec::new();
    for i in 0..inst.ut.len() {
        if !ctx.has_channel[i] {
            continue;
        }
        let ud = &inst.ut[i];
        let sd = minus_mean(&inst.s_channel[i]);
        z.push(ctx.model.channel(i, &pow(ud, 2)));
        z.push(ctx.model.channel(i, &pow(ud, 3)));
        z.push(pow(&sd, 2));
        z.push(pow(&sd, 3));
        z.push(ctx.model.channel(i, &pow(&sd, 3)));
    }
    let s = minus_mean(&inst.s);
    z.push(pow(&s, 2));
    z.push(pow(&s, 3));
    z
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::SeedableRng;
    use rand_distr::{Distribution, StandardNormal};

    /// Two inputs whose controller moves follow PI laws of `follows` (none: the input is its
    /// dither alone, a loop in manual), the channel of input `big` into the output ten times the
    /// other's; the output `y` and a second and third loop's outputs `z`, `w` are independent
    /// AR(1) series. Returns the own actuator found with the dithers as instruments and, with the
    /// whole inputs as instruments (no controller moves: an open loop), the one the variance
    /// rule names.
    fn own_actuator_of(follows: [Option<char>; 2], big: usize) -> (Option<usize>, Option<usize>) {
        let n = 2000;
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(5);
        let mut white = || -> Vec<f64> { (0..n).map(|_| StandardNormal.sample(&mut rng)).collect() };
        let (d1, d2, e_y, e_z, e_w) = (white(), white(), white(), white(), white());
        let ar = |e: &[f64]| -> Vec<f64> {
            let mut x = 0.0;
            e.iter()
                .map(|v| {
                    x = 0.9 * x + v;
                    x
                })
                .collect()
        };
        let pi = |x: &[f64]| -> Vec<f64> {
            let mut u = 0.0;
            (0..n)
                .map(|t| {
                    u += -0.3 * (x[t] - if t > 0 { x[t - 1] } else { 0.0 }) - 0.1 * x[t];
                    u
                })
                .collect()
        };
        let (y, z, w) = (ar(&e_y), ar(&e_z), ar(&e_w));
        let input = |d: &[f64], f: Option<char>| -> Vec<f64> {
            match f {
                None => d.to_vec(),
                Some(c) => d
                    .iter()
                    .zip(pi(match c {
                        'y' => &y,
                        'z' => &z,
                        _ => &w,
                    }))
                    .map(|(d, c)| d + c)
                    .collect(),
            }
        };
        let (u1, u2) = (input(&d1, follows[0]), input(&d2, follows[1]));
        let (k1, k2) = if big == 0 { (1.0, 0.1) } else { (0.1, 1.0) };
        let s: Vec<f64> = (0..n).map(|t| if t > 0 { k1 * u1[t - 1] + k2 * u2[t - 1] } else { 0.0 }).collect();
        let split = Split { closed_loop: true, ..crate::plan::open_split(20..n) };
        let ctx = crate::plan::output_ctx(&[&u1, &u2], &s, &split);
        assert!(ctx.has_channel[0] && ctx.has_channel[1]);
        let r: Vec<f64> = y.iter().zip(&s).map(|(a, b)| a - b).collect();
        let closed = crate::plan::instrument_ctx(&ctx, &[d1, d2]);
        let open = crate::plan::instrument_ctx(&ctx, &[u1.clone(), u2.clone()]);
        (own_actuator(&ctx, &closed, &r, &[0, 1], 20..n), own_actuator(&ctx, &open, &r, &[0, 1], 20..n))
    }

    /// u1's move is a PI law of the output (R² = 1), u2's follows another loop's output. The
    /// pairing names u1, where the variance of the channels' responses, the rule kept for an open
    /// loop, names u2.
    #[test]
    fn own_actuator_is_the_loop_that_controls_the_output() {
        assert_eq!(own_actuator_of([Some('y'), Some('z')], 1), (Some(0), Some(1)));
    }

    /// u1 controls the output and u2 is in manual (its input is its dither): u2 takes no part in
    /// the pairing and u1 is still named. Under the rule before stop 36 one input without moves
    /// turned the pairing off for every input and the variance rule named u2.
    #[test]
    fn an_input_in_manual_leaves_the_pairing_to_the_others() {
        assert_eq!(own_actuator_of([Some('y'), None], 1).0, Some(0));
    }

    /// Neither move answers the output (u1 follows `w`, u2 follows `z`, both independent of `y`):
    /// on this seed neither passes the surrogate test, so the variance rule names the input with
    /// the larger channel, whichever it is. Without the test chance would pick, and the same
    /// input both times (the moves and the output do not change with the channels).
    #[test]
    fn no_loop_on_the_output_falls_back_to_the_variance_rule() {
        assert_eq!(own_actuator_of([Some('w'), Some('z')], 1).0, Some(1));
        assert_eq!(own_actuator_of([Some('w'), Some('z')], 0).0, Some(0));
    }

    /// The pairing's surrogate test holds its stated false-alarm rate on autocorrelated data: an
    /// AR(0.9) output and an independent move whose increments are AR(0.9) (both past their
    /// start-up), 500 samples, 200 seeded draws. A pass is a false alarm, so the count is
    /// Binomial(200, 0.01) if the rate is as stated: mean 2, and 8 or more has probability 0.001.
    /// The χ²(3) floor `n·R² > 16.27` it replaces passes about a quarter of such draws (22-25 %
    /// over 1000 draws in a numpy sketch of this set-up).
    #[test]
    fn the_pairing_test_holds_its_false_alarm_rate_on_autocorrelated_data() {
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(17);
        let n = 500;
        let mut ar = || -> Vec<f64> {
            let mut x = 0.0;
            let v: Vec<f64> = (0..n + 200)
                .map(|_| {
                    let e: f64 = StandardNormal.sample(&mut rng);
                    x = 0.9 * x + e;
                    x
                })
                .collect();
            v[200..].to_vec()
        };
        let mut passes = 0;
        let mut chi2_passes = 0;
        for _ in 0..200 {
            let (y, du) = (ar(), ar());
            let lag = |k: usize| -> Vec<f64> { (2..n).map(|t| y[t - k]).collect() };
            let (y0, y1, y2) = (lag(0), lag(1), lag(2));
            let du = &du[2..];
            if let Some(r2) = pi_law_fit(du, [&y0, &y1, &y2]) {
                passes += 1;
                assert!(r2 >= 0.0);
            }
            let r2 = pi_law_r2(du, [&y0, &y1, &y2]).expect("a full-rank fit");
            if (n - 2) as f64 * r2 > 16.266 {
                chi2_passes += 1;
            }
        }
        assert!(passes <= 7, "{passes} of 200 unrelated moves passed (expected about 2)");
        assert!(
            chi2_passes > 20,
            "the χ² floor passed only {chi2_passes} of 200: the set-up is not autocorrelated enough to tell"
        );
    }

    /// A move that is a PI law of the output, buried in its own noise (R² about 0.2), passes:
    /// the test keeps the power the pairing needs.
    #[test]
    fn a_noisy_pi_law_passes_the_pairing_test() {
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(19);
        let n = 1000;
        let mut x = 0.0;
        let y: Vec<f64> = (0..n)
            .map(|_| {
                let e: f64 = StandardNormal.sample(&mut rng);
                x = 0.9 * x + e;
                x
            })
            .collect();
        let du: Vec<f64> = (2..n)
            .map(|t| {
                let e: f64 = StandardNormal.sample(&mut rng);
                -0.3 * (y[t - 1] - y[t - 2]) - 0.1 * y[t - 1] + 0.8 * e
            })
            .collect();
        let lag = |k: usize| -> Vec<f64> { (2..n).map(|t| y[t - k]).collect() };
        let r2 = pi_law_fit(&du, [&lag(0), &lag(1), &lag(2)]).expect("a PI law passes");
        assert!((0.1..0.4).contains(&r2), "R² {r2}");
    }

    /// `n` samples of an AR(1) series of pole 0.9 with unit Gaussian innovations, from rest.
    fn ar1(seed: u64, n: usize) -> Vec<f64> {
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(seed);
        let mut x = 0.0;
        (0..n)
            .map(|_| {
                let w: f64 = StandardNormal.sample(&mut rng);
                x = 0.9 * x + w;
                x
            })
            .collect()
    }

    /// An AR(1) series with unit innovations: the one-step prediction error of a fitted AR model
    /// is the innovation, so the validation SSE per sample is 1 (closed form). With 10 000
    /// validation samples the mean of the squared innovations has a relative standard deviation
    /// of √(2/10 000) = 1.4 %, and the fit's own error adds O(order/n); 5 % is 3.5 standard
    /// deviations.
    #[test]
    fn prediction_error_of_an_ar1_series_is_its_innovation_variance() {
        let e = ar1(11, 20_000);
        let fit: Vec<usize> = (0..10_000).collect();
        let (sse, used) =
            prediction_sse(&e, NoiseModel { order: PREDICTION_ORDER, ma: Some(1.0) }, &fit, 10_000..20_000)
                .unwrap();
        assert_eq!(used, 10_000);
        let per_sample = sse / used as f64;
        assert!((per_sample - 1.0).abs() < 0.05, "{per_sample}");
        // The raw variance of the same series is 1/(1 − 0.81) ≈ 5.3: the criterion removes it.
        let raw = e[10_000..].iter().map(|v| v * v).sum::<f64>() / 10_000.0;
        assert!(raw > 4.0, "{raw}");
    }

    /// Fit rows with a gap (a cross-validation fold that validates a middle block): the AR fit
    /// must not regress on the block's samples. The block is made wild (a huge spike) so that
    /// using it would ruin the fit; with the gap respected the fit sees only the AR(1) series and
    /// the prediction error after the block is the innovation's, as in the test above (5 % at
    /// 3.5 standard deviations, 10 000 samples summed).
    #[test]
    fn the_noise_model_is_not_fitted_across_the_validation_block() {
        let mut e = ar1(12, 30_000);
        for (k, v) in e[10_000..10_010].iter_mut().enumerate() {
            *v = if k % 2 == 0 { 1e6 } else { -1e6 };
        }
        let fit: Vec<usize> = (0..10_000).chain(10_010..20_000).collect();
        let (sse, used) =
            prediction_sse(&e, NoiseModel { order: PREDICTION_ORDER, ma: Some(1.0) }, &fit, 20_000..30_000)
                .unwrap();
        let per_sample = sse / used as f64;
        assert!((per_sample - 1.0).abs() < 0.05, "{per_sample}");
    }

    /// A random walk (unit innovations, seed 13) with a load step of 10 where the validation
    /// block starts: the model of the differences (θ = 0) predicts each difference, so the prediction error
    /// per sample is the innovation's variance, 1, plus the step's one sample (100 over 10 000
    /// rows, 0.01); 5 % is 3.5 standard deviations of the mean of 10 000 squared innovations.
    #[test]
    fn the_model_of_the_differences_predicts_a_random_walk_by_its_innovation() {
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(13);
        let mut x = 0.0;
        let e: Vec<f64> = (0..20_000)
            .map(|t| {
                let w: f64 = StandardNormal.sample(&mut rng);
                x += w;
                x + if t >= 10_000 { 10.0 } else { 0.0 }
            })
            .collect();
        let fit: Vec<usize> = (0..10_000).collect();
        let noise = NoiseModel { order: PREDICTION_ORDER, ma: Some(0.0) };
        let (sse, used) = prediction_sse(&e, noise, &fit, 10_000..20_000).unwrap();
        assert_eq!(used, 10_000);
        let per_sample = sse / used as f64;
        assert!((per_sample - 1.01).abs() < 0.05, "{per_sample}");
    }

    /// One fold of an AR(1) disturbance (pole 0.9, unit innovations, seed 14), validating the
    /// middle of three blocks of 10 000 rows. Stationary, the AR model of the levels predicts it
    /// better: its error per sample is the innovation's, while an AR(8) of the differences
    /// cannot undo the unit root that differencing puts in the moving average. With load steps
    /// between the blocks (levels 0, +8, −8) the differenced model predicts better: one constant
    /// fitted over two levels, the model of the levels misses the validation block's level on
    /// every row, the differenced one on its first row only. The two errors share their
    /// innovations, so their ratio varies little from seed to seed (margins in
    /// docs/diagnose-history.md, stop 41). With θ chosen on the fit rows, the stationary series
    /// is predicted as by the levels' model.
    #[test]
    fn the_model_of_the_differences_wins_only_for_a_wandering_disturbance() {
        let ar = ar1(14, 30_000);
        let fit: Vec<usize> = (0..10_000).chain(20_000..30_000).collect();
        let per_sample = |e: &[f64], ma: Option<f64>| {
            let noise = NoiseModel { order: PREDICTION_ORDER, ma };
            let (sse, used) = prediction_sse(e, noise, &fit, 10_000..20_000).unwrap();
            sse / used as f64
        };
        let (level, diff) = (per_sample(&ar, Some(1.0)), per_sample(&ar, Some(0.0)));
        assert!(level < diff, "stationary: levels {level}, differences {diff}");
        // θ chosen on the fit rows: the levels' end, whose error is the innovation's (the
        // tolerance of the AR(1) test above).
        let chosen = per_sample(&ar, None);
        assert!((chosen - 1.0).abs() < 0.05, "stationary, θ chosen: {chosen}");
        let steps = [0.0, 8.0, -8.0];
        let stepped: Vec<f64> = ar.iter().enumerate().map(|(t, v)| v + steps[t / 10_000]).collect();
        let (level, diff) = (per_sample(&stepped, Some(1.0)), per_sample(&stepped, Some(0.0)));
        assert!(diff < level, "load steps: levels {level}, differences {diff}");
    }

    /// A series that is exactly ARIMA(0, 1, 1) with θ = 0.9, `e(t) = e(t−1) + w(t) − 0.9·w(t−1)`
    /// (unit innovations, seed 15): a level that follows the series with a memory of about ten
    /// samples. At θ = 0.9, and with θ chosen from [`MA_GRID`] on the fit rows, the one-step
    /// prediction error per sample is the innovation's, 1 (closed form; 5 % is 3.5 standard
    /// deviations of the mean of 10 000 squared innovations). Neither end reaches it: the best
    /// AR(8) of the differences, an MA(1) with θ = 0.9, errs by `1 + θ¹⁸(1 − θ²)/(1 − θ²⁰)` ≈
    /// 1.033 times the innovation's variance, and the levels' AR model with a constant fits a
    /// series without a mean. The ends' excess shares the innovations with the chosen model's
    /// error, so it is about nine of its standard deviations at this length (measured: 0.978
    /// chosen, 1.011 differences, 1.030 levels).
    #[test]
    fn a_local_level_is_predicted_by_its_innovation_with_its_moving_average_chosen() {
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(15);
        let (mut level, mut w_prev) = (0.0, 0.0);
        let e: Vec<f64> = (0..20_000)
            .map(|_| {
                let w: f64 = StandardNormal.sample(&mut rng);
                level += w - 0.9 * w_prev;
                w_prev = w;
                level
            })
            .collect();
        let fit: Vec<usize> = (0..10_000).collect();
        let per_sample = |ma: Option<f64>| {
            let (sse, used) =
                prediction_sse(&e, NoiseModel { order: PREDICTION_ORDER, ma }, &fit, 10_000..20_000).unwrap();
            sse / used as f64
        };
        let (exact, chosen) = (per_sample(Some(0.9)), per_sample(None));
        assert!((exact - 1.0).abs() < 0.05, "θ = 0.9: {exact}");
        assert!((chosen - 1.0).abs() < 0.05, "θ chosen: {chosen}");
        let (levels, differences) = (per_sample(Some(1.0)), per_sample(Some(0.0)));
        assert!(
            chosen < differences && chosen < levels,
            "chosen {chosen}, levels {levels}, differences {differences}"
        );
    }

    /// An offset sinusoid obeys an exact AR(2) recursion with a constant
    /// (`e_t = 2cos ω·e_{t−1} − e_{t−2} + c`), so it is predicted exactly.
    #[test]
    fn an_offset_sinusoid_is_predicted_exactly() {
        let e: Vec<f64> = (0..400).map(|t| (0.3 * t as f64).sin() + 0.1).collect();
        let fit: Vec<usize> = (0..200).collect();
        let (sse, _) = prediction_sse(&e, NoiseModel { order: 2, ma: Some(1.0) }, &fit, 200..400).unwrap();
        assert!(sse < 1e-12, "{sse}");
    }
}
