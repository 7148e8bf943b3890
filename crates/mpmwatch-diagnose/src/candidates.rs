//! The candidate physics: for each vocabulary class, a family of terms built on one input
//! channel (or on the output), each the regressor columns of a correction that is linear in its
//! coefficients once the grid values (a width, a limit, a lag, a pole) are fixed.
//!
//! Input-acting classes pass `φ(u) − u` through the nominal model's own dynamics of the channel
//! (`B_i/A`, see [`super::nominal`]): a dead zone in front of the model is the model applied to
//! the dead-zoned input, so the correction is the model applied to the difference. Output-acting
//! classes act on the simulated output (a clip, an |·| sensor) or feed it back through the
//! channel (cubic stiffness, Coulomb friction), which makes the corrected simulation recursive.
//! A fed-back force is built on the simulation, never on the recorded output: in a closed loop
//! the recorded output is held near its setpoint and carries the disturbance, while the force
//! acts on the plant's state, which the simulation follows. (The same holds on an open-loop
//! record diagnosed with a physical model, which takes this path too.)

use serde::{Deserialize, Serialize};

use super::nominal::{NominalArx, PolyChannels};
use mpmwatch_core::model::DiscreteTf;
use mpmwatch_core::numerics::{self, lagged as delayed, quantile};

/// The fixed vocabulary of left-out physics (DESIGN.md §4.5).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize, Deserialize, PartialOrd, Ord)]
#[serde(rename_all = "snake_case")]
pub enum Physics {
    /// The channel's static gain is off.
    Gain,
    /// The channel's time constant is off.
    TimeConstant,
    /// The channel's dead time is longer than modelled.
    DeadTime,
    /// The model says the input does not reach the output; the plant responds.
    MissingCoupling,
    /// No response to small input moves around the operating point.
    DeadZone,
    /// An actuator limit, or an output overflow or clip.
    Saturation,
    /// A term in the square of the input deviation.
    Quadratic,
    /// A term in the cube of the input (or output) deviation.
    Cubic,
    /// A product of two lagged inputs.
    Bilinear,
    /// Play: the actuator does not move until the input reverses by more than the gap.
    Backlash,
    /// A constant force against the sign of motion.
    CoulombFriction,
    /// The sensor sees the absolute value of the signal.
    AbsSensor,
    /// The residual carries information about the input, but no candidate explains it.
    Unexplained,
}

impl Physics {
    /// Every class but `unexplained`, in report order.
    pub const ALL: [Physics; 12] = [
        Physics::Gain,
        Physics::TimeConstant,
        Physics::DeadTime,
        Physics::MissingCoupling,
        Physics::DeadZone,
        Physics::Saturation,
        Physics::Quadratic,
        Physics::Cubic,
        Physics::Bilinear,
        Physics::Backlash,
        Physics::CoulombFriction,
        Physics::AbsSensor,
    ];

    /// The snake_case name used in reports.
    pub fn name(self) -> &'static str {
        match self {
            Physics::Gain => "gain",
            Physics::TimeConstant => "time_constant",
            Physics::DeadTime => "dead_time",
            Physics::MissingCoupling => "missing_coupling",
            Physics::DeadZone => "dead_zone",
            Physics::Saturation => "saturation",
            Physics::Quadratic => "quadratic",
            Physics::Cubic => "cubic",
            Physics::Bilinear => "bilinear",
            Physics::Backlash => "backlash",
            Physics::CoulombFriction => "coulomb_friction",
            Physics::AbsSensor => "abs_sensor",
            Physics::Unexplained => "unexplained",
        }
    }
}

/// Where the left-out physics acts.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum ActsOn {
    /// On the manipulated variable before the model's dynamics (or, for a state limit of a
    /// physical model, on a state between the input and the measured output).
    Input,
    /// On the output (a sensor, a clip, or a force fed back from the output).
    Output,
}

