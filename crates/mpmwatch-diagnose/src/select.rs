//! Choosing between hypotheses. Every concrete term is fitted and scored by 3-fold
//! cross-validation within the training part (never on the held-out tail), with a BIC-style
//! penalty per coefficient and per grid value. Open loop: the score is the validation error of
//! the corrected residual. Closed loop: by default the one-step prediction error of the corrected
//! residual under an AR noise model (the direct prediction-error method, see [`Scoring`]). The
//! intercept-only correction is the null hypothesis every term must beat.

use super::candidates::{ActsOn, OutputCtx, Term, grid};
use super::frols::frols;
use super::simulate::{FittedTerm, correction};
use super::whiten::{ar_fit, whitenable, whitened};
use crate::minimize::minimize;
use mpmwatch_core::numerics::{Projector, instrumental, lagged as delayed, least_squares_rows, minus_mean};

/// How hypotheses are scored in a closed loop (open-loop records always use the plain
/// validation error of the corrected residual).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum Scoring {
    /// One-step prediction error of the corrected residual under an AR noise model fitted on the
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
    /// [`Scoring::Prediction`] with the AR order of the noise model.
    Prediction(usize),
}

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
    /// AR order of the noise model a term's coefficients are fitted under (see [`fit_term`]):
    /// set in `plan` to [`PREDICTION_ORDER`] whenever excitations are given and hypotheses are
    /// scored by [`Scoring::Prediction`] (whether or not `closed_loop`), else 0 (plain
    /// instrumental variables; plain least squares in open loop).
    pub whiten: usize,
}

/// Fits one term's coefficients on `rows` against the residual `r`.
/// The columns of the term are instrumented by the same columns built on `inst`, the context
/// with the dither-driven part of the inputs in place of the recorded inputs.
///
/// With `whiten = p > 0` the coefficients are then fitted again under an AR(`p`) noise model of
/// the first fit's corrected residual (one step of generalised least squares: the residual, the
/// columns and the instruments pass through the same whitening filter). Unfiltered, a fit under
/// a slow disturbance is dominated by it; whitened, every sample counts by its one-step
/// prediction error, the quantity the closed loop's fold score measures. The intercept is then
/// the plain mean of what the correction leaves on `rows`, so the honesty gate's plain FIT sees
/// no offset. A recursive term's scale grid is scored by the whitened error too. The plain fit
/// is kept when the noise model cannot be fitted (fewer than `10·p` rows with `p` predecessors
/// among `rows`, or a recursive first fit that diverges); FROLS picks bilinear products on the
/// unfiltered residual.
pub fn fit_term(
    ctx: &OutputCtx,
    inst: &OutputCtx,
    r: &[f64],
    input: usize,
    term: Term,
    rows: &[usize],
    whiten: usize,
) -> Option<FittedTerm> {
    let term = match term {
        Term::Bilinear(ref pool) if pool.is_empty() => {
            // FROLS chooses up to two products from the pool on these rows.
            let pool = ctx.bilinear_pool(input);
            let cols = inst.columns(input, &Term::Bilinear(pool.clone()));
            let rc: Vec<f64> = centre_on(r, rows);
            let cc: Vec<Vec<f64>> = cols.iter().map(|c| centre_on(c, rows)).collect();
            let chosen = frols(&cc, &rc, rows, 2, 0.01);
            if chosen.is_empty() {
                return None;
            }
            Term::Bilinear(chosen.iter().map(|&(k, _)| pool[k]).collect())
        }
        t => t,
    };
    let cols = ctx.columns(input, &term);
    if term.fixed_weight() {
        let col = cols.first()?;
        let intercept = rows.iter().map(|&t| r[t] - col[t]).sum::<f64>() / rows.len().max(1) as f64;
        return intercept.is_finite().then_some(FittedTerm { input, term, intercept, coefs: vec![1.0] });
    }
    let ones = vec![1.0; r.len()];
    let mut refs: Vec<&[f64]> = vec![&ones];
    refs.extend(cols.iter().map(|c| c.as_slice()));
    let zcols = inst.columns(input, &term);
    let mut zrefs: Vec<&[f64]> = vec![&ones];
    zrefs.extend(zcols.iter().map(|c| c.as_slice()));
    let th = instrumental(&refs, &zrefs, r, rows)?;
    let mut f = FittedTerm { input, term, intercept: th[0], coefs: th[1..].to_vec() };
    let noise = (whiten > 0).then(|| noise_model(ctx, r, &f, rows, whiten)).flatten();
    if let Some(a) = &noise {
        let used = whitenable(rows, whiten);
        let filt = |x: &[f64]| -> Vec<f64> {
            let mut w = vec![0.0; x.len()];
            used.iter().for_each(|&t| w[t] = whitened(x, a, t));
            w
        };
        let wr = filt(r);
        let wc: Vec<Vec<f64>> = refs.iter().map(|c| filt(c)).collect();
        let wz: Vec<Vec<f64>> = zrefs.iter().map(|c| filt(c)).collect();
        let wc: Vec<&[f64]> = wc.iter().map(Vec::as_slice).collect();
        let wz: Vec<&[f64]> = wz.iter().map(Vec::as_slice).collect();
        if let Some(th) = instrumental(&wc, &wz, &wr, &used) {
            let level = rows
                .iter()
                .map(|&t| r[t] - cols.iter().zip(&th[1..]).map(|(c, b)| c[t] * b).sum::<f64>())
                .sum::<f64>()
                / rows.len() as f64;
            if level.is_finite() && th.iter().all(|v| v.is_finite()) {
                f.intercept = level;
                f.coefs = th[1..].to_vec();
            }
        }
    }
    if f.term.is_recursive() {
        // The linearised coefficient used the nominal simulation; refine its scale in simulation
        // mode on the same rows (a one-dimensional grid), re-centring the intercept each time.
        let base = f.coefs[0];
        let mut best: Option<(f64, FittedTerm)> = None;
        for m in [0.0, 0.25, 0.5, 0.75, 1.0, 1.25, 1.5, 2.0, 3.0] {
            let mut g = FittedTerm { intercept: 0.0, coefs: vec![base * m], ..f.clone() };
            let Some(c) = correction(ctx, &g) else { continue };
            g.intercept = rows.iter().map(|&t| r[t] - c[t]).sum::<f64>() / rows.len() as f64;
            let e: Vec<f64> = r.iter().zip(&c).map(|(a, b)| a - b - g.intercept).collect();
            let sse: f64 = match &noise {
                Some(a) => whitenable(rows, a.len()).iter().map(|&t| whitened(&e, a, t).powi(2)).sum(),
                None => rows.iter().map(|&t| e[t].powi(2)).sum(),
            };
            if best.as_ref().is_none_or(|b| sse < b.0) {
                best = Some((sse, g));
            }
        }
        f = best?.1;
    }
    Some(f)
}

