//! Grey-box hypotheses: each is a model structure, linear dynamics re-estimated from the record
//! composed with one physics element where it acts (a static map on an input, a map on the
//! output, a force fed back from the output), fitted by minimising the simulation error (open
//! loop) or, on a dithered record, the one-step prediction error under an AR noise model
//! (closed loop, [`Data::noise_order`]). A re-fitted linear model always competes: a physics
//! element is named only when it beats the best linear structure out of sample.
//!
//! The structure of every hypothesis, with `w_s` the signals the element makes of the inputs
//! (the inputs themselves for a linear model) and `f_m` the forces it feeds back:
//!
//! ```text
//! x(t) = Σ_k α_k x(t−k) + Σ_s Σ_k β_sk w_s(t−nk_s−k) + Σ_m γ_m f_m(x(t−1), x(t−2)) + c
//! ŷ(t) = g(x(t))            (the element's output map; the identity for most)
//! ```
//!
//! Fitting (see [`fit`]): least squares on the equation error gives the start (the recorded
//! output stands in for `x` on the rows where the output map is invertible), then
//! Levenberg–Marquardt (`levenberg-marquardt`) minimises the simulation error over every
//! coefficient and the element's own parameters (a width, a limit), from each of the
//! element's starting values, then on a dithered record the noise model's coefficients join
//! the search. Choice (see [`explain`]): blocked cross-validation inside the training part,
//! scored in simulation mode, the currency the held-out FIT is reported in (on a dithered
//! record ranked by the cross-validated prediction error, gated by the simulation's FIT).

mod abs_sensor;
mod backlash;
mod bilinear;
mod clip_sensor;
mod dead_zone;
mod explain;
mod friction;
mod linear;
mod polynomial;
mod saturation;
mod stiffness;
mod storage_limit;
mod structure;

use std::collections::BTreeMap;

use crate::minimize::minimize;

use super::candidates::{ActsOn, Physics};
use super::fitness::fit_pct;
use mpmwatch_core::numerics::{least_squares_rows, median, quantile};

/// The record an element is fitted to: inputs, output and the training rows' summaries the
/// elements start from.
#[derive(Debug, Clone)]
pub struct Data<'a> {
    /// Inputs.
    pub u: Vec<&'a [f64]>,
    /// Recorded output.
    pub y: &'a [f64],
    /// Training rows (the held-out tail is after them and never seen).
    pub train: std::ops::Range<usize>,
    /// The nominal simulation, when there is one: what the user's model says the output does,
    /// a start for what the recorded output cannot show (a direction).
    pub nominal: Option<&'a [f64]>,
    /// Order of the autoregressive noise model the fit assumes: 0 fits by simulation (output)
    /// error, right in open loop; above 0 the simulation error `e` is modelled as
    /// `e(t) = Σ_k a_k e(t−k) + ε(t)` and the one-step prediction error `ε` minimised, which in a
    /// closed loop (inputs correlated with the disturbance through the controller) keeps the
    /// dynamics from absorbing the disturbance's colour (the direct prediction-error method).
    pub noise_order: usize,
}

impl Data<'_> {
    /// Quantile `q` of input `i` on the training rows.
    pub fn u_quantile(&self, i: usize, q: f64) -> f64 {
        quantile(&self.u[i][self.train.clone()], q)
    }

    /// Quantile `q` of the output on the training rows.
    pub fn y_quantile(&self, q: f64) -> f64 {
        quantile(&self.y[self.train.clone()], q)
    }

    /// Median of the output on the training rows.
    pub fn y_median(&self) -> f64 {
        median(&self.y[self.train.clone()])
    }
}

