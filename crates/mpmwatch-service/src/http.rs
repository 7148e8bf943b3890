//! The HTTP API (DESIGN.md §4.4) with axum: thin handlers over [`Shared`]. Every error is JSON
//! `{"error": "..."}` with a status code that says what went wrong: 400 for a bad request, 404
//! for an unknown controller, channel or path, 503 while no analysis has produced the answer,
//! and from the guards ([`super::guard`]) 401/403 without a valid token on a non-GET request,
//! 413 for a body over the limit, 429 past the rate limit.

use std::collections::{BTreeMap, HashMap};
use std::sync::Arc;

use axum::Json;
use axum::Router;
use axum::body::Bytes;
use axum::extract::rejection::BytesRejection;
use axum::extract::{DefaultBodyLimit, Path, Query, State};
use axum::http::{StatusCode, header};
use axum::middleware::from_fn_with_state;
use axum::response::{Html, IntoResponse, Response};
use axum::routing::{get, post};
use serde::Serialize;
use serde_json::json;
use tokio::sync::watch;
use tokio::task::JoinHandle;

use super::Shared;
use super::analysis::{self, RunStatus};
use super::guard::{self, Guard};
use super::{page, scheduler};

type AppState = Arc<Shared>;

/// A JSON error with its status code.
pub struct ApiError(StatusCode, String);

impl ApiError {
    /// An error answer.
    pub fn new(status: StatusCode, message: String) -> Self {
        Self(status, message)
    }
}

impl IntoResponse for ApiError {
    fn into_response(self) -> Response {
        (self.0, Json(json!({ "error": self.1 }))).into_response()
    }
}

fn not_found(what: String) -> ApiError {
    ApiError(StatusCode::NOT_FOUND, what)
}

/// The router with its guards: rate limit (outermost), body size, then the token for non-GET.
pub fn router(shared: Arc<Shared>, guard: Arc<Guard>) -> Router {
    Router::new()
        .route("/", get(index))
        .route("/healthz", get(healthz))
        .route("/metrics", get(metrics))
        .route("/api/v1/controllers", get(controllers))
        .route("/api/v1/controllers/{id}", get(controller))
        .route("/api/v1/controllers/{id}/matrix", get(matrix))
        .route("/api/v1/controllers/{id}/alarms", get(alarms))
        .route("/api/v1/controllers/{id}/profile", get(profile))
        .route("/api/v1/controllers/{id}/trend", get(trend))
        .route("/api/v1/controllers/{id}/run", post(run_now))
        .fallback(|| async { not_found("no such path; see GET /api/v1/controllers".into()) })
        .with_state(shared)
        .layer(DefaultBodyLimit::max(guard.max_body()))
        .layer(from_fn_with_state(guard.clone(), guard::require_token))
        .layer(from_fn_with_state(guard.clone(), guard::body_limit))
        .layer(from_fn_with_state(guard, guard::rate_limit))
}

/// Serves until `stop`.
pub fn spawn(
    shared: Arc<Shared>,
    guard: Arc<Guard>,
    listener: tokio::net::TcpListener,
    mut stop: watch::Receiver<bool>,
) -> JoinHandle<()> {
    tokio::spawn(async move {
        let app = router(shared, guard);
        let res = axum::serve(listener, app)
            .with_graceful_shutdown(async move {
                let _ = stop.changed().await;
            })
            .await;
        if let Err(e) = res {
            tracing::error!("http server: {e}");
        }
    })
}

async fn index() -> Html<&'static str> {
    Html(page::INDEX)
}

/// Liveness and the store's health: `status` is `ok`, or `degraded` while the store fails (the
/// analyses go on; only persistence is lost). Always 200: the process is alive and serving.
async fn healthz(State(s): State<AppState>) -> Json<serde_json::Value> {
    let store = s.store_health.snapshot(s.store.is_some());
    let degraded = store.get("ok").and_then(|v| v.as_bool()) == Some(false);
    Json(json!({
        "status": if degraded { "degraded" } else { "ok" },
        "uptime_s": s.started.elapsed().as_secs_f64(),
        "controllers": s.controllers.len(),
        "store": store,
    }))
}

