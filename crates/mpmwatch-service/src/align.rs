//! Alignment of asynchronous tag samples onto a controller's sample grid, and the residual of
//! each aligned row. Pure state machines: the ingest loop feeds them (with the wall clock as an
//! argument), tests drive them directly.
//!
//! A sample's time is snapped to the nearest multiple of the period (its *slot*). Each tag has a
//! *watermark*, the newest slot it has published. Rows wait in a pending map and close strictly
//! in slot order: a row closes once every tag's watermark has reached it (every tag has published
//! it or moved past it), or once it has waited `grace` seconds of wall clock for a tag that went
//! silent, or, when `tolerance` is set, once the newest sample is `tolerance` slots past it. So a
//! historian that publishes one tag's batch after another's, in any order and of any size up to
//! the window, aligns without loss: rows simply wait until the last tag's batch has passed them.
//! A row that closes incomplete is a gap. The pending map never holds more than a window of rows
//! (the oldest closes early, counted as an overflow).
//!
//! Back-fill: a sample for a row already closed incomplete, or for a slot no tag published,
//! fills that *hole* if it lies inside the window; the row is re-emitted (marked `backfill`) once
//! complete. A sample for a complete closed row is a duplicate; one older than the window is late.
//! Holes and the record of closed rows are bounded by the window too.
//!
//! Jumps of the source clock: a sample more than a window ahead of the newest slot, or older than
//! the window, is not trusted at once: one bogus time would otherwise close every open row
//! (ahead), and a clock set back would have everything that follows refused (behind). Such
//! samples start a *jump candidate* and are dropped, as `time_jump` ahead and as `late` behind. A
//! sample on the current timeline cancels the candidate (a glitch); a candidate fed without
//! interruption by enough samples from at least half the columns becomes the new timeline
//! (a jump forward is an ordinary gap once confirmed; a jump back restarts the window).

use std::collections::{BTreeMap, BTreeSet};

use mpmwatch_core::model::{MimoModel, MimoState};

/// Why a sample was dropped.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum DropReason {
    /// Undecodable message (not JSON, wrong shape, bad time); counted once per message.
    BadPayload,
    /// A key whose controller role/tag is not configured.
    UnknownTag,
    /// NaN, ±inf or null value.
    NonFinite,
    /// The slot already holds a value for this tag.
    Duplicate,
    /// Its row had already closed complete: a repeat that arrives after its row left (while the
    /// row is pending, or for a hole the tag already filled, a repeat is a `duplicate`).
    OutOfOrder,
    /// Older than the whole window: of no use any more (e.g. a historian back-fill).
    Late,
    /// Stamped more than a day after the wall clock: a bogus time that would otherwise close
    /// every open row and make all later samples look out of order.
    Future,
    /// Far ahead of or behind the current timeline: held against a possible jump of the source
    /// clock until the jump is confirmed or cancelled (see the module doc).
    TimeJump,
    /// The controller's ingest queue was full (overload); counted once per message, as it was
    /// never decoded.
    QueueFull,
}

impl DropReason {
    /// Every reason, for metrics that must show zeros too.
    pub const ALL: [DropReason; 9] = [
        Self::BadPayload,
        Self::UnknownTag,
        Self::NonFinite,
        Self::Duplicate,
        Self::OutOfOrder,
        Self::Late,
        Self::Future,
        Self::TimeJump,
        Self::QueueFull,
    ];

    /// The metric label.
    pub fn as_str(self) -> &'static str {
        match self {
            Self::BadPayload => "bad_payload",
            Self::UnknownTag => "unknown_tag",
            Self::NonFinite => "non_finite",
            Self::Duplicate => "duplicate",
            Self::OutOfOrder => "out_of_order",
            Self::Late => "late",
            Self::Future => "future",
            Self::TimeJump => "time_jump",
            Self::QueueFull => "queue_full",
        }
    }
}

/// A row leaving the aligner: its slot and one optional value per column.
#[derive(Debug, Clone, PartialEq)]
pub struct ClosedRow {
    /// Slot (time / period, rounded).
    pub slot: i64,
    /// Column values; `None` where the tag never arrived.
    pub values: Vec<Option<f64>>,
    /// A hole of an earlier closed row, now complete by back-fill: it replaces that slot.
    pub backfill: bool,
}

/// A confirmed jump of the source clock.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Jump {
    /// Newest slot of the old timeline.
    pub from: i64,
    /// First slot of the new one.
    pub to: i64,
}