/// Fits hypothesis `f` again on `rows`: its term's coefficients ([`fit_term`]), or, with `grid`
/// (see [`Scored::grid`]), the continuous values refined afresh from that grid term too
/// ([`refine`]).
pub fn fit_hypothesis(
    ctx: &OutputCtx,
    inst: &OutputCtx,
    r: &[f64],
    f: &FittedTerm,
    grid: Option<&Term>,
    rows: &[usize],
    whiten: usize,
) -> Option<FittedTerm> {
    match grid {
        Some(g) => refine(ctx, inst, r, f.input, g, rows, whiten),
        None => fit_term(ctx, inst, r, f.input, f.term.clone(), rows, whiten),
    }
}

/// Grid term `start` on `input`, fitted on `rows` with its continuous grid values
/// ([`Term::continuous`]) refined from `start`'s: by the least squares of what the correction
/// leaves of `r`, whitened by the start's AR noise model when `whiten > 0` (the prediction-error
/// currency), plain otherwise (open loop), with the one solver ([`minimize`]); every evaluation
/// fits the coefficients by [`fit_term`]. A grid spaces its thresholds by quantiles of the input,
/// and where the criterion is sharp in them (a narrow dead zone under a strong dither acts as
/// `−w·sign(u)`, so a width off by a tenth leaves a tenth of the effect) the nearest grid value
/// can lose to a free gain that the exact threshold beats. Values stay where the rows can speak
/// for them ([`admissible`]). When the refinement does not lower the criterion, `start`'s values
/// are kept, with their coefficients fitted on `rows`.
pub fn refine(
    ctx: &OutputCtx,
    inst: &OutputCtx,
    r: &[f64],
    input: usize,
    start: &Term,
    rows: &[usize],
    whiten: usize,
) -> Option<FittedTerm> {
    let start_fit = fit_term(ctx, inst, r, input, start.clone(), rows, whiten)?;
    let x0 = start.continuous();
    if x0.is_empty() || !admissible(ctx, input, rows, start) {
        return Some(start_fit);
    }
    let noise = (whiten > 0).then(|| noise_model(ctx, r, &start_fit, rows, whiten)).flatten();
    let used = noise.as_ref().map_or_else(|| rows.to_vec(), |a| whitenable(rows, a.len()));
    // What the correction leaves, in the criterion's currency, on the rows it is taken over.
    let criterion_residual = |f: &FittedTerm| -> Option<Vec<f64>> {
        let c = correction(ctx, f)?;
        let e: Vec<f64> = r.iter().zip(&c).map(|(a, b)| a - b).collect();
        Some(match &noise {
            Some(a) => used.iter().map(|&t| whitened(&e, a, t)).collect(),
            None => used.iter().map(|&t| e[t]).collect(),
        })
    };
    let residual = |x: &[f64]| -> Option<Vec<f64>> {
        let term = start.with_continuous(x).filter(|t| admissible(ctx, input, rows, t))?;
        criterion_residual(&fit_term(ctx, inst, r, input, term, rows, whiten)?)
    };
    let sse = |e: &[f64]| e.iter().map(|v| v * v).sum::<f64>();
    let start_sse = sse(&criterion_residual(&start_fit)?);
    let scale = 1e3 * (start_sse / used.len().max(1) as f64).sqrt().max(1e-12);
    let x = minimize(&residual, &x0, used.len(), scale);
    let refined = start
        .with_continuous(&x)
        .filter(|t| admissible(ctx, input, rows, t))
        .and_then(|t| fit_term(ctx, inst, r, input, t, rows, whiten))
        .filter(|f| criterion_residual(f).is_some_and(|e| sse(&e) < start_sse));
    Some(refined.unwrap_or(start_fit))
}