/// `POST /api/v1/controllers/{id}/run`: analyses the controller now instead of waiting for its
/// schedule, and answers the run's report (409 while a run is in flight). The body is ignored
/// but bounded like any other.
async fn run_now(
    State(s): State<AppState>,
    Path(id): Path<String>,
    body: Result<Bytes, BytesRejection>,
) -> Result<Response, ApiError> {
    if let Err(e) = body {
        return Err(ApiError(e.status(), e.body_text()));
    }
    if !s.controllers.contains_key(&id) {
        return Err(unknown(&id));
    }
    match scheduler::run_once(&s, &id).await {
        Some(r) => Ok(Json(&*r).into_response()),
        None => Err(ApiError(StatusCode::CONFLICT, format!("an analysis of {id:?} is already running"))),
    }
}

async fn metrics(State(s): State<AppState>) -> Response {
    (
        [(header::CONTENT_TYPE, "application/openmetrics-text; version=1.0.0; charset=utf-8")],
        s.metrics.encode(),
    )
        .into_response()
}

/// One controller's status.
#[derive(Debug, Serialize)]
pub struct ControllerStatus {
    /// Id.
    pub id: String,
    /// Sample period, seconds.
    pub period: f64,
    /// Residual source.
    pub residual: String,
    /// MV tags.
    pub mv: Vec<String>,
    /// Dither tags.
    pub dither: Vec<String>,
    /// CV tags.
    pub cv: Vec<String>,
    /// Rows in the window.
    pub window_len: usize,
    /// Window length.
    pub window_capacity: usize,
    /// Contiguous rows at its end.
    pub window_contiguous: usize,
    /// Rows waiting for tags.
    pub pending_rows: usize,
    /// Samples accepted.
    pub ingested: u64,
    /// Drops by reason.
    pub dropped: BTreeMap<String, u64>,
    /// Slots missing between consecutive window rows (gaps in the data).
    pub gap_rows: u64,
    /// Confirmed jumps of the source clock.
    pub time_jumps: u64,
    /// Gaps inside the window filled by back-fill.
    pub backfilled_rows: u64,
    /// Rows closed early because a window of rows was waiting for tags.
    pub overflow_rows: u64,
    /// Status of the last run.
    pub last_run_status: Option<RunStatus>,
    /// Its time.
    pub last_run_time: Option<String>,
    /// Its duration, seconds.
    pub last_run_duration_s: Option<f64>,
    /// Last run found mismatch.
    pub mismatch: bool,
    /// Channels whose alarm is raised, `dither→cv`.
    pub active_alarms: Vec<String>,
}

fn status(s: &Shared, id: &str) -> Option<ControllerStatus> {
    let c = s.lock(id)?;
    let latest = c.latest.clone();
    Some(ControllerStatus {
        id: id.to_string(),
        period: c.cfg.period,
        residual: format!("{:?}", c.cfg.residual).to_lowercase(),
        mv: c.cfg.mv.clone(),
        dither: c.cfg.dither.clone(),
        cv: c.cfg.cv.clone(),
        window_len: c.window.len(),
        window_capacity: c.window.capacity(),
        window_contiguous: c.window.contiguous_tail(),
        pending_rows: c.pending(),
        ingested: c.ingested,
        dropped: super::align::DropReason::ALL
            .iter()
            .map(|r| (r.as_str().to_string(), c.dropped.get(r).copied().unwrap_or(0)))
            .collect(),
        gap_rows: c.gap_rows,
        time_jumps: c.time_jumps,
        backfilled_rows: c.backfilled_rows,
        overflow_rows: c.overflow_rows,
        last_run_status: latest.as_ref().map(|r| r.status),
        last_run_time: latest.as_ref().map(|r| r.time.clone()),
        last_run_duration_s: latest.as_ref().map(|r| r.duration_s),
        mismatch: latest.as_ref().is_some_and(|r| r.mismatch),
        active_alarms: c.active_alarms().into_iter().map(|(d, cv)| format!("{d}→{cv}")).collect(),
    })
}

