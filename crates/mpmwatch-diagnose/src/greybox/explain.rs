//! From the grey-box hypotheses of one output to its finding: every class against the best
//! re-fitted linear structure and the nominal, by blocked cross-validation in simulation mode.
//!
//! The rule, in the currency of the held-out FIT (simulation mode, out of sample, each
//! validation block against its own mean; [`super::CvScore`]):
//! - a physics element is named when its cross-validated FIT beats the linear re-fit's by
//!   [`NONLINEAR_MARGIN`] points, beats the nominal's by the caller's margin on average, and
//!   lowers no block below the nominal's;
//! - otherwise the linear re-fit is the finding (a gain, a time constant or a dead time,
//!   whichever it changes most) when it passes the same two tests against the nominal;
//! - otherwise the finding is `unexplained`, naming the best candidate, its mean gain and its
//!   worst block's.
//!
//! Either finding also needs a corrected model that settles within a validation block: its
//! slowest pole's time constant shorter than the shortest block. A block checks what a model
//! does within it; a slower mode sets the level the simulation carries from block to block,
//! which no block checks and the held-out tail, longer than a block, exposes (a near-integrator
//! fitted to two tanks drifted off the tail's level by tens of percent, docs/diagnose-history.md, stop
//! 42). A correction that does not settle is withheld, with its time constant; when it is the
//! linear re-fit, the best other pole and tap count that settles and ranks within [`PARSIMONY`]
//! of it is reported in its place (`Judge::settling_refit`). The poles of an
//! element whose own stores carry the dynamics (a tank cascade) are not read: its slow modes'
//! levels are set by its own law and its starting levels are fitted ([`settling_time`]). Poles
//! say nothing of a force fed back that holds the output where it stands (a friction on the
//! output's change sticks it at any level the drive does not beat): a structure with a
//! feedback element must also forget, within a block, a start one standard deviation away
//! ([`memory_time`]).
//!
//! A named element must also act: an element with a kink (a limit, a dead zone) whose fitted
//! kink lies where the record hardly goes, on fewer than [`MIN_ACTING`] of the training rows,
//! is its linear part under a nonlinear name, and the linear re-fit is tried in its place.
//!
//! Among the elements that beat the linear re-fit by the margin and pass the gate, those within
//! [`PARSIMONY`] points of the best, the one with fewest parameters wins; one that fails the
//! gate (it lowers a block) does not hide one below it that passes (stop 72). When the winner
//! is idle, another element of the window can beat its linear part by up to about the
//! margin (the window plus what the idle one gained by fitting noise), so no other is tried
//! (docs/diagnose-history.md, stops 47 and 48). When it does not settle, or remembers its
//! start, its class is set aside and the rule chooses again among the other classes, each
//! choice held to the same margin, gate and checks ([`walk`]): a slow store can lead as one
//! class while another explains the record with dynamics the blocks can check (stop 71).
//! When nothing is reported, the finding is `unexplained` and says why, each withheld
//! correction in the order tried.
//!
//! Before any of it, on an open-loop record: when a drift term raises the re-fitted linear
//! model's cross-validated FIT by the caller's drift margin ([`super::drift_gain`]) and the
//! drift goes one way over both halves of the training part ([`super::drift_is_one_line`]: the
//! slow level a nonlinearity leaves the re-fit to follow can rise on one half and fall, or
//! stay flat, on the other), every
//! structure carries one and the nominal's reference becomes the nominal plus a constant and
//! a line fitted on each fold's fit rows ([`super::Beside::Drift`]), so a finding is credited
//! with what it explains beside the drift and the level. A drift no input carries cannot be
//! forecast: the reported correction holds it, past the training part, at the level it reached
//! there ([`Model::simulate_held`]), so the held-out tail (the raw record's FIT, against the
//! user's nominal) is not credited with a line extrapolated into it. The choice still scores
//! the line extrapolated over the outer validation blocks: holding it there too named more
//! drifting records on development but let a tank fall by 264 points
//! (docs/diagnose-history.md, stop 52).
//!
//! When the training rows show the output's instrument pinned at the end of its range (a
//! pile-up at one extreme value, [`pinned`]), the range is a property of the record, as a
//! drift is: every structure, the linear re-fit included, and the nominal's reference read
//! through it, so that an element or a linear change is credited only with what it explains
//! beside the range. A record that needs the range and one physics element (the cascaded
//! tanks, whose level sensor stops at 10 V) is then fitted with both. (The linear orders, dead
//! times included, are searched on the record as it is, before the range is applied.) When no
//! element is named, the linear re-fit read through the range is one correction of two parts:
//! what the range alone adds (the nominal read through it, against the nominal as it is) and
//! what the linear change adds beside it. The larger names it: a linear change (a transport delay
//! behind a pinned transmitter), or the range itself, a clip on the output, when the re-fit
//! read through it passes the gate against the nominal as it is (a linear plant behind a
//! pinned instrument, a clip the range reproduces).
//!
//! On a dithered record ([`Data::noise_order`] above 0) the candidates, the linear re-fit and
//! the parsimony are ranked instead by the cross-validated one-step prediction error
//! ([`CvScore::rank`]): [`NONLINEAR_MARGIN`] and [`PARSIMONY`] then count points of prediction
//! gain (percent of the nominal's prediction RMS), the same numbers not re-argued for that
//! scale; the gate against the nominal stays the FIT's.

use crate::describe::num;
use mpmwatch_core::numerics::std_dev;
use rayon::prelude::*;
use std::collections::BTreeMap;

use super::clip_sensor::ClipSensor;
use super::linear_change::{at_the_bound, changed_most, linear_change};
use super::{
    Beside, CvScore, Data, Element, Fitted, Layout, Linear, Model, Orders, cv_fit, drift_gain,
    drift_is_one_line, elements, fit, linear_orders, max_dead_time, nominal_cv_fit, pinned, ranked_linear,
    starting_at,
};
use crate::candidates::{ActsOn, Physics};
use crate::nominal::NominalArx;
use crate::report::{Finding, Tried};

/// Points of cross-validated FIT a physics element must gain over the re-fitted linear model:
/// an element nests the linear model, so on a linear plant it gains only by fitting noise.
/// On the development linear plants (30 at 3000 samples under three conditions: as generated,
/// with white noise added, under nominals of other orders) the element the parsimony rule
/// chose gained at most 0.14 points, on 15 at 1500 samples 0.33; half a point is over three
/// times the first and below what a Duffing and a diode the 1-point margin missed gained
/// (+0.71, +0.65). One fresh linear plant (noise pole 0.92) gained 1.3, beyond either margin
/// (docs/diagnose-history.md, stop 48).
pub const NONLINEAR_MARGIN: f64 = 0.5;

/// The least share of the training rows on which a named element's nonlinearity must act
/// ([`Element::acting`]): a limit beyond the record binds on none, and the element is then its
/// linear part under a nonlinear name (an extra pole, for a store); one that binds on a handful
/// is placed by those few noisy samples. One row in a hundred is about twenty rows of a
/// training part of 2100, seven a validation block on average (docs/diagnose-history.md, stop 44, has
/// the shares the named findings reach).
pub const MIN_ACTING: f64 = 0.01;

/// Points of cross-validated FIT within which the element with fewer parameters is preferred.
pub const PARSIMONY: f64 = 0.5;

/// What the grey-box step decided for one output.
pub struct Explanation {
    /// The finding (its FIT fields are the caller's to fill).
    pub finding: Finding,
    /// The corrected simulation over the whole record (`None`: no correction).
    pub corrected: Option<Vec<f64>>,
    /// The named element's map, for its figure (`None`: no element, or one without a map).
    pub curve: Option<super::ElementCurve>,
    /// An `unexplained` finding whose best correction passed the gate against the nominal but
    /// was not reported (it does not settle within a block, or its nonlinearity hardly acts):
    /// the record shows the model wrong, though it cannot show what is right.
    pub withheld: bool,
}

/// Names of the signals, for the report.
pub struct Names<'a> {
    /// Input names, by position.
    pub inputs: Vec<&'a str>,
    /// The output's name.
    pub output: &'a str,
}