impl Jump {
    /// The clock went back: rows already kept lie in the new timeline's future.
    pub fn is_backward(&self) -> bool {
        self.to <= self.from
    }
}

/// Samples far from the current timeline, possibly a new one.
#[derive(Debug, Clone)]
struct Candidate {
    /// Newest slot seen on it.
    newest: i64,
    /// Samples on it since it started, uninterrupted by the current timeline.
    samples: usize,
    /// Columns seen on it.
    columns: Vec<bool>,
}

/// A row waiting for its tags.
#[derive(Debug, Clone)]
struct Pending {
    values: Vec<Option<f64>>,
    /// Wall-clock seconds when its first sample arrived.
    opened: f64,
}

/// Uninterrupted rows' worth of samples that confirm a jump of the clock back. A confirmed jump
/// back discards the window, and a historian back-fill older than the window looks the same at
/// first; a back-fill interleaved with live data never qualifies.
const CONFIRM_BACK_ROWS: usize = 8;

/// Snaps samples to the grid and closes rows in order.
#[derive(Debug, Clone)]
pub struct Aligner {
    period: f64,
    window: i64,
    grace: f64,
    tolerance: Option<i64>,
    required: Vec<bool>,
    pending: BTreeMap<i64, Pending>,
    watermark: Vec<Option<i64>>,
    holes: BTreeMap<i64, Vec<Option<f64>>>,
    done: BTreeSet<i64>,
    newest: Option<i64>,
    closed_through: Option<i64>,
    candidate: Option<Candidate>,
    jumps: Vec<Jump>,
    overflow: u64,
    /// Wall-clock time of the first sample offered.
    started: Option<f64>,
}

impl Aligner {
    /// `required[c]` says whether column `c` must be present for a row to be complete. A row
    /// waits at most `grace` wall-clock seconds for a silent tag; `tolerance` slots past the
    /// newest sample also close it when non-zero (0: watermarks and grace only).
    pub fn new(period: f64, window: usize, grace: f64, tolerance: usize, required: Vec<bool>) -> Self {
        let width = required.len();
        Self {
            period,
            window: window.max(1) as i64,
            grace,
            tolerance: (tolerance > 0).then_some(tolerance as i64),
            required,
            pending: BTreeMap::new(),
            watermark: vec![None; width],
            holes: BTreeMap::new(),
            done: BTreeSet::new(),
            newest: None,
            closed_through: None,
            candidate: None,
            jumps: Vec::new(),
            overflow: 0,
            started: None,
        }
    }

    /// Slots ahead of the newest beyond which a sample is a jump candidate: a window. A jump
    /// forward by less is an ordinary gap; by more, one bogus time would empty the window.
    pub fn jump_threshold(&self) -> i64 {
        self.window
    }

    /// Uninterrupted samples that confirm a jump forward: two rows' worth. Little is lost when
    /// a publisher returns after an outage (a real gap), and one bogus batch is not enough.
    fn confirm_forward(&self) -> usize {
        2 * self.required.len()
    }

    fn confirm_backward(&self) -> usize {
        CONFIRM_BACK_ROWS * self.required.len()
    }

    /// Jumps confirmed since the last call, oldest first (the caller resets what depends on
    /// the timeline).
    pub fn take_jumps(&mut self) -> Vec<Jump> {
        std::mem::take(&mut self.jumps)
    }

    /// Rows closed early because the pending map held a window of rows, since the last call.
    pub fn take_overflow(&mut self) -> u64 {
        std::mem::take(&mut self.overflow)
    }

    /// Whether `slot` lies so far from the current timeline that it may be a jump, and what it
    /// is counted as meanwhile: `time_jump` ahead, `late` behind (older than the window).
    fn far(&self, slot: i64) -> Option<DropReason> {
        if self.newest.is_some_and(|n| slot > n.saturating_add(self.jump_threshold())) {
            Some(DropReason::TimeJump)
        } else if self.closed_through.is_some_and(|c| slot <= c.saturating_sub(self.window)) {
            Some(DropReason::Late)
        } else {
            None
        }
    }

