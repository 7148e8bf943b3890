//! The state of one monitored controller: aligner, residuals, window, counters, the latest
//! report and the alarm debounce. Synchronous; the async shell holds it behind a mutex and keeps
//! each lock short (no analysis runs under it).

use std::collections::{BTreeMap, HashMap, VecDeque};
use std::sync::Arc;

use super::alarm::{AlarmEvent, Debounce};
use super::align::{Aligner, ClosedRow, DropReason, Jump, Layout, Residuals, WindowRow};
use super::analysis::{RunReport, RunStatus};
use super::config::{ControllerConfig, ResidualSource};
use super::payload::{self, Role};
use super::window::Window;

/// Alarm events kept in memory per controller (the store keeps them all).
const HISTORY: usize = 500;

/// Runs kept per channel for the trend (memory only: an hour at `every = 10`).
pub const TREND: usize = 360;

/// How far past the wall clock a sample time may lie (seconds since the Unix epoch): clocks of
/// historians drift, but not by a day.
const FUTURE_SLACK: f64 = 86_400.0;

/// What one message did.
#[derive(Debug, Clone, Default, PartialEq, Eq)]
pub struct IngestOutcome {
    /// Samples accepted onto the grid.
    pub accepted: u64,
    /// Samples (or, for `bad_payload`, messages) dropped, by reason.
    pub dropped: Vec<(DropReason, u64)>,
    /// Why the message or some of its samples were refused, for the log.
    pub problem: Option<String>,
    /// Sample slots skipped between the window's rows that this message closed (a gap in the
    /// data: a publisher away, a lost message, an incomplete row).
    pub gap_rows: u64,
    /// Jumps of the source clock this message confirmed.
    pub time_jumps: u64,
    /// Rows completed by back-fill that this message put into the window.
    pub backfilled_rows: u64,
    /// Rows closed early because a window of rows was already pending.
    pub overflow_rows: u64,
}

impl IngestOutcome {
    fn drop(&mut self, r: DropReason, n: u64) {
        if let Some(e) = self.dropped.iter_mut().find(|(d, _)| *d == r) {
            e.1 += n;
        } else {
            self.dropped.push((r, n));
        }
    }
}

/// One controller's state.
pub struct Controller {
    /// Its configuration.
    pub cfg: ControllerConfig,
    columns: HashMap<(Role, String), usize>,
    aligner: Aligner,
    residuals: Residuals,
    /// The analysis window.
    pub window: Window,
    debounce: BTreeMap<(usize, usize), Debounce>,
    /// The latest report.
    pub latest: Option<Arc<RunReport>>,
    /// Recent alarm events, oldest first.
    pub history: VecDeque<AlarmEvent>,
    /// Per channel (MV index, CV index): its decision in the recent `ok` runs, oldest first.
    pub trend: BTreeMap<(usize, usize), VecDeque<super::analysis::TrendPoint>>,
    /// Window rows not yet written to the store (bounded by the window length).
    pub unsaved: VecDeque<WindowRow>,
    /// Samples accepted since start.
    pub ingested: u64,
    /// Drops since start, by reason.
    pub dropped: HashMap<DropReason, u64>,
    /// An analysis is in flight.
    pub running: bool,
    /// Slots missing between consecutive window rows since start (see [`IngestOutcome::gap_rows`]).
    pub gap_rows: u64,
    /// Confirmed jumps of the source clock since start.
    pub time_jumps: u64,
    /// Rows completed by back-fill since start.
    pub backfilled_rows: u64,
    /// Rows closed early because the pending rows filled a window, since start.
    pub overflow_rows: u64,
    /// The origin of the wall clock the aligner's grace is measured on.
    clock: std::time::Instant,
    /// The stored rows must be replaced, not extended, at the next flush (the clock jumped
    /// back, so they lie in the new timeline's future).
    pub store_reset: bool,
}