/// One physics element composed with linear dynamics. Every class is one file implementing it.
pub trait Element: Sync {
    /// The vocabulary class.
    fn physics(&self) -> Physics;
    /// Where it acts.
    fn acts_on(&self) -> ActsOn;
    /// Starting values of the element's own parameters (empty vector: it has none), acting on
    /// input `i`.
    fn starts(&self, d: &Data<'_>, i: usize) -> Vec<Vec<f64>>;
    /// How many leading parameters of every start are set from the training rows and kept as
    /// they are by the fit (a polynomial's centre, scale and range): not free, so not counted
    /// in the element's complexity either. 0 by default.
    fn fixed(&self) -> usize {
        0
    }
    /// The signals the linear dynamics see, each with its own numerator: by default the inputs.
    /// `i` is the input the element acts on.
    fn signals(&self, _p: &[f64], u: &[&[f64]], _i: usize) -> Vec<Vec<f64>> {
        u.iter().map(|x| x.to_vec()).collect()
    }
    /// Forces fed back from the simulated output (`x(t−1)`, `x(t−2)`).
    fn feedback(&self, _p: &[f64], _x1: f64, _x2: f64, _out: &mut Vec<f64>) {}
    /// How many forces [`Element::feedback`] returns.
    fn feedbacks(&self) -> usize {
        0
    }
    /// The output map `g`.
    fn output(&self, _p: &[f64], x: f64) -> f64 {
        x
    }
    /// Whether the recorded output at a row can stand in for `x` (the output map is the
    /// identity there), for the equation-error start.
    fn invertible(&self, _p: &[f64], _y: f64) -> bool {
        true
    }
    /// Whether the record can tell this element on input `i` from the others at all (a
    /// product of successive samples is the square on an input that barely moves between
    /// samples); an element that cannot be told apart is not tried.
    fn identifiable(&self, _d: &Data<'_>, _i: usize) -> bool {
        true
    }
    /// What stands in for `x` in the equation-error start when the output map loses
    /// information the recorded output cannot give back (a sign): one start per stand-in.
    /// Empty: the recorded output itself.
    fn stand_ins(&self, _d: &Data<'_>, _i: usize, _p: &[f64]) -> Vec<Vec<f64>> {
        Vec::new()
    }
    /// A sentence and the parameters, for the report.
    fn describe(&self, p: &[f64], input: &str, output: &str) -> (String, BTreeMap<String, f64>);
    /// The element's static map at `v`, for its figure: what the dynamics see of an input `v`
    /// (input elements), the reading of a true value `v` (output elements), the force for a
    /// motion `v` weighted by the fitted feedback coefficients `gamma` (feedback elements).
    /// `None`: no single-valued map of its own (backlash is a loop; a polynomial's map lives in
    /// the numerator coefficients, [`Element::map_from_gains`]).
    fn map_at(&self, _p: &[f64], _gamma: &[f64], _v: f64) -> Option<f64> {
        None
    }
    /// The static map at `v` for an element whose map lives in the numerators (a polynomial):
    /// `dc[s]` is the steady-state gain of signal `s` of [`Element::signals`], `p` the fitted
    /// parameters, `i` the input the element acts on. A map and a linear gain are only determined
    /// together, up to a scale and an offset, so the map is drawn with unit slope at the
    /// input's mean (where it meets the identity the nominal assumes). `None` by default.
    fn map_from_gains(&self, _p: &[f64], _dc: &[f64], _i: usize, _v: f64) -> Option<f64> {
        None
    }
    /// For an element with memory, which has no single-valued map: what the dynamics see of an
    /// input that follows `sweep`, for its figure (backlash draws its loop). `None` by default.
    fn trace(&self, _p: &[f64], _sweep: &[f64]) -> Option<Vec<f64>> {
        None
    }
    /// What [`Element::map_at`] maps: the argument's name and range, and the value's name.
    fn map_axes(&self, d: &Data<'_>, i: usize, input: &str, output: &str) -> (String, (f64, f64), String) {
        match self.acts_on() {
            ActsOn::Input => (
                input.to_string(),
                (d.u_quantile(i, 0.0), d.u_quantile(i, 1.0)),
                format!("what the dynamics see of {input}"),
            ),
            ActsOn::Output => (
                format!("true {output}"),
                (d.y_quantile(0.0), d.y_quantile(1.0)),
                format!("{output} as measured"),
            ),
        }
    }
}

/// A fitted element drawn as what it is: its static map over the range the record visits, the
/// loop an element with memory traces over that range, or, for a linear change, the channel's
/// re-fitted step response beside the model's.
#[derive(Debug, Clone, PartialEq)]
pub struct ElementCurve {
    /// The element's class.
    pub physics: Physics,
    /// Name of the map's argument.
    pub x_label: String,
    /// Name of its value.
    pub y_label: String,
    /// The map, 201 points over the range; for an element with memory, its loop (401 points,
    /// down the range and up again).
    pub points: Vec<(f64, f64)>,
    /// What the nominal assumes in its place: the identity for a map on a signal, no force
    /// for a feedback element, the model's own step response for a linear change.
    pub baseline: Vec<(f64, f64)>,
    /// Legend of `points`.
    pub label: String,
    /// Legend of `baseline`.
    pub baseline_label: String,
}

impl Model<'_> {
    /// The fitted element's map ([`Element::map_at`], [`Element::map_from_gains`]) or loop
    /// ([`Element::trace`]) over its range, `None` when it has none.
    pub fn curve(&self, f: &Fitted, d: &Data<'_>, input: &str, output: &str) -> Option<ElementCurve> {
        let sig = self.element.signals(&f.p, &d.u, self.input).len();
        let g0 = self.orders.na + sig * self.orders.nb;
        let gamma = &f.theta[g0..g0 + self.element.feedbacks()];
        let (x_label, (lo, hi), y_label) = self.element.map_axes(d, self.input, input, output);
        let pad = 0.1 * (hi - lo).max(1e-12);
        let at = |k: usize| lo - pad + (hi - lo + 2.0 * pad) * k as f64 / 200.0;
        // An element with memory is driven up, down and up again over the range; the last two
        // legs, which start from a state the first leg has set, close its loop.
        let sweep: Vec<f64> = (0..=200).chain((0..200).rev()).chain(1..=200).map(at).collect();
        if let Some(out) = self.element.trace(&f.p, &sweep) {
            let points: Vec<(f64, f64)> = sweep.iter().copied().zip(out).skip(200).collect();
            let baseline = points.iter().map(|&(v, _)| (v, v)).collect();
            return Some(ElementCurve::against_the_model(
                self.element.physics(),
                x_label,
                y_label,
                points,
                baseline,
            ));
        }
        // Steady-state gain of each signal's numerator through the poles.
        let (na, nb) = (self.orders.na, self.orders.nb);
        let poles = 1.0 - f.theta[..na].iter().sum::<f64>();
        let dc: Vec<f64> =
            (0..sig).map(|s| f.theta[na + s * nb..na + (s + 1) * nb].iter().sum::<f64>() / poles).collect();
        let points = (0..=200)
            .map(|k| {
                let v = at(k);
                self.element
                    .map_at(&f.p, gamma, v)
                    .or_else(|| self.element.map_from_gains(&f.p, &dc, self.input, v))
                    .map(|m| (v, m))
            })
            .collect::<Option<Vec<_>>>()?;
        let fed_back = self.element.feedbacks() > 0;
        let baseline = points.iter().map(|&(v, _)| (v, if fed_back { 0.0 } else { v })).collect();
        Some(ElementCurve::against_the_model(self.element.physics(), x_label, y_label, points, baseline))
    }
}

impl ElementCurve {
    /// A fitted element's curve beside what the nominal assumes without it.
    fn against_the_model(
        physics: Physics,
        x_label: String,
        y_label: String,
        points: Vec<(f64, f64)>,
        baseline: Vec<(f64, f64)>,
    ) -> Self {
        Self {
            physics,
            x_label,
            y_label,
            points,
            baseline,
            label: format!("fitted {}", physics.name()),
            baseline_label: "nominal (without it)".into(),
        }
    }
}

/// The inputs with input `i` replaced by `map` of it: what an element on one input makes of
/// the inputs.
pub fn map_input(u: &[&[f64]], i: usize, map: impl FnOnce(&[f64]) -> Vec<f64>) -> Vec<Vec<f64>> {
    let mut out: Vec<Vec<f64>> = u.iter().map(|x| x.to_vec()).collect();
    out[i] = map(u[i]);
    out
}

/// The linear part's orders: `na` poles, and per input `nb` numerator taps after `nk` samples.
#[derive(Debug, Clone, PartialEq)]
pub struct Orders {
    /// Poles.
    pub na: usize,
    /// Numerator taps per signal.
    pub nb: usize,
    /// Dead time per input, samples.
    pub nk: Vec<usize>,
}

/// A fitted hypothesis: element parameters and the coefficients of the structure.
#[derive(Debug, Clone)]
pub struct Fitted {
    /// The element's own parameters.
    pub p: Vec<f64>,
    /// `α`, then `β` per signal, then `γ`, then `c`.
    pub theta: Vec<f64>,
    /// The AR noise model of a prediction-error fit, `e(t) = Σ_k a_k e(t−k) + ε(t)` for the
    /// simulation error `e`; empty for an output-error fit (white noise).
    pub noise: Vec<f64>,
}