/// One concrete hypothesis: a class with its grid values on one input channel.
#[derive(Debug, Clone, PartialEq)]
pub enum Term {
    /// `θ·s_ji`: the channel's gain scaled by `1 + θ`.
    Gain,
    /// `s_ji(t − d) − s_ji(t)`: `d` more samples of dead time, or with `d < 0` fewer: the
    /// model's delay too long (a pure delay measured in a different line-up, a transport that
    /// got faster). A shorter delay is tried only as far as the model's own delay allows while
    /// the channel stays strictly causal.
    DeadTime(isize),
    /// A unit-gain lead–lag moving the dominant pole from `p0` to `p1`.
    TimeConstant { p0: f64, p1: f64 },
    /// A first-order lag `(1−p) q^−d/(1 − p q^−1)` of the input where the model has none.
    MissingCoupling { pole: f64, delay: usize },
    /// Dead zone of half-width `w` around `centre` (a deviation from the input's median).
    DeadZone { centre: f64, w: f64 },
    /// Input clipped to `[lo, hi]` (deviations from the operating point; ±∞ for one side).
    SaturationIn { lo: f64, hi: f64 },
    /// Output clipped to `[lo, hi]` (absolute values).
    SaturationOut { lo: f64, hi: f64 },
    /// Square of the input deviation through the channel, with a linear term so that the
    /// parabola's centre is free (`q(u − c)² = qu² − 2qcu + qc²`).
    Quadratic,
    /// Cube of the input deviation through the channel, with square and linear terms (a cubic
    /// about a free centre).
    Cubic,
    /// Cube of the simulated output's deviation fed back through the channel (a hardening
    /// spring).
    CubicOut,
    /// Products of lagged input deviations, the lags chosen by FROLS: `(input, lag, input, lag)`.
    Bilinear(Vec<(usize, usize, usize, usize)>),
    /// Play of total width `w`.
    Backlash(f64),
    /// `sign(x̂)` (velocity output) or `sign(Δx̂)` (position output) of the simulated state fed
    /// back through the channel.
    Coulomb { on_change: bool },
    /// The sensor reads `|x − o| + o`.
    AbsSensor(f64),
    /// A state of a physical nominal model never rises above `level`; the fraction `spill` of
    /// what overflows flows on to the next state (an overflowing tank; see [`super::physical`]).
    /// Its column is the re-run model's output minus the nominal simulation, precomputed in
    /// [`OutputCtx::physical_terms`]. `measured`: the state is the measured output itself (the limit
    /// then acts on the output, otherwise on the way from the input to it); `spills`: spill
    /// fractions were tried for this state (a grid value more in the penalty).
    StateLimit { state: usize, level: f64, spill: f64, measured: bool, spills: bool },
    /// Input `input` reaches a physical nominal model multiplied by `ratio` (an actuator whose
    /// gain is off), stated by re-running the model; precomputed like [`Term::StateLimit`].
    ModelGain { input: usize, ratio: f64 },
}

impl Term {
    /// Its vocabulary class.
    pub fn physics(&self) -> Physics {
        match self {
            Term::Gain | Term::ModelGain { .. } => Physics::Gain,
            Term::DeadTime(_) => Physics::DeadTime,
            Term::TimeConstant { .. } => Physics::TimeConstant,
            Term::MissingCoupling { .. } => Physics::MissingCoupling,
            Term::DeadZone { .. } => Physics::DeadZone,
            Term::SaturationIn { .. } | Term::SaturationOut { .. } | Term::StateLimit { .. } => {
                Physics::Saturation
            }
            Term::Quadratic => Physics::Quadratic,
            Term::Cubic | Term::CubicOut => Physics::Cubic,
            Term::Bilinear(_) => Physics::Bilinear,
            Term::Backlash(_) => Physics::Backlash,
            Term::Coulomb { .. } => Physics::CoulombFriction,
            Term::AbsSensor(_) => Physics::AbsSensor,
        }
    }

    /// Where it acts.
    pub fn acts_on(&self) -> ActsOn {
        match self {
            Term::SaturationOut { .. }
            | Term::CubicOut
            | Term::Coulomb { .. }
            | Term::AbsSensor(_)
            | Term::StateLimit { measured: true, .. } => ActsOn::Output,
            _ => ActsOn::Input,
        }
    }

    /// Number of values fixed by a grid or a selection (counted in the complexity penalty).
    pub fn grid_params(&self) -> usize {
        match self {
            Term::Gain | Term::Quadratic | Term::Cubic | Term::CubicOut => 0,
            Term::MissingCoupling { .. } | Term::DeadZone { .. } => 2,
            Term::StateLimit { spills, .. } => 1 + usize::from(*spills),
            Term::ModelGain { .. } => 1,
            Term::SaturationIn { lo, hi } | Term::SaturationOut { lo, hi } => {
                usize::from(lo.is_finite()) + usize::from(hi.is_finite())
            }
            Term::Bilinear(t) => t.len(),
            _ => 1,
        }
    }

    /// Whether the physics fixes the term's weight at 1: the plant is the model applied to
    /// `φ(u)` (a dead zone, a limit, play, a longer delay, a lead–lag, a sensor map), so the
    /// correction is exactly `G0(φ(u) − u)` and only the grid value is free. A free weight would
    /// let, say, a scaled dead zone imitate a gain change.
    pub fn fixed_weight(&self) -> bool {
        matches!(
            self,
            Term::DeadTime(_)
                | Term::TimeConstant { .. }
                | Term::DeadZone { .. }
                | Term::SaturationIn { .. }
                | Term::SaturationOut { .. }
                | Term::Backlash(_)
                | Term::AbsSensor(_)
                | Term::StateLimit { .. }
                | Term::ModelGain { .. }
        )
    }

