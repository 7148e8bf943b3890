//! Periodic work: each controller's analysis on its schedule (in the blocking pool, one run at a
//! time per controller, a tick that finds a run in flight is skipped), the publication of its
//! results and alarms, and the store flush.

use std::sync::Arc;
use std::time::{Duration, Instant};

use tokio::sync::watch;
use tokio::task::JoinHandle;
use tokio::time::MissedTickBehavior;

use super::alarm::AlarmEvent;
use super::analysis::{self, RunReport, RunStatus};
use super::metrics::{ChannelLabels, ControllerLabels, RunLabels, StoreLabels, VerdictLabels};
use super::{Shared, now_rfc3339};

/// One analysis at a time per process. Each run already uses every core (rayon), so running
/// several at once only makes all of them finish late together (measured: 50 concurrent 3×3
/// runs each took 90–120 s instead of a few seconds); one at a time, the runs that fit in the
/// period finish on time and an overloaded instance shows it in `mpm_runs_late_total`.
static ANALYSIS_SLOT: tokio::sync::Semaphore = tokio::sync::Semaphore::const_new(1);

/// Runs controller `id`'s analyses every `every` seconds until `stop`.
///
/// The schedule is a fixed grid `start + phase + k·every`. `phase` spreads the controllers of
/// one instance over the period (controller `i` of `n` starts `i/n` of a period later), so their
/// analyses do not all compete for the cores at the same instant. A run that overruns the next
/// instant is counted in `mpm_runs_late_total`, and the instants it overran are skipped (counted
/// in `mpm_runs_missed_total`), so a slow instance shows in its metrics instead of drifting.
pub fn spawn(shared: Arc<Shared>, id: String, mut stop: watch::Receiver<bool>) -> JoinHandle<()> {
    tokio::spawn(async move {
        let every = Duration::from_secs_f64(shared.lock(&id).map_or(10.0, |c| c.cfg.every));
        let n = shared.controllers.len().max(1);
        let i = shared.controllers.keys().position(|k| k == &id).unwrap_or(0);
        let phase = every.mul_f64(i as f64 / n as f64);
        let labels = ControllerLabels { controller: id.clone() };
        let m = &shared.metrics;
        // The first run comes one period after the start: let data arrive first.
        let mut due = Instant::now() + every + phase;
        loop {
            tokio::select! {
                _ = tokio::time::sleep_until(due.into()) => {}
                _ = stop.changed() => break,
            }
            let slot = tokio::select! {
                p = ANALYSIS_SLOT.acquire() => p.ok(),
                _ = stop.changed() => break,
            };
            // Lateness includes the wait for the analysis slot.
            m.run_lateness.get_or_create(&labels).set(due.elapsed().as_secs_f64());
            run_once(&shared, &id).await;
            drop(slot);
            let (next, missed) = next_due(due, every, Instant::now());
            if missed > 0 {
                m.runs_late.get_or_create(&labels).inc();
                m.runs_missed.get_or_create(&labels).inc_by(missed);
                tracing::warn!(controller = %id, missed, "analysis overran its period");
            }
            due = next;
        }
    })
}

/// The next instant of the grid `due + k·every` (k ≥ 1) that is not yet past at `now`, and how
/// many instants were skipped to reach it.
fn next_due(due: Instant, every: Duration, now: Instant) -> (Instant, u64) {
    let mut next = due + every;
    let mut missed = 0;
    if now > next && !every.is_zero() {
        missed = ((now - next).as_secs_f64() / every.as_secs_f64()).ceil() as u64;
        next += every.mul_f64(missed as f64);
        if next < now {
            next += every;
            missed += 1;
        }
    }
    (next, missed)
}