/// A structure ready to simulate: an element on input `input`, with orders.
pub struct Model<'e> {
    /// The element.
    pub element: &'e dyn Element,
    /// The input it acts on.
    pub input: usize,
    /// The linear part's orders.
    pub orders: Orders,
}

impl Model<'_> {
    fn signals(&self, p: &[f64], u: &[&[f64]]) -> (Vec<Vec<f64>>, Vec<usize>) {
        let sig = self.element.signals(p, u, self.input);
        // The signals beyond the inputs (a polynomial's powers) are of the element's input and
        // share its dead time.
        let nk: Vec<usize> = (0..sig.len())
            .map(|s| if s < u.len() { self.orders.nk[s] } else { self.orders.nk[self.input] })
            .collect();
        (sig, nk)
    }

    /// Coefficients in `theta`.
    fn n_theta(&self, signals: usize) -> usize {
        self.orders.na + signals * self.orders.nb + self.element.feedbacks() + 1
    }

    /// The first row every lag is inside the record.
    fn first_row(&self, nk: &[usize]) -> usize {
        let nkmax = nk.iter().copied().max().unwrap_or(0);
        self.orders.na.max(nkmax + self.orders.nb).max(2)
    }

    /// Simulation of the output over the whole record, from the recorded output's first
    /// samples as initial conditions. `None` when it diverges.
    pub fn simulate(&self, f: &Fitted, u: &[&[f64]], y: &[f64]) -> Option<Vec<f64>> {
        // An optimiser step may leave a parameter non-finite; the maps (a clamp) must not see it.
        if f.p.iter().chain(&f.theta).any(|v| !v.is_finite()) {
            return None;
        }
        let (sig, nk) = self.signals(&f.p, u);
        let n = y.len();
        let o = &self.orders;
        let first = self.first_row(&nk).min(n);
        let mut x: Vec<f64> = y[..first].to_vec();
        x.resize(n, 0.0);
        let scale = 1.0 + y.iter().fold(0.0f64, |m, v| m.max(v.abs()));
        let bound = 1e3 * scale;
        let nf = self.element.feedbacks();
        let fb0 = o.na + sig.len() * o.nb;
        let mut fb = Vec::with_capacity(nf);
        for t in first..n {
            let mut v = f.theta[f.theta.len() - 1];
            for k in 1..=o.na {
                v += f.theta[k - 1] * x[t - k];
            }
            for (s, w) in sig.iter().enumerate() {
                for k in 0..o.nb {
                    v += f.theta[o.na + s * o.nb + k] * w[t - nk[s] - k];
                }
            }
            if nf > 0 {
                fb.clear();
                self.element.feedback(&f.p, x[t - 1], x[t - 2], &mut fb);
                for (m, g) in fb.iter().enumerate() {
                    v += f.theta[fb0 + m] * g;
                }
            }
            if !v.is_finite() || v.abs() > bound {
                return None;
            }
            x[t] = v;
        }
        // The first rows are the recorded start, not predictions: they are returned as
        // recorded (an output map applied to them would count an |x| sensor's offset twice).
        Some(
            x.iter()
                .enumerate()
                .map(|(t, &v)| if t < first { y[t] } else { self.element.output(&f.p, v) })
                .collect(),
        )
    }

    /// The equation-error least-squares fit of the coefficients, the element's parameters
    /// fixed at `p`, on `rows` where the output map is invertible; `y` is the recorded output
    /// or what stands in for `x`.
    fn equation_error(&self, p: &[f64], u: &[&[f64]], y: &[f64], rows: &[usize]) -> Option<Fitted> {
        let (sig, nk) = self.signals(p, u);
        let o = &self.orders;
        let first = self.first_row(&nk);
        let n = y.len();
        let mut cols: Vec<Vec<f64>> = Vec::new();
        let lagged = |x: &[f64], k: usize| -> Vec<f64> {
            (0..n).map(|t| if t >= k { x[t - k] } else { x[0] }).collect()
        };
        for k in 1..=o.na {
            cols.push(lagged(y, k));
        }
        for (s, w) in sig.iter().enumerate() {
            for k in 0..o.nb {
                cols.push(lagged(w, nk[s] + k));
            }
        }
        let nf = self.element.feedbacks();
        if nf > 0 {
            let mut f = vec![vec![0.0; n]; nf];
            let mut buf = Vec::with_capacity(nf);
            for t in 2..n {
                buf.clear();
                self.element.feedback(p, y[t - 1], y[t - 2], &mut buf);
                for (m, g) in buf.iter().enumerate() {
                    f[m][t] = *g;
                }
            }
            cols.extend(f);
        }
        cols.push(vec![1.0; n]);
        let ok = |t: usize| (0..=o.na).all(|k| t >= k && self.element.invertible(p, y[t - k]));
        let used: Vec<usize> = rows.iter().copied().filter(|&t| t >= first && ok(t)).collect();
        if used.len() < 3 * cols.len() {
            return None;
        }
        let refs: Vec<&[f64]> = cols.iter().map(Vec::as_slice).collect();
        let theta = least_squares_rows(&refs, y, &used)?;
        debug_assert_eq!(theta.len(), self.n_theta(sig.len()));
        Some(Fitted { p: p.to_vec(), theta, noise: Vec::new() })
    }
}