/// Explains one output. `s` is the nominal simulation, `nominal` the nominal model identified
/// from it, `flagged` the inputs the localisation implicated, `folds` the blocked folds of the
/// training rows, `min_gain` the smallest gain in points that counts, `drift_min_gain` the
/// points of cross-validated FIT a drift term must add to the re-fitted linear model for every
/// structure to carry one ([`drift_gain`]; open loop only, +∞ never), `ts` the sample time.
///
/// In four steps: the reference every hypothesis is scored against (`Reference::of`), every
/// element scored on every linear order set (`candidates`, which also settles the linear
/// competitor: the re-fit's orders or the nominal's), then the first of three corrections that
/// is reported (a named element, a linear change, the instrument's range alone; `Judge`), and
/// otherwise `unexplained`.
#[allow(clippy::too_many_arguments)]
pub fn explain(
    d: &Data<'_>,
    s: &[f64],
    nominal: &NominalArx,
    flagged: &[usize],
    folds: &[(Vec<usize>, std::ops::Range<usize>)],
    warmup: usize,
    min_gain: f64,
    drift_min_gain: f64,
    ts: f64,
    names: &Names<'_>,
) -> Explanation {
    let els = elements();
    let mut reference = Reference::of(d, s, nominal, folds, drift_min_gain);
    let (order_sets, scored) = candidates(d, &mut reference, &els, flagged);
    let block = reference.folds.iter().map(|f| f.1.len()).min().unwrap_or(0) as f64;
    let mut judge = Judge {
        d,
        s,
        nominal,
        flagged,
        names,
        ts,
        min_gain,
        els: &els,
        tried: tried(&scored, &els, &reference.nominal_cv),
        train_rows: (d.train.start + warmup..d.train.end).collect(),
        block,
        withheld: Vec::new(),
        reference: &reference,
    };
    if let Some(e) = judge.element(&scored, &order_sets) {
        return e;
    }
    if let Some(e) = judge.linear_refit() {
        return e;
    }
    if let Some(e) = judge.range_alone() {
        return e;
    }
    judge.unexplained(&scored)
}

/// What every hypothesis of one output is scored against: the best re-fitted linear
/// structure, the nominal's score, and the nuisances every structure carries (a drift, an
/// instrument's range; see the module's doc).
struct Reference {
    /// The longest dead time the linear search offers.
    longest: usize,
    /// A range the output's instrument reads within, when the training rows show one.
    reading: Option<super::Reading>,
    /// What a drift term adds to the re-fitted linear model, when it was tried.
    with_drift: Option<f64>,
    /// Whether every structure carries a drift term.
    drift: bool,
    /// The nominal's own linear orders.
    from_nominal: Orders,
    /// The blocked folds, every validation block after the rows a simulation copies.
    folds: Vec<(Vec<usize>, std::ops::Range<usize>)>,
    /// The best linear structure and its score: the re-fit's orders, or the nominal's when
    /// [`candidates`] finds they rank higher.
    linear: Option<(Orders, CvScore)>,
    /// The nominal's score, read as every structure is.
    nominal_cv: CvScore,
    /// With a range, the nominal's score not read through it (the range alone's reference).
    raw: Option<CvScore>,
    /// The record's noise order (0: fitted by simulation error, as in open loop), which sets
    /// the ranking currency.
    noise_order: usize,
}

impl Reference {
    fn of(
        d: &Data<'_>,
        s: &[f64],
        nominal: &NominalArx,
        folds: &[(Vec<usize>, std::ops::Range<usize>)],
        drift_min_gain: f64,
    ) -> Reference {
        let longest = max_dead_time(folds);
        let reading = pinned(&d.y[d.train.clone()]);
        // The linear dynamics every hypothesis starts from: the best re-fitted orders, and the
        // nominal's own (a nonlinearity can bias the linear search, and the nominal's orders
        // are the user's knowledge of the plant). The linear model competes at both.
        let mut linear = linear_orders(
            d,
            folds,
            &nominal_cv_fit(s, d.y, folds, d.noise_order, Beside::Nothing, None),
            false,
        );
        // Read through the range, as every structure is scored, before it decides the drift.
        let read = |l: Option<(Orders, CvScore)>, folds: &[(Vec<usize>, std::ops::Range<usize>)]| {
            l.and_then(|(o, _)| {
                let o = Orders { reading, ..o };
                cv_fit(&Model { element: &Linear, input: 0, orders: o.clone() }, d, folds).map(|v| (o, v))
            })
        };
        if reading.is_some() {
            linear = read(linear, folds);
        }
        // An output that drifts in a way no input carries: every structure and the nominal's
        // reference then carry the same nuisance, so that what a hypothesis is credited with
        // is what it explains beside it.
        let with_drift = match &linear {
            Some(l) if d.noise_order == 0 && drift_min_gain.is_finite() => drift_gain(d, folds, l),
            _ => None,
        };
        let drift = with_drift.is_some_and(|g| g >= drift_min_gain)
            && linear.as_ref().is_some_and(|l| drift_is_one_line(d, folds, &l.0));
        let beside = if drift { Beside::Drift } else { Beside::Nothing };
        if drift {
            linear =
                linear_orders(d, folds, &nominal_cv_fit(s, d.y, folds, d.noise_order, beside, None), true);
        }
        let from_nominal = Orders { trend: drift, reading, ..nominal_orders(nominal, d.u.len(), longest) };
        // A simulation copies the record up to its longest dead time and taps, so those rows
        // have no error; every block is scored after them, or a long dead time would be
        // credited with them against the nominal.
        let reach = linear.iter().map(|l| &l.0).chain([&from_nominal]).map(|o| o.reach()).max().unwrap_or(0);
        let trim = folds.first().is_some_and(|f| f.1.start < reach);
        let folds = if trim { starting_at(folds, reach) } else { folds.to_vec() };
        // The orders were searched on the record as it is; the linear re-fit is scored as every
        // structure is, after the rows a simulation copies and read through the range.
        if trim || reading.is_some() {
            linear = read(linear, &folds);
        }
        let nominal_cv = nominal_cv_fit(s, d.y, &folds, d.noise_order, beside, reading);
        let raw = reading.map(|_| nominal_cv_fit(s, d.y, &folds, d.noise_order, beside, None));
        Reference {
            longest,
            reading,
            with_drift,
            drift,
            from_nominal,
            folds,
            linear,
            nominal_cv,
            raw,
            noise_order: d.noise_order,
        }
    }

    /// A candidate's score in the currency its fit was made in (see [`CvScore::rank`]); the
    /// gate is always the plain FIT's.
    fn rank(&self, v: &CvScore) -> f64 {
        v.rank(&self.nominal_cv, self.noise_order)
    }

    /// With a range, what the range alone adds: the nominal read through it, against the
    /// nominal as it is (−∞ without one). It and what a linear change adds beside it are two
    /// parts of one correction, and the larger names it.
    fn range_part(&self) -> f64 {
        self.raw.as_ref().map_or(f64::NEG_INFINITY, |r| self.nominal_cv.mean - r.mean)
    }
}

/// Every element on every linear order set it is tried on, scored by blocked
/// cross-validation: the order sets (the re-fit's, the nominal's when they differ, and last
/// the static part, tried only behind elements that carry the dynamics) and the scores. The
/// nominal's orders replace the re-fit's as the linear competitor when they rank higher.
fn candidates(
    d: &Data<'_>,
    r: &mut Reference,
    els: &[Box<dyn Element>],
    flagged: &[usize],
) -> (Vec<Orders>, Vec<Scored>) {
    let mut order_sets: Vec<Orders> = r.linear.iter().map(|l| l.0.clone()).collect();
    if !order_sets.contains(&r.from_nominal) {
        let m = Model { element: &Linear, input: 0, orders: r.from_nominal.clone() };
        if let Some(v) = cv_fit(&m, d, &r.folds) {
            if r.linear.as_ref().is_none_or(|l| r.rank(&v) > r.rank(&l.1)) {
                r.linear = Some((r.from_nominal.clone(), v));
            }
            order_sets.push(r.from_nominal.clone());
        }
    }
    // In open loop the localisation's MI against a least-squares nominal's residual misses
    // much of what a fit shows (see `crate::explain`), so an element is tried on every input;
    // with dithers and a noise model, on the flagged ones.
    let candidates: Vec<usize> = if d.noise_order == 0 { (0..d.u.len()).collect() } else { flagged.to_vec() };
    let first = flagged.first().copied().unwrap_or(0);
    let static_part = order_sets.len();
    order_sets.push(Orders { na: 0, nb: 1, ..r.from_nominal.clone() });
    let mut tries: Vec<(usize, usize, usize)> = Vec::new();
    for o in 0..order_sets.len() {
        for (k, el) in els.iter().enumerate().filter(|(_, el)| o < static_part || el.carries_dynamics()) {
            // An output map reads the sum of every channel, so one channel carries it as well as
            // another; a fed-back force sits in the channel whose output it feeds back.
            let inputs: Vec<usize> = match el.acts_on() {
                ActsOn::Output if el.feedbacks() == 0 => vec![first],
                _ => candidates.clone(),
            };
            tries.extend(inputs.into_iter().filter(|&i| el.identifiable(d, i)).map(|i| (o, k, i)));
        }
    }
    // The fits are independent and each takes a simulation per step, so they share the cores;
    // the scores come back in the order above, and the choice does not depend on the threads.
    let folds = &r.folds;
    let scored: Vec<Scored> = tries
        .into_par_iter()
        .filter_map(|(o, k, i)| {
            let (el, orders) = (els[k].as_ref(), &order_sets[o]);
            let m = Model { element: el, input: i, orders: orders.clone() };
            cv_fit(&m, d, folds).map(|v| (v, k, i, complexity(el, d, i, orders), o))
        })
        .collect();
    (order_sets, scored)
}