/// Whether a term's continuous values stay where `rows` can speak for them: thresholds, limits
/// and offsets inside the range the input (on the output side, the simulation) covers there,
/// widths and plays within that range's span, a time constant within 0.1–10 times the model's
/// (the grid spans 0.3–5), a pole of a missing coupling at most 0.99 (the grid's largest is
/// 0.95). Beyond them a limit never acts on the rows and its criterion is flat, and a width
/// past the span silences the channel.
fn admissible(ctx: &OutputCtx, input: usize, rows: &[usize], term: &Term) -> bool {
    let span = |x: &[f64]| {
        rows.iter().fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), &t| (lo.min(x[t]), hi.max(x[t])))
    };
    let (ulo, uhi) = span(&ctx.ut[input]);
    let (slo, shi) = span(&ctx.s);
    let in_u = |v: &f64| !v.is_finite() || (ulo..=uhi).contains(v);
    let in_s = |v: &f64| !v.is_finite() || (slo..=shi).contains(v);
    match term {
        Term::DeadZone { centre, w } => in_u(centre) && *w <= uhi - ulo,
        Term::SaturationIn { lo, hi } => in_u(lo) && in_u(hi),
        Term::SaturationOut { lo, hi } => in_s(lo) && in_s(hi),
        Term::Backlash(w) => *w <= uhi - ulo,
        Term::AbsSensor(o) => in_s(o),
        Term::TimeConstant { p0, p1 } => (0.1..=10.0).contains(&(p0.ln() / p1.ln())),
        Term::MissingCoupling { pole, .. } => *pole <= 0.99,
        _ => true,
    }
}

/// The AR(`p`) noise model of what `f`'s correction leaves of `r` on `rows`, its mean removed
/// (`None`: the correction cannot be simulated or too few rows).
fn noise_model(ctx: &OutputCtx, r: &[f64], f: &FittedTerm, rows: &[usize], p: usize) -> Option<Vec<f64>> {
    let c = correction(ctx, f)?;
    let e: Vec<f64> = r.iter().zip(&c).map(|(a, b)| a - b).collect();
    ar_fit(&centre_on(&e, rows), rows, p)
}

fn centre_on(x: &[f64], rows: &[usize]) -> Vec<f64> {
    let m = rows.iter().map(|&t| x[t]).sum::<f64>() / rows.len().max(1) as f64;
    x.iter().map(|v| v - m).collect()
}