    /// Its grid values that vary continuously (a dead zone's centre and half-width, a limit,
    /// a play, a sensor's offset, a pole), in the order [`Term::with_continuous`] reads them;
    /// empty for a term with none (a dead time is a whole number of samples).
    pub fn continuous(&self) -> Vec<f64> {
        match self {
            Term::DeadZone { centre, w } => vec![*centre, *w],
            Term::SaturationIn { lo, hi } | Term::SaturationOut { lo, hi } => {
                [*lo, *hi].into_iter().filter(|v| v.is_finite()).collect()
            }
            Term::Backlash(w) => vec![*w],
            Term::AbsSensor(o) => vec![*o],
            Term::TimeConstant { p1, .. } => vec![*p1],
            Term::MissingCoupling { pole, .. } => vec![*pole],
            _ => Vec::new(),
        }
    }

    /// The same term with its continuous grid values replaced by `x` (as [`Term::continuous`]
    /// lists them); `None` where `x` leaves the values' domain (a negative width, crossed
    /// limits, a pole outside [0, 1)).
    pub fn with_continuous(&self, x: &[f64]) -> Option<Term> {
        let t = match (self, x) {
            (Term::DeadZone { .. }, &[centre, w]) if w >= 0.0 => Term::DeadZone { centre, w },
            (Term::SaturationIn { lo, hi }, _) | (Term::SaturationOut { lo, hi }, _) => {
                let mut it = x.iter().copied();
                let lo = if lo.is_finite() { it.next()? } else { *lo };
                let hi = if hi.is_finite() { it.next()? } else { *hi };
                if lo >= hi || it.next().is_some() {
                    return None;
                }
                if matches!(self, Term::SaturationIn { .. }) {
                    Term::SaturationIn { lo, hi }
                } else {
                    Term::SaturationOut { lo, hi }
                }
            }
            (Term::Backlash(_), &[w]) if w >= 0.0 => Term::Backlash(w),
            (Term::AbsSensor(_), &[o]) => Term::AbsSensor(o),
            (Term::TimeConstant { p0, .. }, &[p1]) if (0.0..1.0).contains(&p1) => {
                Term::TimeConstant { p0: *p0, p1 }
            }
            (Term::MissingCoupling { delay, .. }, &[pole]) if (0.0..1.0).contains(&pole) => {
                Term::MissingCoupling { pole, delay: *delay }
            }
            _ => return None,
        };
        Some(t)
    }

    /// Whether the correction feeds back its own simulated state (simulated step by step).
    pub fn is_recursive(&self) -> bool {
        matches!(self, Term::CubicOut | Term::Coulomb { .. })
    }
}

/// Everything the terms of one output are built from.
#[derive(Debug, Clone)]
pub struct OutputCtx {
    /// Recorded inputs minus their operating point (median over the training part).
    pub ut: Vec<Vec<f64>>,
    /// The operating points.
    pub u0: Vec<f64>,
    /// Per input, the range of `ut` over the training rows: beyond it the polynomial terms'
    /// powers go on along their tangent at its edges (see [`OutputCtx::columns`]).
    pub u_range: Vec<(f64, f64)>,
    /// Nominal simulation of this output.
    pub s: Vec<f64>,
    /// Operating point of the output (median of the simulation over the training part).
    pub y0: f64,
    /// The nominal model identified from the simulation.
    pub model: NominalArx,
    /// The nominal's channels as polynomials of the inputs, when the simulation is not linear
    /// in them ([`crate::nominal::identify_polynomial`]); `None` for a linear nominal.
    pub poly: Option<PolyChannels>,
    /// Per input: does the model have this channel at all.
    pub has_channel: Vec<bool>,
    /// Per input: `s_ji`, the model's response to the centred input
    /// ([`OutputCtx::channel_response`]).
    pub s_channel: Vec<Vec<f64>>,
    /// With a physical nominal model: every hypothesis stated by re-running it (state limits,
    /// actuator gains) and its correction (see [`super::physical`]); empty otherwise.
    pub physical_terms: Vec<(Term, Vec<f64>)>,
    /// With a physical nominal model: the name of each of its states.
    pub state_names: Vec<String>,
}

impl OutputCtx {
    /// The nominal's response to input `i` moved by `x` from its operating point: through the
    /// polynomial channels when the nominal has them, else through the linear channel.
    pub fn channel_response(&self, i: usize, x: &[f64]) -> Vec<f64> {
        match &self.poly {
            Some(p) => {
                let u0 = self.u0[i];
                p.response(i, &x.iter().map(|v| v + u0).collect::<Vec<_>>(), u0)
            }
            None => self.model.channel(i, x),
        }
    }

    /// Input i's channel as the model has it at the operating point: the linear nominal's, or
    /// with polynomial channels their linearisation at `u0` ([`PolyChannels::linearised`]).
    fn channel_tf(&self, i: usize) -> Option<mpmwatch_core::model::DiscreteTf> {
        self.poly.as_ref().and_then(|p| p.linearised(i, self.u0[i]))
    }

