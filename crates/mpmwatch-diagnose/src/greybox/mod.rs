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
//! x(t) = Σ_k α_k x(t−k) + Σ_s Σ_k β_sk w_s(t−nk_s−k) + Σ_m γ_m f_m(x(t−1), x(t−2)) [+ δ·t/1000] + c
//! ŷ(t) = g(x(t))            (the element's output map; the identity for most)
//! ```
//!
//! With several inputs, every input but the one the element acts on has its own linear
//! channel, `x_j(t) = Σ_k α_jk x_j(t−k) + Σ_k β_jk u_j(t−nk_j−k)`, and the output map reads the
//! sum `g(x(t) + Σ_j x_j(t))` (see [`Layout`]): each MV→CV submodel keeps its own poles, as a
//! controller's model matrix has them, where one denominator shared by every input would make
//! the element make up for the paths it does not act on.
//!
//! The drift term `δ` is a nuisance every structure carries when the output drifts in a way
//! no input carries ([`Orders::trend`], decided by [`drift_gain`] and [`drift_is_one_line`]).
//!
//! Fitting (see [`fit`]; the noise model in [`noise`]): least squares on the equation error
//! gives the start (the recorded output stands in for `x` on the rows where the output map is
//! invertible), then Levenberg–Marquardt (`levenberg-marquardt`) minimises the simulation error
//! over every coefficient and the element's own parameters (a width, a limit), from each of
//! the element's starting values, then on a dithered record the noise model's coefficients
//! join the search. Choice (see [`explain`], scored by [`cv`]): blocked cross-validation inside
//! the training part, scored in simulation mode, the currency the held-out FIT is reported in
//! (on a dithered record ranked by the cross-validated prediction error, gated by the
//! simulation's FIT).

mod abs_sensor;
mod backlash;
mod bilinear;
mod clip_sensor;
mod curve;
mod cv;
mod dead_zone;
mod draining_tank;
mod explain;
mod friction;
mod linear;
mod linear_change;
mod noise;
mod polynomial;
mod reading;
mod saturation;
mod sensor_polynomial;
mod stiffness;
mod storage_limit;
mod structure;
mod tank_cascade;

use std::collections::BTreeMap;

use crate::minimize::minimize;

use super::candidates::{ActsOn, Physics};
pub use curve::ElementCurve;
use mpmwatch_core::model::DiscreteTf;
use mpmwatch_core::numerics::{least_squares_rows, median, quantile};
pub use reading::{Reading, pinned};

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
    /// How many leading parameters of every start are set from the data, not searched, and kept
    /// as they are by the fit (a polynomial's centre, scale and range, read off the rows fitted
    /// by [`Element::fixed_on`]): not free, so not counted in the element's complexity either.
    /// 0 by default.
    fn fixed(&self) -> usize {
        0
    }
    /// The fixed leading parameters of a fit on `rows` of input `i`, for an element that reads
    /// them off the rows it is fitted on (a map's centre, scale and range); `None` keeps the
    /// starts'. A map is not known beyond the range its fit rows visit: fitted on a fold, its
    /// validation block then scores what it does where the fit never went, as the held-out
    /// tail scores what the map fitted on the training part does beyond that part's range.
    fn fixed_on(&self, _d: &Data<'_>, _i: usize, _rows: &[usize]) -> Option<Vec<f64>> {
        None
    }
    /// The element's own poles, for an element with linear memory of its own (a store): a
    /// corrected model settles only as fast as its slowest pole, the element's included
    /// ([`Model::slowest_pole`]). Empty by default: a static map has none, nor has a memory
    /// without a decaying mode (backlash). A feedback element (cubic stiffness) moves the
    /// linear part's poles with the operating point instead, which is not read here; how long
    /// a structure with one remembers where it started is simulated instead (`memory_time` in
    /// explain/judge.rs).
    fn poles(&self, _p: &[f64]) -> Vec<f64> {
        Vec::new()
    }
    /// Whether the element's own stores can carry all of the plant's dynamics (a tank cascade):
    /// it is then also tried behind a static linear part, no poles and one tap per input at the
    /// nominal's dead time, which the linear orders searched for a linear model would not give
    /// it (a linear model follows slow stores with poles and long dead times that an element
    /// with the stores needs none of; an argument, not a measurement of its own). Its own poles
    /// are then left out of the settling rule, which reads the linear part's only (see
    /// `explain`). False by default.
    fn carries_dynamics(&self) -> bool {
        false
    }
    /// The signals the linear dynamics see, each with its own numerator: by default the inputs.
    /// `i` is the input the element acts on.
    fn signals(&self, _p: &[f64], u: &[&[f64]], _i: usize) -> Vec<Vec<f64>> {
        u.iter().map(|x| x.to_vec()).collect()
    }
    /// Forces fed back from the simulated output (`x(t−1)`, `x(t−2)`).
    fn feedback(&self, _p: &[f64], _x1: f64, _x2: f64, _out: &mut Vec<f64>) {}
    /// The next value of the linear part's output `x` (before the output map) once the
    /// fed-back forces have acted: `free` without them, `forced` with them weighted by their
    /// fitted coefficients `gamma`, `x1` and `x2` the two values before. By default `forced`;
    /// friction uses it to stick at rest (`friction::Coulomb`).
    fn constrain(&self, _p: &[f64], _gamma: &[f64], _free: f64, forced: f64, _x1: f64, _x2: f64) -> f64 {
        forced
    }
    /// Per sample, whether the element's nonlinearity acts there under `p` (a limit binds, an
    /// input sits inside a dead zone), `u` the inputs, `i` the input it acts on and `yhat` the
    /// model's simulated output, `p` finite (as every fitted model's is). An element with a kink
    /// can place it beyond the record, where it is its linear part under a nonlinear name; this
    /// is how [`explain`] tells. `None` (the default): a smooth map, a force or a play, which
    /// departs from a line wherever its signal moves, tested only by its margin over the linear
    /// re-fit; and the |x| sensor, whose kink is at `x = 0` where `yhat`, a magnitude, does not
    /// show which side `x` is on.
    fn acting(&self, _p: &[f64], _u: &[&[f64]], _i: usize, _yhat: &[f64]) -> Option<Vec<bool>> {
        None
    }
    /// Whether the element, its kink idle ([`Element::acting`] on too few rows for a name,
    /// `explain`'s `MIN_ACTING`), is its linear part: a limit or a dead zone beyond the record
    /// leaves a line (with a store, a line with one pole more). True by default; false for a
    /// tank, whose square-root outflow bends the dynamics at every level whether or not its rim
    /// is reached.
    fn idle_is_linear(&self) -> bool {
        true
    }
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