impl Controller {
    /// A fresh state; the config must have been validated.
    pub fn new(cfg: ControllerConfig) -> Result<Self, String> {
        let layout = Layout {
            mv: cfg.mv.len(),
            dither: cfg.dither.len(),
            cv: cfg.cv.len(),
            pred: if cfg.residual == ResidualSource::Pred { cfg.pred.len() } else { 0 },
        };
        let mut columns = HashMap::new();
        for (i, t) in cfg.mv.iter().enumerate() {
            columns.insert((Role::Mv, t.clone()), i);
        }
        for (i, t) in cfg.dither.iter().enumerate() {
            columns.insert((Role::Dither, t.clone()), layout.dither_at() + i);
        }
        for (i, t) in cfg.cv.iter().enumerate() {
            columns.insert((Role::Cv, t.clone()), layout.cv_at() + i);
        }
        if layout.pred > 0 {
            for (i, t) in cfg.pred.iter().enumerate() {
                columns.insert((Role::Pred, t.clone()), layout.pred_at() + i);
            }
        }
        let residuals = match cfg.residual {
            ResidualSource::Pred => Residuals::from_pred(layout),
            ResidualSource::Model => Residuals::from_model(layout, cfg.nominal_model()?, cfg.window),
        };
        let aligner = Aligner::new(cfg.period, cfg.window, cfg.grace, cfg.tolerance, residuals.required());
        Ok(Self {
            columns,
            aligner,
            residuals,
            window: Window::new(cfg.window),
            debounce: BTreeMap::new(),
            latest: None,
            history: VecDeque::new(),
            trend: BTreeMap::new(),
            unsaved: VecDeque::new(),
            ingested: 0,
            dropped: HashMap::new(),
            running: false,
            gap_rows: 0,
            time_jumps: 0,
            backfilled_rows: 0,
            overflow_rows: 0,
            clock: std::time::Instant::now(),
            store_reset: false,
            cfg,
        })
    }

    /// Decodes and aligns one message on `<role>/<tag>`, and counts what it did.
    pub fn ingest(&mut self, role: Role, tag: &str, bytes: &[u8]) -> IngestOutcome {
        let now = self.clock.elapsed().as_secs_f64();
        self.ingest_at(role, tag, bytes, now)
    }

    /// [`Controller::ingest`] at wall-clock `now` (seconds since the controller started).
    pub fn ingest_at(&mut self, role: Role, tag: &str, bytes: &[u8], now: f64) -> IngestOutcome {
        let out = self.ingest_uncounted(role, tag, bytes, now);
        self.count(&out);
        out
    }

    /// Closes the rows whose grace has expired (called before each analysis, so a tag that went
    /// silent holds rows for at most its grace even when nothing else arrives).
    pub fn tick(&mut self) -> IngestOutcome {
        let now = self.clock.elapsed().as_secs_f64();
        self.tick_at(now)
    }

    /// [`Controller::tick`] at wall-clock `now`.
    pub fn tick_at(&mut self, now: f64) -> IngestOutcome {
        let mut out = IngestOutcome::default();
        let mut closed = Vec::new();
        self.aligner.tick(now, &mut closed);
        self.take_rows(closed, &mut out);
        self.count(&out);
        out
    }

    fn count(&mut self, out: &IngestOutcome) {
        self.ingested += out.accepted;
        self.gap_rows += out.gap_rows;
        self.backfilled_rows += out.backfilled_rows;
        self.overflow_rows += out.overflow_rows;
        for (r, n) in &out.dropped {
            *self.dropped.entry(*r).or_default() += n;
        }
    }

    /// Counts drops decided outside [`Controller::ingest`] (a key of the wrong shape).
    pub fn count_drop(&mut self, reason: DropReason, n: u64) {
        *self.dropped.entry(reason).or_default() += n;
    }

    fn ingest_uncounted(&mut self, role: Role, tag: &str, bytes: &[u8], now: f64) -> IngestOutcome {
        let mut out = IngestOutcome::default();
        let samples = match payload::decode(bytes) {
            Ok(s) => s,
            Err(e) => {
                out.drop(DropReason::BadPayload, 1);
                out.problem = Some(e.to_string());
                return out;
            }
        };
        let Some(&col) = self.columns.get(&(role, tag.to_string())) else {
            out.drop(DropReason::UnknownTag, samples.len() as u64);
            out.problem = Some(format!("tag {}/{tag} is not configured", role.as_str()));
            return out;
        };
        let mut closed: Vec<ClosedRow> = Vec::new();
        let latest_ok = chrono::Utc::now().timestamp() as f64 + FUTURE_SLACK;
        for s in samples {
            let res = if s.t > latest_ok {
                Err(DropReason::Future)
            } else {
                self.aligner.offer(col, s.t, s.v, now, &mut closed)
            };
            match res {
                Ok(()) => out.accepted += 1,
                Err(r) => {
                    out.drop(r, 1);
                    if out.problem.is_none() {
                        out.problem = Some(format!("{}/{tag} at t = {}: {}", role.as_str(), s.t, r.as_str()));
                    }
                }
            }
            // Rows of the old timeline are done before a jump resets what depends on it.
            self.take_rows(std::mem::take(&mut closed), &mut out);
            for jump in self.aligner.take_jumps() {
                out.time_jumps += 1;
                self.on_jump(jump);
            }
        }
        out
    }