    /// DC gain of input i's channel at the operating point.
    pub fn dc_gain(&self, i: usize) -> f64 {
        self.channel_tf(i).map_or_else(|| self.model.dc_gain(i), |tf| tf.dc_gain().unwrap_or(f64::NAN))
    }

    /// Pure delay of input i's channel, samples.
    pub fn delay(&self, i: usize) -> usize {
        self.channel_tf(i).map_or_else(|| self.model.delay(i), |tf| crate::nominal::delay(&tf))
    }

    /// The regressor columns of a non-recursive term on input `i` (the intercept is added by the
    /// fitter). For a recursive term: its columns linearised at the nominal simulation (the
    /// first step of the recursion).
    pub fn columns(&self, i: usize, term: &Term) -> Vec<Vec<f64>> {
        let u = &self.ut[i];
        let g0 = |x: &[f64]| self.model.channel(i, x);
        let sc = &self.s_channel[i];
        // A static map in front of the channel, given as what it takes off the input (`delta`):
        // through the linear channel, or, with polynomial channels, the nominal's own response
        // to the mapped input minus its response to the input (the map acts before the
        // nominal's curvature, as before its dynamics).
        let in_front = |delta: Vec<f64>| -> Vec<f64> {
            if self.poly.is_none() {
                return g0(&delta);
            }
            let mapped: Vec<f64> = u.iter().zip(&delta).map(|(a, b)| a + b).collect();
            self.channel_response(i, &mapped).iter().zip(sc).map(|(a, b)| a - b).collect()
        };
        match term {
            Term::Gain => vec![sc.clone()],
            Term::DeadTime(d) => {
                // A shorter delay is the channel's response to the input moved earlier; the
                // input's held last value is never reached (the grid keeps `−d` below the delay).
                let shifted = match usize::try_from(*d) {
                    Ok(later) => delayed(sc, later),
                    Err(_) => self.channel_response(i, &advanced(u, d.unsigned_abs())),
                };
                vec![shifted.iter().zip(sc).map(|(a, b)| a - b).collect()]
            }
            Term::TimeConstant { p0, p1 } => {
                let k = (1.0 - p1) / (1.0 - p0);
                let ll = first_order(vec![k, -k * p0], *p1, sc);
                vec![ll.iter().zip(sc).map(|(a, b)| a - b).collect()]
            }
            Term::MissingCoupling { pole, delay } => {
                let mut b = vec![0.0; delay + 1];
                b[*delay] = 1.0 - pole;
                vec![first_order(b, *pole, u)]
            }
            Term::DeadZone { centre, w } => {
                vec![in_front(u.iter().map(|v| -(v - centre).clamp(-w, *w)).collect())]
            }
            Term::SaturationIn { lo, hi } => {
                vec![in_front(u.iter().map(|v| v.clamp(*lo, *hi) - v).collect())]
            }
            Term::SaturationOut { lo, hi } => vec![self.s.iter().map(|v| v.clamp(*lo, *hi) - v).collect()],
            // The grey-box polynomial's rule ([`crate::greybox::power`]): the powers go on along
            // their tangent beyond the training range, known only within it.
            Term::Quadratic | Term::Cubic => {
                let (lo, hi) = self.u_range.get(i).copied().unwrap_or((f64::NEG_INFINITY, f64::INFINITY));
                let p = [0.0, 1.0, lo, hi];
                let power =
                    |k: i32| g0(&u.iter().map(|&v| crate::greybox::power(&p, v, k)).collect::<Vec<_>>());
                let mut cols =
                    if matches!(term, Term::Cubic) { vec![power(3), power(2)] } else { vec![power(2)] };
                cols.push(self.s_channel[i].clone());
                cols
            }
            Term::CubicOut => vec![g0(&self.s.iter().map(|v| (v - self.y0).powi(3)).collect::<Vec<_>>())],
            Term::Bilinear(pairs) => pairs
                .iter()
                .map(|&(ia, la, ib, lb)| {
                    let (a, b) = (delayed(&self.ut[ia], la), delayed(&self.ut[ib], lb));
                    g0(&a.iter().zip(&b).map(|(x, y)| x * y).collect::<Vec<_>>())
                })
                .collect(),
            Term::Backlash(w) => {
                let p = play(u, *w);
                vec![in_front(p.iter().zip(u).map(|(a, b)| a - b).collect())]
            }
            Term::Coulomb { on_change } => vec![g0(&coulomb_input(&self.s, *on_change))],
            Term::AbsSensor(o) => vec![self.s.iter().map(|v| (v - o).abs() + o - v).collect()],
            Term::StateLimit { .. } | Term::ModelGain { .. } => self
                .physical_terms
                .iter()
                .filter(|(t, _)| t == term)
                .map(|(_, c)| c.clone())
                .take(1)
                .collect(),
        }
    }