/// Fits a model on `rows` by simulation error: the equation-error start at each of the
/// element's starting values, refined by Levenberg–Marquardt; the fit with the least
/// simulation error on `rows` wins; with a noise model (`d.noise_order` above 0) it is then
/// refined by its prediction error ([`prediction_error_fit`]). `None` when no start gives a
/// stable simulation.
pub fn fit(model: &Model<'_>, d: &Data<'_>, rows: &[usize]) -> Option<Fitted> {
    let mut starts = model.element.starts(d, model.input);
    if starts.is_empty() {
        starts.push(Vec::new());
    }
    let scale = mpmwatch_core::numerics::std_dev(&d.y[d.train.clone()], 0).max(1e-12);
    let sse = |f: &Fitted| -> Option<f64> {
        let s = model.simulate(f, &d.u, d.y)?;
        let e: f64 = rows.iter().map(|&t| (s[t] - d.y[t]).powi(2)).sum();
        e.is_finite().then_some(e)
    };
    let mut best: Option<(f64, Fitted)> = None;
    let tries = starts.into_iter().flat_map(|p| {
        let mut targets = model.element.stand_ins(d, model.input, &p);
        if targets.is_empty() {
            targets.push(d.y.to_vec());
        }
        targets.into_iter().map(move |t| (p.clone(), t))
    });
    for (p, target) in tries {
        let Some(start) = model.equation_error(&p, &d.u, &target, rows) else { continue };
        let mut candidates = vec![start.clone()];
        let (fixed, free) = p.split_at(model.element.fixed().min(p.len()));
        let n_p = free.len();
        // The element's fixed leading parameters stay; the free ones and θ are searched.
        let fitted = |x: &[f64]| Fitted {
            p: fixed.iter().chain(&x[..n_p]).copied().collect(),
            theta: x[n_p..].to_vec(),
            noise: Vec::new(),
        };
        let residual = |x: &[f64]| -> Option<Vec<f64>> {
            let s = model.simulate(&fitted(x), &d.u, d.y)?;
            Some(rows.iter().map(|&t| s[t] - d.y[t]).collect())
        };
        let x0: Vec<f64> = free.iter().chain(&start.theta).copied().collect();
        // A simulation that diverges from the equation-error start has nothing to refine.
        if sse(&start).is_some() {
            candidates.push(fitted(&minimize(&residual, &x0, rows.len(), 1e3 * scale)));
        }
        for c in candidates {
            if let Some(e) = sse(&c)
                && best.as_ref().is_none_or(|b| e < b.0)
            {
                best = Some((e, c));
            }
        }
    }
    let best = best.map(|b| b.1)?;
    if d.noise_order == 0 {
        return Some(best);
    }
    Some(prediction_error_fit(model, d, rows, best, scale))
}

/// The rows of `rows` whose `p` predecessors are rows too: where a whitening filter of order
/// `p` reaches no excluded block.
fn whitenable(rows: &[usize], p: usize) -> Vec<usize> {
    let inside: std::collections::HashSet<usize> = rows.iter().copied().collect();
    rows.iter().copied().filter(|&t| t >= p && (1..=p).all(|k| inside.contains(&(t - k)))).collect()
}

/// The AR(`p`) model `e(t) = Σ_k a_k e(t−k) + ε(t)` of `e` by least squares on `rows` (each
/// with its `p` predecessors); `None` when too few rows or the fit fails, empty for `p = 0`.
fn ar_fit(e: &[f64], rows: &[usize], p: usize) -> Option<Vec<f64>> {
    if p == 0 {
        return Some(Vec::new());
    }
    let used = whitenable(rows, p);
    if used.len() < 10 * p {
        return None;
    }
    let lagged: Vec<Vec<f64>> =
        (1..=p).map(|k| (0..e.len()).map(|t| if t >= k { e[t - k] } else { 0.0 }).collect()).collect();
    let refs: Vec<&[f64]> = lagged.iter().map(Vec::as_slice).collect();
    least_squares_rows(&refs, e, &used)
}

/// The one-step prediction error at `t` of a simulation error `e` under the AR noise model `a`
/// (`t` must have `a.len()` predecessors).
fn whitened(e: &[f64], a: &[f64], t: usize) -> f64 {
    e[t] - a.iter().enumerate().map(|(k, ak)| ak * e[t - k - 1]).sum::<f64>()
}

/// The prediction-error refinement of an output-error fit `start`: an AR noise model of order
/// `d.noise_order` fitted to its simulation error gives the start of the noise coefficients,
/// then they, every coefficient and the element's free parameters are searched together for
/// the least one-step prediction error on the rows of `rows` the whitening can use
/// ([`whitenable`]: it reaches no excluded block). The start is returned when the refinement
/// cannot simulate.
fn prediction_error_fit(
    model: &Model<'_>,
    d: &Data<'_>,
    rows: &[usize],
    start: Fitted,
    scale: f64,
) -> Fitted {
    let p = d.noise_order;
    let used = whitenable(rows, p);
    if used.len() < 3 * (p + start.theta.len()) {
        return start;
    }
    let Some(s0) = model.simulate(&start, &d.u, d.y) else { return start };
    let e0: Vec<f64> = s0.iter().zip(d.y).map(|(a, b)| a - b).collect();
    let Some(ar) = ar_fit(&e0, rows, p) else { return start };
    let (fixed, free) = start.p.split_at(model.element.fixed().min(start.p.len()));
    let (n_p, n_theta) = (free.len(), start.theta.len());
    let fitted = |x: &[f64]| Fitted {
        p: fixed.iter().chain(&x[..n_p]).copied().collect(),
        theta: x[n_p..n_p + n_theta].to_vec(),
        noise: x[n_p + n_theta..].to_vec(),
    };
    let residual = |x: &[f64]| -> Option<Vec<f64>> {
        let s = model.simulate(&fitted(x), &d.u, d.y)?;
        let e: Vec<f64> = s.iter().zip(d.y).map(|(a, b)| a - b).collect();
        Some(used.iter().map(|&t| whitened(&e, &x[n_p + n_theta..], t)).collect())
    };
    let x0: Vec<f64> = free.iter().chain(&start.theta).chain(&ar).copied().collect();
    let x = minimize(&residual, &x0, used.len(), 1e3 * scale);
    if x.iter().any(|v| !v.is_finite()) {
        return start;
    }
    let f = fitted(&x);
    if model.simulate(&f, &d.u, d.y).is_some() { f } else { start }
}

/// The classes, in the order of their parsimony (a later class must beat an earlier one by
/// the margin to be preferred at equal fit).
pub fn elements() -> Vec<Box<dyn Element>> {
    vec![
        Box::new(dead_zone::DeadZone),
        Box::new(saturation::InputSaturation),
        Box::new(storage_limit::StorageLimit),
        Box::new(clip_sensor::ClipSensor),
        Box::new(abs_sensor::AbsSensor),
        Box::new(polynomial::Polynomial { degree: 2 }),
        Box::new(bilinear::Bilinear),
        Box::new(stiffness::CubicStiffness),
        Box::new(friction::Coulomb { on_change: false }),
        Box::new(friction::Coulomb { on_change: true }),
        Box::new(backlash::Backlash),
        Box::new(polynomial::Polynomial { degree: 3 }),
    ]
}

pub use explain::{Names, explain};
pub use linear::Linear;
pub use structure::{FittedGreyBox, GreyBox, Structure};