async fn controllers(State(s): State<AppState>) -> Json<Vec<ControllerStatus>> {
    Json(s.controllers.keys().filter_map(|id| status(&s, id)).collect())
}

async fn controller(
    State(s): State<AppState>,
    Path(id): Path<String>,
) -> Result<Json<ControllerStatus>, ApiError> {
    status(&s, &id).map(Json).ok_or_else(|| unknown(&id))
}

fn unknown(id: &str) -> ApiError {
    not_found(format!("unknown controller {id:?}"))
}

async fn matrix(State(s): State<AppState>, Path(id): Path<String>) -> Result<Response, ApiError> {
    let latest = s.lock(&id).ok_or_else(|| unknown(&id))?.latest.clone();
    let r = latest.ok_or_else(|| {
        ApiError(StatusCode::SERVICE_UNAVAILABLE, format!("no analysis of {id:?} has run yet"))
    })?;
    Ok(Json(&*r).into_response())
}

async fn alarms(
    State(s): State<AppState>,
    Path(id): Path<String>,
    Query(q): Query<HashMap<String, String>>,
) -> Result<Json<serde_json::Value>, ApiError> {
    let limit = match q.get("limit") {
        None => 100,
        Some(v) => v.parse::<usize>().ok().filter(|&n| (1..=10_000).contains(&n)).ok_or_else(|| {
            ApiError(StatusCode::BAD_REQUEST, format!("limit {v:?} must be an integer in 1..=10000"))
        })?,
    };
    let (active, memory) = {
        let c = s.lock(&id).ok_or_else(|| unknown(&id))?;
        (c.active_alarms(), c.history.iter().cloned().collect::<Vec<_>>())
    };
    let history = match s.store.clone() {
        Some(store) => {
            let id2 = id.clone();
            tokio::task::spawn_blocking(move || store.alarms(&id2, limit))
                .await
                .map_err(|e| ApiError(StatusCode::INTERNAL_SERVER_ERROR, e.to_string()))?
                .map_err(|e| ApiError(StatusCode::INTERNAL_SERVER_ERROR, e.to_string()))?
        }
        None => memory.iter().rev().take(limit).rev().cloned().collect(),
    };
    Ok(Json(json!({
        "controller": id,
        "active": active.iter().map(|(d, cv)| json!({"channel": format!("{d}→{cv}"), "dither": d, "cv": cv})).collect::<Vec<_>>(),
        "history": history,
    })))
}

/// The (dither index, CV index) of `?mv=..&cv=..` (an MV or dither tag and a CV tag).
fn channel_of(s: &Shared, id: &str, q: &HashMap<String, String>) -> Result<(usize, usize), ApiError> {
    let (Some(mv), Some(cv)) = (q.get("mv"), q.get("cv")) else {
        return Err(ApiError(
            StatusCode::BAD_REQUEST,
            "query parameters mv and cv are required (tags)".into(),
        ));
    };
    let c = s.lock(id).ok_or_else(|| unknown(id))?;
    let i = c.cfg.mv.iter().position(|t| t == mv).or_else(|| c.cfg.dither.iter().position(|t| t == mv));
    let j = c.cfg.cv.iter().position(|t| t == cv);
    match (i, j) {
        (None, _) => Err(not_found(format!("controller {id:?} has no MV or dither tag {mv:?}"))),
        (_, None) => Err(not_found(format!("controller {id:?} has no CV tag {cv:?}"))),
        (Some(i), Some(j)) => Ok((i, j)),
    }
}

