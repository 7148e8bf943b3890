//! The plan of a diagnosis: which rows fit and which validate (the training part, its three
//! cross-validation folds, the held-out tail), whether the record was taken in a closed loop,
//! and the context every hypothesis of an output is stated in (the nominal model identified from
//! the simulation, its channels, and with a physical model the limits and gains it can re-run).

use mpmwatch_core::detect::Signal;
use mpmwatch_core::numerics::{lagged as delayed, least_squares, median};

use crate::candidates::OutputCtx;
use crate::error::DiagnoseError;
use crate::input::{DiagnoseInput, DiagnoseOptions, validate};
use crate::select::{PREDICTION_ORDER, Scoring, Split};
use crate::{nominal, physical};

/// What every later step reads: the rows, the residuals and the contexts.
pub(crate) struct Plan<'a> {
    /// The excitation of each input (the inputs themselves on an open-loop record).
    pub exc: Vec<Signal<'a>>,
    /// Samples in the training part; the held-out tail starts here.
    pub n_train: usize,
    /// The sample time, seconds.
    pub ts: f64,
    /// The training part's rows and folds, and whether the loop is closed.
    pub split: Split,
    /// Recorded minus simulated, per output, over the whole record.
    pub residuals: Vec<Vec<f64>>,
    /// The outputs whose residual varies on the training part (the others need no correction).
    pub testable: Vec<usize>,
    /// The recorded inputs.
    pub u_all: Vec<&'a [f64]>,
    /// The dither-driven part of each input (the input itself on an open-loop record).
    pub u_driven: Vec<Vec<f64>>,
    /// The context of each testable output, in the order of `testable`.
    pub ctxs: Vec<OutputCtx>,
    /// Per testable output, how many of its context's physical hypotheses (at their head) are
    /// state limits; the rest are actuator gains. Zero without a physical model.
    pub limits: Vec<usize>,
}

/// Checks the input and lays out the diagnosis.
pub(crate) fn plan<'a>(input: &DiagnoseInput<'a>, opts: &DiagnoseOptions) -> Result<Plan<'a>, DiagnoseError> {
    let checked = validate(input, opts)?;
    let (exc, n_train, ts) = (checked.exc, checked.n_train, checked.ts);
    let w0 = opts.warmup;
    let n_fit = w0 + (0.7 * (n_train - w0) as f64) as usize;
    let features =
        input.excitations.as_ref().map(|e| dither_features(&e.iter().map(|s| s.values).collect::<Vec<_>>()));
    // Three contiguous folds of the training part: each block validates a fit on the other two.
    let edges: Vec<usize> = (0..=3).map(|k| w0 + k * (n_train - w0) / 3).collect();
    let folds = (0..3)
        .map(|k| {
            let fit: Vec<usize> = (w0..n_train).filter(|&t| t < edges[k] || t >= edges[k + 1]).collect();
            (fit, edges[k]..edges[k + 1])
        })
        .collect();
    // Scored by prediction error (dithers given): coefficients fitted under the same noise model.
    let whiten = if features.is_some() && opts.scoring == Scoring::Prediction { PREDICTION_ORDER } else { 0 };
    let mut split = Split { features, fit: w0..n_fit, train: w0..n_train, folds, closed_loop: false, whiten };

    let residuals: Vec<Vec<f64>> = input
        .outputs
        .iter()
        .zip(&input.simulated)
        .map(|(y, s)| y.values.iter().zip(s.values).map(|(a, b)| a - b).collect())
        .collect();
    // Outputs whose residual is constant on the training part (a perfect simulation) cannot be
    // tested and need no correction.
    let testable: Vec<usize> = (0..residuals.len())
        .filter(|&j| mpmwatch_core::info::not_constant("residual", &residuals[j][..n_train]).is_ok())
        .collect();
    let u_all: Vec<&[f64]> = input.inputs.iter().map(|u| u.values).collect();
    let u_driven: Vec<Vec<f64>> = match &input.excitations {
        Some(e) => {
            let ev: Vec<&[f64]> = e.iter().map(|s| s.values).collect();
            u_all.iter().map(|u| dither_driven(u, &ev, split.train.clone())).collect()
        }
        None => u_all.iter().map(|u| u.to_vec()).collect(),
    };
    // Closed loop only when some input holds more than its excitations explain: an input that
    // is its own excitation (or a lagged linear image of the excitations) has no feedback path,
    // and there the plain validation FIT must rise for a finding, as in open loop.
    split.closed_loop = input.excitations.is_some()
        && u_all.iter().zip(&u_driven).any(|(u, d)| {
            let rows = split.train.clone();
            let var = |v: &[f64]| mpmwatch_core::numerics::std_dev(&v[rows.clone()], 0).powi(2);
            let rest: Vec<f64> = u.iter().zip(d).map(|(a, b)| a - b).collect();
            var(&rest) > CLOSED_LOOP_SHARE * var(u)
        });
    // The context (nominal model, channels) of every testable output.
    let mut ctxs: Vec<OutputCtx> =
        testable.iter().map(|&j| output_ctx(&u_all, input.simulated[j].values, &split)).collect();
    // A physical model's limits and actuator gains are hypotheses stated by re-running it; its
    // simulation is the one handed in (checked), so it is the nominal.
    let mut limits = vec![0; testable.len()];
    for (cv, &j) in testable.iter().enumerate() {
        let Some(m) = input.physical.get(j).copied().flatten() else { continue };
        let nominal = input.simulated[j].values;
        ctxs[cv].state_names = m.state_names();
        ctxs[cv].physical_terms = physical::limit_terms(m, nominal, split.train.clone());
        limits[cv] = ctxs[cv].physical_terms.len();
        ctxs[cv].physical_terms.extend(physical::gain_terms(m, nominal));
    }
    Ok(Plan { exc, n_train, ts, split, residuals, testable, u_all, u_driven, ctxs, limits })
}