/// Each physics class tried, with the best mean gain over the nominal any of its candidates
/// reached.
fn tried(scored: &[Scored], els: &[Box<dyn Element>], nominal_cv: &CvScore) -> Vec<Tried> {
    let mut tried: Vec<Tried> = Vec::new();
    for (v, k, _, _, _) in scored {
        let (gain, ph) = (v.mean - nominal_cv.mean, els[*k].physics());
        match tried.iter_mut().find(|t| t.physics == ph) {
            Some(t) if t.validation_gain_pct >= gain => {}
            Some(t) => t.validation_gain_pct = gain,
            None => tried.push(Tried { physics: ph, score_vs_null: None, validation_gain_pct: gain }),
        }
    }
    tried
}

/// The decision for one output, against its [`Reference`]: each correction in turn, the first
/// that passes every test reported, each that passed the gate and was not reported kept with
/// its reason for the `unexplained` finding.
struct Judge<'a> {
    d: &'a Data<'a>,
    /// The nominal simulation.
    s: &'a [f64],
    nominal: &'a NominalArx,
    flagged: &'a [usize],
    names: &'a Names<'a>,
    ts: f64,
    min_gain: f64,
    els: &'a [Box<dyn Element>],
    reference: &'a Reference,
    /// Each class tried and its best gain, for the finding.
    tried: Vec<Tried>,
    /// The training rows a correction is fitted on.
    train_rows: Vec<usize>,
    /// The shortest validation block, samples.
    block: f64,
    /// Each correction that passed the gate and was not reported, in the order tried.
    withheld: Vec<Withheld>,
}