/// One analysis of controller `id`, with everything that follows it. Returns the report, or
/// `None` when a run was already in flight.
pub async fn run_once(shared: &Arc<Shared>, id: &str) -> Option<Arc<RunReport>> {
    let (cfg, snap) = {
        let mut ctl = shared.lock(id)?;
        if ctl.running {
            return None;
        }
        ctl.running = true;
        let ticked = ctl.tick();
        let (fill, contiguous) = (ctl.window.fill(), ctl.window.contiguous_tail());
        super::ingest::record(shared, id, &ticked, fill, contiguous);
        (ctl.cfg.clone(), ctl.window.snapshot(ctl.cfg.min_samples, super::analysis::min_segment(&ctl.cfg)))
    };
    let time = now_rfc3339();
    let report = match snap {
        Err(why) => RunReport::insufficient(&cfg, why, time),
        Ok(snap) => {
            let started = Instant::now();
            let c = cfg.clone();
            let t = time.clone();
            let joined = tokio::task::spawn_blocking(move || analysis::run(&c, &snap, t)).await;
            let mut r = joined.unwrap_or_else(|e| {
                let mut r =
                    RunReport::insufficient(&cfg, super::window::Insufficient { usable: 0, needed: 0 }, time);
                r.status = RunStatus::Error;
                r.message = Some(format!("analysis failed: {e}"));
                r
            });
            r.duration_s = started.elapsed().as_secs_f64();
            r
        }
    };
    let report = Arc::new(report);
    let (events, active) = {
        let mut ctl = shared.lock(id)?;
        ctl.running = false;
        ctl.latest = Some(report.clone());
        let events = ctl.apply(&report);
        let active: Vec<(usize, usize, bool)> = report
            .channels
            .iter()
            .map(|ch| (ch.mv_index, ch.cv_index, ctl.alarm_active(ch.mv_index, ch.cv_index)))
            .collect();
        (events, active)
    };
    record_metrics(shared, &report, &active);
    tracing::info!(
        controller = id,
        status = report.status.as_str(),
        n = report.n,
        duration_s = report.duration_s,
        mismatch = report.mismatch,
        "analysis"
    );
    publish(shared, id, &report, &events).await;
    Some(report)
}

fn record_metrics(shared: &Shared, r: &RunReport, active: &[(usize, usize, bool)]) {
    let m = &shared.metrics;
    let c = ControllerLabels { controller: r.controller.clone() };
    m.runs
        .get_or_create(&RunLabels { controller: r.controller.clone(), status: r.status.as_str().into() })
        .inc();
    m.run_duration.get_or_create(&c).set(r.duration_s);
    m.run_time.get_or_create(&c).set(chrono::Utc::now().timestamp_millis() as f64 / 1000.0);
    m.active_alarms.get_or_create(&c).set(active.iter().filter(|a| a.2).count() as i64);
    for (ch, a) in r.channels.iter().zip(active) {
        let l = ChannelLabels {
            controller: r.controller.clone(),
            mv: ch.mv.clone(),
            dither: ch.dither.clone(),
            cv: ch.cv.clone(),
        };
        m.norm_mi.get_or_create(&l).set(ch.norm_bits);
        m.critical.get_or_create(&l).set(ch.critical_bits);
        m.significant.get_or_create(&l).set(i64::from(ch.significant));
        m.alarm.get_or_create(&l).set(i64::from(a.2));
        for v in ["mismatch", "clean", "implicated_by_feedback"] {
            let vl = VerdictLabels {
                controller: r.controller.clone(),
                mv: ch.mv.clone(),
                cv: ch.cv.clone(),
                verdict: v.into(),
            };
            m.verdict.get_or_create(&vl).set(i64::from(ch.verdict == v));
        }
    }
}

async fn publish(shared: &Arc<Shared>, id: &str, report: &RunReport, events: &[AlarmEvent]) {
    let key = shared.key(id, "matrix");
    if let Err(e) = shared.session.put(&key, serde_json::to_string(report).unwrap_or_default()).await {
        tracing::warn!(%key, "publish failed: {e}");
    }
    let akey = shared.key(id, "alarm");
    for e in events {
        tracing::warn!(controller = id, channel = %e.channel, event = e.event.as_str(), verdict = %e.verdict, "alarm");
        if let Err(err) = shared.session.put(&akey, serde_json::to_string(e).unwrap_or_default()).await {
            tracing::warn!(key = %akey, "publish failed: {err}");
        }
    }
    if let Some(store) = shared.store.clone()
        && !events.is_empty()
    {
        let events = events.to_vec();
        let res =
            tokio::task::spawn_blocking(move || events.iter().try_for_each(|e| store.append_alarm(e))).await;
        match res {
            Ok(Ok(())) => store_ok(shared),
            Ok(Err(e)) => store_failed(shared, "alarm", format!("alarm history not stored: {e}")),
            Err(e) => store_failed(shared, "alarm", format!("alarm store task failed: {e}")),
        }
    }
}