    /// Every candidate bilinear product on input `i`: the same input at two different lags
    /// (0..=3), and input `i` times each other input at lags 0..=2.
    pub fn bilinear_pool(&self, i: usize) -> Vec<(usize, usize, usize, usize)> {
        let mut pool = Vec::new();
        for la in 0..=3 {
            for lb in la + 1..=3 {
                pool.push((i, la, i, lb));
            }
        }
        for k in 0..self.ut.len() {
            if k != i {
                for l in 0..=2 {
                    pool.push((i, 0, k, l));
                    if l > 0 {
                        pool.push((i, l, k, 0));
                    }
                }
            }
        }
        pool
    }
}

/// The input of the friction term on a simulated state `x`: `sign(x)` for a velocity,
/// `sign(x(t) − x(t−1))` for a position.
pub fn coulomb_input(x: &[f64], on_change: bool) -> Vec<f64> {
    (0..x.len())
        .map(|t| {
            let v = if on_change { if t > 0 { x[t] - x[t - 1] } else { 0.0 } } else { x[t] };
            if v > 0.0 {
                1.0
            } else if v < 0.0 {
                -1.0
            } else {
                0.0
            }
        })
        .collect()
}

/// The play (backlash) operator of total width `w`: the output follows the input only once the
/// input has moved more than `w/2` past it, starting at the first input value.
pub fn play(u: &[f64], w: f64) -> Vec<f64> {
    let h = w / 2.0;
    let mut out = Vec::with_capacity(u.len());
    let mut z = u.first().copied().unwrap_or(0.0);
    for &v in u {
        if v > z + h {
            z = v - h;
        } else if v < z - h {
            z = v + h;
        }
        out.push(z);
    }
    out
}

/// Dead-zone widths and symmetric limits tried besides the quantiles of `|u − c|`, as fractions
/// of its 95th percentile (see [`grid`]).
const EVEN_WIDTHS: [f64; 5] = [0.2, 0.35, 0.5, 0.65, 0.8];

/// `x(t + d)`, the last value held past the end.
fn advanced(x: &[f64], d: usize) -> Vec<f64> {
    let last = x.len().saturating_sub(1);
    (0..x.len()).map(|t| x[(t + d).min(last)]).collect()
}