impl Judge<'_> {
    /// The honesty gate, as on the closed-loop path: the correction must raise the mean block
    /// FIT by `min_gain` points and lower no block.
    fn passes(&self, v: &CvScore) -> bool {
        passes(v, &self.reference.nominal_cv, self.min_gain)
    }

    /// The corrected simulation of a fitted structure over the whole record, when it settles
    /// within a validation block (its poles, and with a feedback element its memory of where it
    /// started, [`memory_time`]) and its element, if it says where it acts, acts on at least
    /// [`MIN_ACTING`] of the training rows. Otherwise the reason, `Err(Some(why))`, and the
    /// correction is kept in `withheld` with it and its gain `v` against `against`, the score
    /// its gate measured it with; `Err(None)`, with nothing kept, when it cannot be simulated.
    fn reportable(
        &mut self,
        m: &Model<'_>,
        f: &Fitted,
        physics: Physics,
        v: &CvScore,
        against: &CvScore,
    ) -> Result<Vec<f64>, Option<Why>> {
        let mut hold = |why: Why| {
            let (mean, worst) = (v.mean - against.mean, v.min_gain_over(against));
            self.withheld.push(Withheld { physics, why, mean, worst });
            Err(Some(why))
        };
        let tau = settling_time(m, f);
        if tau >= self.block {
            return hold(Why::Slow(tau));
        }
        let d = self.d;
        if m.element.feedbacks() > 0 {
            let memory = memory_time(m, f, d).ok_or(None)?;
            if memory >= self.block {
                return hold(Why::Remembers(memory));
            }
        }
        let sim = m.simulate_held(f, &d.u, d.y, d.train.end.saturating_sub(1)).ok_or(None)?;
        let share = m.acting_share(f, &d.u, &sim, &self.train_rows);
        if let Some(share) = share.filter(|&a| a.is_nan() || a < MIN_ACTING) {
            return hold(Why::Idle(share));
        }
        Ok(sim)
    }

    /// The physics element chosen ([`chosen`]) among those that beat the linear re-fit by
    /// [`NONLINEAR_MARGIN`] and pass the gate, when it settles and acts; when the chosen one
    /// does not settle, the next class down the ranking ([`walk`]).
    fn element(&mut self, scored: &[Scored], order_sets: &[Orders]) -> Option<Explanation> {
        let (r, els, min_gain) = (self.reference, self.els, self.min_gain);
        let linear_cv = r.linear.as_ref().map_or(f64::NEG_INFINITY, |l| r.rank(&l.1));
        let beats =
            |v: &CvScore| r.rank(v) - linear_cv >= NONLINEAR_MARGIN && passes(v, &r.nominal_cv, min_gain);
        let (i, el, m, f, sim) = walk(
            scored,
            &|v: &CvScore| r.rank(v),
            beats,
            |s| els[s.1].physics(),
            |(v, k, i, _, o)| {
                let el = els[*k].as_ref();
                let m = Model { element: el, input: *i, orders: order_sets[*o].clone() };
                let Some(f) = fit(&m, self.d, &self.train_rows) else { return Attempt::Ends };
                match self.reportable(&m, &f, el.physics(), v, &r.nominal_cv) {
                    Ok(sim) => Attempt::Reported((*i, el, m, f, sim)),
                    Err(Some(Why::Idle(_))) => Attempt::Ends,
                    Err(_) => Attempt::SetAside,
                }
            },
        )?;
        let (d, names) = (self.d, self.names);
        let (mut summary, parameters) = el.describe(&f.p, names.inputs[i], names.output);
        for w in &self.withheld {
            summary += &format!(
                "; {} ranked higher (it raises the cross-validated FIT by {:+.1} points) and is not reported: {}",
                w.name(),
                w.mean,
                w.why.text(self.block)
            );
        }
        summary += &drift_note(&m, &f, d, names.output);
        summary += &reading_note(r.reading, names.output);
        let tried = std::mem::take(&mut self.tried);
        Some(Explanation {
            finding: finding(names, i, el.physics(), el.acts_on(), summary, parameters, tried),
            corrected: Some(sim),
            curve: m.curve(&f, d, names.inputs[i], names.output),
            withheld: false,
        })
    }

    /// Whether the re-fitted linear model `v` passes the gate and adds more than the range alone
    /// would.
    fn linear_passes(&self, v: &CvScore) -> bool {
        let r = self.reference;
        self.passes(v) && v.mean - r.nominal_cv.mean >= r.range_part()
    }

    /// The re-fitted linear model as a linear change (a gain, a time constant, a dead time, a
    /// missing coupling), when it passes the gate, adds more than the range alone would and
    /// settles; when the best by the blocks does not settle, the best that does
    /// ([`Self::settling_refit`]).
    fn linear_refit(&mut self) -> Option<Explanation> {
        let r = self.reference;
        let (best, best_v) = r.linear.as_ref()?;
        if !self.linear_passes(best_v) {
            return None;
        }
        let (d, names) = (self.d, self.names);
        let m = Model { element: &Linear, input: 0, orders: best.clone() };
        let f = fit(&m, d, &self.train_rows)?;
        let (orders, v, f, sim, slower) =
            match self.reportable(&m, &f, Physics::Unexplained, best_v, &r.nominal_cv) {
                Ok(sim) => (best.clone(), best_v.clone(), f, sim, None),
                Err(Some(Why::Slow(tau))) => {
                    let (o, v, f, sim) = self.settling_refit(best, best_v)?;
                    (o, v, f, sim, Some(tau))
                }
                Err(_) => return None,
            };
        let orders = &orders;
        let m = Model { element: &Linear, input: 0, orders: orders.clone() };
        let i = if d.u.len() > 1 {
            changed_most(self.nominal, &f, orders, &d.u, d.train.clone())
        } else {
            self.flagged.first().copied().unwrap_or(0)
        };
        let modelled = self.nominal.has_channel(i, d.u[i], self.s);
        let (physics, mut summary, parameters, curve) =
            linear_change(self.nominal, &f, orders, i, modelled, self.ts, names);
        if let Some(tau) = slower {
            summary += &format!(
                "; the re-fit the blocks rank first ({} poles, {} taps, {:+.1} points) is not reported: {}; this one ({} poles, {} taps, {:+.1} points) is the best that settles within a block",
                best.na,
                best.nb,
                best_v.mean - r.nominal_cv.mean,
                Why::Slow(tau).text(self.block),
                orders.na,
                orders.nb,
                v.mean - r.nominal_cv.mean,
            );
        }
        summary += &at_the_bound(physics, orders, i, r.longest);
        summary += &drift_note(&m, &f, d, names.output);
        summary += &reading_note(r.reading, names.output);
        let mut tried = std::mem::take(&mut self.tried);
        tried.push(Tried { physics, score_vs_null: None, validation_gain_pct: v.mean - r.nominal_cv.mean });
        Some(Explanation {
            finding: finding(names, i, physics, ActsOn::Input, summary, parameters, tried),
            corrected: Some(sim),
            curve: Some(curve),
            withheld: false,
        })
    }

    /// When the best re-fitted linear model (`slow`, scored `slow_v`) does not settle within a
    /// block: the other pole and tap counts at its dead times, drift term and range
    /// ([`ranked_linear`]), in the blocks' order and within [`PARSIMONY`] points of it, the
    /// first that passes the gate, adds more than the range alone would and settles, with its
    /// score, fit and corrected simulation. Within [`PARSIMONY`] the blocks do not need the
    /// slow mode, and a structure that settles is one they check throughout: a plant with a
    /// time constant of a few samples, under coloured noise, got a best re-fit that reached its
    /// gain within a dozen samples and crept on to twice it over thousands, 0.2 points above
    /// one pole. Further below, the slow mode carries what the blocks score, and a structure
    /// without it misses a level the held-out tail sees: a tank's store, 5.8 points above the
    /// best that settles, which fell by 40 points on the tail (docs/diagnose-history.md, stop
    /// 69).
    fn settling_refit(&self, slow: &Orders, slow_v: &CvScore) -> Option<(Orders, CvScore, Fitted, Vec<f64>)> {
        let (r, d) = (self.reference, self.d);
        ranked_linear(d, &r.folds, &r.nominal_cv, slow)
            .into_iter()
            .filter(|(o, v)| o != slow && r.rank(v) >= r.rank(slow_v) - PARSIMONY && self.linear_passes(v))
            .find_map(|(o, v)| {
                let m = Model { element: &Linear, input: 0, orders: o.clone() };
                let f = fit(&m, d, &self.train_rows)?;
                if settling_time(&m, &f) >= self.block {
                    return None;
                }
                let sim = m.simulate_held(&f, &d.u, d.y, d.train.end.saturating_sub(1))?;
                Some((o, v, f, sim))
            })
    }

    /// The instrument's range alone, a clip on the output: the linear re-fit read through it,
    /// against the nominal as it is, when the range adds more than the linear change beside it.
    fn range_alone(&mut self) -> Option<Explanation> {
        let r = self.reference;
        let (Some(range), Some(raw), Some((orders, lv))) = (r.reading, r.raw.as_ref(), r.linear.as_ref())
        else {
            return None;
        };
        let bigger = r.range_part() > lv.mean - r.nominal_cv.mean;
        if !bigger {
            return None;
        }
        let (d, names) = (self.d, self.names);
        let el = ClipSensor { range: Some(range) };
        let m = Model { element: &el, input: 0, orders: orders.clone() };
        let v = cv_fit(&m, d, &r.folds)?;
        let gated = v.mean - raw.mean >= self.min_gain && v.min_gain_over(raw) >= 0.0;
        if !gated {
            return None;
        }
        let f = fit(&m, d, &self.train_rows)?;
        // Its gains, withheld or reported, are against the nominal as it is (`raw`), the
        // currency of its gate.
        let sim = self.reportable(&m, &f, Physics::Saturation, &v, raw).ok()?;
        let i = self.flagged.first().copied().unwrap_or(0);
        let (mut summary, parameters) = el.describe(&f.p, names.inputs[i], names.output);
        summary += &drift_note(&m, &f, d, names.output);
        let gain = v.mean - raw.mean;
        let mut tried = std::mem::take(&mut self.tried);
        match tried.iter_mut().find(|t| t.physics == Physics::Saturation) {
            Some(t) => t.validation_gain_pct = t.validation_gain_pct.max(gain),
            None => tried.push(Tried {
                physics: Physics::Saturation,
                score_vs_null: None,
                validation_gain_pct: gain,
            }),
        }
        Some(Explanation {
            finding: finding(names, i, Physics::Saturation, ActsOn::Output, summary, parameters, tried),
            corrected: Some(sim),
            // Nothing of the clip is fitted: its limits are the record's.
            curve: m.curve(&f, d, names.inputs[i], names.output).map(|mut c| {
                c.label = "the range read off the record".into();
                c
            }),
            withheld: false,
        })
    }

    /// Nothing reported: the finding is `unexplained` and says why, each withheld correction in
    /// the order tried, or the best candidate's and the linear re-fit's gains.
    fn unexplained(self, scored: &[Scored]) -> Explanation {
        let (r, names, block) = (self.reference, self.names, self.block);
        let top = scored.iter().max_by(|a, b| r.rank(&a.0).total_cmp(&r.rank(&b.0)));
        let summary = match (self.withheld.split_first(), top, &r.linear) {
            (Some((first, next)), ..) => {
                let mut text = format!(
                    "{}'s simulation misses something, and the best correction, {}, raises the cross-validated FIT by {:+.1} points on average ({:+.1} on its worst block), but {}, so it is not reported{}",
                    names.output,
                    first.name(),
                    first.mean,
                    first.worst,
                    first.why.text(block),
                    first.why.advice(block, self.d.y.len()),
                );
                for w in next {
                    text += &format!(
                        "; the next, {} ({:+.1} points), is not reported either: {}{}",
                        w.name(),
                        w.mean,
                        w.why.text(block),
                        w.why.advice(block, self.d.y.len())
                    );
                }
                if matches!(first.why, Why::Idle(_))
                    && !next.iter().any(|w| w.physics == Physics::Unexplained)
                {
                    text += "; no re-fitted linear model is reported in its place";
                }
                text
            }
            (None, Some((v, k, ..)), Some((_, lv))) => format!(
                "{}'s simulation misses something, but nothing tried improves it out of sample by {} points on average without lowering a validation block: the best candidate, {}, changes the cross-validated FIT by {:+.1} points on average and {:+.1} on its worst block, the re-fitted linear model by {:+.1} and {:+.1}",
                names.output,
                self.min_gain,
                self.els[*k].physics().name(),
                v.mean - r.nominal_cv.mean,
                v.min_gain_over(&r.nominal_cv),
                lv.mean - r.nominal_cv.mean,
                lv.min_gain_over(&r.nominal_cv),
            ),
            _ => format!("{}'s simulation misses something, but no candidate could be fitted", names.output),
        } + &match r.with_drift.filter(|_| r.drift) {
            Some(g) => format!(
                "; every structure tried carried a drift term, a straight line in time that no input explains (with one, the re-fitted linear model gains {g:+.1} points)"
            ),
            None => String::new(),
        } + &reading_note(r.reading, names.output);
        let i = self.flagged.first().copied().unwrap_or(0);
        Explanation {
            finding: finding(
                names,
                i,
                Physics::Unexplained,
                ActsOn::Input,
                summary,
                BTreeMap::new(),
                self.tried,
            ),
            corrected: None,
            curve: None,
            withheld: !self.withheld.is_empty(),
        }
    }
}

/// The sentence a finding carries when its structure was fitted beside a drift: how much the
/// drift term moves the simulated output over the training rows ([`Model::drift_over`]), and
/// that it is held after them ([`Model::simulate_held`]). Empty without one.
fn drift_note(m: &Model<'_>, f: &Fitted, d: &Data<'_>, output: &str) -> String {
    let rows: Vec<usize> = d.train.clone().collect();
    let Some(over) = m.drift_over(f, &d.u, d.y, &rows) else { return String::new() };
    format!(
        "; fitted beside a drift of {output} that no input explains ({}{} over the training part, a straight line in time; past the training part it is held at the level it reached)",
        if over >= 0.0 { "+" } else { "" },
        num(over)
    )
}

/// The sentence a finding carries when every structure, the nominal's reference included, was
/// read through the instrument's range the record shows ([`pinned`]); empty without one.
fn reading_note(reading: Option<super::Reading>, output: &str) -> String {
    reading.map_or(String::new(), |r| {
        format!("; every structure, and the nominal compared with them, read through the range the record shows: {}", r.describe(output))
    })
}

/// A correction that passed the gate and was not reported.
struct Withheld {
    /// Its class (`Unexplained` for the re-fitted linear model).
    physics: Physics,
    why: Why,
    /// Its cross-validated FIT gain over the score its gate measured it against (the nominal's;
    /// for the range alone, the nominal's not read through the range), on average and on its
    /// worst block.
    mean: f64,
    worst: f64,
}

impl Withheld {
    fn name(&self) -> &'static str {
        if self.physics == Physics::Unexplained { "a re-fitted linear model" } else { self.physics.name() }
    }
}