/// Share of an input's variance that its excitations may leave unexplained before the loop
/// counts as closed: numerical noise only (an input equal to its excitation leaves about 1e-30).
const CLOSED_LOOP_SHARE: f64 = 1e-6;

/// For tests: an open-loop split that fits and trains on `rows`, with no folds.
#[cfg(test)]
pub(crate) fn open_split(rows: std::ops::Range<usize>) -> Split {
    Split { features: None, fit: rows.clone(), train: rows, folds: Vec::new(), closed_loop: false, whiten: 0 }
}

/// For tests: the context of one input whose nominal is a one-sample delay of gain `k`
/// (`s(t) = k·u(t−1)`), open loop, every row from 20 on a fit and training row.
#[cfg(test)]
pub(crate) fn delay_ctx(u: &[f64], k: f64) -> OutputCtx {
    let n = u.len();
    let s: Vec<f64> = (0..n).map(|t| if t > 0 { k * u[t - 1] } else { 0.0 }).collect();
    output_ctx(&[u], &s, &open_split(20..n))
}

/// The context of one output: centred inputs, the identified nominal model and its channels.
pub(crate) fn output_ctx(u: &[&[f64]], s: &[f64], split: &Split) -> OutputCtx {
    let model = nominal::identify(u, s, split.train.clone());
    let u0: Vec<f64> = u.iter().map(|x| median(&x[split.train.clone()])).collect();
    let ut: Vec<Vec<f64>> = u.iter().zip(&u0).map(|(x, m)| x.iter().map(|v| v - m).collect()).collect();
    let has_channel: Vec<bool> = (0..u.len()).map(|i| model.has_channel(i, u[i], s)).collect();
    let poly = nominal::identify_polynomial(u, s, split.train.clone(), &model);
    let u_range = ut
        .iter()
        .map(|x| {
            let train = &x[split.train.clone()];
            (
                train.iter().copied().fold(f64::INFINITY, f64::min),
                train.iter().copied().fold(f64::NEG_INFINITY, f64::max),
            )
        })
        .collect();
    let mut ctx = OutputCtx {
        y0: median(&s[split.train.clone()]),
        ut,
        u0,
        u_range,
        s: s.to_vec(),
        model,
        poly,
        has_channel,
        s_channel: Vec::new(),
        physical_terms: Vec::new(),
        state_names: Vec::new(),
    };
    ctx.s_channel = (0..u.len()).map(|i| ctx.channel_response(i, &ctx.ut[i])).collect();
    ctx
}