/// The inputs with input `i` replaced by `map` of it: what an element on one input makes of
/// the inputs.
pub fn map_input(u: &[&[f64]], i: usize, map: impl FnOnce(&[f64]) -> Vec<f64>) -> Vec<Vec<f64>> {
    let mut out: Vec<Vec<f64>> = u.iter().map(|x| x.to_vec()).collect();
    out[i] = map(u[i]);
    out
}

/// The linear part's orders: `na` poles, and per input `nb` numerator taps after `nk` samples;
/// with `trend`, a drift term `δ·τ(t)` beside the constant `c` of the recursion, `τ(t)` the row
/// index in thousands of samples ([`TREND_UNIT`]). The trend is a nuisance: an output drifting
/// in a way no input carries (a sensor's drift, a slow unmeasured load) would otherwise bend
/// every structure's dynamics, the linear re-fit's as much as an element's.
#[derive(Debug, Clone, PartialEq)]
pub struct Orders {
    /// Poles.
    pub na: usize,
    /// Numerator taps per signal.
    pub nb: usize,
    /// Dead time per input, samples.
    pub nk: Vec<usize>,
    /// Whether the recursion carries a drift term.
    pub trend: bool,
    /// The range the output's instrument reads within, when the record shows one
    /// ([`reading::pinned`]): the simulated reading is held inside it after the element's own
    /// output map.
    pub reading: Option<Reading>,
}

/// Samples per unit of the drift term's time `τ(t) = t / TREND_UNIT`: a drift over a record of
/// thousands of samples then has a coefficient of the output's own order, as the optimiser's
/// steps expect.
pub const TREND_UNIT: f64 = 1000.0;

impl Orders {
    /// The first row at which every lag is inside the record: a simulation under these orders
    /// predicts from it on, and returns the record's own rows before it ([`Model::simulate`]).
    pub fn reach(&self) -> usize {
        let nkmax = self.nk.iter().copied().max().unwrap_or(0);
        self.na.max(nkmax + self.nb).max(2)
    }
}

/// A fitted hypothesis: element parameters and the coefficients of the structure.
#[derive(Debug, Clone)]
pub struct Fitted {
    /// The element's own parameters.
    pub p: Vec<f64>,
    /// The linear part's coefficients and the forces', drift's and constant's, where
    /// [`Layout`] puts them (with one input: `α`, `β` per signal, `γ`, the drift's `δ` with
    /// [`Orders::trend`], `c`).
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

/// Where each coefficient of a structure sits in [`Fitted::theta`]: the poles of the element's
/// channel (`na`), the poles of every other input's channel in input order (`na` each), the
/// numerator of every signal (`nb` each; a signal beyond the inputs, a polynomial's power, is
/// of the element's input and in its channel), the fed-back forces' `γ`, the drift's `δ`
/// (with [`Orders::trend`]), and the constant `c`. With one input: `α`, `β`, `γ`, `δ`, `c`.
#[derive(Debug, Clone, Copy)]
pub(crate) struct Layout {
    na: usize,
    nb: usize,
    inputs: usize,
    /// The input the element acts on: its channel carries the element, the forces, the drift
    /// and the constant.
    input: usize,
    signals: usize,
    feedbacks: usize,
    trend: bool,
}

impl Layout {
    /// The layout of `orders` with `signals` signals and `feedbacks` forces, the element on
    /// input `input`.
    pub(crate) fn new(orders: &Orders, signals: usize, input: usize, feedbacks: usize) -> Self {
        let inputs = orders.nk.len().max(1);
        Layout { na: orders.na, nb: orders.nb, inputs, input, signals, feedbacks, trend: orders.trend }
    }

    /// The inputs with a channel of their own: every one but the element's.
    pub(crate) fn others(&self) -> impl Iterator<Item = usize> + '_ {
        (0..self.inputs).filter(move |&j| j != self.input)
    }

    /// The channel signal `s` is in: its own input's for an input other than the element's.
    pub(crate) fn channel(&self, s: usize) -> usize {
        if s < self.inputs { s } else { self.input }
    }