    /// Feeds a far sample to the candidate; `true` when it confirms the jump.
    fn feed_candidate(&mut self, col: usize, slot: i64) -> bool {
        let j = self.jump_threshold();
        let width = self.required.len();
        let same = self.candidate.as_ref().is_some_and(|c| (slot - c.newest).abs() <= j);
        if !same {
            self.candidate = Some(Candidate { newest: slot, samples: 0, columns: vec![false; width] });
        }
        let (forward, backward) = (self.confirm_forward(), self.confirm_backward());
        let newest = self.newest;
        let Some(c) = self.candidate.as_mut() else { return false };
        c.newest = c.newest.max(slot);
        c.samples += 1;
        c.columns[col] = true;
        let distinct = c.columns.iter().filter(|&&x| x).count();
        let needed = if newest.is_some_and(|n| c.newest < n) { backward } else { forward };
        c.samples >= needed && 2 * distinct >= width
    }

    /// Makes the candidate's timeline the current one: open rows close as gaps, and the next
    /// samples start afresh after `to − 1`.
    fn confirm_jump(&mut self, to: i64, out: &mut Vec<ClosedRow>) {
        let from = self.newest.unwrap_or(to);
        while let Some((slot, row)) = self.pending.pop_first() {
            out.push(ClosedRow { slot, values: row.values, backfill: false });
        }
        self.candidate = None;
        self.closed_through = None;
        self.holes.clear();
        self.done.clear();
        self.watermark.iter_mut().for_each(|w| *w = None);
        self.newest = Some(to);
        self.jumps.push(Jump { from, to });
    }

    /// Continues after the rows of `slots` (ascending) were restored from the store: they are
    /// closed and complete, so a repeat of one is `out_of_order`, while the slots between them
    /// stay open to back-fill.
    pub fn resume_after(&mut self, slots: &[i64]) {
        let Some(&slot) = slots.last() else { return };
        self.closed_through = Some(slot);
        self.newest = Some(self.newest.map_or(slot, |n| n.max(slot)));
        self.done.extend(slots.iter().copied().filter(|&s| s > slot - self.window));
    }

    /// The slot of time `t`, if representable.
    pub fn slot(&self, t: f64) -> Option<i64> {
        let s = (t / self.period).round();
        (s.is_finite() && s.abs() < 9.0e15).then_some(s as i64)
    }

    /// Rows waiting for tags (at most a window).
    pub fn pending(&self) -> usize {
        self.pending.len()
    }

    /// Offers one sample of column `col` at wall-clock time `now` (seconds, any monotonic
    /// origin); rows that close as a result are appended to `out`.
    pub fn offer(
        &mut self,
        col: usize,
        t: f64,
        v: f64,
        now: f64,
        out: &mut Vec<ClosedRow>,
    ) -> Result<(), DropReason> {
        if !v.is_finite() {
            return Err(DropReason::NonFinite);
        }
        let slot = self.slot(t).ok_or(DropReason::BadPayload)?;
        self.started.get_or_insert(now);
        if let Some(reason) = self.far(slot) {
            if self.feed_candidate(col, slot) {
                let to = self.candidate.as_ref().map_or(slot, |c| c.newest);
                self.confirm_jump(to, out);
            }
            return Err(reason);
        }
        if let Some(c) = self.closed_through
            && slot <= c
        {
            self.backfill(col, slot, v, out)?;
        } else {
            let width = self.required.len();
            let row = self
                .pending
                .entry(slot)
                .or_insert_with(|| Pending { values: vec![None; width], opened: now });
            if row.values[col].is_some() {
                return Err(DropReason::Duplicate);
            }
            row.values[col] = Some(v);
        }
        // A sample on the current timeline: a pending jump was a glitch.
        self.candidate = None;
        self.newest = Some(self.newest.map_or(slot, |n| n.max(slot)));
        let w = &mut self.watermark[col];
        *w = Some(w.map_or(slot, |m| m.max(slot)));
        self.close(now, out);
        Ok(())
    }

    /// Closes the rows whose grace has expired at wall-clock `now` (the scheduler calls this
    /// before an analysis, so a tag that went silent does not hold rows while nothing arrives).
    pub fn tick(&mut self, now: f64, out: &mut Vec<ClosedRow>) {
        self.close(now, out);
    }