/// The dither-driven part of an input: its least-squares projection on the excitations at lags
/// 0..=30 (and a constant) over the training rows. The excitations are independent of the
/// disturbance, so this part is too; it is what the instruments are built from.
pub(crate) fn dither_driven(u: &[f64], exc: &[&[f64]], rows: std::ops::Range<usize>) -> Vec<f64> {
    let ones = vec![1.0; u.len()];
    let mut cols: Vec<Vec<f64>> = Vec::new();
    for e in exc {
        for l in 0..=30 {
            cols.push(delayed(e, l));
        }
    }
    let mut refs: Vec<&[f64]> = vec![&ones];
    refs.extend(cols.iter().map(|c| c.as_slice()));
    match least_squares(&refs, u, rows) {
        Some(th) => (0..u.len()).map(|t| refs.iter().zip(&th).map(|(c, b)| c[t] * b).sum()).collect(),
        None => u.to_vec(),
    }
}

/// Features of the dither history on which closed-loop scores are projected: a constant, each
/// dither at lags 0..=20, its square at lags 0..=4 (non-binary dithers), and products of its
/// lags 0..=4 (what an even nonlinearity makes of a binary dither).
pub(crate) fn dither_features(exc: &[&[f64]]) -> Vec<Vec<f64>> {
    let n = exc.first().map_or(0, |e| e.len());
    let mut z = vec![vec![1.0; n]];
    for e in exc {
        let lags: Vec<Vec<f64>> = (0..=20).map(|l| delayed(e, l)).collect();
        let amp = e.iter().fold(0.0f64, |m, v| m.max(v.abs()));
        let binary = e.iter().all(|v| (v.abs() - amp).abs() <= 1e-12 * amp);
        for a in 0..=4 {
            if !binary {
                z.push(lags[a].iter().map(|v| v * v).collect());
            }
            for b in a + 1..=4 {
                z.push(lags[a].iter().zip(&lags[b]).map(|(x, y)| x * y).collect());
            }
        }
        z.extend(lags);
    }
    z
}

/// The closed-loop scoring contexts: inputs = dither-driven part + the disturbance-driven part
/// (`u − u_d`) circularly shifted by 1/5, 2/5, 3/5 and 4/5 of the record.
pub(crate) fn scoring_ctxs(ctx: &OutputCtx, u: &[&[f64]], u_driven: &[Vec<f64>]) -> Vec<OutputCtx> {
    let n = u.first().map_or(0, |x| x.len());
    (1..=4)
        .map(|k| {
            let shift = k * n / 5;
            let uk: Vec<Vec<f64>> = u
                .iter()
                .zip(u_driven)
                .map(|(x, d)| (0..n).map(|t| d[t] + (x[(t + shift) % n] - d[(t + shift) % n])).collect())
                .collect();
            instrument_ctx(ctx, &uk)
        })
        .collect()
}

/// The instrument context: `ctx` with the dither-driven inputs in place of the recorded ones,
/// and the model's response to them in place of the simulated output.
pub(crate) fn instrument_ctx(ctx: &OutputCtx, u_driven: &[Vec<f64>]) -> OutputCtx {
    let ut: Vec<Vec<f64>> =
        u_driven.iter().zip(&ctx.u0).map(|(x, m)| x.iter().map(|v| v - m).collect()).collect();
    let s_channel: Vec<Vec<f64>> = (0..ut.len()).map(|i| ctx.channel_response(i, &ut[i])).collect();
    // The level: the model's output at the operating point, `s − Σ s_ji` (constant for a linear
    // model; its mean otherwise). Not the median of `s`: with a skewed input (a loop working
    // against an |x| sensor) the two differ, measured by 0.33 on casebook case c23, which put
    // every output-side hypothesis (a sensor map, a clip, a fed-back force) at the wrong level.
    let n = ctx.s.len().max(1) as f64;
    let level =
        (0..ctx.s.len()).map(|t| ctx.s[t] - ctx.s_channel.iter().map(|c| c[t]).sum::<f64>()).sum::<f64>() / n;
    let mut s = vec![level; ctx.s.len()];
    for c in &s_channel {
        s.iter_mut().zip(c).for_each(|(a, b)| *a += b);
    }
    OutputCtx { ut, s_channel, s, ..ctx.clone() }
}