    /// The poles of input `j`'s channel (the element's channel for `j` the element's input).
    pub(crate) fn alpha(&self, j: usize) -> std::ops::Range<usize> {
        let rank = match j.cmp(&self.input) {
            std::cmp::Ordering::Equal => 0,
            std::cmp::Ordering::Less => j + 1,
            std::cmp::Ordering::Greater => j,
        };
        rank * self.na..(rank + 1) * self.na
    }

    /// The numerator of signal `s`.
    pub(crate) fn beta(&self, s: usize) -> std::ops::Range<usize> {
        let b = self.inputs * self.na + s * self.nb;
        b..b + self.nb
    }

    /// The fed-back forces' coefficients.
    pub(crate) fn gamma(&self) -> std::ops::Range<usize> {
        let g = self.inputs * self.na + self.signals * self.nb;
        g..g + self.feedbacks
    }

    /// Coefficients in all.
    pub(crate) fn len(&self) -> usize {
        self.gamma().end + usize::from(self.trend) + 1
    }

    /// `common`, the coefficients of one denominator shared by every signal (`α`, `β`, `γ`,
    /// `δ`, `c`, as the equation error fits them), laid out with that denominator copied to
    /// every other channel: the same model, since `Σ_s (B_s/A)·w_s` is `Σ_s B_s·w_s / A`.
    fn spread_shared(&self, common: &[f64]) -> Vec<f64> {
        let na = self.na.min(common.len());
        let mut theta = common[..na].to_vec();
        for _ in self.others() {
            theta.extend_from_slice(&common[..na]);
        }
        theta.extend_from_slice(&common[na..]);
        theta
    }
}

/// The largest modulus of the roots of `z^n − Σ α_k z^(n−k)`, to 1e-10: the radius below which
/// the Schur–Cohn test finds the denominator rescaled by it stable, by bisection (the poles of
/// `A(ρ·q⁻¹)` are those of `A` divided by `ρ`). `alpha` finite.
fn pole_radius(alpha: &[f64]) -> f64 {
    let inside = |rho: f64| {
        let a: Vec<f64> = std::iter::once(1.0)
            .chain(alpha.iter().enumerate().map(|(k, c)| -c / rho.powi(k as i32 + 1)))
            .collect();
        DiscreteTf::new(vec![1.0], a, 0).is_ok_and(|tf| tf.is_stable())
    };
    // Cauchy's bound: every root lies within 1 + max |α_k|.
    let (mut lo, mut hi) = (0.0, 1.0 + alpha.iter().fold(0.0f64, |m, c| m.max(c.abs())));
    while hi - lo > 1e-10 {
        let mid = 0.5 * (lo + hi);
        if inside(mid) { hi = mid } else { lo = mid }
    }
    hi
}