/// Why a correction was withheld.
#[derive(Clone, Copy)]
enum Why {
    /// Its slowest time constant, in samples, is at least a validation block.
    Slow(f64),
    /// Its nonlinearity acts on this share of the training rows, under [`MIN_ACTING`].
    Idle(f64),
    /// Its simulation remembers where it started for this many samples ([`memory_time`]), at
    /// least a validation block.
    Remembers(f64),
}

impl Why {
    /// What record would check a slow correction ([`record_for`]); empty otherwise.
    fn advice(&self, block: f64, n: usize) -> String {
        match *self {
            Why::Slow(tau) | Why::Remembers(tau) => record_for(tau, block, n),
            Why::Idle(_) => String::new(),
        }
    }

    /// The reason in words, with `block` the shortest validation block.
    fn text(&self, block: f64) -> String {
        match *self {
            Why::Slow(tau) => format!(
                "its slowest time constant, {}, is longer than the {} samples of a validation block: the blocks cannot check the level it carries from one to the next",
                if tau.is_finite() {
                    format!("{} samples", num(tau))
                } else {
                    "infinite (an integrator or unstable)".to_string()
                },
                block,
            ),
            Why::Idle(share) => format!(
                "the kink it is named for (a limit, a dead zone, a rim) acts on {:.1} % of the training rows (a named one must act on {} %)",
                100.0 * share,
                100.0 * MIN_ACTING,
            ),
            Why::Remembers(t) if t.is_finite() => format!(
                "its simulation, started one standard deviation away, still differs by more than 1/e of that after {} samples, at least the {} samples of a validation block: the force it feeds back can hold the output where it stands, and the blocks cannot check the level it carries from one to the next",
                num(t),
                block,
            ),
            Why::Remembers(_) => format!(
                "its simulation, started one standard deviation away, does not come back within 1/e of that by the end of the training part (or cannot be simulated from there), longer than the {} samples of a validation block: the force it feeds back can hold the output where it stands, and the blocks cannot check the level it carries from one to the next",
                block,
            ),
        }
    }
}

/// A scored candidate: its cross-validated score, the element's index in [`elements`], the
/// input it acts on, its parameter count and the index of its linear orders.
type Scored = (CvScore, usize, usize, usize, usize);

/// The parsimony rule: among the candidates within [`PARSIMONY`] points of the best by `rank`,
/// the one with the fewest parameters (the better ranked on a tie).
fn chosen<'a>(
    scored: impl IntoIterator<Item = &'a Scored> + Clone,
    rank: &impl Fn(&CvScore) -> f64,
) -> Option<&'a Scored> {
    let best = scored.clone().into_iter().map(|s| rank(&s.0)).fold(f64::NEG_INFINITY, f64::max);
    scored
        .into_iter()
        .filter(|s| rank(&s.0) >= best - PARSIMONY)
        .min_by(|a, b| a.3.cmp(&b.3).then(rank(&b.0).total_cmp(&rank(&a.0))))
}

/// The honesty gate: `v` raises the mean block FIT over the nominal's `n` by `min_gain`
/// points and lowers no block.
fn passes(v: &CvScore, n: &CvScore, min_gain: f64) -> bool {
    v.mean - n.mean >= min_gain && v.min_gain_over(n) >= 0.0
}

/// What trying a chosen candidate came to, in [`walk`].
enum Attempt<T> {
    /// It passed every check: the finding.
    Reported(T),
    /// Withheld as slower than a block or as remembering its start: another class may
    /// explain the record with dynamics the blocks can check. A fit that cannot be simulated
    /// over the record is set aside too, with nothing kept of it.
    SetAside,
    /// Withheld as idle (it is then its linear part, and no other candidate of the parsimony
    /// window can beat that by the margin, docs/diagnose-history.md, stop 47), or not fitted.
    Ends,
}

/// The parsimony rule walked down the ranking: it chooses ([`chosen`]) among the candidates
/// that pass `beats` (the margin over the linear re-fit and the gate), so one that lowers a
/// block does not hide one below it that passes (docs/diagnose-history.md, stop 72); the choice
/// is tried, and when it is set aside, every candidate of its class (`class`) is too, and the
/// rule chooses again among the rest. A slow store can rank first as one class (a quadratic
/// on the input, whose fitted linear part carries a mode slower than a block) while another
/// class, ranked below it, explains the same record with dynamics the blocks can check
/// (docs/diagnose-history.md, stops 68, 70 and 71).
fn walk<T>(
    scored: &[Scored],
    rank: &impl Fn(&CvScore) -> f64,
    beats: impl Fn(&CvScore) -> bool,
    class: impl Fn(&Scored) -> Physics,
    mut attempt: impl FnMut(&Scored) -> Attempt<T>,
) -> Option<T> {
    let mut left: Vec<&Scored> = scored.iter().filter(|s| beats(&s.0)).collect();
    loop {
        let next = chosen(left.iter().copied(), rank)?;
        match attempt(next) {
            Attempt::Reported(t) => return Some(t),
            Attempt::Ends => return None,
            Attempt::SetAside => {
                let set_aside = class(next);
                left.retain(|s| class(s) != set_aside);
            }
        }
    }
}

/// The advice beside a correction withheld as slower than a validation block: the record
/// length, with the same share held out, whose blocks would be as long as its time constant
/// `tau` (blocks grow with the record); empty for an integrator.
fn record_for(tau: f64, block: f64, n: usize) -> String {
    if !(tau.is_finite() && block > 0.0) {
        return String::new();
    }
    format!(
        "; a record of at least {} samples, with the same share held out, would give blocks that long",
        num((tau / block * n as f64).ceil())
    )
}

fn finding(
    names: &Names<'_>,
    i: usize,
    physics: Physics,
    acts_on: ActsOn,
    summary: String,
    parameters: BTreeMap<String, f64>,
    mut tried: Vec<Tried>,
) -> Finding {
    tried.sort_by(|a, b| b.validation_gain_pct.total_cmp(&a.validation_gain_pct));
    Finding {
        input: names.inputs[i].to_string(),
        output: names.output.to_string(),
        physics,
        acts_on,
        summary,
        parameters,
        fit_before_pct: f64::NAN,
        fit_after_pct: f64::NAN,
        tried,
    }
}

/// The nominal's linear orders as the grey-box structure writes them: its poles (1 to 3), and
/// per input the dead time before the first numerator coefficient above a thousandth of the
/// largest (at most `longest`), with up to 3 taps after it (the same for every input: the
/// longest).
fn nominal_orders(nominal: &NominalArx, inputs: usize, longest: usize) -> Orders {
    let na = nominal.arx.denominator().len().saturating_sub(1).clamp(1, 3);
    let mut nb = 1;
    let nk = (0..inputs)
        .map(|i| {
            let b = nominal.arx.numerator(i);
            let top = b.iter().fold(0.0f64, |m, v| m.max(v.abs()));
            let first = b.iter().position(|v| v.abs() > 1e-3 * top).unwrap_or(0);
            let last = b.iter().rposition(|v| v.abs() > 1e-3 * top).unwrap_or(first);
            nb = nb.max((last - first + 1).min(3));
            first.min(longest)
        })
        .collect();
    Orders { na, nb, nk, trend: false, reading: None }
}

/// The time constant (samples) the settling rule reads off a fitted structure: its slowest
/// pole's ([`Model::slowest_pole`]), +∞ for a pole on or outside the unit circle. For an
/// element whose stores carry the plant's dynamics ([`Element::carries_dynamics`]) only the
/// linear part's poles count. The rule guards against a slow linear mode, whose settled level
/// (`b/(1 − a)`) is ever less determined as its pole nears one; a store's settled level is set
/// by its own law (a tank's level goes with the square of its inflow) and the levels it starts
/// from are fitted. Measured on the development tanks before it was kept
/// (docs/diagnose-history.md, stop 59).
fn settling_time(m: &Model<'_>, f: &Fitted) -> f64 {
    let r = if m.element.carries_dynamics() {
        Model { element: &Linear, input: m.input, orders: m.orders.clone() }.slowest_pole(f)
    } else {
        m.slowest_pole(f)
    };
    if r >= 1.0 { f64::INFINITY } else { -1.0 / r.max(f64::MIN_POSITIVE).ln() }
}