/// One channel's decisions over the recent runs (memory only, [`crate::controller::TREND`]
/// runs), with the rule's alpha: the page draws the p-value against it.
async fn trend(
    State(s): State<AppState>,
    Path(id): Path<String>,
    Query(q): Query<HashMap<String, String>>,
) -> Result<Json<serde_json::Value>, ApiError> {
    let (i, j) = channel_of(&s, &id, &q)?;
    let c = s.lock(&id).ok_or_else(|| unknown(&id))?;
    let points: Vec<_> = c.trend.get(&(i, j)).map(|t| t.iter().cloned().collect()).unwrap_or_default();
    Ok(Json(json!({
        "controller": id,
        "dither": c.cfg.dither[i],
        "cv": c.cfg.cv[j],
        "method": c.cfg.method,
        "alpha": (c.cfg.method == mpmwatch_core::detect::Method::Family).then_some(c.cfg.alpha),
        "points": points,
    })))
}

async fn profile(
    State(s): State<AppState>,
    Path(id): Path<String>,
    Query(q): Query<HashMap<String, String>>,
) -> Result<Response, ApiError> {
    let latest = s.lock(&id).ok_or_else(|| unknown(&id))?.latest.clone();
    let (Some(mv), Some(cv)) = (q.get("mv"), q.get("cv")) else {
        return Err(ApiError(
            StatusCode::BAD_REQUEST,
            "query parameters mv and cv are required (tags)".into(),
        ));
    };
    let (mvs, cvs) = {
        let c = s.lock(&id).ok_or_else(|| unknown(&id))?;
        (c.cfg.mv.iter().chain(&c.cfg.dither).cloned().collect::<Vec<_>>(), c.cfg.cv.clone())
    };
    if !mvs.contains(mv) {
        return Err(not_found(format!("controller {id:?} has no MV or dither tag {mv:?}")));
    }
    if !cvs.contains(cv) {
        return Err(not_found(format!("controller {id:?} has no CV tag {cv:?}")));
    }
    let r = latest.ok_or_else(|| {
        ApiError(StatusCode::SERVICE_UNAVAILABLE, format!("no analysis of {id:?} has run yet"))
    })?;
    if r.status != RunStatus::Ok {
        return Err(ApiError(
            StatusCode::SERVICE_UNAVAILABLE,
            format!(
                "the last run of {id:?} was {}: {}",
                r.status.as_str(),
                r.message.clone().unwrap_or_default()
            ),
        ));
    }
    let ch = r.channel(mv, cv).ok_or_else(|| {
        ApiError(
            StatusCode::SERVICE_UNAVAILABLE,
            format!("{mv}→{cv} was not tested in the last run (dither not excited)"),
        )
    })?;
    let p = analysis::profile(&r, ch).ok_or_else(|| {
        ApiError(StatusCode::INTERNAL_SERVER_ERROR, "profile missing from the last run".into())
    })?;
    Ok(Json(p).into_response())
}

#[cfg(test)]
mod tests {
    use std::collections::BTreeMap;
    use std::sync::{Arc, Mutex};
    use std::time::Instant;

    use axum::body::{Body, to_bytes};
    use axum::http::{Request, StatusCode, header};
    use tower::ServiceExt;

    use super::router;
    use crate::config::{Config, Secret};
    use crate::guard::Guard;
    use crate::metrics::Metrics;
    use crate::store::StoreHealth;
    use crate::{Controller, Shared};

    const CONFIG: &str = r#"
prefix = "mpm"
[zenoh]
mode = "peer"
multicast_scouting = false
[http]
bind = "127.0.0.1:0"
[[controller]]
id = "c1"
period = 1.0
mv = ["u1"]
dither = ["ud1"]
cv = ["y1"]
pred = ["p1"]
window = 300
min_samples = 200
lag_min = 1
lag_max = 3
surrogates = 30
"#;