/// Scores a fitted term on the validation rows: `n·ln(SSE/n) + penalty·k·ln(n)`.
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
    f: Option<FittedTerm>,
    fit_rows: &[usize],
    validate: std::ops::Range<usize>,
    penalty: f64,
) -> Option<Scored> {
    let (c, complexity) = match &f {
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
        Criterion::Prediction(order) => {
            let e: Vec<f64> = r.iter().zip(&c).map(|(a, b)| a - b).collect();
            let (sse, used) = prediction_sse(&e, order, fit_rows, validate.clone())?;
            n = used as f64;
            sse
        }
        Criterion::Plain | Criterion::Shifted(_) => validate.clone().map(|t| (r[t] - c[t]).powi(2)).sum(),
    };
    if !sse.is_finite() || n < 1.0 {
        return None;
    }
    let score = n * (sse / n).max(1e-300).ln() + penalty * complexity as f64 * n.ln();
    Some(Scored { fitted: f, sse, complexity, score, grid: None })
}

/// One-step prediction of `e` by an AR(`order`) model with a constant, fitted by least squares
/// on the rows of `fit_rows` whose `order` past samples are fit rows too (the folds' fit rows
/// are not contiguous: a row just after the validation block would otherwise regress on
/// validation samples). Returns the squared prediction error summed over the validation rows
/// from `order` on, and how many rows that sum covers.
pub fn prediction_sse(
    e: &[f64],
    order: usize,
    fit_rows: &[usize],
    validate: std::ops::Range<usize>,
) -> Option<(f64, usize)> {
    let lags: Vec<Vec<f64>> = (1..=order).map(|k| delayed(e, k)).collect();
    let ones = vec![1.0; e.len()];
    let mut cols: Vec<&[f64]> = vec![&ones];
    cols.extend(lags.iter().map(|c| c.as_slice()));
    let rows: Vec<usize> = whitenable(fit_rows, order).into_iter().filter(|&t| t < e.len()).collect();
    let th = least_squares_rows(&cols, e, &rows)?;
    let used: Vec<usize> = validate.filter(|&t| t >= order && t < e.len()).collect();
    let sse =
        used.iter().map(|&t| (e[t] - cols.iter().zip(&th).map(|(c, b)| c[t] * b).sum::<f64>()).powi(2)).sum();
    Some((sse, used.len()))
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
    // Each hypothesis: fitted and scored on every fold; its score is the sum over folds.
    let fold_score = |f: Option<&FittedTerm>, grid: Option<&Term>| -> Option<(f64, f64, usize)> {
        let mut total = (0.0, 0.0, 0);
        for (k, (fit_rows, val)) in split.folds.iter().enumerate() {
            let fitted = match f {
                Some(f) => Some(fit_hypothesis(ctx, inst, r, f, grid, fit_rows, split.whiten)?),
                None => None,
            };
            let crit = match (&split.features, &projectors, scoring_mode) {
                (None, _, _) => Criterion::Plain,
                (Some(_), Some(p), _) => Criterion::Projected(&p[k]),
                (Some(_), None, Scoring::Prediction) => Criterion::Prediction(PREDICTION_ORDER),
                (Some(_), None, _) => Criterion::Shifted(scoring),
            };
            let s = score(ctx, crit, r, fitted, fit_rows, val.clone(), penalty)?;
            total = (total.0 + s.score, total.1 + s.sse, s.complexity);
        }
        Some(total)
    };
    let fit_rows: Vec<usize> = split.fit.clone().collect();
    let mut out: Vec<Scored> = Vec::new();
    if let Some((score, sse, complexity)) = fold_score(None, None) {
        out.push(Scored { fitted: None, sse, complexity, score, grid: None });
    }
    // An output-side effect (a sensor map, an output clip, a force fed back from the output) is a
    // property of the output, not of one channel: it is tried once, through the flagged input
    // whose dither-driven response carries the most of this output's variance (its own
    // actuator). When two channels share their dynamics, the data cannot tell through which one
    // a fed-back force enters; trying it on every flagged input would let noise pick.
    let var_of = |x: &[f64]| {
        let rows = split.train.clone();
        let m = x[rows.clone()].iter().sum::<f64>() / rows.len().max(1) as f64;
        x[rows].iter().map(|v| (v - m).powi(2)).sum::<f64>()
    };
    let dominant = inputs
        .iter()
        .copied()
        .filter(|&i| ctx.has_channel[i])
        .max_by(|&a, &b| var_of(&inst.s_channel[a]).total_cmp(&var_of(&inst.s_channel[b])));
    for &i in inputs {
        let mut terms = grid(ctx, i, split.fit.clone());
        if dominant.is_some_and(|d| d != i) {
            terms.retain(|t| t.acts_on() == ActsOn::Input);
        }
        if ctx.has_channel[i] {
            terms.push(Term::Bilinear(Vec::new()));
        }
        let from = out.len();
        for t in terms {
            // The bilinear products are chosen once by FROLS on the fit rows, then kept fixed.
            let Some(f) = fit_term(ctx, inst, r, i, t, &fit_rows, split.whiten) else { continue };
            if let Some((score, sse, complexity)) = fold_score(Some(&f), None) {
                out.push(Scored { fitted: Some(f), sse, complexity, score, grid: None });
            }
        }
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
        for g in starts {
            let Some(f) = refine(ctx, inst, r, i, &g, &fit_rows, split.whiten) else { continue };
            if f.term == g {
                continue;
            }
            if let Some((score, sse, complexity)) = fold_score(Some(&f), Some(&g)) {
                out.push(Scored { fitted: Some(f), sse, complexity, score, grid: Some(g) });
            }
        }
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

    /// An AR(1) series with unit innovations: the one-step prediction error of a fitted AR model
    /// is the innovation, so the validation SSE per sample is 1 (closed form). With 10 000
    /// validation samples the mean of the squared innovations has a relative standard deviation
    /// of √(2/10 000) = 1.4 %, and the fit's own error adds O(order/n); 5 % is 3.5 standard
    /// deviations.
    #[test]
    fn prediction_error_of_an_ar1_series_is_its_innovation_variance() {
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(11);
        let mut x = 0.0;
        let e: Vec<f64> = (0..20_000)
            .map(|_| {
                let w: f64 = StandardNormal.sample(&mut rng);
                x = 0.9 * x + w;
                x
            })
            .collect();
        let fit: Vec<usize> = (0..10_000).collect();
        let (sse, used) = prediction_sse(&e, PREDICTION_ORDER, &fit, 10_000..20_000).unwrap();
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
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(12);
        let mut x = 0.0;
        let mut e: Vec<f64> = (0..30_000)
            .map(|_| {
                let w: f64 = StandardNormal.sample(&mut rng);
                x = 0.9 * x + w;
                x
            })
            .collect();
        for (k, v) in e[10_000..10_010].iter_mut().enumerate() {
            *v = if k % 2 == 0 { 1e6 } else { -1e6 };
        }
        let fit: Vec<usize> = (0..10_000).chain(10_010..20_000).collect();
        let (sse, used) = prediction_sse(&e, PREDICTION_ORDER, &fit, 20_000..30_000).unwrap();
        let per_sample = sse / used as f64;
        assert!((per_sample - 1.0).abs() < 0.05, "{per_sample}");
    }

    /// A gain error `r = b·x + v` on a white channel response `x` (the nominal is a pure delay of
    /// a white input, unit variance) under an AR(1) disturbance `v` of pole ρ = 0.98 and unit
    /// innovations, 1980 fit rows, seeds 1-20. Closed forms (x white, independent of v): the
    /// unfiltered estimate's standard deviation is `σ_v/(σ_x·√n)` = 5.0/√1980 = 0.113; after
    /// the whitening `x − ρx(t−1)` has variance `1 + ρ²`, so it is `1/√(1980·1.96)` = 0.016, a
    /// seventh. Every whitened estimate must lie within 5 of its standard deviations (0.08,
    /// leaving room for the AR(8) being estimated), and over the 20 seeds the unfiltered RMS
    /// error must be at least 3 times the whitened one (expected 7; each RMS over 20 seeds is
    /// known to about 16 %).
    #[test]
    fn whitened_coefficients_have_the_gls_variance() {
        let (n, b, rho) = (2000, 0.5, 0.98);
        let (mut plain, mut white) = (0.0, 0.0);
        for seed in 1..=20u64 {
            let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(seed);
            let u: Vec<f64> = (0..n).map(|_| StandardNormal.sample(&mut rng)).collect();
            let s: Vec<f64> = (0..n).map(|t| if t > 0 { u[t - 1] } else { 0.0 }).collect();
            let mut v = 0.0;
            let r: Vec<f64> = s
                .iter()
                .map(|x| {
                    let w: f64 = StandardNormal.sample(&mut rng);
                    v = rho * v + w;
                    b * x + v
                })
                .collect();
            let split = Split {
                features: None,
                fit: 20..n,
                train: 20..n,
                folds: Vec::new(),
                closed_loop: false,
                whiten: 0,
            };
            let ctx = crate::plan::output_ctx(&[&u], &s, &split);
            let rows: Vec<usize> = (20..n).collect();
            let est = |p: usize| fit_term(&ctx, &ctx, &r, 0, Term::Gain, &rows, p).unwrap().coefs[0];
            let (e0, e8) = (est(0) - b, est(PREDICTION_ORDER) - b);
            assert!(e8.abs() < 0.08, "seed {seed}: whitened estimate off by {e8}");
            plain += e0 * e0 / 20.0;
            white += e8 * e8 / 20.0;
        }
        assert!(
            plain.sqrt() > 3.0 * white.sqrt(),
            "RMS errors: unfiltered {} whitened {}",
            plain.sqrt(),
            white.sqrt()
        );
    }

    /// `fit_term`'s whitened step is generalised instrumental variables: the residual, the
    /// columns with the constant and the instruments through one AR(8) filter, fitted to the
    /// first fit's centred residual, on fold rows with a gap. Reproduced here from the
    /// primitives (`instrumental`, `ar_fit`, `whitenable`, `whitened`), so the two must agree to
    /// rounding (1e-9). Leaving the instruments unfiltered moves the estimate by far more than
    /// that (checked below), so the comparison can fail.
    #[test]
    fn the_whitened_fit_is_generalised_iv_on_the_rows_given() {
        let n = 1200;
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(5);
        let mut draw = || -> f64 { StandardNormal.sample(&mut rng) };
        let u: Vec<f64> = (0..n).map(|_| draw()).collect();
        let s: Vec<f64> = (0..n).map(|t| if t > 0 { u[t - 1] } else { 0.0 }).collect();
        let ud: Vec<f64> = u.iter().map(|v| 0.7 * v + 0.3 * draw()).collect();
        let mut v = 0.0;
        let r: Vec<f64> = s
            .iter()
            .map(|x| {
                v = 0.9 * v + draw();
                0.4 * x + v + 0.2
            })
            .collect();
        let split = Split {
            features: None,
            fit: 20..n,
            train: 20..n,
            folds: Vec::new(),
            closed_loop: false,
            whiten: 0,
        };
        let ctx = crate::plan::output_ctx(&[&u], &s, &split);
        let inst = crate::plan::instrument_ctx(&ctx, &[ud]);
        let rows: Vec<usize> = (20..500).chain(700..n).collect();
        let col = ctx.columns(0, &Term::Gain).remove(0);
        let zc = inst.columns(0, &Term::Gain).remove(0);
        let ones = vec![1.0; n];
        let th0 = instrumental(&[&ones, &col], &[&ones, &zc], &r, &rows).unwrap();
        let e: Vec<f64> = (0..n).map(|t| r[t] - th0[0] - th0[1] * col[t]).collect();
        let a = ar_fit(&centre_on(&e, &rows), &rows, PREDICTION_ORDER).unwrap();
        let used = whitenable(&rows, PREDICTION_ORDER);
        let w = |x: &[f64]| -> Vec<f64> {
            let mut o = vec![0.0; n];
            used.iter().for_each(|&t| o[t] = whitened(x, &a, t));
            o
        };
        let th = instrumental(&[&w(&ones), &w(&col)], &[&w(&ones), &w(&zc)], &w(&r), &used).unwrap();
        let intercept = rows.iter().map(|&t| r[t] - th[1] * col[t]).sum::<f64>() / rows.len() as f64;
        let f = fit_term(&ctx, &inst, &r, 0, Term::Gain, &rows, PREDICTION_ORDER).unwrap();
        assert!((f.coefs[0] - th[1]).abs() < 1e-9, "{} against {}", f.coefs[0], th[1]);
        assert!((f.intercept - intercept).abs() < 1e-9, "{} against {intercept}", f.intercept);
        let unfiltered_instruments =
            instrumental(&[&w(&ones), &w(&col)], &[&ones, &zc], &w(&r), &used).unwrap();
        assert!((unfiltered_instruments[1] - th[1]).abs() > 1e-6, "the check cannot tell the two apart");
    }

    /// A dead zone of half-width 0.3 about 0.1 on a uniform input, noise-free: refined from a
    /// grid value beside it, (0.0, 0.25), the fit reaches the exact values, where the corrected
    /// residual is zero and nowhere else. Reached exactly on this seed; the bound, 1e-4, is
    /// a tenth of the spacing between neighbouring input samples near the edges (1500 uniform
    /// samples on [−1, 1]), within which the criterion is smooth, so a miss by a grid step would
    /// fail it. A term with nothing continuous is fitted as it is.
    #[test]
    fn refinement_reaches_a_threshold_between_grid_values() {
        use rand::Rng;
        let n = 1500;
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(6);
        let u: Vec<f64> = (0..n).map(|_| rng.random_range(-1.0..1.0)).collect();
        let s: Vec<f64> = (0..n).map(|t| if t > 0 { u[t - 1] } else { 0.0 }).collect();
        let split = Split {
            features: None,
            fit: 20..n,
            train: 20..n,
            folds: Vec::new(),
            closed_loop: false,
            whiten: 0,
        };
        let ctx = crate::plan::output_ctx(&[&u], &s, &split);
        let r = ctx.columns(0, &Term::DeadZone { centre: 0.1, w: 0.3 }).remove(0);
        let rows: Vec<usize> = (20..n).collect();
        let f = refine(&ctx, &ctx, &r, 0, &Term::DeadZone { centre: 0.0, w: 0.25 }, &rows, 0).unwrap();
        let Term::DeadZone { centre, w } = f.term else { panic!("{:?}", f.term) };
        assert!((centre - 0.1).abs() < 1e-4 && (w - 0.3).abs() < 1e-4, "centre {centre}, half-width {w}");
        let gain = fit_term(&ctx, &ctx, &r, 0, Term::Gain, &rows, 0);
        assert_eq!(refine(&ctx, &ctx, &r, 0, &Term::Gain, &rows, 0), gain);
    }

    /// The refinement, whitened (the closed loop's path), on fold rows with a gap never reaches
    /// the gap: wild values there (±1e3 against an effect of order 0.1) leave the refined term
    /// exactly as it is with the true values there. The residual is a dead zone plus an AR(1)
    /// disturbance, so the whitening and the solver both have work to do.
    #[test]
    fn refinement_never_reaches_an_excluded_block() {
        use rand::Rng;
        let n = 1500;
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(7);
        let u: Vec<f64> = (0..n).map(|_| rng.random_range(-1.0..1.0)).collect();
        let s: Vec<f64> = (0..n).map(|t| if t > 0 { u[t - 1] } else { 0.0 }).collect();
        let split = Split {
            features: None,
            fit: 20..n,
            train: 20..n,
            folds: Vec::new(),
            closed_loop: false,
            whiten: 0,
        };
        let ctx = crate::plan::output_ctx(&[&u], &s, &split);
        let effect = ctx.columns(0, &Term::DeadZone { centre: 0.1, w: 0.3 }).remove(0);
        let mut v = 0.0;
        let r: Vec<f64> = effect
            .iter()
            .map(|x| {
                let w: f64 = StandardNormal.sample(&mut rng);
                v = 0.9 * v + 0.05 * w;
                x + v
            })
            .collect();
        let mut wild = r.clone();
        wild[600..800].iter_mut().enumerate().for_each(|(k, x)| *x = if k % 2 == 0 { 1e3 } else { -1e3 });
        let rows: Vec<usize> = (20..600).chain(800..n).collect();
        let start = Term::DeadZone { centre: 0.0, w: 0.25 };
        let a = refine(&ctx, &ctx, &r, 0, &start, &rows, PREDICTION_ORDER).unwrap();
        let b = refine(&ctx, &ctx, &wild, 0, &start, &rows, PREDICTION_ORDER).unwrap();
        assert_ne!(a.term, start, "the refinement did not move, so the test shows nothing");
        assert_eq!(a, b);
    }

    /// An offset sinusoid obeys an exact AR(2) recursion with a constant
    /// (`e_t = 2cos ω·e_{t−1} − e_{t−2} + c`), so it is predicted exactly.
    #[test]
    fn an_offset_sinusoid_is_predicted_exactly() {
        let e: Vec<f64> = (0..400).map(|t| (0.3 * t as f64).sin() + 0.1).collect();
        let fit: Vec<usize> = (0..200).collect();
        let (sse, _) = prediction_sse(&e, 2, &fit, 200..400).unwrap();
        assert!(sse < 1e-12, "{sse}");
    }
}