    /// Moves closed rows into the window. A back-filled row takes its slot's place; from a
    /// model, the window's residuals are then recomputed in slot order and all rewritten.
    fn take_rows(&mut self, closed: Vec<ClosedRow>, out: &mut IngestOutcome) {
        let mut backfilled = false;
        for row in closed {
            if row.backfill {
                if let Some(w) = self.residuals.backfilled(&row)
                    && self.window.insert(w.clone())
                {
                    out.backfilled_rows += 1;
                    backfilled = true;
                    self.queue_unsaved(w);
                }
                continue;
            }
            if let Some(w) = self.residuals.process(&row) {
                if let Some(last) = self.window.last_slot()
                    && w.slot > last + 1
                {
                    out.gap_rows += (w.slot - last - 1) as u64;
                }
                self.push_row(w);
            }
        }
        if backfilled && self.residuals.uses_model() {
            self.residuals.recompute(self.window.rows_mut());
            self.unsaved = self.window.rows().cloned().collect();
        }
        out.overflow_rows += self.aligner.take_overflow();
    }

    /// A confirmed jump of the source clock. Forward it is a gap and needs nothing; back, the
    /// window's rows and the stored ones lie in the new timeline's future and are dropped.
    fn on_jump(&mut self, jump: Jump) {
        self.time_jumps += 1;
        tracing::warn!(
            controller = %self.cfg.id,
            from_s = jump.from as f64 * self.cfg.period,
            to_s = jump.to as f64 * self.cfg.period,
            "the source clock jumped {}; continuing on the new timeline",
            if jump.is_backward() { "back: the window restarts" } else { "forward: a gap" }
        );
        if jump.is_backward() {
            self.window.clear();
            self.unsaved.clear();
            self.residuals.reset();
            self.store_reset = true;
        }
    }

    fn push_row(&mut self, w: WindowRow) {
        if self.window.push(w.clone()) {
            self.queue_unsaved(w);
        }
    }

    fn queue_unsaved(&mut self, w: WindowRow) {
        if self.unsaved.len() == self.cfg.window {
            self.unsaved.pop_front();
        }
        self.unsaved.push_back(w);
    }

    /// Puts rows whose write failed back in front of the unsaved queue, keeping at most a
    /// window's worth (older rows have left the window and need no saving).
    pub fn requeue_unsaved(&mut self, rows: Vec<WindowRow>) {
        for r in rows.into_iter().rev() {
            if self.unsaved.len() >= self.cfg.window {
                break;
            }
            self.unsaved.push_front(r);
        }
    }

    /// Restores window rows (oldest first) and the channels whose alarm was active.
    pub fn restore(&mut self, rows: Vec<WindowRow>, active: &[(String, String)], history: Vec<AlarmEvent>) {
        self.residuals.replay(&rows);
        let slots: Vec<i64> = rows.iter().map(|r| r.slot).collect();
        for r in rows {
            self.window.push(r);
        }
        self.aligner.resume_after(&slots);
        for (dither, cv) in active {
            if let (Some(i), Some(j)) =
                (self.cfg.dither.iter().position(|d| d == dither), self.cfg.cv.iter().position(|c| c == cv))
            {
                self.debounce.insert((i, j), Debounce::active());
            }
        }
        self.history = history.into();
    }

    /// Feeds a run's verdicts to the debounce; returns the alarm events it caused. Runs that did
    /// not analyse (insufficient data, errors) change nothing.
    pub fn apply(&mut self, report: &RunReport) -> Vec<AlarmEvent> {
        if report.status != RunStatus::Ok {
            return Vec::new();
        }
        for (key, point) in super::analysis::trend_points(report) {
            let t = self.trend.entry(key).or_default();
            if t.len() == TREND {
                t.pop_front();
            }
            t.push_back(point);
        }
        let mut events = Vec::new();
        for ch in &report.channels {
            let d = self.debounce.entry((ch.mv_index, ch.cv_index)).or_default();
            if let Some(t) = d.update(ch.significant, self.cfg.raise_after, self.cfg.clear_after) {
                events.push(AlarmEvent {
                    controller: self.cfg.id.clone(),
                    event: t,
                    channel: format!("{}→{}", ch.dither, ch.cv),
                    mv: ch.mv.clone(),
                    dither: ch.dither.clone(),
                    cv: ch.cv.clone(),
                    statistic: ch.statistic.clone(),
                    value_bits: ch.statistic_bits,
                    critical_bits: ch.statistic_critical_bits,
                    p_value: Some(ch.p_value),
                    verdict: ch.verdict.clone(),
                    time: report.time.clone(),
                    data_time: report.last_time.unwrap_or(f64::NAN),
                });
            }
        }
        for e in &events {
            if self.history.len() == HISTORY {
                self.history.pop_front();
            }
            self.history.push_back(e.clone());
        }
        events
    }

