//! The zenoh side of a controller: the subscription on `<prefix>/<id>/*/*` feeding its state,
//! and the queryable on `<prefix>/<id>/matrix` answering `get` with the latest report. Thin:
//! decoding and alignment live in [`super::controller`].

use std::sync::Arc;

use tokio::sync::watch;
use tokio::task::JoinHandle;

use super::metrics::{ControllerLabels, DropLabels};
use super::payload::parse_key;
use super::{ServiceError, Shared};

/// Subscribes to the controller's inputs.
pub async fn spawn_subscriber(
    shared: Arc<Shared>,
    id: String,
    mut stop: watch::Receiver<bool>,
) -> Result<JoinHandle<()>, ServiceError> {
    let key = shared.key(&id, "*/*");
    let sub = shared
        .session
        .declare_subscriber(&key)
        .await
        .map_err(|e| ServiceError::Zenoh(format!("subscribe {key}: {e}")))?;
    tracing::info!(%key, "subscribed");
    Ok(tokio::spawn(async move {
        loop {
            let sample = tokio::select! {
                s = sub.recv_async() => match s { Ok(s) => s, Err(_) => break },
                _ = stop.changed() => break,
            };
            let bytes = sample.payload().to_bytes();
            on_message(&shared, &id, sample.key_expr().as_str(), &bytes);
        }
    }))
}

/// Handles one message on `key` (public for tests that bypass zenoh).
pub fn on_message(shared: &Shared, id: &str, key: &str, bytes: &[u8]) {
    let labels = ControllerLabels { controller: id.to_string() };
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
    let m = &shared.metrics;
    m.ingested.get_or_create(&labels).inc_by(outcome.accepted);
    m.gap_rows.get_or_create(&labels).inc_by(outcome.gap_rows);
    m.time_jumps.get_or_create(&labels).inc_by(outcome.time_jumps);
    for (r, n) in &outcome.dropped {
        m.dropped
            .get_or_create(&DropLabels { controller: id.to_string(), reason: r.as_str().into() })
            .inc_by(*n);
    }
    m.window_fill.get_or_create(&labels).set(fill);
    m.window_contiguous.get_or_create(&labels).set(contiguous as i64);
    if let Some(p) = outcome.problem {
        tracing::debug!(controller = id, key, "dropped: {p}");
    }
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
