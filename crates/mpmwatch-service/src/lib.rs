//! The online monitor behind `mpmwatch serve` and `mpmwatch demo`: the imperative shell around
//! the pure core.
//!
//! * [`config`]: the TOML configuration and its validation.
//! * [`payload`]: key expressions and JSON payloads (DESIGN.md §4.3).
//! * [`align`]: samples onto the sample grid, rows in order, residuals.
//! * [`window`]: the bounded ring buffer analysed.
//! * [`analysis`]: one run of `detect::analyze` on a window snapshot and its report.
//! * [`alarm`]: debounce and alarm events.
//! * [`controller`]: one controller's state, behind a mutex.
//! * [`store`]: SQLite persistence of windows and alarms.
//! * [`metrics`], [`http`], [`page`]: Prometheus text, the HTTP API (DESIGN.md §4.4), the status page.
//! * [`guard`]: the HTTP API's bearer token, body size and rate limits.
//! * [`ingest`], [`scheduler`]: the async tasks (zenoh subscription, queryable, periodic runs).
//!
//! The demo plant and the load generator live in the binary crate.
//!
//! Only the last group and [`Service::start`] touch tokio and zenoh.

#![warn(missing_docs)]

mod alarm;
mod align;
mod analysis;
pub mod config;
mod controller;
mod guard;
mod http;
mod ingest;
mod metrics;
mod page;
pub mod payload;
mod scheduler;
mod store;
mod window;

pub use analysis::RunStatus;
pub use controller::Controller;
pub use scheduler::run_once;

use std::collections::BTreeMap;
use std::net::SocketAddr;
use std::sync::{Arc, Mutex, MutexGuard};
use std::time::Instant;

use tokio::sync::watch;
use tokio::task::JoinHandle;

use self::config::{Config, ZenohConfig};
use self::metrics::Metrics;
use self::store::{Store, StoreHealth};

/// Alarm events kept per controller on restore.
const RESTORE_HISTORY: usize = 500;

/// Why the service could not start.
#[derive(Debug, thiserror::Error)]
pub enum ServiceError {
    /// Zenoh configuration or session failure.
    #[error("zenoh: {0}")]
    Zenoh(String),
    /// The store could not be opened or read.
    #[error(transparent)]
    Store(#[from] store::StoreError),
    /// The HTTP address could not be bound.
    #[error("http: cannot bind {addr}: {source}")]
    Bind {
        /// Address.
        addr: String,
        /// Error.
        source: std::io::Error,
    },
    /// A setting that can only be checked at start (e.g. an environment variable it names).
    #[error("config: {0}")]
    Config(String),
    /// A controller could not be built.
    #[error("controller {id}: {message}")]
    Controller {
        /// Id.
        id: String,
        /// Why.
        message: String,
    },
}

/// State shared by the tasks and the HTTP handlers.
pub struct Shared {
    /// The configuration.
    pub config: Config,
    /// Controllers by id.
    pub controllers: BTreeMap<String, Mutex<Controller>>,
    /// Metrics.
    pub metrics: Metrics,
    /// The store, when configured.
    pub store: Option<Arc<Store>>,
    /// Whether the store's writes succeed (shown by `/healthz`).
    pub store_health: StoreHealth,
    /// The zenoh session.
    pub session: zenoh::Session,
    /// Start time.
    pub started: Instant,
}

impl Shared {
    /// Locks a controller. A panic elsewhere never leaves it unusable: the state is plain data.
    pub fn lock<'a>(&'a self, id: &str) -> Option<MutexGuard<'a, Controller>> {
        self.controllers.get(id).map(|m| m.lock().unwrap_or_else(|e| e.into_inner()))
    }

    /// The key `<prefix>/<controller>/<leaf>`.
    pub fn key(&self, controller: &str, leaf: &str) -> String {
        format!("{}/{controller}/{leaf}", self.config.prefix)
    }
}

/// A running service.
pub struct Service {
    /// Shared state.
    pub shared: Arc<Shared>,
    /// The bound HTTP address (useful with port 0).
    pub http_addr: SocketAddr,
    shutdown: watch::Sender<bool>,
    tasks: Vec<JoinHandle<()>>,
}