impl Model<'_> {
    /// Where the coefficients sit for `signals` signals ([`Layout`]).
    pub(crate) fn layout(&self, signals: usize) -> Layout {
        Layout::new(&self.orders, signals, self.input, self.element.feedbacks())
    }

    fn signals(&self, p: &[f64], u: &[&[f64]]) -> (Vec<Vec<f64>>, Vec<usize>) {
        let sig = self.element.signals(p, u, self.input);
        // The signals beyond the inputs (a polynomial's powers) are of the element's input and
        // share its dead time.
        let nk: Vec<usize> = (0..sig.len())
            .map(|s| if s < u.len() { self.orders.nk[s] } else { self.orders.nk[self.input] })
            .collect();
        (sig, nk)
    }

    /// The largest pole modulus of the corrected model, to 1e-9: every channel's linear part
    /// (`α`, [`pole_radius`]) and the element's own ([`Element::poles`]), +∞ when one of those
    /// is not finite. Feedback forces (`γ`) are not linearised into it.
    pub fn slowest_pole(&self, f: &Fitted) -> f64 {
        // The poles come first in every layout, whatever the signals.
        let l = self.layout(0);
        let channels: Vec<&[f64]> = std::iter::once(self.input)
            .chain(l.others())
            .map(|j| &f.theta[l.alpha(j).start.min(f.theta.len())..l.alpha(j).end.min(f.theta.len())])
            .collect();
        let own = self.element.poles(&f.p);
        if !channels.iter().flat_map(|a| a.iter()).chain(&own).all(|c| c.is_finite()) {
            return f64::INFINITY;
        }
        let linear = channels.iter().map(|a| pole_radius(a)).fold(0.0, f64::max);
        own.iter().fold(linear, |m, r| m.max(r.abs()))
    }

    /// The share of `rows` on which the fitted element's nonlinearity acts
    /// ([`Element::acting`]), `sim` the model's simulation; `None` for an element that does not
    /// say, or no rows.
    pub fn acting_share(&self, f: &Fitted, u: &[&[f64]], sim: &[f64], rows: &[usize]) -> Option<f64> {
        let acts = self.element.acting(&f.p, u, self.input, sim)?;
        if rows.is_empty() {
            return None;
        }
        Some(rows.iter().filter(|&&t| acts[t]).count() as f64 / rows.len() as f64)
    }

    /// How much the fitted drift term moves the simulated output over `rows`: the straight
    /// line's rise (slope × rows) through the difference between the simulation as fitted
    /// and with `δ` at 0. Read off the simulation, not off `δ / (1 − Σα)`, because an output
    /// map (a clip, a sensor's bend) or a fed-back force changes what a drift of the linear
    /// part does to the reading. `None` without [`Orders::trend`] or when either diverges.
    pub fn drift_over(&self, f: &Fitted, u: &[&[f64]], y: &[f64], rows: &[usize]) -> Option<f64> {
        if !self.orders.trend || f.theta.len() < 2 || rows.len() < 2 {
            return None;
        }
        let mut still = f.clone();
        let k = still.theta.len() - 2;
        still.theta[k] = 0.0;
        let (with, without) = (self.simulate(f, u, y)?, self.simulate(&still, u, y)?);
        let diff: Vec<f64> = with.iter().zip(&without).map(|(a, b)| a - b).collect();
        let ones = vec![1.0; diff.len()];
        let time: Vec<f64> = (0..diff.len()).map(|t| t as f64).collect();
        let c = least_squares_rows(&[&ones, &time], &diff, rows)?;
        Some(c[1] * rows.len() as f64)
    }

    /// Simulation of the output over the whole record, from the recorded output's first
    /// samples as initial conditions. `None` when it diverges.
    pub fn simulate(&self, f: &Fitted, u: &[&[f64]], y: &[f64]) -> Option<Vec<f64>> {
        self.simulate_held(f, u, y, usize::MAX)
    }

    /// [`Model::simulate`] with the drift term held after row `last` at the value it has
    /// there. A drift no input carries cannot be forecast: the corrected simulation of the
    /// held-out tail keeps the level the drift reached by the end of the training part rather
    /// than extrapolating its line (the forecast of a random walk). Without [`Orders::trend`]
    /// the same as [`Model::simulate`].
    pub fn simulate_held(&self, f: &Fitted, u: &[&[f64]], y: &[f64], last: usize) -> Option<Vec<f64>> {
        // An optimiser step may leave a parameter non-finite; the maps (a clamp) must not see it.
        if f.p.iter().chain(&f.theta).any(|v| !v.is_finite()) {
            return None;
        }
        let (sig, nk) = self.signals(&f.p, u);
        let l = self.layout(sig.len());
        if f.theta.len() != l.len() {
            return None;
        }
        let n = y.len();
        let o = &self.orders;
        let first = self.orders.reach().min(n);
        let scale = 1.0 + y.iter().fold(0.0f64, |m, v| m.max(v.abs()));
        let bound = 1e3 * scale;
        // Every other input's channel starts at rest at its first input (at 0 when it has no
        // steady state); the element's channel takes the rest of the recorded start.
        let others: Vec<usize> = l.others().collect();
        let mut xo: Vec<Vec<f64>> = others
            .iter()
            .map(|&j| {
                let den = 1.0 - f.theta[l.alpha(j)].iter().sum::<f64>();
                let gain = f.theta[l.beta(j)].iter().sum::<f64>();
                let rest =
                    if den.abs() > 1e-9 { gain * sig[j].first().copied().unwrap_or(0.0) / den } else { 0.0 };
                vec![rest; n]
            })
            .collect();
        let sum_others = |xo: &[Vec<f64>], t: usize| xo.iter().map(|c| c[t]).sum::<f64>();
        let mut x: Vec<f64> = (0..first).map(|t| y[t] - sum_others(&xo, t)).collect();
        x.resize(n, 0.0);
        let own: Vec<usize> = (0..sig.len()).filter(|&s| l.channel(s) == self.input).collect();
        let nf = self.element.feedbacks();
        let fb0 = l.gamma().start;
        let mut fb = Vec::with_capacity(nf);
        let drift = if o.trend { f.theta[f.theta.len() - 2] } else { 0.0 };
        for t in first..n {
            let mut v = f.theta[f.theta.len() - 1] + drift * t.min(last) as f64 / TREND_UNIT;
            for k in 1..=o.na {
                v += f.theta[k - 1] * x[t - k];
            }
            for &s in &own {
                let b = l.beta(s).start;
                for k in 0..o.nb {
                    v += f.theta[b + k] * sig[s][t - nk[s] - k];
                }
            }
            if nf > 0 {
                fb.clear();
                self.element.feedback(&f.p, x[t - 1], x[t - 2], &mut fb);
                let gamma = &f.theta[fb0..fb0 + nf];
                let forced = v + fb.iter().zip(gamma).map(|(g, c)| c * g).sum::<f64>();
                v = self.element.constrain(&f.p, gamma, v, forced, x[t - 1], x[t - 2]);
            }
            if !v.is_finite() || v.abs() > bound {
                return None;
            }
            x[t] = v;
            for (c, &j) in others.iter().enumerate() {
                let (a, b) = (l.alpha(j).start, l.beta(j).start);
                let mut w = 0.0;
                for k in 1..=o.na {
                    w += f.theta[a + k - 1] * xo[c][t - k];
                }
                for k in 0..o.nb {
                    w += f.theta[b + k] * sig[j][t - nk[j] - k];
                }
                if !w.is_finite() || w.abs() > bound {
                    return None;
                }
                xo[c][t] = w;
            }
        }
        // The first rows are the recorded start, not predictions: they are returned as
        // recorded (an output map applied to them would count an |x| sensor's offset twice).
        Some(
            (0..n)
                .map(|t| {
                    if t < first {
                        y[t]
                    } else if others.is_empty() {
                        self.read(self.element.output(&f.p, x[t]))
                    } else {
                        self.read(self.element.output(&f.p, x[t] + sum_others(&xo, t)))
                    }
                })
                .collect(),
        )
    }

    /// `v` as the output's instrument reads it ([`Orders::reading`]).
    fn read(&self, v: f64) -> f64 {
        self.orders.reading.map_or(v, |r| r.read(v))
    }

    /// The equation-error least-squares fit of the coefficients, the element's parameters
    /// fixed at `p`, on `rows` where the output map is invertible and the `recorded` output is
    /// inside the instrument's range; `y` is the recorded output or what stands in for `x`.
    fn equation_error(
        &self,
        p: &[f64],
        u: &[&[f64]],
        y: &[f64],
        recorded: &[f64],
        rows: &[usize],
    ) -> Option<Fitted> {
        let (sig, nk) = self.signals(p, u);
        let o = &self.orders;
        let first = self.orders.reach();
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
        if o.trend {
            cols.push((0..n).map(|t| t as f64 / TREND_UNIT).collect());
        }
        cols.push(vec![1.0; n]);
        // A reading held at the instrument's range says only that the value is beyond it.
        let ok = |t: usize| {
            (0..=o.na).all(|k| {
                t >= k
                    && self.element.invertible(p, y[t - k])
                    && o.reading.is_none_or(|r| r.inside(recorded[t - k]))
            })
        };
        let used: Vec<usize> = rows.iter().copied().filter(|&t| t >= first && ok(t)).collect();
        if used.len() < 3 * cols.len() {
            return None;
        }
        let refs: Vec<&[f64]> = cols.iter().map(Vec::as_slice).collect();
        let common = least_squares_rows(&refs, y, &used)?;
        let l = self.layout(sig.len());
        let theta = l.spread_shared(&common);
        debug_assert_eq!(theta.len(), l.len());
        Some(Fitted { p: p.to_vec(), theta, noise: Vec::new() })
    }
}