/// Records a successful store write (health and metric).
fn store_ok(shared: &Shared) {
    shared.store_health.record_ok(now_rfc3339());
    shared.metrics.store_ok.set(1);
}

/// Records a failed store write: logged, counted, and shown by `/healthz` until a write succeeds.
fn store_failed(shared: &Shared, op: &str, message: String) {
    if !shared.store_health.failing() {
        tracing::error!(op, "store write failed, continuing without persistence: {message}");
    } else {
        tracing::debug!(op, "store write failed again: {message}");
    }
    shared.store_health.record_error(message, now_rfc3339());
    shared.metrics.store_errors.get_or_create(&StoreLabels { op: op.into() }).inc();
    shared.metrics.store_ok.set(0);
}

/// Writes every controller's unsaved rows every `flush_interval_ms`.
pub fn spawn_flush(shared: Arc<Shared>, mut stop: watch::Receiver<bool>) -> JoinHandle<()> {
    tokio::spawn(async move {
        let mut tick = tokio::time::interval(Duration::from_millis(shared.config.store.flush_interval_ms));
        tick.set_missed_tick_behavior(MissedTickBehavior::Delay);
        loop {
            tokio::select! {
                _ = tick.tick() => {}
                _ = stop.changed() => break,
            }
            flush(&shared).await;
        }
    })
}

/// Writes the unsaved rows of every controller and trims rows that left the window. Rows of a
/// failed write go back to the unsaved queue (still bounded by the window length), so a store
/// that recovers, e.g. once disk space is freed, catches up.
pub async fn flush(shared: &Arc<Shared>) {
    let Some(store) = shared.store.clone() else { return };
    for id in shared.controllers.keys() {
        let (rows, keep_from, replace) = {
            let Some(mut ctl) = shared.lock(id) else { continue };
            if ctl.unsaved.is_empty() && !ctl.store_reset {
                continue;
            }
            let rows: Vec<_> = ctl.unsaved.drain(..).collect();
            let keep = ctl.window.rows().next().map(|r| r.slot);
            (rows, keep, std::mem::take(&mut ctl.store_reset))
        };
        let (s, id2) = (store.clone(), id.clone());
        let rows = Arc::new(rows);
        let r2 = rows.clone();
        let res = tokio::task::spawn_blocking(move || s.save_rows(&id2, &r2, keep_from, replace)).await;
        let failure = match res {
            Ok(Ok(())) => None,
            Ok(Err(e)) => Some(format!("flush of {id} failed: {e}")),
            Err(e) => Some(format!("flush task of {id} failed: {e}")),
        };
        match failure {
            None => store_ok(shared),
            Some(message) => {
                store_failed(shared, "flush", message);
                if let Some(mut ctl) = shared.lock(id) {
                    ctl.requeue_unsaved(Arc::try_unwrap(rows).unwrap_or_else(|a| (*a).clone()));
                    ctl.store_reset |= replace;
                }
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn overrun_instants_are_skipped_and_counted() {
        let t0 = Instant::now();
        let s = Duration::from_secs(10);
        assert_eq!(next_due(t0, s, t0 + Duration::from_secs(3)), (t0 + s, 0));
        assert_eq!(next_due(t0, s, t0 + Duration::from_secs(10)), (t0 + s, 0));
        assert_eq!(next_due(t0, s, t0 + Duration::from_secs(11)), (t0 + 2 * s, 1));
        assert_eq!(next_due(t0, s, t0 + Duration::from_secs(35)), (t0 + 4 * s, 3));
    }
}
