//! The zenoh side of a controller: the subscription on `<prefix>/<id>/*/*` feeding its state
//! through a bounded queue (overload drops and counts messages, it never grows memory), and the
//! queryable on `<prefix>/<id>/matrix` answering `get` with the latest report. Thin:
//! decoding and alignment live in [`super::controller`].

use std::sync::Arc;
use std::sync::atomic::{AtomicU64, AtomicUsize, Ordering};

use tokio::sync::{mpsc, watch};
use tokio::task::JoinHandle;
use zenoh::sample::Sample;

use super::align::DropReason;
use super::metrics::{ControllerLabels, DropLabels};
use super::payload::parse_key;
use super::{ServiceError, Shared};

/// The bounded queue between zenoh's receive thread and a controller's ingest task: at most
/// `ingest.queue_messages` messages and `ingest.queue_bytes` payload bytes wait. The zenoh
/// callback only enqueues (never blocks, never decodes); what does not fit is dropped and
/// counted as `queue_full`, once per message.
struct Queue {
    bytes: AtomicUsize,
    max_bytes: usize,
    /// `queue_full` drops not yet added to the controller's own counters (the callback does not
    /// take the controller's lock; the ingest task folds them in).
    unfolded: AtomicU64,
}

impl Queue {
    /// Reserves room for `n` bytes; false when the byte budget is spent.
    fn reserve(&self, n: usize) -> bool {
        self.bytes
            .fetch_update(Ordering::AcqRel, Ordering::Acquire, |b| (b + n <= self.max_bytes).then_some(b + n))
            .is_ok()
    }

    fn release(&self, n: usize) {
        self.bytes.fetch_sub(n, Ordering::AcqRel);
    }
}

/// Subscribes to the controller's inputs through its bounded queue, and spawns the task that
/// drains it.
pub async fn spawn_subscriber(
    shared: Arc<Shared>,
    id: String,
    mut stop: watch::Receiver<bool>,
) -> Result<JoinHandle<()>, ServiceError> {
    let key = shared.key(&id, "*/*");
    let cfg = &shared.config.ingest;
    let (tx, mut rx) = mpsc::channel::<(Sample, usize)>(cfg.queue_messages);
    let queue = Arc::new(Queue {
        bytes: AtomicUsize::new(0),
        max_bytes: cfg.queue_bytes,
        unfolded: AtomicU64::new(0),
    });
    let labels = ControllerLabels { controller: id.clone() };
    let full = shared
        .metrics
        .dropped
        .get_or_create(&DropLabels { controller: id.clone(), reason: DropReason::QueueFull.as_str().into() })
        .clone();
    let (q, full_log) = (queue.clone(), id.clone());
    let sub = shared
        .session
        .declare_subscriber(&key)
        .callback(move |sample: Sample| {
            let n = sample.payload().len();
            let queued = q.reserve(n)
                && match tx.try_send((sample, n)) {
                    Ok(()) => true,
                    Err(_) => {
                        q.release(n);
                        false
                    }
                };
            if !queued {
                full.inc();
                if q.unfolded.fetch_add(1, Ordering::AcqRel) == 0 {
                    tracing::debug!(controller = %full_log, "ingest queue full: dropping messages");
                }
            }
        })
        .await
        .map_err(|e| ServiceError::Zenoh(format!("subscribe {key}: {e}")))?;
    tracing::info!(%key, "subscribed");
    Ok(tokio::spawn(async move {
        // Dropping the subscriber undeclares it: it lives as long as this task.
        let _sub = sub;
        let m = &shared.metrics;
        loop {
            let (sample, n) = tokio::select! {
                s = rx.recv() => match s { Some(s) => s, None => break },
                _ = stop.changed() => break,
            };
            queue.release(n);
            let bytes = sample.payload().to_bytes();
            on_message(&shared, &id, sample.key_expr().as_str(), &bytes);
            fold(&shared, &id, &queue);
            m.queue_messages.get_or_create(&labels).set(rx.len() as i64);
            m.queue_bytes.get_or_create(&labels).set(queue.bytes.load(Ordering::Acquire) as i64);
        }
    }))
}