/// Fits a model on `rows` by simulation error: the equation-error start at each of the
/// element's starting values, refined by Levenberg–Marquardt; the fit with the least
/// simulation error on `rows` wins; with a noise model (`d.noise_order` above 0) it is then
/// refined by its prediction error ([`noise::prediction_error_fit`]). `None` when no start gives a
/// stable simulation.
pub fn fit(model: &Model<'_>, d: &Data<'_>, rows: &[usize]) -> Option<Fitted> {
    let mut starts = model.element.starts(d, model.input);
    if starts.is_empty() {
        starts.push(Vec::new());
    }
    if let Some(on_rows) = model.element.fixed_on(d, model.input, rows) {
        for p in &mut starts {
            let k = on_rows.len().min(p.len());
            p[..k].copy_from_slice(&on_rows[..k]);
        }
    }
    let scale = mpmwatch_core::numerics::std_dev(&d.y[d.train.clone()], 0).max(f64::MIN_POSITIVE);
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
        let Some(start) = model.equation_error(&p, &d.u, &target, d.y, rows) else { continue };
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
    Some(noise::prediction_error_fit(model, d, rows, best, scale))
}

/// The classes, in the order of their parsimony (a later class must beat an earlier one by
/// the margin to be preferred at equal fit).
pub fn elements() -> Vec<Box<dyn Element>> {
    vec![
        Box::new(dead_zone::DeadZone),
        Box::new(saturation::InputSaturation),
        Box::new(storage_limit::StorageLimit),
        Box::new(draining_tank::DrainingTank),
        Box::new(tank_cascade::TankCascade),
        Box::new(clip_sensor::ClipSensor { range: None }),
        Box::new(abs_sensor::AbsSensor),
        Box::new(sensor_polynomial::SensorPolynomial),
        Box::new(polynomial::Polynomial { degree: 2 }),
        Box::new(bilinear::Bilinear),
        Box::new(stiffness::CubicStiffness),
        Box::new(friction::Coulomb { on_change: false }),
        Box::new(friction::Coulomb { on_change: true }),
        Box::new(backlash::Backlash),
        Box::new(polynomial::Polynomial { degree: 3 }),
    ]
}

pub use cv::{
    Beside, CvScore, cv_fit, drift_gain, drift_is_one_line, linear_orders, max_dead_time, nominal_cv_fit,
    ranked_linear, starting_at,
};
pub use explain::{Explanation, MIN_ACTING, Margins, Names, Output, explain};
pub use linear::Linear;
pub(crate) use polynomial::power;
pub use structure::{FittedGreyBox, GreyBox, Structure};

#[cfg(test)]
mod tests {
    use super::*;
    use crate::fitness::fit_pct;

    /// The slowest pole against closed forms: a real pole, two real poles (0.8 and 0.7), a
    /// complex pair of modulus 0.9, an integrator, an unstable pole and a pure delay line
    /// (pole 0), then a store's own pole beside a linear part. The bisection stops at 1e-10 on
    /// the radius; 1e-9 leaves it a factor of ten.
    #[test]
    fn the_slowest_pole_is_the_largest_root_modulus() {
        let phi: f64 = 0.6;
        let cases: [(&[f64], f64); 6] = [
            (&[0.99], 0.99),
            (&[1.5, -0.56], 0.8),
            (&[2.0 * 0.9 * phi.cos(), -0.81], 0.9),
            (&[1.0], 1.0),
            (&[1.2], 1.2),
            (&[0.0], 0.0),
        ];
        for (alpha, want) in cases {
            let m = Model {
                element: &Linear,
                input: 0,
                orders: Orders { na: alpha.len(), nb: 1, nk: vec![1], trend: false, reading: None },
            };
            let mut theta = alpha.to_vec();
            theta.extend([0.5, 0.0]);
            let f = Fitted { p: Vec::new(), theta, noise: Vec::new() };
            let got = m.slowest_pole(&f);
            assert!((got - want).abs() < 1e-9, "{alpha:?}: {got} against {want}");
        }
        // A store's own pole counts: slower than the linear part's 0.5, it is the slowest;
        // faster, the linear part's is. A non-finite parameter reads as never settling.
        let m = Model {
            element: &storage_limit::StorageLimit,
            input: 0,
            orders: Orders { na: 1, nb: 1, nk: vec![1], trend: false, reading: None },
        };
        for (store, want) in [(0.999, 0.999), (0.3, 0.5), (f64::NAN, f64::INFINITY)] {
            let f = Fitted { p: vec![store, -1.0, 1.0], theta: vec![0.5, 0.5, 0.0], noise: Vec::new() };
            let got = m.slowest_pole(&f);
            assert!(got == want || (got - want).abs() < 1e-9, "store {store}: {got} against {want}");
        }
    }

