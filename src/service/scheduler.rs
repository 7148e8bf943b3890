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

/// Runs controller `id`'s analyses every `every` seconds until `stop`.
pub fn spawn(shared: Arc<Shared>, id: String, mut stop: watch::Receiver<bool>) -> JoinHandle<()> {
    tokio::spawn(async move {
        let every = shared.lock(&id).map_or(10.0, |c| c.cfg.every);
        let mut tick = tokio::time::interval(Duration::from_secs_f64(every));
        tick.set_missed_tick_behavior(MissedTickBehavior::Delay);
        tick.tick().await; // the first tick fires at once: let data arrive first
        loop {
            tokio::select! {
                _ = tick.tick() => {}
                _ = stop.changed() => break,
            }
            run_once(&shared, &id).await;
        }
    })
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
        (ctl.cfg.clone(), ctl.window.snapshot(ctl.cfg.min_samples))
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
                let mut r = RunReport::insufficient(
                    &cfg,
                    super::window::Insufficient { contiguous: 0, needed: 0 },
                    time,
                );
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