/// The grid of concrete terms tried on input `i` of this output (bilinear excluded: its lags
/// are chosen by FROLS in the fitter).
pub fn grid(ctx: &OutputCtx, i: usize, rows: std::ops::Range<usize>) -> Vec<Term> {
    let mut out = Vec::new();
    if !ctx.has_channel[i] {
        for pole in [0.0, 0.5, 0.7, 0.8, 0.9, 0.95] {
            for delay in 1..=6 {
                out.push(Term::MissingCoupling { pole, delay });
            }
        }
        return out;
    }
    let u = &ctx.ut[i][rows.clone()];
    let s = &ctx.s[rows.clone()];
    out.push(Term::Gain);
    out.extend((1..=8).map(Term::DeadTime));
    let shorter = ctx.delay(i).saturating_sub(1).min(8) as isize;
    out.extend((1..=shorter).map(|d| Term::DeadTime(-d)));
    // The dominant pole is the linear nominal's also where polynomial channels exist: their
    // denominator is shared by every power of every input, so their linearisation's step is a
    // poor reading of one channel's speed (docs/diagnose-history.md, stop 40).
    let p0 = ctx.model.dominant_pole(i, 2000);
    let tau0 = -1.0 / p0.ln();
    for rho in [0.3, 0.4, 0.5, 0.6, 0.7, 0.8, 1.25, 1.5, 1.75, 2.0, 2.5, 3.0, 3.5, 4.0, 5.0] {
        out.push(Term::TimeConstant { p0, p1: (-1.0 / (rho * tau0)).exp() });
    }
    // Centres of the symmetric nonlinearities: quantiles of the input, and its mean. The mean
    // matters under a binary dither: the input is then two clusters (±1 plus the controller's
    // move) and its median falls anywhere in the gap between them, so no quantile sits at the
    // operating point. (Casebook c09 is still named a gain with it: over two clusters a dead zone
    // and a gain reduction move the input alike, and the dead zone loses by its penalty.)
    let mean = numerics::mean(u);
    let centres: Vec<f64> =
        [0.3, 0.4, 0.5, 0.6, 0.7].iter().map(|&q| quantile(u, q)).chain(std::iter::once(mean)).collect();
    // Under a binary dither the distance from a centre, |u − c|, falls in two clusters, and its
    // quantiles jump across the gap between them, where a dead zone's edge or a limit may well
    // sit; widths spaced evenly up to the 95th percentile fill that gap.
    let dev: Vec<Vec<f64>> = centres.iter().map(|c| u.iter().map(|v| (v - c).abs()).collect()).collect();
    for (&centre, d) in centres.iter().zip(&dev) {
        let top = quantile(d, 0.95);
        let quantiles =
            [0.05, 0.1, 0.15, 0.2, 0.25, 0.3, 0.35, 0.4, 0.5, 0.6, 0.7, 0.8].map(|q| quantile(d, q));
        let evenly = EVEN_WIDTHS.map(|f| f * top);
        out.extend(quantiles.into_iter().chain(evenly).map(|w| Term::DeadZone { centre, w }));
    }
    // Symmetric limits about the middle three quantile centres and the mean, down to a tenth
    // of `|u − c|`'s distribution: an actuator that spends most of the record at its limits (a
    // strongly saturated one) passes only its smallest moves. An input that sits at a centre
    // for a tenth of the rows or more (a quantised valve, a loop in manual) gives a limit of
    // width zero there, a dead channel rather than a limit, which is not offered.
    let symmetric = [1, 2, 3, 5];
    for q in [0.1, 0.2, 0.3, 0.4] {
        for &k in &symmetric {
            let (c, a) = (centres[k], quantile(&dev[k], q));
            if a > 0.0 {
                out.push(Term::SaturationIn { lo: c - a, hi: c + a });
            }
        }
    }
    for q in [0.5, 0.6, 0.65, 0.7, 0.75, 0.8, 0.85, 0.9, 0.95] {
        out.push(Term::SaturationIn { lo: f64::NEG_INFINITY, hi: quantile(u, q) });
        out.push(Term::SaturationIn { lo: quantile(u, 1.0 - q), hi: f64::INFINITY });
        for &k in &symmetric {
            let (c, a) = (centres[k], quantile(&dev[k], q));
            out.push(Term::SaturationIn { lo: c - a, hi: c + a });
        }
        out.push(Term::SaturationOut { lo: f64::NEG_INFINITY, hi: quantile(s, q) });
        out.push(Term::SaturationOut { lo: quantile(s, 1.0 - q), hi: f64::INFINITY });
    }
    for &k in &symmetric {
        let (c, top) = (centres[k], quantile(&dev[k], 0.95));
        out.extend(EVEN_WIDTHS.map(|f| Term::SaturationIn { lo: c - f * top, hi: c + f * top }));
    }
    out.push(Term::Quadratic);
    out.push(Term::Cubic);
    out.push(Term::CubicOut);
    let sd = (u.iter().map(|v| v * v).sum::<f64>() / u.len().max(1) as f64).sqrt();
    for f in [0.1, 0.2, 0.3, 0.4, 0.5, 0.6, 0.8, 1.0, 1.3, 1.6, 2.0] {
        out.push(Term::Backlash(f * sd));
    }
    out.push(Term::Coulomb { on_change: false });
    out.push(Term::Coulomb { on_change: true });
    let mut offs = vec![0.0];
    offs.extend([0.1, 0.25, 0.5, 0.75, 0.9].iter().map(|&q| quantile(s, q)));
    out.extend(offs.into_iter().map(Term::AbsSensor));
    out
}