    /// A sample for a closed slot inside the window: it fills that slot's hole.
    fn backfill(
        &mut self,
        col: usize,
        slot: i64,
        v: f64,
        out: &mut Vec<ClosedRow>,
    ) -> Result<(), DropReason> {
        if self.done.contains(&slot) {
            return Err(DropReason::OutOfOrder);
        }
        let width = self.required.len();
        let hole = self.holes.entry(slot).or_insert_with(|| vec![None; width]);
        if hole[col].is_some() {
            return Err(DropReason::Duplicate);
        }
        hole[col] = Some(v);
        if self.is_complete(&self.holes[&slot]) {
            let values = self.holes.remove(&slot).unwrap_or_default();
            self.done.insert(slot);
            out.push(ClosedRow { slot, values, backfill: true });
        }
        Ok(())
    }

    fn is_complete(&self, values: &[Option<f64>]) -> bool {
        values.iter().zip(&self.required).all(|(v, &req)| !req || v.is_some())
    }

    fn close(&mut self, now: f64, out: &mut Vec<ClosedRow>) {
        // A tag that has not published once in `grace` seconds since the first sample (an
        // optional MV nobody publishes) holds no row; a tag that has published holds rows until
        // its watermark passes them or their own grace expires.
        let given_up = self.started.is_some_and(|s| now - s >= self.grace);
        let passed_by_all = self
            .watermark
            .iter()
            .zip(&self.required)
            .filter(|(w, req)| **req && !(w.is_none() && given_up))
            .map(|(w, _)| *w)
            .min()
            .flatten();
        let newest = self.newest.unwrap_or(i64::MIN);
        while let Some((&slot, row)) = self.pending.first_key_value() {
            let passed = passed_by_all.is_some_and(|w| slot <= w);
            let waited = now - row.opened >= self.grace;
            let behind = self.tolerance.is_some_and(|tol| slot <= newest - tol);
            let overflow = self.pending.len() as i64 > self.window;
            if !(passed || waited || behind || overflow) {
                break;
            }
            if overflow && !(passed || waited || behind) {
                self.overflow += 1;
            }
            let Some((_, row)) = self.pending.pop_first() else { break };
            if self.is_complete(&row.values) {
                self.done.insert(slot);
            } else {
                self.holes.insert(slot, row.values.clone());
            }
            self.closed_through = Some(slot);
            out.push(ClosedRow { slot, values: row.values, backfill: false });
        }
        if let Some(c) = self.closed_through {
            let keep_from = c.saturating_sub(self.window) + 1;
            while self.done.first().is_some_and(|&s| s < keep_from) {
                self.done.pop_first();
            }
            while self.holes.first_key_value().is_some_and(|(&s, _)| s < keep_from) {
                self.holes.pop_first();
            }
        }
    }
}

/// Column layout of a controller's rows: MVs, dithers, CVs, predictions.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Layout {
    /// MV count.
    pub mv: usize,
    /// Dither count (= MV count).
    pub dither: usize,
    /// CV count.
    pub cv: usize,
    /// Prediction count (= CV count in pred mode, else 0).
    pub pred: usize,
}

impl Layout {
    /// Total columns.
    pub fn width(&self) -> usize {
        self.mv + self.dither + self.cv + self.pred
    }
    /// First dither column.
    pub fn dither_at(&self) -> usize {
        self.mv
    }
    /// First CV column.
    pub fn cv_at(&self) -> usize {
        self.mv + self.dither
    }
    /// First prediction column.
    pub fn pred_at(&self) -> usize {
        self.mv + self.dither + self.cv
    }
}

/// An aligned, complete row as the window keeps it.
#[derive(Debug, Clone, PartialEq)]
pub struct WindowRow {
    /// Slot.
    pub slot: i64,
    /// MVs (NaN where absent: MVs are optional when predictions are published).
    pub mv: Vec<f64>,
    /// Dithers.
    pub dither: Vec<f64>,
    /// CVs.
    pub cv: Vec<f64>,
    /// Residuals `cv − prediction`.
    pub residual: Vec<f64>,
}

/// Samples the nominal model is run at the first MVs before its predictions are used, so its
/// initial conditions have died out (as the closed-loop simulator does).
const WARM_UP: usize = 200;

/// Turns closed rows into window rows: `e = cv − pred`, or `e = cv − G0(mv)` with the nominal
/// model stepped once per slot (MVs held over missing slots; restarted after a gap longer than
/// the window).
#[derive(Debug, Clone)]
pub struct Residuals {
    layout: Layout,
    model: Option<MimoModel>,
    state: Option<MimoState>,
    last_slot: Option<i64>,
    last_u: Vec<f64>,
    max_hold: i64,
}

