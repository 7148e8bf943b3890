//! Fitting one hypothesis on given rows: a term's coefficients by instrumental variables (one
//! step of generalised least squares under the closed loop's noise model), and the continuous
//! grid values of a grid term refined by Levenberg–Marquardt. [`super::select`] ranks what these
//! fit; `decide` refits the winner.

use super::candidates::{OutputCtx, Term};
use super::frols::frols;
use super::simulate::{FittedTerm, correction};
use super::whiten::{ar_fit, whitenable, whitened};
use crate::minimize::minimize;
use mpmwatch_core::numerics::instrumental;

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

#[cfg(test)]
mod tests {
    use super::*;
    use crate::select::PREDICTION_ORDER;
    use rand::SeedableRng;
    use rand_distr::{Distribution, StandardNormal};

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
            let ctx = crate::plan::delay_ctx(&u, 1.0);
            let s = &ctx.s;
            let mut v = 0.0;
            let r: Vec<f64> = s
                .iter()
                .map(|x| {
                    let w: f64 = StandardNormal.sample(&mut rng);
                    v = rho * v + w;
                    b * x + v
                })
                .collect();
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
        let ctx = crate::plan::delay_ctx(&u, 1.0);
        let s = &ctx.s;
        let ud: Vec<f64> = u.iter().map(|v| 0.7 * v + 0.3 * draw()).collect();
        let mut v = 0.0;
        let r: Vec<f64> = s
            .iter()
            .map(|x| {
                v = 0.9 * v + draw();
                0.4 * x + v + 0.2
            })
            .collect();
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

    /// 1500 uniform samples on [−1, 1] drawn with `seed` through a one-sample delay, and the
    /// column of a dead zone of half-width 0.3 about 0.1 on them; the generator goes on.
    fn dead_zone_on_uniform(seed: u64) -> (OutputCtx, Vec<f64>, rand_chacha::ChaCha8Rng) {
        use rand::Rng;
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(seed);
        let u: Vec<f64> = (0..1500).map(|_| rng.random_range(-1.0..1.0)).collect();
        let ctx = crate::plan::delay_ctx(&u, 1.0);
        let effect = ctx.columns(0, &Term::DeadZone { centre: 0.1, w: 0.3 }).remove(0);
        (ctx, effect, rng)
    }

    /// A dead zone of half-width 0.3 about 0.1 on a uniform input, noise-free: refined from a
    /// grid value beside it, (0.0, 0.25), the fit reaches the exact values, where the corrected
    /// residual is zero and nowhere else. Reached exactly on this seed; the bound, 1e-4, is
    /// a tenth of the spacing between neighbouring input samples near the edges (1500 uniform
    /// samples on [−1, 1]), within which the criterion is smooth, so a miss by a grid step would
    /// fail it. A term with nothing continuous is fitted as it is.
    #[test]
    fn refinement_reaches_a_threshold_between_grid_values() {
        let (ctx, r, _) = dead_zone_on_uniform(6);
        let n = r.len();
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
        let (ctx, effect, mut rng) = dead_zone_on_uniform(7);
        let n = effect.len();
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
}