    /// The equation-error start leaves out the rows whose recorded reading is held at the
    /// instrument's range, whatever stands in for `x` there: a noise-free first-order plant
    /// `x(t) = 0.8 x(t−1) + 0.5 u(t−1)` read through a range whose top sits where the record
    /// is corrupted (those rows replaced by the top, a reading the plant never gave), fitted
    /// from the record negated (a stand-in on which the top never binds: every value is
    /// below it) as a sign-losing sensor's start can be. Rows held at the top dropped, the
    /// stand-in's own equation holds on every row left and the coefficients come back to
    /// the least-squares solve's rounding (1e-9); a filter on the stand-in keeps the corrupted
    /// rows and misses the pole by more than a thousandth.
    #[test]
    fn the_equation_error_start_drops_rows_held_at_the_range_by_the_reading() {
        let n = 400;
        let u: Vec<f64> = (0..n).map(|t| if (t / 20) % 2 == 0 { 1.0 } else { -1.0 }).collect();
        let mut x = vec![0.0; n];
        for t in 1..n {
            x[t] = 0.8 * x[t - 1] + 0.5 * u[t - 1];
        }
        let top = 5.0;
        let mut y = x.clone();
        for t in (50..n).step_by(37) {
            y[t] = top;
        }
        let stand_in: Vec<f64> = y.iter().map(|v| -v).collect();
        let reading = Reading { lower: f64::NEG_INFINITY, upper: top, at_lower: 0, at_upper: 10 };
        let m = Model {
            element: &Linear,
            input: 0,
            orders: Orders { na: 1, nb: 1, nk: vec![1], trend: false, reading: Some(reading) },
        };
        let rows: Vec<usize> = (2..n).collect();
        let f = m.equation_error(&[], &[&u], &stand_in, &y, &rows).unwrap();
        // The negated record obeys the same recursion with the input negated: a = 0.8, b = −0.5.
        assert!((f.theta[0] - 0.8).abs() < 1e-9 && (f.theta[1] + 0.5).abs() < 1e-9, "{:?}", f.theta);
        let kept_all = m.equation_error(&[], &[&u], &stand_in, &stand_in, &rows).unwrap();
        assert!((kept_all.theta[0] - 0.8).abs() > 1e-3, "{:?}", kept_all.theta);
    }

    /// Two inputs through paths with poles of their own, `y = x1 + x2` with
    /// `x1(t) = 0.9 x1(t−1) + 0.1 u1(t−1)` and `x2(t) = 0.4 x2(t−1) + 0.6 u2(t−1)`, noise-free
    /// and at rest at the start: one pole per channel ([`Layout`]) holds it, so the fit on the
    /// first 1400 rows recovers every coefficient (the optimiser's tolerance; 1e-3) and
    /// simulates the 600 rows after them exactly (FIT above 99.9 %), and the slowest pole is
    /// the first channel's 0.9. One denominator shared by both inputs cannot follow both: the
    /// equation-error start, which shares it, falls short.
    #[test]
    fn each_input_has_a_channel_with_its_own_poles() {
        let n = 2000;
        let u1: Vec<f64> = (0..n).map(|t| ((t / 29 * 7919) % 37) as f64 / 18.0 - 1.0).collect();
        let u2: Vec<f64> = (0..n).map(|t| ((t / 17 * 104_729) % 23) as f64 / 11.0 - 1.0).collect();
        // At rest at the first inputs: both paths have unit gain.
        let (mut x1, mut x2) = (vec![u1[0]; n], vec![u2[0]; n]);
        for t in 1..n {
            x1[t] = 0.9 * x1[t - 1] + 0.1 * u1[t - 1];
            x2[t] = 0.4 * x2[t - 1] + 0.6 * u2[t - 1];
        }
        let y: Vec<f64> = x1.iter().zip(&x2).map(|(a, b)| a + b).collect();
        let d = Data { u: vec![&u1, &u2], y: &y, train: 0..1400, nominal: None, noise_order: 0 };
        let rows: Vec<usize> = (2..1400).collect();
        let m = Model {
            element: &Linear,
            input: 0,
            orders: Orders { na: 1, nb: 1, nk: vec![1, 1], trend: false, reading: None },
        };
        let f = fit(&m, &d, &rows).unwrap();
        // [α of u1's channel, α of u2's, β of u1, β of u2, c].
        let want = [0.9, 0.4, 0.1, 0.6, 0.0];
        assert!(f.theta.iter().zip(want).all(|(a, b)| (a - b).abs() < 1e-3), "{f:?}");
        let sim = m.simulate(&f, &d.u, &y).unwrap();
        assert!(fit_pct(&y[1400..], &sim[1400..]) > 99.9, "{f:?}");
        assert!((m.slowest_pole(&f) - 0.9).abs() < 1e-3);
        let shared = m.equation_error(&[], &d.u, &y, &y, &rows).unwrap();
        let sim = m.simulate(&shared, &d.u, &y).unwrap();
        assert!(fit_pct(&y[1400..], &sim[1400..]) < 99.0, "{shared:?}");
    }