    /// The router over a real state, as `Service::start` builds it, with a zenoh session that
    /// listens nowhere and scouts for nobody: handlers are exercised without a socket.
    async fn app(token: Option<&str>) -> axum::Router {
        let config = Config::parse(CONFIG, "test").unwrap();
        let mut z = zenoh::Config::default();
        z.insert_json5("mode", "\"peer\"").unwrap();
        z.insert_json5("scouting/multicast/enabled", "false").unwrap();
        z.insert_json5("listen/endpoints", "[]").unwrap();
        let session = zenoh::open(z).await.unwrap();
        let guard = Arc::new(Guard::new(&config.http, token.map(Secret::new)));
        let mut controllers = BTreeMap::new();
        for c in &config.controllers {
            controllers.insert(c.id.clone(), Mutex::new(Controller::new(c.clone()).unwrap()));
        }
        let shared = Arc::new(Shared {
            config,
            controllers,
            metrics: Metrics::new(),
            store: None,
            store_health: StoreHealth::default(),
            session,
            started: Instant::now(),
        });
        shared.metrics.init("c1");
        router(shared, guard)
    }

    async fn call(app: axum::Router, req: Request<Body>) -> (StatusCode, String) {
        let res = app.oneshot(req).await.unwrap();
        let status = res.status();
        let body = to_bytes(res.into_body(), 1 << 20).await.unwrap();
        (status, String::from_utf8_lossy(&body).into_owned())
    }

    fn get(path: &str) -> Request<Body> {
        Request::get(path).body(Body::empty()).unwrap()
    }

    #[tokio::test(flavor = "multi_thread")]
    async fn read_endpoints_answer_json_and_errors_name_what_is_missing() {
        let app = app(None).await;
        let (code, body) = call(app.clone(), get("/healthz")).await;
        assert_eq!(code, StatusCode::OK, "{body}");
        let (code, body) = call(app.clone(), get("/api/v1/controllers")).await;
        assert_eq!(code, StatusCode::OK);
        assert!(body.contains("\"c1\""), "{body}");
        let (code, body) = call(app.clone(), get("/api/v1/controllers/nosuch/matrix")).await;
        assert_eq!(code, StatusCode::NOT_FOUND);
        let v: serde_json::Value = serde_json::from_str(&body).unwrap();
        assert!(v["error"].as_str().unwrap().contains("nosuch"), "{body}");
        let (code, body) = call(app.clone(), get("/no/such/path")).await;
        assert_eq!(code, StatusCode::NOT_FOUND);
        assert!(body.contains("error"), "{body}");
        let (code, body) = call(app, get("/metrics")).await;
        assert_eq!(code, StatusCode::OK);
        assert!(body.contains("mpm_samples_ingested_total{controller=\"c1\"} 0"), "{body}");
    }

    #[tokio::test(flavor = "multi_thread")]
    async fn a_run_needs_the_bearer_token() {
        let run = |auth: Option<&str>| {
            let mut r = Request::post("/api/v1/controllers/c1/run");
            if let Some(a) = auth {
                r = r.header(header::AUTHORIZATION, a);
            }
            r.body(Body::empty()).unwrap()
        };
        let (code, _) = call(app(None).await, run(Some("Bearer anything"))).await;
        assert_eq!(code, StatusCode::FORBIDDEN, "no token configured: non-GET is refused");
        let app = app(Some("s3cret-token")).await;
        let (code, body) = call(app.clone(), run(None)).await;
        assert_eq!(code, StatusCode::UNAUTHORIZED, "{body}");
        let (code, _) = call(app.clone(), run(Some("Bearer wrong"))).await;
        assert_eq!(code, StatusCode::UNAUTHORIZED);
        // The right token passes the guard; the run on an empty window reports it as such.
        let (code, body) = call(app, run(Some("Bearer s3cret-token"))).await;
        assert_eq!(code, StatusCode::OK, "{body}");
        assert!(body.contains("insufficient_data"), "{body}");
    }
}