/// How long (samples) a fitted structure with a feedback element remembers where its
/// simulation started: over the record up to the end of the training part, started from the
/// recorded output offset by one training standard deviation either way, the last row at
/// which it still differs from the simulation from the recorded start by more than `1/e` of
/// that offset, counted from the first simulated row; +∞ when it still does on the last
/// training row or an offset start cannot be simulated, `None` when the recorded start cannot.
/// The settling rule's test ([`settling_time`]) reads poles, which say nothing of a force that
/// holds the output where it stands (a friction on the output's change sticks it at any level
/// the drive does not beat, an integrator the poles do not show); for a first-order linear
/// structure the two agree to within a sample, a difference decaying by `1/e` in one time
/// constant. The `1/e` and the block are the settling rule's; the offset of one standard
/// deviation is this rule's own choice (for a nonlinear element the memory depends on it).
/// The held-out tail is not simulated.
fn memory_time(m: &Model<'_>, f: &Fitted, d: &Data<'_>) -> Option<f64> {
    let end = d.train.end.min(d.y.len());
    let (y, rows) = (&d.y[..end], &d.y[d.train.start.min(end)..end]);
    let u: Vec<&[f64]> = d.u.iter().map(|x| &x[..end.min(x.len())]).collect();
    let sd = std_dev(rows, 0);
    let first = m.orders.reach().min(end);
    let base = m.simulate_held(f, &u, y, end.saturating_sub(1))?;
    let mut longest = 0.0f64;
    for offset in [sd, -sd] {
        let started: Vec<f64> =
            y.iter().enumerate().map(|(t, &v)| if t < first { v + offset } else { v }).collect();
        let Some(other) = m.simulate_held(f, &u, &started, end.saturating_sub(1)) else {
            return Some(f64::INFINITY);
        };
        let apart = |t: usize| (other[t] - base[t]).abs() > offset.abs() / std::f64::consts::E;
        match (first..end).rev().find(|&t| apart(t)) {
            Some(t) if t + 1 == end => return Some(f64::INFINITY),
            Some(t) => longest = longest.max((t + 1 - first) as f64),
            None => {}
        }
    }
    Some(longest)
}

/// Free parameters of an element on the linear orders: the element's own and every
/// coefficient of its [`Layout`], each input's channel with its poles, the drift term included.
fn complexity(el: &dyn Element, d: &Data<'_>, i: usize, orders: &Orders) -> usize {
    let p = el.starts(d, i).into_iter().next().unwrap_or_default();
    let signals = el.signals(&p, &d.u, i).len();
    p.len().saturating_sub(el.fixed()) + Layout::new(orders, signals, i, el.feedbacks()).len()
}

#[cfg(test)]
mod tests {
    use super::super::friction::Coulomb;
    use super::*;
    use mpmwatch_core::model::Arx;

    fn nominal(a: Vec<f64>, b: Vec<Vec<f64>>) -> NominalArx {
        let delays = vec![0; b.len()];
        NominalArx { arx: Arx::new(a, b, delays).unwrap(), fit_pct: 100.0, score: f64::INFINITY }
    }

    /// The nominal's orders read off its coefficients: poles from `A`, the dead time as the
    /// leading numerator coefficients below a thousandth of the largest, taps from the first
    /// to the last significant one (at most 3), the longest over the inputs.
    #[test]
    fn nominal_orders_are_read_off_the_coefficients() {
        let n = nominal(vec![1.0, -1.5, 0.6], vec![vec![0.0, 1e-6, 0.4, 0.2], vec![0.3, 0.0, 0.0, 0.0]]);
        assert_eq!(
            nominal_orders(&n, 2, 20),
            Orders { na: 2, nb: 2, nk: vec![2, 0], trend: false, reading: None }
        );
        // More than 3 poles or taps are capped; an all-zero numerator gives a tap at lag 0.
        let n = nominal(vec![1.0, -0.5, 0.1, 0.01, 0.001], vec![vec![0.1, 0.2, 0.3, 0.4, 0.5], vec![0.0; 5]]);
        assert_eq!(
            nominal_orders(&n, 2, 20),
            Orders { na: 3, nb: 3, nk: vec![0, 0], trend: false, reading: None }
        );
    }

    /// A structure's free parameters count every channel's poles: the linear re-fit of
    /// `na = 2`, `nb = 2` has 2 + 2 + 1 (the constant) with one input and 2·2 + 2·2 + 1 with
    /// two, each input's channel with its own denominator ([`Layout`]); a drift adds one.
    #[test]
    fn complexity_counts_every_channels_poles() {
        let u = vec![0.0; 100];
        let orders =
            |inputs: usize, trend: bool| Orders { na: 2, nb: 2, nk: vec![1; inputs], trend, reading: None };
        let one = Data { u: vec![&u], y: &u, train: 0..100, nominal: None, noise_order: 0 };
        let two = Data { u: vec![&u, &u], y: &u, train: 0..100, nominal: None, noise_order: 0 };
        assert_eq!(complexity(&Linear, &one, 0, &orders(1, false)), 5);
        assert_eq!(complexity(&Linear, &two, 0, &orders(2, false)), 9);
        assert_eq!(complexity(&Linear, &two, 1, &orders(2, true)), 10);
    }

    /// The settling tests' input: a staircase of 1500 rows between −1 and 1.
    fn staircase() -> Vec<f64> {
        (0..1500).map(|t| ((t / 37 * 7919) % 41) as f64 / 20.0 - 1.0).collect()
    }

    /// `y` explained against the settling tests' nominal, `s(t) = 0.9 s(t−1) + 0.1 u(t−1)`
    /// driven by `u`: the first 1050 rows train, in three blocks of 350; gate margin half a
    /// point, drift margin one point (the defaults), unit sample time.
    fn against_the_settling_nominal(u: &[f64], y: &[f64]) -> Explanation {
        let model = nominal(vec![1.0, -0.9], vec![vec![0.0, 0.1]]);
        let s = model.simulate(&[u]);
        let train = 0..1050;
        let folds: Vec<(Vec<usize>, std::ops::Range<usize>)> = (0..3)
            .map(|k| (train.clone().filter(|t| t / 350 != k).collect(), k * 350..(k + 1) * 350))
            .collect();
        let names = Names { inputs: vec!["u"], output: "y" };
        let d = Data { u: vec![u], y, train, nominal: Some(&s), noise_order: 0 };
        explain(&d, &s, &model, &[0], &folds, 0, 0.5, 1.0, 1.0, &names)
    }

    /// The settling rule, both ways. A noise-free first-order plant of unit gain on a
    /// staircase, the nominal `s(t) = 0.9 s(t−1) + 0.1 u(t−1)` (time constant 9.5 samples),
    /// 1500 rows of which 1050 train in three blocks of 350, the first scored from its third row
    /// (the two before are the simulation's initial conditions, copied from the record). The
    /// plant's pole 0.95 (time constant 19.5 samples) is a time constant, reported; its pole
    /// 0.998 (500 samples, longer than a block) is the same finding by the blocks' FIT,
    /// withheld as `unexplained` with its time constant.
    #[test]
    fn a_correction_slower_than_a_validation_block_is_withheld() {
        let u = staircase();
        let first_order = |a: f64| {
            let mut y = vec![0.0; u.len()];
            for t in 1..u.len() {
                y[t] = a * y[t - 1] + (1.0 - a) * u[t - 1];
            }
            y
        };
        let explained = |y: &[f64]| against_the_settling_nominal(&u, y);

        let fast = explained(&first_order(0.95));
        assert!(!fast.withheld);
        let fast = fast.finding;
        assert_eq!(fast.physics, Physics::TimeConstant, "{}", fast.summary);

        let slow = explained(&first_order(0.998));
        assert!(slow.withheld, "a correction that passed the gate is withheld, not absent");
        let slow = slow.finding;
        assert_eq!(slow.physics, Physics::Unexplained, "{}", slow.summary);
        // The time constant stated is the re-fit's: noise-free, its pole is the plant's to the
        // optimiser's tolerance, but near 1 a millionth of pole is a quarter sample of time
        // constant, so it is read to 1 % of the plant's 499.5 samples.
        let (head, _) =
            slow.summary.split_once(" samples, is longer than the 348 samples").expect(&slow.summary);
        let stated: f64 = head.rsplit(' ').next().and_then(|v| v.parse().ok()).expect(&slow.summary);
        assert!((stated / (-1.0 / 0.998f64.ln()) - 1.0).abs() < 0.01, "{}", slow.summary);
        assert!(slow.summary.contains("a re-fitted linear model"), "{}", slow.summary);
        // The record that would check it: blocks, the shortest 348 of 1500 rows, as long as the
        // time constant; from the stated (rounded) value, so within two samples.
        let (_, tail) = slow.summary.split_once("a record of at least ").expect(&slow.summary);
        let advised: f64 = tail.split(' ').next().and_then(|v| v.parse().ok()).expect(&slow.summary);
        assert!((advised - stated * 1500.0 / 348.0).abs() <= 2.0, "{}", slow.summary);
    }