/// Adds the callback's `queue_full` drops to the controller's counters (the HTTP API's). A drop
/// only happens while the queue holds messages, so a fold after each message misses none.
fn fold(shared: &Shared, id: &str, queue: &Queue) {
    let n = queue.unfolded.swap(0, Ordering::AcqRel);
    if n > 0
        && let Some(mut ctl) = shared.lock(id)
    {
        ctl.count_drop(DropReason::QueueFull, n);
    }
}

/// Handles one message on `key` (public for tests that bypass zenoh).
pub fn on_message(shared: &Shared, id: &str, key: &str, bytes: &[u8]) {
    let Some(mut ctl) = shared.lock(id) else { return };
    let outcome = match parse_key(&shared.config.prefix, key) {
        Some(k) if k.controller == id => ctl.ingest(k.role, k.tag, bytes),
        _ => {
            let mut o = super::controller::IngestOutcome::default();
            o.dropped.push((super::align::DropReason::UnknownTag, 1));
            o.problem = Some(format!("key {key} is not <prefix>/{id}/<mv|dither|cv|pred>/<tag>"));
            ctl.count_drop(super::align::DropReason::UnknownTag, 1);
            o
        }
    };
    let fill = ctl.window.fill();
    let contiguous = ctl.window.contiguous_tail();
    drop(ctl);
    record(shared, id, &outcome, fill, contiguous);
    if let Some(p) = outcome.problem {
        tracing::debug!(controller = id, key, "dropped: {p}");
    }
}

/// Adds what an ingest (or a grace tick) did to the metrics.
pub fn record(
    shared: &Shared,
    id: &str,
    outcome: &super::controller::IngestOutcome,
    fill: f64,
    contiguous: usize,
) {
    let labels = ControllerLabels { controller: id.to_string() };
    let m = &shared.metrics;
    m.ingested.get_or_create(&labels).inc_by(outcome.accepted);
    m.gap_rows.get_or_create(&labels).inc_by(outcome.gap_rows);
    m.time_jumps.get_or_create(&labels).inc_by(outcome.time_jumps);
    m.backfilled_rows.get_or_create(&labels).inc_by(outcome.backfilled_rows);
    m.overflow_rows.get_or_create(&labels).inc_by(outcome.overflow_rows);
    for (r, n) in &outcome.dropped {
        m.dropped
            .get_or_create(&DropLabels { controller: id.to_string(), reason: r.as_str().into() })
            .inc_by(*n);
    }
    m.window_fill.get_or_create(&labels).set(fill);
    m.window_contiguous.get_or_create(&labels).set(contiguous as i64);
}

/// Answers `get` on `<prefix>/<id>/matrix` with the latest report (or an error reply before the
/// first run).
pub async fn spawn_queryable(
    shared: Arc<Shared>,
    id: String,
    mut stop: watch::Receiver<bool>,
) -> Result<JoinHandle<()>, ServiceError> {
    let key = shared.key(&id, "matrix");
    let q = shared
        .session
        .declare_queryable(&key)
        .await
        .map_err(|e| ServiceError::Zenoh(format!("queryable {key}: {e}")))?;
    Ok(tokio::spawn(async move {
        loop {
            let query = tokio::select! {
                s = q.recv_async() => match s { Ok(s) => s, Err(_) => break },
                _ = stop.changed() => break,
            };
            let latest = shared.lock(&id).and_then(|c| c.latest.clone());
            let res = match latest {
                Some(r) => query.reply(&key, serde_json::to_string(&*r).unwrap_or_default()).await,
                None => query.reply_err(format!("{{\"error\":\"no analysis of {id} has run yet\"}}")).await,
            };
            if let Err(e) = res {
                tracing::warn!(%key, "query reply failed: {e}");
            }
        }
    }))
}