/// FIT% on each validation block of the folds, each block against its own mean as the held-out
/// tail is scored, and their mean (the ranking score in open loop); with the RMS of the one-step
/// prediction error on each block (the ranking currency on a dithered record, see
/// [`CvScore::prediction_gain_over`]).
#[derive(Debug, Clone, PartialEq)]
pub struct CvScore {
    /// The mean of `blocks`.
    pub mean: f64,
    /// FIT% per validation block, in the folds' order.
    pub blocks: Vec<f64>,
    /// RMS of the one-step prediction error per validation block under the fit's noise model
    /// (the simulation error itself for an output-error fit), in the order of `blocks`.
    pub prediction_rms: Vec<f64>,
}

impl CvScore {
    fn of(blocks: Vec<f64>, prediction_rms: Vec<f64>) -> Self {
        // No block to score is no score (NaN fails every comparison).
        let mean =
            if blocks.is_empty() { f64::NAN } else { blocks.iter().sum::<f64>() / blocks.len() as f64 };
        CvScore { mean, blocks, prediction_rms }
    }

    /// The smallest block-by-block gain over `base` (+∞ without blocks).
    pub fn min_gain_over(&self, base: &CvScore) -> f64 {
        self.blocks.iter().zip(&base.blocks).map(|(a, b)| a - b).fold(f64::INFINITY, f64::min)
    }

    /// How much smaller the one-step prediction error is than `base`'s, percent of `base`'s
    /// RMS, averaged over the blocks (NaN without blocks). In a closed loop the disturbance
    /// dominates a simulation's error and every candidate's FIT alike; the prediction error,
    /// with the disturbance's colour removed by each fit's noise model, is the currency the
    /// fits were made in and separates candidates by what they explain of the plant.
    pub fn prediction_gain_over(&self, base: &CvScore) -> f64 {
        // A base that predicts a block perfectly leaves nothing to gain: 0 for a candidate as
        // perfect, −∞ for any other (never NaN, which no comparison would rank).
        let g: Vec<f64> = self
            .prediction_rms
            .iter()
            .zip(&base.prediction_rms)
            .map(|(a, b)| 100.0 * (b - a) / b.max(f64::MIN_POSITIVE))
            .collect();
        if g.is_empty() { f64::NAN } else { g.iter().sum::<f64>() / g.len() as f64 }
    }

    /// The score candidates are ranked by, against the nominal's `base`: the mean FIT for an
    /// output-error fit (`noise_order` 0, open loop), the prediction gain for a
    /// prediction-error fit (a dithered record).
    pub fn rank(&self, base: &CvScore, noise_order: usize) -> f64 {
        if noise_order > 0 { self.prediction_gain_over(base) } else { self.mean }
    }
}

/// RMS over `block` of the one-step prediction error of a simulation `s` of `y` under the AR
/// noise model `a` (the first `a.len()` rows of the record have no prediction and are skipped).
fn prediction_rms(s: &[f64], y: &[f64], a: &[f64], block: std::ops::Range<usize>) -> f64 {
    let e: Vec<f64> = s.iter().zip(y).map(|(a, b)| a - b).collect();
    let rows = block.start.max(a.len())..block.end;
    let n = rows.len().max(1) as f64;
    (rows.map(|t| whitened(&e, a, t).powi(2)).sum::<f64>() / n).sqrt()
}

/// The cross-validated FIT of a model: each validation block of `folds` simulated by the model
/// fitted on the other rows and scored against its own mean, as the held-out tail is (pooled
/// over blocks, a model would be credited for following the level differences between blocks,
/// which the tail, one block, does not reward), and its one-step prediction error there.
/// `None` when a fit fails or diverges.
pub fn cv_fit(
    model: &Model<'_>,
    d: &Data<'_>,
    folds: &[(Vec<usize>, std::ops::Range<usize>)],
) -> Option<CvScore> {
    let (mut blocks, mut rms) = (Vec::with_capacity(folds.len()), Vec::with_capacity(folds.len()));
    for (fit_rows, block) in folds.iter().filter(|(_, b)| varies(&d.y[b.clone()])) {
        let f = fit(model, d, fit_rows)?;
        let s = model.simulate(&f, &d.u, d.y)?;
        blocks.push(fit_pct(&d.y[block.clone()], &s[block.clone()]));
        // A fit whose prediction-error refinement gave up has no noise model; it is whitened
        // as the nominal is, by an AR model of its error on the fit rows, so that every
        // candidate is scored in one currency.
        let noise = if f.noise.len() == d.noise_order {
            f.noise.clone()
        } else {
            let e: Vec<f64> = s.iter().zip(d.y).map(|(a, b)| a - b).collect();
            ar_fit(&e, fit_rows, d.noise_order)?
        };
        let r = prediction_rms(&s, d.y, &noise, block.clone());
        if !r.is_finite() {
            return None;
        }
        rms.push(r);
    }
    let score = CvScore::of(blocks, rms);
    score.mean.is_finite().then_some(score)
}

/// The nominal's FIT over the same validation blocks, scored as [`cv_fit`] scores; its
/// prediction error under an AR model of order `noise_order` of its simulation error, fitted on
/// each fold's fit rows (none for 0).
pub fn nominal_cv_fit(
    s: &[f64],
    y: &[f64],
    folds: &[(Vec<usize>, std::ops::Range<usize>)],
    noise_order: usize,
) -> CvScore {
    let e: Vec<f64> = s.iter().zip(y).map(|(a, b)| a - b).collect();
    let (mut blocks, mut rms) = (Vec::new(), Vec::new());
    for (fit_rows, b) in folds.iter().filter(|(_, b)| varies(&y[b.clone()])) {
        blocks.push(fit_pct(&y[b.clone()], &s[b.clone()]));
        let a = ar_fit(&e, fit_rows, noise_order).unwrap_or_default();
        rms.push(prediction_rms(s, y, &a, b.clone()));
    }
    CvScore::of(blocks, rms)
}

/// Whether a validation block's output moves at all: a constant block (a stuck sensor, a level
/// held at its rim) has no FIT (−∞ for any error), so it is left out of every score alike.
fn varies(y: &[f64]) -> bool {
    y.first().is_some_and(|&f| y.iter().any(|&v| v != f))
}