    /// A noise-free first-order plant `x(t) = 0.9 x(t−1) + 0.3 u(t−1)` read with a drift,
    /// `y = x + 0.002·t`: then `y(t) = 0.9 y(t−1) + 0.3 u(t−1) + 0.0002·t + 0.0018` exactly, a
    /// recursion the trend term holds (δ = 0.2 per thousand samples, c = 0.0018). Fitted on the
    /// first 2100 rows, every coefficient is recovered and the 900 rows after them, beyond
    /// every row it saw, are simulated to the optimiser's tolerance; the drift read off the
    /// simulation is 0.002 a sample, and held after the training rows it stops. Without the
    /// trend the same structure cannot follow.
    #[test]
    fn a_trend_term_carries_a_drift_beyond_the_fit_rows_or_holds_it() {
        let n = 3000;
        let u: Vec<f64> = (0..n).map(|t| ((t / 23 * 7919) % 41) as f64 / 20.0 - 1.0).collect();
        let mut y = vec![0.0; n];
        let mut x = 0.0;
        for t in 1..n {
            x = 0.9 * x + 0.3 * u[t - 1];
            y[t] = x + 0.002 * t as f64;
        }
        let d = Data { u: vec![&u], y: &y, train: 0..2100, nominal: None, noise_order: 0 };
        let rows: Vec<usize> = (10..2100).collect();
        let model = |trend: bool| Model {
            element: &Linear,
            input: 0,
            orders: Orders { na: 1, nb: 1, nk: vec![1], trend, reading: None },
        };
        let m = model(true);
        let f = fit(&m, &d, &rows).unwrap();
        let with = m.simulate(&f, &d.u, &y).unwrap();
        assert!(fit_pct(&y[2100..], &with[2100..]) > 99.9, "{f:?}");
        let want = [0.9, 0.3, 0.2, 0.0018];
        assert!(f.theta.iter().zip(want).all(|(a, b)| (a - b).abs() < 1e-3), "{f:?}");
        let drift = m.drift_over(&f, &d.u, &y, &rows).unwrap();
        assert!((drift / rows.len() as f64 - 0.002).abs() < 1e-5, "{drift}");
        // Held after row 2099, the drift stops: the two simulations agree to that row, then
        // part by what the line would have added through the pole, `0.002·(t − 2099) − 0.018`
        // once settled (a ramp through `1/(1 − 0.9q⁻¹)` lags by 0.0002·0.9/0.1²), 1.782 at the
        // last row; 0.05 covers the fitted coefficients' 1e-3 carried through `δ/(1 − α)`.
        let held = m.simulate_held(&f, &d.u, &y, 2099).unwrap();
        assert!(held[..2100] == with[..2100], "the two differ before row 2100");
        assert!((with[n - 1] - held[n - 1] - 1.782).abs() < 0.05, "{}", with[n - 1] - held[n - 1]);
        let m = model(false);
        let f = fit(&m, &d, &rows).unwrap();
        let without = m.simulate(&f, &d.u, &y).unwrap();
        assert!(fit_pct(&y[2100..], &without[2100..]) < 99.0);
        assert_eq!(m.drift_over(&f, &d.u, &y, &rows), None);
    }