impl Residuals {
    /// From published predictions.
    pub fn from_pred(layout: Layout) -> Self {
        Self { layout, model: None, state: None, last_slot: None, last_u: Vec::new(), max_hold: 0 }
    }

    /// From a nominal model simulated on the MVs; holds MVs over gaps up to `max_hold` slots.
    pub fn from_model(layout: Layout, model: MimoModel, max_hold: usize) -> Self {
        Self {
            layout,
            model: Some(model),
            state: None,
            last_slot: None,
            last_u: Vec::new(),
            max_hold: max_hold as i64,
        }
    }

    /// The columns a row waits for before it closes early: all of them, MVs included even when
    /// predictions are published (an MV that comes last would otherwise find its row closed).
    /// A row that closes on the tolerance without its MVs is still used in `pred` mode.
    pub fn required(&self) -> Vec<bool> {
        vec![true; self.layout.width()]
    }

    /// The window row of a closed row, or `None` when it is incomplete (a gap).
    pub fn process(&mut self, row: &ClosedRow) -> Option<WindowRow> {
        let l = self.layout;
        let get = |c: usize| row.values[c];
        let mv: Vec<f64> = (0..l.mv).map(|c| get(c).unwrap_or(f64::NAN)).collect();
        let dither: Option<Vec<f64>> = (0..l.dither).map(|c| get(l.dither_at() + c)).collect();
        let cv: Option<Vec<f64>> = (0..l.cv).map(|c| get(l.cv_at() + c)).collect();
        let pred: Vec<f64> = if self.model.is_some() {
            self.step_model(row.slot, &mv)?
        } else {
            (0..l.pred).map(|c| get(l.pred_at() + c)).collect::<Option<Vec<f64>>>()?
        };
        let (dither, cv) = (dither?, cv?);
        if mv.iter().any(|v| v.is_nan()) && self.model.is_some() {
            return None;
        }
        let residual = cv.iter().zip(&pred).map(|(y, p)| y - p).collect();
        Some(WindowRow { slot: row.slot, mv, dither, cv, residual })
    }

    /// The window row of a row completed by back-fill, which replaces a gap inside the window.
    /// From predictions its residual is final; from a model it is left NaN, because the model
    /// must be re-run through the window in slot order ([`Residuals::recompute`]).
    pub fn backfilled(&self, row: &ClosedRow) -> Option<WindowRow> {
        let l = self.layout;
        let get = |c: usize| row.values[c];
        let mv: Vec<f64> = (0..l.mv).map(|c| get(c).unwrap_or(f64::NAN)).collect();
        let dither: Vec<f64> = (0..l.dither).map(|c| get(l.dither_at() + c)).collect::<Option<_>>()?;
        let cv: Vec<f64> = (0..l.cv).map(|c| get(l.cv_at() + c)).collect::<Option<_>>()?;
        let residual = if self.model.is_some() {
            if mv.iter().any(|v| v.is_nan()) {
                return None;
            }
            vec![f64::NAN; l.cv]
        } else {
            let pred: Vec<f64> = (0..l.pred).map(|c| get(l.pred_at() + c)).collect::<Option<_>>()?;
            cv.iter().zip(&pred).map(|(y, p)| y - p).collect()
        };
        Some(WindowRow { slot: row.slot, mv, dither, cv, residual })
    }

    /// Whether residuals come from a model (and back-fill needs [`Residuals::recompute`]).
    pub fn uses_model(&self) -> bool {
        self.model.is_some()
    }