/// The best linear orders by blocked cross-validation: dead times input by input, by the
/// simulation error on the training rows (the same rows for every dead time; on a dithered
/// record the one-step prediction error under the fit's noise model) of a [`fit`] at two poles
/// and two taps, then poles and taps by cross-validation ([`CvScore::rank`] against `base`). The dead time is judged on
/// a fit by simulation error, not on the equation-error fit alone, which coloured noise and a
/// slow pole bias (docs/diagnose.md, "The dead-time search of the linear re-fit").
pub fn linear_orders(
    d: &Data<'_>,
    folds: &[(Vec<usize>, std::ops::Range<usize>)],
    base: &CvScore,
) -> Option<(Orders, CvScore)> {
    let lin = Linear;
    // Every dead time is scored on the same rows: from the folds' first row (after the
    // warm-up) and past the longest dead time's initial rows, which a simulation copies from
    // the record (zero error there would favour the longer dead times).
    let first = folds.first().map_or(d.train.start, |f| f.1.start).max(d.train.start + MAX_DEAD_TIME + 2);
    let rows: Vec<usize> = (first..d.train.end).collect();
    let mut nk = vec![1usize; d.u.len()];
    let sim_err = |orders: &Orders| -> f64 {
        let m = Model { element: &lin, input: 0, orders: orders.clone() };
        fit(&m, d, &rows).and_then(|f| m.simulate(&f, &d.u, d.y).map(|s| (f, s))).map_or(
            f64::INFINITY,
            |(f, s)| {
                let e: Vec<f64> = s.iter().zip(d.y).map(|(a, b)| a - b).collect();
                rows.iter().map(|&t| whitened(&e, &f.noise, t).powi(2)).sum()
            },
        )
    };
    for i in 0..d.u.len() {
        let mut best = (f64::INFINITY, 1);
        for k in 0..=MAX_DEAD_TIME {
            let mut o = Orders { na: 2, nb: 2, nk: nk.clone() };
            o.nk[i] = k;
            let e = sim_err(&o);
            if e < best.0 {
                best = (e, k);
            }
        }
        nk[i] = best.1;
    }
    let mut best: Option<(Orders, CvScore)> = None;
    for na in 1..=3 {
        for nb in 1..=3 {
            let orders = Orders { na, nb, nk: nk.clone() };
            let m = Model { element: &lin, input: 0, orders: orders.clone() };
            let Some(v) = cv_fit(&m, d, folds) else { continue };
            // One more pole or tap must earn a tenth of a point (of FIT, or of prediction gain).
            let score = |v: &CvScore, o: &Orders| v.rank(base, d.noise_order) - 0.1 * (o.na + o.nb) as f64;
            if best.as_ref().is_none_or(|b| score(&v, &orders) > score(&b.1, &b.0)) {
                best = Some((orders, v));
            }
        }
    }
    best
}

/// Longest dead time searched, samples.
pub const MAX_DEAD_TIME: usize = 20;

#[cfg(test)]
mod tests {
    use super::*;

    /// Each block is scored against its own mean: a simulation that only follows the blocks'
    /// levels earns FIT 0 on every block (pooled, it would earn the share of the variance the
    /// level differences carry); the gate's smallest gain is the worst block's.
    #[test]
    fn blocks_are_scored_against_their_own_means() {
        let y: Vec<f64> =
            (0..60).map(|t| (t / 20) as f64 * 10.0 + if t % 2 == 0 { 1.0 } else { -1.0 }).collect();
        let s: Vec<f64> = (0..60).map(|t| (t / 20) as f64 * 10.0).collect();
        let folds: Vec<(Vec<usize>, std::ops::Range<usize>)> =
            (0..3).map(|k| (Vec::new(), 20 * k..20 * (k + 1))).collect();
        let score = nominal_cv_fit(&s, &y, &folds, 0);
        assert_eq!(score.blocks, vec![0.0, 0.0, 0.0]);
        assert_eq!(score.mean, 0.0);
        assert!(fit_pct(&y, &s) > 80.0);
        let other = CvScore::of(vec![5.0, -2.0, 3.0], vec![1.0, 3.0, 2.0]);
        assert_eq!(other.mean, 2.0);
        assert_eq!(other.min_gain_over(&score), -2.0);
        // A constant block has no FIT (−∞ for any error) and is left out.
        let mut flat = y.clone();
        flat[20..40].iter_mut().for_each(|v| *v = 10.0);
        assert_eq!(nominal_cv_fit(&s, &flat, &folds, 0).blocks, vec![0.0, 0.0]);
        assert!(CvScore::of(Vec::new(), Vec::new()).mean.is_nan());
        // The prediction currency: per block the share of the base's RMS removed, averaged
        // (an output-error score's RMS is its simulation error's: ±1 about the levels here).
        assert_eq!(score.prediction_rms, vec![1.0, 1.0, 1.0]);
        let base = CvScore::of(vec![0.0; 3], vec![2.0, 4.0, 2.0]);
        assert_eq!(other.prediction_gain_over(&base), (50.0 + 25.0 + 0.0) / 3.0);
        assert!(CvScore::of(Vec::new(), Vec::new()).prediction_gain_over(&base).is_nan());
        // A base that predicts perfectly: nothing to gain for a perfect candidate, an unbounded
        // loss (−∞, which ranks last) for any other, never NaN.
        let perfect = CvScore::of(vec![0.0], vec![0.0]);
        assert_eq!(CvScore::of(vec![0.0], vec![0.0]).prediction_gain_over(&perfect), 0.0);
        let worse = CvScore::of(vec![0.0], vec![1.0]).prediction_gain_over(&perfect);
        assert_eq!(worse, f64::NEG_INFINITY);
    }

    /// A closed loop: `x(t) = 0.9 x(t−1) + 0.2 u(t−1)` (pole 0.9, gain 2) measured with an AR(1)
    /// disturbance of pole 0.95, under `u(t) = −0.5 y(t) + d(t)` with a ±1 dither, N = 3000,
    /// seeds 1–4. The recorded input carries the controller's answer to the disturbance, so
    /// the output-error fit, which takes the error for white, lets the dynamics absorb it; the
    /// prediction-error fit with an AR noise model (order 4 ⊇ the true 1) is consistent (the
    /// direct method; Ljung, *System Identification*, §13.4). Over seeds 1–12 the
    /// prediction-error pole scattered with a standard deviation of 0.009 around 0.899 and the
    /// gain with 0.19 around 1.98; the bounds are three of those. The output-error pole was
    /// 0.07–0.17 low on every seed: a bias, not scatter.
    #[test]
    fn a_noise_model_removes_the_closed_loop_bias() {
        use rand::{Rng, SeedableRng};
        let n = 3000;
        for seed in 1..=4 {
            let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(seed);
            let (mut x, mut v) = (0.0, 0.0);
            let (mut u, mut y) = (vec![0.0; n], vec![0.0; n]);
            for t in 0..n {
                let u_prev = if t > 0 { u[t - 1] } else { 0.0 };
                x = 0.9 * x + 0.2 * u_prev;
                let e: f64 = rng.random::<f64>() - 0.5;
                v = 0.95 * v + 0.5 * e;
                y[t] = x + v;
                let dither = if rng.random::<bool>() { 1.0 } else { -1.0 };
                u[t] = -0.5 * y[t] + dither;
            }
            let rows: Vec<usize> = (20..n).collect();
            let m = Model { element: &Linear, input: 0, orders: Orders { na: 1, nb: 1, nk: vec![1] } };
            let gain_pole = |noise_order: usize| {
                let d = Data { u: vec![&u], y: &y, train: 0..n, nominal: None, noise_order };
                let f = fit(&m, &d, &rows).unwrap();
                (f.theta[1] / (1.0 - f.theta[0]), f.theta[0])
            };
            let (pe_gain, pe_pole) = gain_pole(4);
            assert!(
                (pe_gain - 2.0).abs() < 0.6 && (pe_pole - 0.9).abs() < 0.03,
                "seed {seed}: {pe_gain} {pe_pole}"
            );
            let (_, oe_pole) = gain_pole(0);
            assert!(oe_pole < 0.85, "seed {seed}: the output-error fit is unbiased here ({oe_pole})");
        }
    }