    /// A best re-fit that does not settle gives way to the best that does when the blocks
    /// hardly need its slow mode, and only then. The plant is the settling tests' staircase
    /// through a fast pole with a slow creep beside it, noise-free,
    /// `y = 0.8·u/(1 − 0.7 q⁻¹)·0.3 q⁻¹ + g·u/(1 − 0.998 q⁻¹)·0.002 q⁻¹`: two poles and two taps
    /// are the plant, and their slow pole (499.5 samples) is longer than a block (347), so the
    /// blocks' best re-fit is not reported. The creep follows the staircase's mean over
    /// hundreds of samples:
    /// - with `g = 0.02` it is worth a fraction of a point on the blocks, within
    ///   [`PARSIMONY`], and one pole, which settles, is reported in its place: a time constant,
    ///   the fast pole's, nearer its `0.7/(1 − 0.7)` = 2.3 samples than the nominal's 9 (the
    ///   convention that states the nominal's 9.000 s);
    /// - with `g = 0.5` (a fifth of the fast part's swing) it is worth points, no structure
    ///   without it comes within [`PARSIMONY`], and the slow re-fit is withheld, as before.
    #[test]
    fn a_re_fit_that_does_not_settle_gives_way_only_to_one_as_good() {
        let u = staircase();
        let with_creep = |g: f64| {
            let (mut fast, mut slow) = (0.0, 0.0);
            let mut y = vec![0.0; u.len()];
            for t in 1..u.len() {
                fast = 0.7 * fast + 0.3 * 0.8 * u[t - 1];
                slow = 0.998 * slow + 0.002 * g * u[t - 1];
                y[t] = fast + slow;
            }
            against_the_settling_nominal(&u, &y)
        };
        let small = with_creep(0.02);
        let f = small.finding;
        assert!(!small.withheld && small.corrected.is_some(), "{}", f.summary);
        assert_eq!(f.physics, Physics::TimeConstant, "{}", f.summary);
        assert!(f.summary.contains("the re-fit the blocks rank first (2 poles, 2 taps"), "{}", f.summary);
        assert!(
            f.summary.contains("taps, +") && f.summary.contains("is the best that settles"),
            "{}",
            f.summary
        );
        assert_eq!(f.parameters["model_time_constant_s"], 9.0, "{:?}", f.parameters);
        assert!(f.parameters["time_constant_s"] < 5.65, "{:?}", f.parameters);

        let large = with_creep(0.5);
        assert!(large.withheld && large.corrected.is_none(), "{}", large.finding.summary);
        assert_eq!(large.finding.physics, Physics::Unexplained, "{}", large.finding.summary);
    }

    /// The candidates are fitted on every core, and what is decided does not depend on how
    /// many there are: the settling test's plant with pole 0.95 explained on one thread and on
    /// four gives the same finding and the same corrected simulation, bit for bit (the scores
    /// come back in the order they were listed, whichever thread fitted them).
    #[test]
    fn the_decision_does_not_depend_on_the_threads() {
        let u = staircase();
        let mut y = vec![0.0; u.len()];
        for t in 1..u.len() {
            y[t] = 0.95 * y[t - 1] + 0.05 * u[t - 1];
        }
        let on = |threads: usize| {
            let pool = rayon::ThreadPoolBuilder::new().num_threads(threads).build().unwrap();
            let e = pool.install(|| against_the_settling_nominal(&u, &y));
            assert_eq!(e.finding.physics, Physics::TimeConstant, "{}", e.finding.summary);
            (serde_json::to_string(&e.finding).unwrap(), e.corrected, e.withheld)
        };
        assert_eq!(on(1), on(4));
    }

    /// A pair of tanks is named as one: a noise-free cascade (orifices 0.3 and 0.25, the
    /// upper tank overflowing at level 30, both settled at the first inflow when the record
    /// starts) on the settling tests' staircase lifted to inflows of 0.1 to 2.1, the lower level
    /// read a sample later as `y = 2·s + 1`, against the settling tests' first-order nominal.
    /// The tanks' time constants at the mean inflow, 24 and 34 samples, settle within the
    /// shortest block (348 rows) and the rim binds on the high steps; the cascade, the only
    /// structure that is the plant, is named, with its orifices. (On these orders the nominal's
    /// own linear part can be static too, so this does not single out the static part the
    /// cascade is also tried behind; no measurement isolates that part, see
    /// docs/diagnose-history.md, stop 58.)
    #[test]
    fn a_pair_of_tanks_is_named_with_its_orifices() {
        let u: Vec<f64> = staircase().iter().map(|v| v + 1.1).collect();
        let mean = u[..1050].iter().sum::<f64>() / 1050.0;
        let p = [mean, u[0], 0.3, 30.0, 0.25];
        let signal = super::super::tank_cascade::TankCascade.signals(&p, &[&u], 0).remove(0);
        // One sample late, as the nominal's input is.
        let y: Vec<f64> = (0..u.len()).map(|t| 2.0 * signal[t.saturating_sub(1)] + 1.0).collect();
        let e = against_the_settling_nominal(&u, &y);
        let f = e.finding;
        assert_eq!(f.physics, Physics::Saturation, "{} {:?}", f.summary, f.tried);
        let (k1, k2) = (f.parameters["upper_orifice"], f.parameters["lower_orifice"]);
        assert!((k1 - 0.3).abs() < 0.01 && (k2 - 0.25).abs() < 0.01, "{:?}", f.parameters);
    }

    /// The settling rule reads a tank cascade by its linear part alone and a single draining
    /// tank by its store too: both with stores of 400 samples at the mean inflow (`ū` = 2,
    /// orifices 0.1: `exp(−k²/(2ū))`) behind a linear part with one pole at 0.9 (9.49 samples,
    /// `−1/ln 0.9`). The cascade settles in the linear part's 9.49, the single tank in its
    /// store's 400.
    #[test]
    fn the_settling_rule_reads_a_cascade_by_its_linear_part_alone() {
        let orders = Orders { na: 1, nb: 1, nk: vec![1], trend: false, reading: None };
        // α, β and the constant; only α is read.
        let theta = vec![0.9, 0.1, 0.0];
        let tau = |element: &dyn Element, p: Vec<f64>| {
            let m = Model { element, input: 0, orders: orders.clone() };
            settling_time(&m, &Fitted { p, theta: theta.clone(), noise: vec![] })
        };
        let linear = -1.0 / 0.9f64.ln();
        let cascade = tau(&super::super::tank_cascade::TankCascade, vec![2.0, 2.0, 0.1, 500.0, 0.1]);
        assert!((cascade - linear).abs() < 1e-6, "{cascade} against {linear}");
        let single = tau(&super::super::draining_tank::DrainingTank, vec![2.0, 0.1, 500.0]);
        assert!((single - 400.0).abs() < 1e-6, "{single}");
    }

    /// [`memory_time`] of `element` with parameters `p` and first-order linear part `theta`
    /// (`na = nb = nk = 1`), all training, on the settling tests' staircase read as `y = 0.5·u`.
    fn memory_on_the_staircase(element: &dyn Element, p: Vec<f64>, theta: Vec<f64>) -> Option<f64> {
        let u = staircase();
        let y: Vec<f64> = u.iter().map(|v| 0.5 * v).collect();
        let d = Data { u: vec![&u], y: &y, train: 0..u.len(), nominal: None, noise_order: 0 };
        let orders = Orders { na: 1, nb: 1, nk: vec![1], trend: false, reading: None };
        let m = Model { element, input: 0, orders };
        memory_time(&m, &Fitted { p, theta, noise: vec![] }, &d)
    }

    /// How long a structure remembers its start, on the settling tests' staircase (1500 rows,
    /// all training), with `α = 0.9`, `β = 0.1`:
    /// - linear: an offset `δ` in the recorded start is `0.9^(j+1)·δ` on the `j`-th simulated
    ///   row, above `δ/e` while `j + 1 < −1/ln 0.9 = 9.49`, so the last row apart is `j = 8`
    ///   and the memory 9 samples, the pole's time constant to within a sample;
    /// - a friction on the output's change of `γ = −0.3`: the drive from rest,
    ///   `0.1·(u − x)`, never beats it on inputs within ±1 from a start within ±1, so the
    ///   output stays where it starts and the memory is infinite, where the settling rule
    ///   reads 9.49 samples off the pole;
    /// - a friction on the velocity (`γ = −0.05`, rest at 0), where the record starts at −0.5
    ///   on the staircase's first level, −1, held 37 rows: the friction's fixed point there,
    ///   `x = 0.9x − 0.1 + 0.05`, is −0.5, and both offset starts (±σ, σ ≈ 0.3) stay below
    ///   rest over that level, where the friction only adds a constant, so the difference
    ///   decays by 0.9 a sample as the linear structure's (to about 2 % of σ by the level's end,
    ///   before any crossing of rest) and the memory is again 9: a friction that is not
    ///   holding the output is not read as memory.
    #[test]
    fn a_force_that_holds_the_output_where_it_starts_is_remembered() {
        let u = staircase();
        let y: Vec<f64> = u.iter().map(|v| 0.5 * v).collect();
        let orders = Orders { na: 1, nb: 1, nk: vec![1], trend: false, reading: None };
        let memory = memory_on_the_staircase;
        assert_eq!(memory(&Linear, vec![], vec![0.9, 0.1, 0.0]), Some(9.0));
        let position = Coulomb { on_change: true };
        let held = memory(&position, vec![], vec![0.9, 0.1, -0.3, 0.0]);
        assert_eq!(held, Some(f64::INFINITY));
        let poles = Model { element: &position, input: 0, orders };
        let fitted = Fitted { p: vec![], theta: vec![0.9, 0.1, -0.3, 0.0], noise: vec![] };
        // Infinite because it holds, not because it could not be simulated: it stays at its start.
        let sim = poles.simulate(&fitted, &[&u], &y).expect("it simulates");
        assert!(sim.iter().all(|&v| v == y[0]), "it moved");
        assert!(settling_time(&poles, &fitted) < 10.0);
        let velocity = memory(&Coulomb { on_change: false }, vec![0.0], vec![0.9, 0.1, -0.05, 0.0]);
        assert_eq!(velocity, Some(9.0));
    }