    /// Where each element with a kink acts, counted on a ramp of 100 samples from 0 to 0.99
    /// (limits between its steps, so no sample sits on one): limits at 0.205 and 0.905 bind on
    /// 0 to 0.20 and 0.91 to 0.99 (21 + 9 samples), 21 of them among the first 50; a store
    /// without memory is the input itself, so it binds where the actuator limit does; a dead
    /// zone of half-width 0.105 about 0.5 holds 0.40 to 0.60 (21); a reading clipped at 0.905 is
    /// held at it from 0.91 up (9). Limits beyond the ramp, or a zone of no width, act nowhere.
    /// A smooth map does not answer.
    #[test]
    fn an_element_with_a_kink_says_where_it_acts() {
        let u: Vec<f64> = (0..100).map(|t| t as f64 / 100.0).collect();
        let all: Vec<usize> = (0..100).collect();
        // The simulated reading as a clip returns it, the limit itself where it clips.
        let read: Vec<f64> = u.iter().map(|v| v.min(0.905)).collect();
        let share = |el: &dyn Element, p: Vec<f64>, rows: &[usize]| {
            let m = Model {
                element: el,
                input: 0,
                orders: Orders { na: 1, nb: 1, nk: vec![1], trend: false, reading: None },
            };
            let f = Fitted { p, theta: vec![0.0, 1.0, 0.0], noise: Vec::new() };
            m.acting_share(&f, &[&u], &read, rows)
        };
        let sat = &saturation::InputSaturation;
        let store = &storage_limit::StorageLimit;
        let (dz, clip) = (&dead_zone::DeadZone, &clip_sensor::ClipSensor { range: None });
        assert_eq!(share(sat, vec![0.905, 0.205], &all), Some(0.3));
        assert_eq!(share(sat, vec![-1.0, 2.0], &all), Some(0.0));
        assert_eq!(share(sat, vec![0.205, 0.905], &all[..50]), Some(0.42));
        assert_eq!(share(store, vec![0.0, 0.205, 0.905], &all), Some(0.3));
        assert_eq!(share(store, vec![0.95, -1.0, 2.0], &all), Some(0.0));
        assert_eq!(share(dz, vec![0.5, -0.105], &all), Some(0.21));
        assert_eq!(share(dz, vec![0.5, 0.0], &all), Some(0.0));
        assert_eq!(share(clip, vec![-1.0, 0.905], &all), Some(0.09));
        assert_eq!(share(clip, vec![-1.0, 2.0], &all), Some(0.0));
        assert_eq!(share(sat, vec![0.205, 0.905], &[]), None);
        assert_eq!(share(&polynomial::Polynomial { degree: 2 }, vec![0.0, 1.0, 0.0, 1.0], &all), None);
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
        let m = Model {
            element: &el,
            input: 0,
            orders: Orders { na: 1, nb: 1, nk: vec![2], trend: false, reading: None },
        };
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
        let m = Model {
            element: &el,
            input: 0,
            orders: Orders { na: 1, nb: 1, nk: vec![1], trend: false, reading: None },
        };
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
        // The map's centre is the fitted rows' mean (the first ten rows are the lags' warm-up).
        let m = u[10..].iter().sum::<f64>() / (u.len() - 10) as f64;
        for (degree, c) in [(2, 0.4), (3, 0.3)] {
            let w_of = |v: f64| v + c * v.powi(degree);
            let slope = 1.0 + c * f64::from(degree) * m.powi(degree - 1);
            let mut y = vec![0.0; u.len()];
            for t in 2..u.len() {
                y[t] = 0.8 * y[t - 1] + 0.5 * w_of(u[t - 2]);
            }
            let d = Data { u: vec![&u], y: &y, train: 10..1200, nominal: None, noise_order: 0 };
            let el = polynomial::Polynomial { degree };
            let model = Model {
                element: &el,
                input: 0,
                orders: Orders { na: 1, nb: 1, nk: vec![2], trend: false, reading: None },
            };
            let rows: Vec<usize> = (10..1200).collect();
            let f = fit(&model, &d, &rows).unwrap();
            let curve = model.curve(&f, &d, "u", "y").expect("a polynomial has a map");
            let truth = |v: f64| (w_of(v) - w_of(m)) / slope + m;
            let span = curve.points.iter().map(|p| truth(p.0)).fold(f64::NEG_INFINITY, f64::max)
                - curve.points.iter().map(|p| truth(p.0)).fold(f64::INFINITY, f64::min);
            // The map is the fitted one over the training range; beyond it, its tangent.
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

    /// A map fitted on some rows takes its centre, scale and range from those rows, not from
    /// the training part: fitted on a fold whose rows never reach the input's top, its powers
    /// go on along their tangent from the fold's own edge over the validation block that does,
    /// as the held-out tail sees a map fitted on the training part. Exact: the fixed parameters
    /// are copied, never searched.
    #[test]
    fn a_map_fitted_on_a_fold_keeps_that_folds_range() {
        let u: Vec<f64> =
            (0..1200).map(|t| ((t / 13 * 7919) % 41) as f64 / 20.0 + t as f64 / 400.0).collect();
        let mut y = vec![0.0; u.len()];
        for t in 1..u.len() {
            y[t] = 0.8 * y[t - 1] + 0.2 * (u[t - 1] + 0.3 * u[t - 1].powi(2));
        }
        let d = Data { u: vec![&u], y: &y, train: 0..1200, nominal: None, noise_order: 0 };
        let rows: Vec<usize> = (10..800).collect();
        for el in [&polynomial::Polynomial { degree: 2 } as &dyn Element, &bilinear::Bilinear] {
            let model = Model {
                element: el,
                input: 0,
                orders: Orders { na: 1, nb: 1, nk: vec![1], trend: false, reading: None },
            };
            let f = fit(&model, &d, &rows).unwrap();
            let on_rows = polynomial::centring_of(&u[10..800]);
            assert_eq!(&f.p[..4], on_rows.as_slice());
            assert!(on_rows[3] < polynomial::centring_of(&u)[3], "the fold must stop short of the top");
        }
    }

    /// A fitted polynomial keeps the centre and scale of its training rows: simulating the first
    /// half of the record alone gives the first half of the whole record's simulation (the
    /// simulation is causal, so only the arithmetic's rounding may differ, 1e-9 of the output's
    /// range), and the centre is the mean of the rows fitted, not the record's. Centred on the
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
        let model = Model {
            element: &el,
            input: 0,
            orders: Orders { na: 1, nb: 1, nk: vec![2], trend: false, reading: None },
        };
        let rows: Vec<usize> = (10..800).collect();
        let f = fit(&model, &d, &rows).unwrap();
        let fitted_mean = u[10..800].iter().sum::<f64>() / 790.0;
        assert_eq!(f.p[0], fitted_mean);
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
        let m = Model {
            element: &el,
            input: 0,
            orders: Orders { na: 1, nb: 1, nk: vec![1], trend: false, reading: None },
        };
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
        let m = Model {
            element: &el,
            input: 0,
            orders: Orders { na: 2, nb: 1, nk: vec![1], trend: false, reading: None },
        };
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