    /// A noise-free Hammerstein plant, a dead zone of half-width 0.3 before
    /// `x(t) = 0.8 x(t−1) + 0.5 w(t−2)`: the fit from a start at 0.1 recovers the width and the
    /// coefficients to the optimiser's tolerance (the simulation error is zero at the truth, so
    /// any other optimum would need a different map to give the same output on a staircase
    /// that visits the whole range; 1e-3 leaves room for the forward-difference Jacobian).
    #[test]
    fn a_noise_free_dead_zone_is_recovered() {
        let u: Vec<f64> = (0..1200).map(|t| ((t / 17 * 7919) % 41) as f64 / 20.0 - 1.0).collect();
        let w: Vec<f64> = u.iter().map(|&v| v.signum() * (v.abs() - 0.3).max(0.0)).collect();
        let mut y = vec![0.0; u.len()];
        for t in 2..u.len() {
            y[t] = 0.8 * y[t - 1] + 0.5 * w[t - 2];
        }
        let d = Data { u: vec![&u], y: &y, train: 0..1200, nominal: None, noise_order: 0 };
        let el = dead_zone::DeadZone;
        let m = Model { element: &el, input: 0, orders: Orders { na: 1, nb: 1, nk: vec![2] } };
        let rows: Vec<usize> = (10..1200).collect();
        let f = fit(&m, &d, &rows).unwrap();
        assert!((f.p[1].abs() - 0.3).abs() < 1e-3, "{f:?}");
        assert!((f.theta[0] - 0.8).abs() < 1e-3 && (f.theta[1] - 0.5).abs() < 1e-3, "{f:?}");
        // Its figure is the dead zone's own map over the input's range: flat inside ±0.3, the
        // excess beyond (the closed form; the width's 1e-3 and the gain's carried into a value
        // of the map).
        let c = m.curve(&f, &d, "u", "y").unwrap();
        assert_eq!(c.points.len(), 201);
        for &(v, w) in &c.points {
            let truth = v.signum() * (v.abs() - 0.3).max(0.0);
            assert!((w - truth).abs() < 2e-3, "{v}: {w} against {truth}");
        }
        assert!(c.baseline.iter().all(|&(v, b)| v == b));
    }

    /// Backlash of width 0.4 is drawn as its loop: coming down the range the actuator sits
    /// half the width above the command, going up half below (the play operator's closed
    /// form, away from the turning points where it crosses the gap), and the loop closes.
    #[test]
    fn backlash_is_drawn_as_its_loop() {
        let u: Vec<f64> = (0..400).map(|t| ((t / 9 * 7919) % 41) as f64 / 20.0 - 1.0).collect();
        let d = Data { u: vec![&u], y: &u, train: 0..400, nominal: None, noise_order: 0 };
        let el = backlash::Backlash;
        let m = Model { element: &el, input: 0, orders: Orders { na: 1, nb: 1, nk: vec![1] } };
        let f = Fitted { p: vec![0.4], theta: vec![0.8, 0.5, 0.0], noise: vec![] };
        let c = m.curve(&f, &d, "u", "y").expect("backlash has a loop");
        assert_eq!(c.points.len(), 401);
        let (top, bottom) = (c.points[0].0, c.points[200].0);
        assert!(top > 1.0 && bottom < -1.0, "{top} {bottom}");
        for (k, &(v, w)) in c.points.iter().enumerate() {
            let away = (v - bottom).min(top - v) > 0.4 + 1e-9;
            if away {
                let expected = if k <= 200 { v + 0.2 } else { v - 0.2 };
                assert!((w - expected).abs() < 1e-12, "{k}: {v} -> {w}, not {expected}");
            }
        }
        assert!((c.points[0].1 - c.points[400].1).abs() < 1e-12);
        assert!(c.baseline.iter().all(|&(v, b)| v == b));
    }

    /// Noise-free Hammerstein plants, `w = u + 0.4·u²` and `w = u + 0.3·u³` through
    /// `y(t) = 0.8 y(t−1) + 0.5 w(t−2)`: the polynomial's drawn map is the true one, up to the
    /// scale and offset that a map and a linear gain share (the truth is drawn with unit slope
    /// at the input's mean, as the figure draws the fit). 1e-3 of the map's range: the fit is
    /// exact in structure, so only the optimiser's tolerance is left.
    #[test]
    fn a_noise_free_polynomial_is_drawn_as_its_map() {
        let u: Vec<f64> = (0..1200).map(|t| ((t / 13 * 7919) % 41) as f64 / 20.0 - 0.7).collect();
        let n = u.len() as f64;
        let m = u.iter().sum::<f64>() / n;
        for (degree, c) in [(2, 0.4), (3, 0.3)] {
            let w_of = |v: f64| v + c * v.powi(degree);
            let slope = 1.0 + c * f64::from(degree) * m.powi(degree - 1);
            let mut y = vec![0.0; u.len()];
            for t in 2..u.len() {
                y[t] = 0.8 * y[t - 1] + 0.5 * w_of(u[t - 2]);
            }
            let d = Data { u: vec![&u], y: &y, train: 0..1200, nominal: None, noise_order: 0 };
            let el = polynomial::Polynomial { degree };
            let model = Model { element: &el, input: 0, orders: Orders { na: 1, nb: 1, nk: vec![2] } };
            let rows: Vec<usize> = (10..1200).collect();
            let f = fit(&model, &d, &rows).unwrap();
            let curve = model.curve(&f, &d, "u", "y").expect("a polynomial has a map");
            let truth = |v: f64| (w_of(v) - w_of(m)) / slope + m;
            let span = curve.points.iter().map(|p| truth(p.0)).fold(f64::NEG_INFINITY, f64::max)
                - curve.points.iter().map(|p| truth(p.0)).fold(f64::INFINITY, f64::min);
            // The map is the fitted one over the training range; beyond it the powers hold.
            let (lo, hi) = (d.u_quantile(0, 0.0), d.u_quantile(0, 1.0));
            for &(v, got) in curve.points.iter().filter(|p| (lo..=hi).contains(&p.0)) {
                assert!(
                    (got - truth(v)).abs() < 1e-3 * span,
                    "degree {degree}, {v}: {got} against {}",
                    truth(v)
                );
            }
        }
    }