    /// A cubic spring, `x(t) = 0.9·x(t−1) + 0.1·u(t−1) + γ·x(t−1)³`, on the same staircase: two
    /// simulations apart by `δ` close by `0.9 + 3γξ²` a sample, `ξ` between them (the mean
    /// value theorem). The record starts at −0.5 on the first level, −1, held 37 rows; from
    /// −0.5 ± σ (σ ≈ 0.29) both simulations move toward the level's fixed point (about −0.7
    /// for `γ = −0.05`, −1.03 for `γ = +0.02`) and stay beyond −0.2 and within ±1.1, so:
    /// - a stiffening spring (`γ = −0.05`) closes by at most `0.9 − 0.15·0.2² = 0.894` a
    ///   sample, and `0.894⁹ = 0.365 < 1/e`: it forgets within 8 samples, before the linear
    ///   structure's 9;
    /// - a softening spring (`γ = +0.02`) closes by at least 0.9 and at most
    ///   `0.9 + 0.06·1.1² = 0.973` a sample: it remembers at least the linear structure's 9
    ///   samples, and forgets within the level (`0.973³⁷ < 1/e`).
    #[test]
    fn a_spring_forgets_as_fast_as_its_cube_pulls_back() {
        let memory = |gamma: f64| {
            let spring = super::super::stiffness::CubicStiffness;
            memory_on_the_staircase(&spring, vec![0.0], vec![0.9, 0.1, gamma, 0.0])
                .expect("the recorded start simulates")
        };
        let stiff = memory(-0.05);
        assert!((1.0..=8.0).contains(&stiff), "{stiff}");
        let soft = memory(0.02);
        assert!((9.0..=37.0).contains(&soft), "{soft}");
    }

    /// A known limit of the drift test, pinned down. The plant of the settling test with pole
    /// 0.95 read with a ramp of 0.3 over its 1500 rows, noise-free: a re-fit with two poles
    /// holds the ramp exactly as a pole at 1 fed by its constant beside the pole at 0.95, so a
    /// drift term adds nothing to it and no drift is decided; that re-fit never settles, so it
    /// is withheld, with its infinite time constant, rather than reported. Without the ramp the
    /// same plant is named a time constant (the settling test). Deciding the drift against
    /// the best re-fit that settles is not built (docs/diagnose-history.md, stop 51).
    #[test]
    fn a_ramp_held_by_an_integrator_pole_is_withheld() {
        let u = staircase();
        let n = u.len();
        let mut y = vec![0.0; n];
        let mut x = 0.0;
        for t in 1..n {
            x = 0.95 * x + 0.05 * u[t - 1];
            y[t] = x + 0.3 * t as f64 / n as f64;
        }
        let e = against_the_settling_nominal(&u, &y);
        assert!(e.withheld && e.corrected.is_none());
        assert_eq!(e.finding.physics, Physics::Unexplained, "{}", e.finding.summary);
        assert!(e.finding.summary.contains("infinite (an integrator or unstable)"), "{}", e.finding.summary);
        assert!(!e.finding.summary.contains("drift"), "{}", e.finding.summary);
    }

    /// The parsimony rule: among candidates within half a point of the best, the fewest
    /// parameters win, and on equal counts the better score.
    #[test]
    fn the_parsimony_rule_takes_the_simplest_within_half_a_point() {
        let c = |mean: f64, complexity: usize| {
            (CvScore { mean, blocks: vec![mean], prediction_rms: vec![] }, 0, 0, complexity, 0)
        };
        let rank = |v: &CvScore| v.mean;
        let mean_of = |s: &[Scored]| chosen(s, &rank).map(|s| s.0.mean);
        // 49.4 is simplest but 0.6 below the best; 49.7 and 49.6 tie on parameters.
        assert_eq!(mean_of(&[c(50.0, 9), c(49.7, 7), c(49.6, 7), c(49.4, 5)]), Some(49.7));
        // Within half a point, the simplest wins over the best.
        assert_eq!(mean_of(&[c(50.0, 9), c(49.6, 7), c(49.5, 5)]), Some(49.5));
        assert_eq!(mean_of(&[c(50.0, 9)]), Some(50.0));
        assert_eq!(mean_of(&[]), None);
    }

    /// The walk down the ranking, on scores alone: the element index (the second field) stands
    /// for the class, `beats` for the margin over a linear re-fit at 40 and the gate, and
    /// `attempt` for the fit and its checks, by class.
    /// - A class set aside (slow) passes the choice to the next class; the set-aside class's
    ///   other candidates go with it, even within the window.
    /// - An idle one or a failed fit ends the walk with nothing, and so does a choice left with
    ///   no candidate that beats the linear re-fit.
    /// - A candidate that fails the gate is not chosen, and does not hide one that passes.
    #[test]
    fn a_slow_choice_gives_way_to_the_next_class_and_an_idle_one_ends_the_walk() {
        let c = |mean: f64, class: usize, complexity: usize| {
            (CvScore { mean, blocks: vec![mean], prediction_rms: vec![] }, class, 0, complexity, 0)
        };
        let rank = |v: &CvScore| v.mean;
        let beats = |v: &CvScore| v.mean - 40.0 >= NONLINEAR_MARGIN;
        let class = |s: &Scored| [Physics::Quadratic, Physics::Saturation, Physics::DeadZone][s.1];
        let scored = [c(50.0, 0, 9), c(49.8, 0, 7), c(49.0, 1, 5), c(45.0, 2, 5), c(40.2, 2, 3)];
        let run = |slow: &[usize], idle: &[usize]| {
            let mut tried = Vec::new();
            let got = walk(&scored, &rank, beats, class, |s| {
                tried.push(s.1);
                if slow.contains(&s.1) {
                    Attempt::SetAside
                } else if idle.contains(&s.1) {
                    Attempt::Ends
                } else {
                    Attempt::Reported(s.0.mean)
                }
            });
            (got, tried)
        };
        // Nothing withheld: the parsimony rule's choice, the quadratic's simpler fit.
        assert_eq!(run(&[], &[]), (Some(49.8), vec![0]));
        // The quadratic slow: its 50.0 goes with it, and the saturation (49.0) is reported.
        assert_eq!(run(&[0], &[]), (Some(49.0), vec![0, 1]));
        // The quadratic and the saturation slow: the dead zone's 45.0 beats the linear 40.
        assert_eq!(run(&[0, 1], &[]), (Some(45.0), vec![0, 1, 2]));
        // The quadratic idle: the walk ends, the saturation is not tried.
        assert_eq!(run(&[], &[0]), (None, vec![0]));
        // Every class slow: nothing left to choose.
        assert_eq!(run(&[0, 1, 2], &[]), (None, vec![0, 1, 2]));
        // Only the dead zone's 40.2 left: it does not beat the linear re-fit by the margin.
        let weak = [c(50.0, 0, 9), c(40.2, 2, 3)];
        let got = walk(&weak, &rank, beats, class, |s| match s.1 {
            0 => Attempt::SetAside,
            _ => Attempt::Reported(s.0.mean),
        });
        assert_eq!(got, None);
        // The best by the blocks fails the gate (a block below the nominal's 30): it does not
        // hide the dead zone below it, which passes and beats the linear re-fit.
        let gated = |v: &CvScore| beats(v) && v.blocks.iter().all(|&b| b >= 30.0);
        let mut lower = c(50.0, 0, 9);
        lower.0.blocks = vec![80.0, 60.0, 10.0];
        let hidden = [lower, c(45.0, 2, 5)];
        let got = walk(&hidden, &rank, gated, class, |s| Attempt::Reported(s.0.mean));
        assert_eq!(got, Some(45.0));
    }
}