    /// Re-runs the model from a fresh warm-up through `rows` (the window, oldest first) and
    /// rewrites their residuals; the state then continues after the newest row.
    pub fn recompute<'r>(&mut self, rows: impl Iterator<Item = &'r mut WindowRow>) {
        if self.model.is_none() {
            return;
        }
        self.reset();
        for r in rows {
            if let Some(pred) = self.step_model(r.slot, &r.mv) {
                r.residual = r.cv.iter().zip(&pred).map(|(y, p)| y - p).collect();
            }
        }
    }

    /// Forgets the model state after a jump of the clock back: it restarts (warm-up) at the
    /// next row as after a long gap.
    pub fn reset(&mut self) {
        self.state = None;
        self.last_slot = None;
        self.last_u.clear();
    }

    /// Runs the model through the MVs of restored rows so it continues where it stopped.
    pub fn replay(&mut self, rows: &[WindowRow]) {
        if self.model.is_none() {
            return;
        }
        for r in rows {
            let _ = self.step_model(r.slot, &r.mv);
        }
    }

    /// `G0(u)` at `slot` (before `u(slot)` acts), then advances the model with `u(slot)`. Missing
    /// MVs are held from the previous slot.
    fn step_model(&mut self, slot: i64, mv: &[f64]) -> Option<Vec<f64>> {
        let model = self.model.as_ref()?;
        let u: Vec<f64> = if mv.iter().any(|v| v.is_nan()) {
            if self.last_u.is_empty() {
                return None;
            }
            mv.iter().zip(&self.last_u).map(|(v, last)| if v.is_nan() { *last } else { *v }).collect()
        } else {
            mv.to_vec()
        };
        let gap = self.last_slot.map_or(i64::MAX, |s| slot - s - 1);
        if self.state.is_none() || gap > self.max_hold {
            let mut st = model.state();
            for _ in 0..WARM_UP {
                st.step(&u).ok()?;
            }
            self.state = Some(st);
        } else if let Some(st) = self.state.as_mut() {
            for _ in 0..gap.max(0) {
                st.step(&self.last_u).ok()?;
            }
        }
        let st = self.state.as_mut()?;
        let pred = st.peek();
        st.step(&u).ok()?;
        self.last_u = u;
        self.last_slot = Some(slot);
        Some(pred)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use mpmwatch_core::model::{DiscreteTf, Hammerstein};

    fn run(a: &mut Aligner, col: usize, t: f64, v: f64) -> (Result<(), DropReason>, Vec<i64>) {
        let mut out = Vec::new();
        let r = a.offer(col, t, v, 0.0, &mut out);
        (r, out.iter().map(|r| r.slot).collect())
    }

    fn aligner(period: f64, window: usize, width: usize) -> Aligner {
        Aligner::new(period, window, 30.0, 0, vec![true; width])
    }

    #[test]
    fn rows_close_once_every_tag_has_passed_them_and_snap_to_the_grid() {
        let mut a = aligner(0.5, 100, 2);
        assert_eq!(run(&mut a, 0, 1.02, 1.0), (Ok(()), vec![]));
        assert_eq!(run(&mut a, 1, 0.98, 2.0), (Ok(()), vec![2]));
        // Both tags jump from slot 2 to 4: slot 3 is a hole, and 4 closes.
        let _ = run(&mut a, 0, 2.0, 1.0);
        assert_eq!(run(&mut a, 1, 2.0, 1.0), (Ok(()), vec![4]));
        // Slot 3 arriving afterwards is a back-fill: the row comes out when complete.
        assert_eq!(run(&mut a, 0, 1.5, 1.0), (Ok(()), vec![]));
        let mut out = Vec::new();
        a.offer(1, 1.5, 1.0, 0.0, &mut out).unwrap();
        assert_eq!(out, vec![ClosedRow { slot: 3, values: vec![Some(1.0), Some(1.0)], backfill: true }]);
    }

    #[test]
    fn per_tag_batches_in_any_order_align_without_loss() {
        // Three tags, 250-sample batches, tag order shuffled each round, window 1000.
        let mut a = aligner(1.0, 1000, 3);
        let mut out = Vec::new();
        let orders = [[2, 0, 1], [0, 1, 2], [1, 2, 0], [2, 1, 0]];
        for (round, order) in orders.iter().enumerate() {
            for &col in order {
                for k in 0..250 {
                    let t = (round * 250 + k) as f64;
                    assert_eq!(a.offer(col, t, t, 0.0, &mut out), Ok(()));
                }
            }
        }
        assert_eq!(out.len(), 1000);
        assert!(out.iter().enumerate().all(|(k, r)| r.slot == k as i64
            && !r.backfill
            && r.values.iter().all(|v| *v == Some(k as f64))));
        assert_eq!(a.pending(), 0);
        assert_eq!(a.take_overflow(), 0);
    }

    #[test]
    fn a_silent_tag_holds_rows_for_the_grace_and_its_back_fill_completes_them() {
        let mut a = Aligner::new(1.0, 100, 30.0, 0, vec![true, true]);
        let mut out = Vec::new();
        for t in 0..5 {
            a.offer(0, t as f64, 1.0, 0.0, &mut out).unwrap();
            a.offer(1, t as f64, 2.0, 0.0, &mut out).unwrap();
        }
        assert_eq!(out.len(), 5);
        out.clear();
        // Tag 1 goes silent: tag 0's rows wait, then close as gaps once their grace expires.
        for t in 5..10 {
            a.offer(0, t as f64, 1.0, 10.0, &mut out).unwrap();
        }
        assert!(out.is_empty());
        a.tick(39.9, &mut out);
        assert!(out.is_empty());
        a.tick(40.0, &mut out);
        assert_eq!(out.iter().map(|r| r.slot).collect::<Vec<_>>(), vec![5, 6, 7, 8, 9]);
        assert!(out.iter().all(|r| r.values[1].is_none() && !r.backfill));
        out.clear();
        // It comes back and back-fills: each hole is re-emitted complete.
        for t in 5..10 {
            a.offer(1, t as f64, 2.0, 50.0, &mut out).unwrap();
        }
        assert_eq!(
            out.iter().map(|r| (r.slot, r.backfill)).collect::<Vec<_>>(),
            (5..10).map(|s| (s, true)).collect::<Vec<_>>()
        );
        assert_eq!(a.offer(1, 7.0, 2.0, 50.0, &mut Vec::new()), Err(DropReason::OutOfOrder));
    }

    #[test]
    fn a_tag_nobody_publishes_holds_rows_only_until_the_grace_after_the_first_sample() {
        let mut a = Aligner::new(1.0, 100, 5.0, 0, vec![true, true]);
        let mut out = Vec::new();
        a.offer(0, 0.0, 1.0, 0.0, &mut out).unwrap();
        a.offer(0, 1.0, 1.0, 1.0, &mut out).unwrap();
        assert!(out.is_empty());
        a.offer(0, 2.0, 1.0, 5.0, &mut out).unwrap();
        assert_eq!(out.iter().map(|r| r.slot).collect::<Vec<_>>(), vec![0, 1, 2]);
    }

    #[test]
    fn a_tolerance_closes_rows_on_event_time_too() {
        let mut a = Aligner::new(1.0, 100, 30.0, 2, vec![true, true]);
        let _ = run(&mut a, 0, 0.0, 1.0);
        let _ = run(&mut a, 0, 1.0, 1.0);
        assert_eq!(run(&mut a, 0, 2.0, 1.0).1, vec![0]);
        let mut out = Vec::new();
        a.offer(0, 3.0, 1.0, 0.0, &mut out).unwrap();
        assert_eq!(out[0].values, vec![Some(1.0), None]);
    }

    #[test]
    fn every_drop_reason() {
        let mut a = aligner(1.0, 10, 1);
        assert_eq!(run(&mut a, 0, 0.0, f64::NAN).0, Err(DropReason::NonFinite));
        assert_eq!(run(&mut a, 0, f64::INFINITY, 1.0).0, Err(DropReason::BadPayload));
        for t in 0..30 {
            let _ = run(&mut a, 0, t as f64, 1.0);
        }
        assert_eq!(run(&mut a, 0, 29.0, 1.0).0, Err(DropReason::OutOfOrder));
        assert_eq!(run(&mut a, 0, 25.0, 1.0).0, Err(DropReason::OutOfOrder));
        assert_eq!(run(&mut a, 0, 3.0, 1.0).0, Err(DropReason::Late));
        let mut b = aligner(1.0, 10, 2);
        let _ = run(&mut b, 0, 5.0, 1.0);
        assert_eq!(run(&mut b, 0, 5.0, 1.0).0, Err(DropReason::Duplicate));
    }

    /// Offers one sample per column at `t`; returns the closed slots and the drops.
    fn round(a: &mut Aligner, t: f64) -> (Vec<i64>, Vec<DropReason>) {
        let mut out = Vec::new();
        let drops = (0..a.required.len()).filter_map(|c| a.offer(c, t, 1.0, 0.0, &mut out).err()).collect();
        (out.iter().filter(|r| r.values.iter().all(Option::is_some)).map(|r| r.slot).collect(), drops)
    }

    #[test]
    fn a_single_bogus_time_ahead_is_a_glitch_and_disturbs_nothing() {
        let mut a = aligner(1.0, 100, 2);
        for t in 0..10 {
            round(&mut a, t as f64);
        }
        let mut out = Vec::new();
        assert_eq!(a.offer(0, 10_800.0, 1.0, 0.0, &mut out), Err(DropReason::TimeJump));
        assert!(out.is_empty(), "no open row closes on a bogus time");
        assert_eq!(round(&mut a, 10.0), (vec![10], vec![]));
        assert!(a.take_jumps().is_empty());
    }

    #[test]
    fn a_jump_ahead_confirmed_by_all_columns_becomes_the_timeline() {
        let mut a = aligner(1.0, 100, 2);
        for t in 0..10 {
            round(&mut a, t as f64);
        }
        // Two rows' worth of samples on the new timeline: four, dropped while unconfirmed.
        let (_, d1) = round(&mut a, 10_000.0);
        let (_, d2) = round(&mut a, 10_001.0);
        assert_eq!([d1, d2].concat(), vec![DropReason::TimeJump; 4]);
        assert_eq!(a.take_jumps(), vec![Jump { from: 9, to: 10_001 }]);
        assert_eq!(round(&mut a, 10_002.0), (vec![10_002], vec![]));
        assert_eq!(round(&mut a, 10_003.0), (vec![10_003], vec![]));
    }

    #[test]
    fn a_jump_back_needs_a_longer_uninterrupted_run_and_restarts_the_timeline() {
        let mut a = aligner(1.0, 10, 2);
        for t in 1000..1020 {
            round(&mut a, t as f64);
        }
        // Interleaved with the current timeline it is a back-fill: late, never a jump.
        for t in 0..10 {
            assert_eq!(round(&mut a, t as f64).1, vec![DropReason::Late; 2]);
            round(&mut a, (1020 + t) as f64);
        }
        assert!(a.take_jumps().is_empty());
        // Alone it is a clock set back: CONFIRM_BACK_ROWS rows' worth confirm it.
        for t in 100..100 + CONFIRM_BACK_ROWS as i64 {
            assert_eq!(round(&mut a, t as f64).1, vec![DropReason::Late; 2]);
        }
        let jumps = a.take_jumps();
        let to = 100 + CONFIRM_BACK_ROWS as i64 - 1;
        assert_eq!(jumps, vec![Jump { from: 1029, to }]);
        assert!(jumps[0].is_backward());
        assert_eq!(round(&mut a, (to + 1) as f64), (vec![to + 1], vec![]));
    }

    #[test]
    fn memory_stays_bounded_whatever_the_times() {
        let mut a = aligner(1.0, 10, 2);
        let mut out = Vec::new();
        for k in 0..10_000u64 {
            let t = ((k * 7919) % 1000) as f64;
            let _ = a.offer((k % 2) as usize, t, 1.0, 0.0, &mut out);
            assert!(a.pending() <= 10);
            assert!(a.holes.len() <= 10 && a.done.len() <= 10);
        }
        // One tag far ahead of the other: the pending rows are capped at the window.
        let mut b = aligner(1.0, 10, 2);
        for t in 0..50 {
            let _ = b.offer(0, t as f64, 1.0, 0.0, &mut out);
        }
        assert_eq!(b.pending(), 10);
        assert_eq!(b.take_overflow(), 40);
    }

    #[test]
    fn model_residuals_match_a_whole_record_simulation() {
        let g = DiscreteTf::new(vec![0.0, 0.5], vec![1.0, -0.5], 0).unwrap();
        let model = MimoModel::new(vec![vec![Some(Hammerstein::linear(g))]]).unwrap();
        let layout = Layout { mv: 1, dither: 1, cv: 1, pred: 0 };
        let mut r = Residuals::from_model(layout, model.clone(), 10);
        assert_eq!(r.required(), vec![true, true, true]);
        let u: Vec<f64> = (0..50).map(|k| ((k * 37) % 11) as f64 - 5.0).collect();
        // the model warms up at u[0]: a whole-record simulation with that prefix
        let mut full = vec![u[0]; WARM_UP];
        full.extend(&u);
        let y = model.simulate(&[full]).unwrap().remove(0);
        for (k, &uk) in u.iter().enumerate() {
            let yk = y[WARM_UP + k];
            let row = ClosedRow {
                slot: k as i64,
                values: vec![Some(uk), Some(0.0), Some(yk + 1.0)],
                backfill: false,
            };
            let w = r.process(&row).unwrap();
            assert!((w.residual[0] - 1.0).abs() < 1e-12, "k {k}: {:?}", w.residual);
        }
        // a gap (missing CV) is no row, but the model keeps time
        assert!(
            r.process(&ClosedRow { slot: 50, values: vec![Some(0.0), Some(0.0), None], backfill: false })
                .is_none()
        );
    }
}