    /// A fitted polynomial keeps the centre and scale of its training rows: simulating the first
    /// half of the record alone gives the first half of the whole record's simulation (the
    /// simulation is causal, so only the arithmetic's rounding may differ, 1e-9 of the output's
    /// range), and the centre is the training rows' mean, not the record's. Centred on the
    /// record it is given, the same coefficients would act on other powers.
    #[test]
    fn a_fitted_polynomial_means_the_same_map_on_any_record() {
        let u: Vec<f64> =
            (0..1200).map(|t| ((t / 13 * 7919) % 41) as f64 / 20.0 - 0.7 + t as f64 / 1200.0).collect();
        let mut y = vec![0.0; u.len()];
        for t in 2..u.len() {
            y[t] = 0.8 * y[t - 1] + 0.5 * (u[t - 2] + 0.4 * u[t - 2].powi(2));
        }
        let d = Data { u: vec![&u], y: &y, train: 0..800, nominal: None, noise_order: 0 };
        let el = polynomial::Polynomial { degree: 2 };
        let model = Model { element: &el, input: 0, orders: Orders { na: 1, nb: 1, nk: vec![2] } };
        let rows: Vec<usize> = (10..800).collect();
        let f = fit(&model, &d, &rows).unwrap();
        let train_mean = u[..800].iter().sum::<f64>() / 800.0;
        assert_eq!(f.p[0], train_mean);
        let whole = model.simulate(&f, &[&u], &y).unwrap();
        let half = model.simulate(&f, &[&u[..600]], &y[..600]).unwrap();
        let range = y.iter().fold(f64::NEG_INFINITY, |a, &b| a.max(b))
            - y.iter().fold(f64::INFINITY, |a, &b| a.min(b));
        for t in 0..600 {
            assert!((whole[t] - half[t]).abs() <= 1e-9 * range, "{t}: {} against {}", whole[t], half[t]);
        }
    }

    /// A noise-free |x| sensor after `x(t) = 0.9 x(t−1) + 0.3 u(t−1)` driven by a staircase
    /// that changes sign: started from the sign the nominal (the signed linear simulation)
    /// gives, the fit simulates the magnitude exactly (FIT > 99.9 %; the structure holds the
    /// truth, so only the optimiser's tolerance is left), and the same fit started from the
    /// recorded magnitude alone (no nominal, the low-passed input's sign) gets there too. The
    /// simulation starts from the recorded magnitude, whose sign may be wrong (here x(1) < 0):
    /// that transient decays as 0.9ᵗ, below 1e-4 of its size after 100 samples, so fit and
    /// score start there.
    #[test]
    fn a_noise_free_abs_sensor_is_recovered() {
        let u: Vec<f64> = (0..1500).map(|t| ((t / 23 * 7919) % 41) as f64 / 20.0 - 1.0).collect();
        let mut x = vec![0.0; u.len()];
        for t in 1..u.len() {
            x[t] = 0.9 * x[t - 1] + 0.3 * u[t - 1];
        }
        let y: Vec<f64> = x.iter().map(|v| v.abs()).collect();
        let el = abs_sensor::AbsSensor;
        let m = Model { element: &el, input: 0, orders: Orders { na: 1, nb: 1, nk: vec![1] } };
        let rows: Vec<usize> = (100..1500).collect();
        for nominal in [Some(&x[..]), None] {
            let d = Data { u: vec![&u], y: &y, train: 0..1500, nominal, noise_order: 0 };
            let f = fit(&m, &d, &rows).unwrap();
            let s = m.simulate(&f, &d.u, &y).unwrap();
            assert!(fit_pct(&y[100..], &s[100..]) > 99.9, "nominal {}: {f:?}", nominal.is_some());
        }
    }

    /// A Duffing-type recursion with a cubic feedback term is recovered exactly from noise-free
    /// data: the structure is linear in its coefficients, so the equation-error start is
    /// already the truth and the simulation error is zero there.
    #[test]
    fn a_noise_free_cubic_feedback_is_recovered() {
        let u: Vec<f64> = (0..1500)
            .map(|t| if (t / 40) % 2 == 0 { 1.0 } else { -1.0 } * (1.0 + (t / 80 % 3) as f64 * 0.5))
            .collect();
        let mut y = vec![0.0; u.len()];
        for t in 2..u.len() {
            y[t] = 1.6 * y[t - 1] - 0.7 * y[t - 2] + 0.05 * u[t - 1] - 0.02 * y[t - 1].powi(3);
        }
        let d = Data { u: vec![&u], y: &y, train: 0..1500, nominal: None, noise_order: 0 };
        let el = stiffness::CubicStiffness;
        let m = Model { element: &el, input: 0, orders: Orders { na: 2, nb: 1, nk: vec![1] } };
        let rows: Vec<usize> = (10..1500).collect();
        let f = fit(&m, &d, &rows).unwrap();
        let s = m.simulate(&f, &d.u, &y).unwrap();
        assert!(fit_pct(&y[10..], &s[10..]) > 99.9, "{f:?}");
        // Its figure is the fed-back force −0.02·x³ (the level fitted at 0 to 1e-3 of the
        // output's range, the coefficient exact on noise-free data).
        let c = m.curve(&f, &d, "u", "y").unwrap();
        let span = c.points.last().unwrap().0 - c.points[0].0;
        for &(x, g) in &c.points {
            assert!((g + 0.02 * x.powi(3)).abs() < 1e-3 * 0.02 * span.powi(3), "{x}: {g}");
        }
        assert!(c.baseline.iter().all(|&(_, b)| b == 0.0));
    }
}