/// `B(q⁻¹)/(1 − pole·q⁻¹)` applied to `x`, started in steady state (the grids' poles are in
/// [0, 1), so the filter exists; a non-finite coefficient gives a zero column that no fit uses).
fn first_order(b: Vec<f64>, pole: f64, x: &[f64]) -> Vec<f64> {
    DiscreteTf::new(b, vec![1.0, -pole], 0).map_or_else(|_| vec![0.0; x.len()], |g| g.simulate_from_rest(x))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A dead zone in front of a square-law nominal (`s = G(u²)`, uniform input, seed 5): the
    /// dead-zone column is the nominal's own response to the dead-zoned input minus its response
    /// to the input, to 1e-6 of its spread (the nominal is in the polynomial class, so only
    /// rounding is left); through the linear approximation of the channel it would miss the
    /// curvature.
    #[test]
    fn an_input_map_acts_before_a_polynomial_nominal() {
        use mpmwatch_core::model::DiscreteTf;
        use rand::{Rng, SeedableRng};
        let n = 600;
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(5);
        let u: Vec<f64> = (0..n).map(|_| rng.random_range(0.0..3.0)).collect();
        let g = DiscreteTf::new(vec![0.0, 0.3], vec![1.0, -0.7], 0).unwrap();
        let law = |x: &[f64]| g.simulate_from_rest(&x.iter().map(|v| v * v).collect::<Vec<_>>());
        let ctx = crate::plan::output_ctx(&[&u], &law(&u), &crate::plan::open_split(20..n));
        assert!(ctx.poly.is_some(), "a square law has polynomial channels");
        let (centre, w) = (0.2, 0.5);
        let u0 = ctx.u0[0];
        let dz: Vec<f64> = u.iter().map(|v| v - (v - u0 - centre).clamp(-w, w)).collect();
        let (after, before) = (law(&dz), law(&u));
        let want: Vec<f64> = after.iter().zip(&before).map(|(a, b)| a - b).collect();
        let got = &ctx.columns(0, &Term::DeadZone { centre, w })[0];
        let spread = mpmwatch_core::numerics::rms(&want);
        let err = (20..n).map(|t| (got[t] - want[t]).abs()).fold(0.0, f64::max);
        assert!(err < 1e-6 * spread, "largest error {err} against a spread of {spread}");
    }

    /// Every term with continuous grid values gives them back unchanged, and values outside
    /// their domain (a negative width, crossed limits, a pole at 1) are refused.
    #[test]
    fn continuous_values_round_trip_and_keep_their_domain() {
        let inf = f64::INFINITY;
        for t in [
            Term::DeadZone { centre: 0.1, w: 0.3 },
            Term::SaturationIn { lo: -inf, hi: 0.5 },
            Term::SaturationIn { lo: -0.2, hi: 0.5 },
            Term::SaturationOut { lo: 0.1, hi: inf },
            Term::Backlash(0.3),
            Term::AbsSensor(-0.4),
            Term::TimeConstant { p0: 0.8, p1: 0.9 },
            Term::MissingCoupling { pole: 0.5, delay: 2 },
        ] {
            assert_eq!(t.with_continuous(&t.continuous()), Some(t.clone()));
        }
        assert!(Term::Gain.continuous().is_empty() && Term::DeadTime(3).continuous().is_empty());
        assert_eq!(Term::DeadZone { centre: 0.0, w: 0.3 }.with_continuous(&[0.0, -0.1]), None);
        assert_eq!(Term::SaturationIn { lo: -0.2, hi: 0.5 }.with_continuous(&[0.6, 0.5]), None);
        assert_eq!(Term::TimeConstant { p0: 0.8, p1: 0.9 }.with_continuous(&[1.0]), None);
        assert_eq!(Term::Backlash(0.3).with_continuous(&[0.3, 0.1]), None);
        assert_eq!(Term::SaturationIn { lo: -inf, hi: 0.5 }.with_continuous(&[0.4, 0.6]), None);
        assert_eq!(Term::MissingCoupling { pole: 0.5, delay: 2 }.with_continuous(&[1.0]), None);
    }

    /// The polynomial terms continue their powers along the tangent beyond the training range,
    /// as the grey-box polynomial does: on a record whose tail leaves that range, each power
    /// column is the channel's response to `z_e^k + k z_e^(k−1) (z − z_e)` (`z_e` the input held
    /// at the range's edge), built here by hand and compared at 1e-12 (the same arithmetic, one
    /// linear filter), and against the column the powers held at the edge would give, which it
    /// must miss by more than 0.1 at row 450, 50 rows into the tail (so the test tells the two
    /// rules apart); the linear column still follows the input itself.
    #[test]
    fn polynomial_columns_go_on_along_their_tangent_beyond_the_training_range() {
        let n = 600;
        let u: Vec<f64> =
            (0..n).map(|t| ((t / 7 * 7919) % 23) as f64 / 10.0 + if t >= 400 { 3.0 } else { 0.0 }).collect();
        let mut s = vec![0.0; n];
        for t in 1..n {
            s[t] = 0.8 * s[t - 1] + 0.5 * u[t - 1];
        }
        let split = crate::select::Split {
            features: None,
            fit: 20..280,
            train: 20..400,
            folds: Vec::new(),
            closed_loop: false,
            whiten: 0,
        };
        let ctx = crate::plan::output_ctx(&[&u], &s, &split);
        let (lo, hi) = ctx.u_range[0];
        assert!(ctx.ut[0][400..].iter().all(|&z| z > hi + 0.5), "the tail must leave the range");
        let tangent = |z: f64, k: i32| {
            let ze = z.clamp(lo, hi);
            ze.powi(k) + f64::from(k) * ze.powi(k - 1) * (z - ze)
        };
        for term in [Term::Quadratic, Term::Cubic] {
            let cols = ctx.columns(0, &term);
            let powers: Vec<i32> = if matches!(term, Term::Cubic) { vec![3, 2] } else { vec![2] };
            for (col, &k) in cols.iter().zip(&powers) {
                let want =
                    ctx.model.channel(0, &ctx.ut[0].iter().map(|&z| tangent(z, k)).collect::<Vec<_>>());
                let worst = col.iter().zip(&want).fold(0.0f64, |m, (x, y)| m.max((x - y).abs()));
                assert!(worst < 1e-12, "{term:?} power {k}: {worst}");
                let held = ctx
                    .model
                    .channel(0, &ctx.ut[0].iter().map(|&z| z.clamp(lo, hi).powi(k)).collect::<Vec<_>>());
                assert!(
                    (col[450] - held[450]).abs() > 0.1,
                    "{term:?} power {k}: indistinguishable from held"
                );
            }
            assert_eq!(cols[powers.len()], ctx.s_channel[0], "{term:?}: the linear column");
        }
    }

    /// Under a binary input (two clusters at ±1, a small move on each) the quantiles of `|u − c|`
    /// sit near 0 and 2 from a centre in one cluster and near 1 from the mean; the grid still
    /// offers dead-zone widths and symmetric limits well inside the gap between the clusters
    /// (0.2 to 0.8 from the mean), where an actuator limit of, say, ±0.5 would lie.
    #[test]
    fn binary_input_grid_reaches_into_the_gap() {
        let n = 600;
        let u: Vec<f64> = (0..n)
            .map(
                |t| if (t * 7919 / 13) % 2 == 0 { 1.0 } else { -1.0 } + 0.05 * ((t % 11) as f64 / 10.0 - 0.5),
            )
            .collect();
        let s: Vec<f64> = u.iter().map(|v| 0.5 * v).collect();
        let ctx = crate::plan::output_ctx(&[&u], &s, &crate::plan::open_split(20..400));
        let terms = grid(&ctx, 0, 20..400);
        let inside = |w: f64| (0.2..0.8).contains(&w);
        assert!(
            terms.iter().any(|t| matches!(t, Term::DeadZone { w, .. } if inside(*w))),
            "no dead zone in the gap"
        );
        assert!(
            terms.iter().any(|t| matches!(t, Term::SaturationIn { lo, hi } if inside((hi - lo) / 2.0))),
            "no symmetric limit in the gap"
        );
    }

    /// An actuator that clips most of its moves: under a uniform input on [−1, 1] a limit of
    /// ±0.1 passes a tenth of the samples. The grid offers a symmetric limit there (the tenth
    /// quantile of `|u − c|`); its evenly spaced limits start at 0.2 of the 95th percentile (0.19).
    #[test]
    fn grid_offers_limits_that_clip_most_moves() {
        let n = 1000;
        let u: Vec<f64> = (0..n).map(|t| ((t * 7919) % n) as f64 / n as f64 * 2.0 - 1.0).collect();
        let s: Vec<f64> = u.iter().map(|v| 0.5 * v).collect();
        let ctx = crate::plan::output_ctx(&[&u], &s, &crate::plan::open_split(0..n));
        let terms = grid(&ctx, 0, 0..n);
        assert!(
            terms.iter().any(
                |t| matches!(t, Term::SaturationIn { lo, hi } if (0.05..0.15).contains(&((hi - lo) / 2.0)) && ((lo + hi) / 2.0).abs() < 0.05)
            ),
            "no symmetric limit clipping nine moves in ten"
        );
        // Held at zero for a fifth of the rows: no limit of width zero is offered.
        let held: Vec<f64> = u.iter().enumerate().map(|(t, &v)| if t % 5 == 0 { 0.0 } else { v }).collect();
        let ctx = crate::plan::output_ctx(&[&held], &s, &crate::plan::open_split(0..n));
        assert!(
            !grid(&ctx, 0, 0..n).iter().any(|t| matches!(t, Term::SaturationIn { lo, hi } if lo >= hi)),
            "a limit of width zero"
        );
    }

    /// A model whose delay is two samples too long (four where the plant has two, a first-order
    /// channel, uniform input, seed 9): the grid offers shorter delays down to one sample
    /// (strictly causal) and no further, and the two-samples-shorter column is the plant's
    /// output minus the model's exactly, once the start's transient (pole 0.7, from row 100
    /// below 1e-15) has gone.
    #[test]
    fn a_delay_shorter_than_the_models_is_the_channel_moved_earlier() {
        use mpmwatch_core::model::DiscreteTf;
        use rand::{Rng, SeedableRng};
        let n = 800;
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(9);
        let u: Vec<f64> = (0..n).map(|_| rng.random_range(-1.0..1.0)).collect();
        let with_delay = |d| DiscreteTf::new(vec![0.3], vec![1.0, -0.7], d).unwrap().simulate_from_rest(&u);
        let (s, y) = (with_delay(4), with_delay(2));
        let ctx = crate::plan::output_ctx(&[&u], &s, &crate::plan::open_split(20..n));
        assert_eq!(ctx.delay(0), 4);
        let shorter: Vec<isize> = grid(&ctx, 0, 20..n)
            .iter()
            .filter_map(|t| match t {
                Term::DeadTime(d) if *d < 0 => Some(*d),
                _ => None,
            })
            .collect();
        assert_eq!(shorter, vec![-1, -2, -3]);
        let col = &ctx.columns(0, &Term::DeadTime(-2))[0];
        let spread = mpmwatch_core::numerics::rms(&s);
        let err = (100..n).map(|t| (col[t] - (y[t] - s[t])).abs()).fold(0.0, f64::max);
        assert!(err < 1e-9 * spread, "largest error {err} against a spread of {spread}");
    }

    #[test]
    fn play_holds_inside_the_gap() {
        let p = play(&[0.0, 0.4, 1.0, 0.8, 0.2, -1.0], 1.0);
        assert_eq!(p, vec![0.0, 0.0, 0.5, 0.5, 0.5, -0.5]);
    }
}
