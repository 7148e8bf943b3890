//! The decision for one output: the scored hypotheses against the [`Reference`], each
//! correction in turn, the first that passes every test reported.
//!
//! The rule, in the currency of the held-out FIT (simulation mode, out of sample, each
//! validation block against its own mean; [`super::super::CvScore`]):
//! - a physics element is named when its cross-validated FIT beats the linear re-fit's by
//!   [`NONLINEAR_MARGIN`] points, beats the nominal's by the caller's margin on average, and
//!   lowers no block below the nominal's;
//! - otherwise the linear re-fit is the finding (a gain, a time constant or a dead time,
//!   whichever it changes most) when it passes the same two tests against the nominal;
//! - otherwise, on a record read through its instrument's range, the range alone when it adds
//!   more than the linear change beside it (the parent module's doc);
//! - otherwise the finding is `unexplained`, naming the best candidate, its mean gain and its
//!   worst block's.
//!
//! On a dithered record the ranking currency is the one-step prediction error instead (the
//! parent module's doc; [`super::super::CvScore::rank`]).
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
//! (docs/diagnose-history.md, stops 47 and 48). That holds where an idle element is its
//! linear part ([`Element::idle_is_linear`]); a tank whose rim is idle still bends the dynamics
//! with its square-root outflow, a nonlinearity the vocabulary has no class for, and its class
//! is set aside as a slow one's is (stop 74). When it does not settle, or remembers its
//! start, its class is set aside and the rule chooses again among the other classes, each
//! choice held to the same margin, gate and checks ([`walk`]): a slow store can lead as one
//! class while another explains the record with dynamics the blocks can check (stop 71).
//! When nothing is reported, the finding is `unexplained` and says why, each withheld
//! correction in the order tried.

use crate::describe::num;
use mpmwatch_core::numerics::std_dev;
use std::collections::BTreeMap;

use super::super::clip_sensor::ClipSensor;
use super::super::linear_change::{at_the_bound, changed_most, linear_change};
use super::super::{CvScore, Data, Element, Fitted, Linear, Model, Orders, cv_fit, fit, ranked_linear};
use super::{Explanation, Margins, Names, Output, Reference, Scored, tried};
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

/// The decision for one output, against its [`Reference`]: each correction in turn, the first
/// that passes every test reported, each that passed the gate and was not reported kept with
/// its reason for the `unexplained` finding.
pub(super) struct Judge<'a> {
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

impl<'a> Judge<'a> {
    /// The decision for output `o` under margins `m`, with the classes `els`, their `scored`
    /// candidates and the `reference` they were scored against.
    pub(super) fn new(
        o: &Output<'a>,
        m: &Margins,
        els: &'a [Box<dyn Element>],
        scored: &[Scored],
        reference: &'a Reference,
    ) -> Self {
        let d = o.d;
        Judge {
            d,
            s: o.s,
            nominal: o.nominal,
            flagged: o.flagged,
            names: o.names,
            ts: o.ts,
            min_gain: m.min_gain,
            els,
            reference,
            tried: tried(scored, els, &reference.nominal_cv),
            train_rows: (d.train.start + m.warmup..d.train.end).collect(),
            block: reference.folds.iter().map(|f| f.1.len()).min().unwrap_or(0) as f64,
            withheld: Vec::new(),
        }
    }
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
    pub(super) fn element(&mut self, scored: &[Scored], order_sets: &[Orders]) -> Option<Explanation> {
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
                    Err(Some(Why::Idle(_))) if el.idle_is_linear() => Attempt::Ends,
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
    pub(super) fn linear_refit(&mut self) -> Option<Explanation> {
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
    pub(super) fn range_alone(&mut self) -> Option<Explanation> {
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
    pub(super) fn unexplained(self, scored: &[Scored]) -> Explanation {
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
/// read through the instrument's range the record shows ([`super::super::pinned`]); empty without one.
fn reading_note(reading: Option<super::super::Reading>, output: &str) -> String {
    reading.map_or(String::new(), |r| {
        format!("; every structure, and the nominal compared with them, read through the range the record shows: {}", r.describe(output))
    })
}

/// A correction that passed the gate and was not reported.
pub(super) struct Withheld {
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
    /// explain the record with dynamics the blocks can check. Likewise a tank whose rim is
    /// idle, and a fit that cannot be simulated over the record (nothing kept of it).
    SetAside,
    /// Withheld as idle where that leaves its linear part (no other candidate of the parsimony
    /// window can then beat it by the margin, docs/diagnose-history.md, stop 47), or not
    /// fitted.
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

#[cfg(test)]
mod tests {
    use super::super::super::friction::Coulomb;
    use super::super::tests::staircase;
    use super::*;

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
        let cascade = tau(&super::super::super::tank_cascade::TankCascade, vec![2.0, 2.0, 0.1, 500.0, 0.1]);
        assert!((cascade - linear).abs() < 1e-6, "{cascade} against {linear}");
        let single = tau(&super::super::super::draining_tank::DrainingTank, vec![2.0, 0.1, 500.0]);
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
            let spring = super::super::super::stiffness::CubicStiffness;
            memory_on_the_staircase(&spring, vec![0.0], vec![0.9, 0.1, gamma, 0.0])
                .expect("the recorded start simulates")
        };
        let stiff = memory(-0.05);
        assert!((1.0..=8.0).contains(&stiff), "{stiff}");
        let soft = memory(0.02);
        assert!((9.0..=37.0).contains(&soft), "{soft}");
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