/// The zenoh configuration from ours.
pub fn zenoh_config(z: &ZenohConfig) -> Result<zenoh::Config, ServiceError> {
    let err = |e: zenoh::Error| ServiceError::Zenoh(e.to_string());
    let json = |v: &[String]| serde_json::to_string(v).unwrap_or_else(|_| "[]".into());
    let mut c = match &z.config_file {
        Some(p) => zenoh::Config::from_file(p).map_err(err)?,
        None => {
            let mut c = zenoh::Config::default();
            c.insert_json5("mode", &format!("{:?}", z.mode)).map_err(err)?;
            c.insert_json5("scouting/multicast/enabled", &z.multicast_scouting.to_string()).map_err(err)?;
            c
        }
    };
    if !z.listen.is_empty() {
        c.insert_json5("listen/endpoints", &json(&z.listen)).map_err(err)?;
    }
    if !z.connect.is_empty() {
        c.insert_json5("connect/endpoints", &json(&z.connect)).map_err(err)?;
    }
    Ok(c)
}

/// Now as RFC 3339 (UTC, milliseconds).
pub fn now_rfc3339() -> String {
    chrono::Utc::now().to_rfc3339_opts(chrono::SecondsFormat::Millis, true)
}

impl Service {
    /// Opens the store and restores the windows, opens the zenoh session, starts ingest,
    /// queryables, schedulers, the store flush and the HTTP server.
    pub async fn start(config: Config) -> Result<Self, ServiceError> {
        let token =
            config.http.resolve_token(|name| std::env::var(name).ok()).map_err(ServiceError::Config)?;
        if token.is_none() {
            tracing::info!(
                "no HTTP API token configured (http.token_env or {}): non-GET endpoints answer 403",
                config::TOKEN_ENV
            );
        }
        let guard = Arc::new(guard::Guard::new(&config.http, token));
        let store = match &config.store.path {
            Some(p) => {
                let (p, cap) = (p.clone(), config.store.max_bytes);
                let s = tokio::task::spawn_blocking(move || {
                    let s = Store::open(&p)?;
                    if let Some(b) = cap {
                        s.limit_size(b)?;
                    }
                    Ok::<_, store::StoreError>(s)
                })
                .await
                .map_err(|e| ServiceError::Config(format!("store task: {e}")))??;
                Some(Arc::new(s))
            }
            None => None,
        };
        let mut controllers = BTreeMap::new();
        for c in &config.controllers {
            let mut ctl = Controller::new(c.clone())
                .map_err(|message| ServiceError::Controller { id: c.id.clone(), message })?;
            if let Some(s) = &store {
                let rows = s.load_rows(&c.id, c.window)?;
                let active = s.active_alarms(&c.id)?;
                let history = s.alarms(&c.id, RESTORE_HISTORY)?;
                tracing::info!(controller = %c.id, rows = rows.len(), active = active.len(), "restored from the store");
                ctl.restore(rows, &active, history);
            }
            controllers.insert(c.id.clone(), Mutex::new(ctl));
        }
        let session = zenoh::open(zenoh_config(&config.zenoh)?)
            .await
            .map_err(|e| ServiceError::Zenoh(e.to_string()))?;
        let bind = config.http.bind.clone();
        let shared = Arc::new(Shared {
            config,
            controllers,
            metrics: Metrics::new(),
            store,
            store_health: StoreHealth::default(),
            session,
            started: Instant::now(),
        });
        for id in shared.controllers.keys() {
            shared.metrics.init(id);
        }
        let (shutdown, rx) = watch::channel(false);
        let mut tasks = Vec::new();
        for id in shared.controllers.keys() {
            tasks.push(ingest::spawn_subscriber(shared.clone(), id.clone(), rx.clone()).await?);
            tasks.push(ingest::spawn_queryable(shared.clone(), id.clone(), rx.clone()).await?);
            tasks.push(scheduler::spawn(shared.clone(), id.clone(), rx.clone()));
        }
        if shared.store.is_some() {
            tasks.push(scheduler::spawn_flush(shared.clone(), rx.clone()));
        }
        let listener = tokio::net::TcpListener::bind(&bind)
            .await
            .map_err(|source| ServiceError::Bind { addr: bind.clone(), source })?;
        let http_addr = listener.local_addr().map_err(|source| ServiceError::Bind { addr: bind, source })?;
        tasks.push(http::spawn(shared.clone(), guard, listener, rx));
        tracing::info!(%http_addr, controllers = shared.controllers.len(), "mpmwatch serving");
        Ok(Self { shared, http_addr, shutdown, tasks })
    }

    /// Stops the tasks, flushes the store once more and closes the zenoh session.
    pub async fn stop(self) {
        let _ = self.shutdown.send(true);
        for t in self.tasks {
            let _ = t.await;
        }
        scheduler::flush(&self.shared).await;
        let _ = self.shared.session.close().await;
    }

    /// Stops without the final flush, as a crash would (tests of the restore path).
    pub async fn abort(self) {
        for t in &self.tasks {
            t.abort();
        }
        let _ = self.shared.session.close().await;
    }
}