    /// Whether the alarm of channel (mv index, cv index) is active.
    pub fn alarm_active(&self, mv: usize, cv: usize) -> bool {
        self.debounce.get(&(mv, cv)).is_some_and(|d| d.active)
    }

    /// Channels whose alarm is active, as (dither, cv) tags.
    pub fn active_alarms(&self) -> Vec<(String, String)> {
        self.debounce
            .iter()
            .filter(|(_, d)| d.active)
            .map(|(&(i, j), _)| (self.cfg.dither[i].clone(), self.cfg.cv[j].clone()))
            .collect()
    }

    /// Rows waiting in the aligner.
    pub fn pending(&self) -> usize {
        self.aligner.pending()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::config::Config;

    fn controller() -> Controller {
        let cfg = Config::parse(
            r#"
[[controller]]
id = "c1"
period = 1.0
mv = ["u1"]
dither = ["ud1"]
cv = ["y1"]
pred = ["p1"]
window = 64
min_samples = 32
lag_max = 3
tolerance = 2
"#,
            "t",
        )
        .unwrap();
        Controller::new(cfg.controllers[0].clone()).unwrap()
    }

    #[test]
    fn complete_rows_reach_the_window_and_bad_input_is_counted() {
        let mut c = controller();
        for k in 0..10 {
            let t = k as f64;
            c.ingest(Role::Dither, "ud1", payload::encode(t, 1.0).as_bytes());
            c.ingest(Role::Cv, "y1", payload::encode(t, 3.0).as_bytes());
            c.ingest(Role::Pred, "p1", payload::encode(t, 1.0).as_bytes());
        }
        // no MVs published: rows close on the tolerance (2), so the last two still wait
        assert_eq!(c.window.len(), 8);
        assert_eq!(c.window.rows().next().unwrap().residual, vec![2.0]);
        assert!(c.window.rows().next().unwrap().mv[0].is_nan(), "MVs are optional with predictions");
        let o = c.ingest(Role::Cv, "nope", payload::encode(11.0, 1.0).as_bytes());
        assert_eq!(o.dropped, vec![(DropReason::UnknownTag, 1)]);
        let o = c.ingest(Role::Cv, "y1", b"{");
        assert_eq!(o.dropped, vec![(DropReason::BadPayload, 1)]);
        let o = c.ingest(Role::Cv, "y1", br#"{"t": [20, 21, 3], "v": [1, "NaN", 2]}"#);
        assert_eq!(o.accepted, 1);
        assert_eq!(
            o.dropped,
            vec![(DropReason::NonFinite, 1), (DropReason::Duplicate, 1)],
            "slot 3 holds y1 already"
        );
        assert_eq!(c.ingested, 31);
        let o = c.ingest(Role::Cv, "y1", br#"{"t": "2999-01-01T00:00:00Z", "v": 1}"#);
        assert_eq!(o.dropped, vec![(DropReason::Future, 1)]);
        let o = c.ingest(Role::Cv, "y1", payload::encode(22.0, 1.0).as_bytes());
        assert_eq!(o.accepted, 1, "a bogus future time does not disturb what follows");
        assert_eq!(c.dropped[&DropReason::UnknownTag], 1);
        assert_eq!(c.dropped[&DropReason::BadPayload], 1);
    }

    /// A SISO controller whose residuals come from the model `0.5 q⁻¹ / (1 − 0.7 q⁻¹)`.
    fn model_controller(window: usize, extra: &str) -> ControllerConfig {
        let text = format!(
            "[[controller]]\nid = \"m1\"\nperiod = 1.0\nmv = [\"u1\"]\ndither = [\"ud1\"]\ncv = [\"y1\"]\n\
             residual = \"model\"\nwindow = {window}\nmin_samples = 32\nlag_max = 3\n{extra}\n\
             [[controller.model]]\nmv = \"u1\"\ncv = \"y1\"\nb = [0.0, 0.5]\na = [1.0, -0.7]\n"
        );
        Config::parse(&text, "t").unwrap().controllers[0].clone()
    }

    #[test]
    fn per_tag_batches_and_a_back_fill_give_the_rows_of_an_in_order_feed() {
        let cfg = model_controller(128, "grace = 30.0");
        let u = |k: usize| ((k * 7) % 5) as f64;
        let d = |k: usize| if (k * 13) % 7 < 3 { 1.0 } else { -1.0 };
        let y = |k: usize| (k as f64 * 0.3).sin();
        let batch = |f: &dyn Fn(usize) -> f64, ks: std::ops::Range<usize>| {
            let t: Vec<f64> = ks.clone().map(|k| k as f64).collect();
            let v: Vec<f64> = ks.map(f).collect();
            serde_json::json!({ "t": t, "v": v }).to_string()
        };
        let mut in_order = Controller::new(cfg.clone()).unwrap();
        for k in 0..100 {
            in_order.ingest_at(Role::Mv, "u1", payload::encode(k as f64, u(k)).as_bytes(), 0.0);
            in_order.ingest_at(Role::Dither, "ud1", payload::encode(k as f64, d(k)).as_bytes(), 0.0);
            in_order.ingest_at(Role::Cv, "y1", payload::encode(k as f64, y(k)).as_bytes(), 0.0);
        }
        // Per-tag batches of 50, CV first; then the CV falls silent for 20 samples past the
        // grace, and back-fills them after the other tags have moved on.
        let mut batched = Controller::new(cfg).unwrap();
        let mut accepted = 0;
        for ks in [0..50, 50..100] {
            let cv_ks = if ks.start == 50 { 50..60 } else { ks.clone() };
            accepted += batched.ingest_at(Role::Cv, "y1", batch(&y, cv_ks).as_bytes(), 0.0).accepted;
            accepted +=
                batched.ingest_at(Role::Dither, "ud1", batch(&d, ks.clone()).as_bytes(), 0.0).accepted;
            accepted += batched.ingest_at(Role::Mv, "u1", batch(&u, ks).as_bytes(), 0.0).accepted;
        }
        batched.tick_at(31.0);
        assert_eq!(batched.window.len(), 60, "rows 60..100 closed as gaps after the grace");
        let fill = batched.ingest_at(Role::Cv, "y1", batch(&y, 60..100).as_bytes(), 40.0);
        accepted += fill.accepted;
        assert_eq!(fill.backfilled_rows, 40);
        assert_eq!(accepted, 300, "every sample is ingested");
        assert!(batched.dropped.values().all(|&n| n == 0), "{:?}", batched.dropped);
        let rows = |c: &Controller| c.window.rows().map(|r| (r.slot, r.residual[0])).collect::<Vec<_>>();
        let (a, b) = (rows(&in_order), rows(&batched));
        assert_eq!(a.len(), 100);
        assert_eq!(a.iter().map(|r| r.0).collect::<Vec<_>>(), b.iter().map(|r| r.0).collect::<Vec<_>>());
        assert!(a.iter().zip(&b).all(|(p, q)| (p.1 - q.1).abs() < 1e-12), "residuals after recompute");
    }

    #[test]
    fn a_restored_model_controller_continues_with_the_same_residuals() {
        let cfg = model_controller(64, "");
        let mut a = Controller::new(cfg.clone()).unwrap();
        let feed = |c: &mut Controller, k: usize| {
            let t = k as f64;
            let u = ((k * 7) % 5) as f64;
            c.ingest(Role::Mv, "u1", payload::encode(t, u).as_bytes());
            c.ingest(Role::Dither, "ud1", payload::encode(t, 1.0).as_bytes());
            c.ingest(Role::Cv, "y1", payload::encode(t, t.sin()).as_bytes());
        };
        for k in 0..40 {
            feed(&mut a, k);
        }
        let mut b = Controller::new(cfg).unwrap();
        b.restore(a.window.rows().cloned().collect(), &[("ud1".into(), "y1".into())], Vec::new());
        assert_eq!(b.window.len(), 40);
        assert!(b.alarm_active(0, 0));
        let again = b.ingest(Role::Cv, "y1", payload::encode(10.0, 0.0).as_bytes());
        assert_eq!(again.dropped, vec![(DropReason::OutOfOrder, 1)], "a restored row is closed and complete");
        for k in 40..45 {
            feed(&mut a, k);
            feed(&mut b, k);
        }
        let ra: Vec<f64> = a.window.rows().map(|r| r.residual[0]).collect();
        let rb: Vec<f64> = b.window.rows().map(|r| r.residual[0]).collect();
        assert_eq!(ra, rb);
        assert_eq!(b.window.len(), 45);
    }
}
