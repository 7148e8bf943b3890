//! The service's TOML configuration (`config/default.toml` documents every key) and its
//! validation. Validation collects every problem, each naming its key, so that an operator fixes
//! a bad file in one pass instead of one error per restart.

use std::collections::HashSet;
use std::net::SocketAddr;
use std::path::{Path, PathBuf};

use serde::Deserialize;

use mpmwatch_core::detect::Method;
use mpmwatch_core::model::{DiscreteTf, Hammerstein, MimoModel, StaticMap};

/// A configuration that could not be read or that failed validation.
#[derive(Debug, thiserror::Error)]
pub enum ConfigError {
    /// The file could not be read.
    #[error("cannot read config {path}: {source}")]
    Read {
        /// The file.
        path: PathBuf,
        /// The I/O error.
        source: std::io::Error,
    },
    /// TOML syntax, a wrong type or an unknown key (the message names it).
    #[error("config {path}: {message}")]
    Parse {
        /// The file.
        path: String,
        /// toml's message, with the line and the key.
        message: String,
    },
    /// Semantic problems, one line each.
    #[error("config {path} has {} problem(s):\n{}", .problems.len(), .problems.join("\n"))]
    Invalid {
        /// The file.
        path: String,
        /// One message per problem, each starting with the key.
        problems: Vec<String>,
    },
}

/// The whole service configuration.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Config {
    /// First segment of every key expression (`<prefix>/<controller>/...`).
    #[serde(default = "default_prefix")]
    pub prefix: String,
    /// How the zenoh session is opened.
    #[serde(default)]
    pub zenoh: ZenohConfig,
    /// The HTTP API.
    #[serde(default)]
    pub http: HttpConfig,
    /// The SQLite store.
    #[serde(default)]
    pub store: StoreConfig,
    /// The bounded queue between zenoh and each controller's ingest task.
    #[serde(default)]
    pub ingest: IngestConfig,
    /// The monitored controllers (`[[controller]]` tables).
    #[serde(default, rename = "controller")]
    pub controllers: Vec<ControllerConfig>,
}

fn default_prefix() -> String {
    "mpm".into()
}

/// Zenoh session settings.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ZenohConfig {
    /// `peer` (embedded, the default), `client` (through a router) or `router`.
    #[serde(default = "default_mode")]
    pub mode: String,
    /// Endpoints to listen on, e.g. `tcp/127.0.0.1:7447`.
    #[serde(default)]
    pub listen: Vec<String>,
    /// Endpoints to connect to (a router or peers).
    #[serde(default)]
    pub connect: Vec<String>,
    /// Multicast scouting: find peers on the LAN without `connect`. Off by default, so a
    /// monitor only talks to the endpoints it is told.
    #[serde(default)]
    pub multicast_scouting: bool,
    /// A full zenoh configuration file (JSON5) for TLS, access control and the rest. When set,
    /// `mode` and `multicast_scouting` come from the file, and `listen` and `connect` replace
    /// the file's endpoints only when they are not empty.
    #[serde(default)]
    pub config_file: Option<PathBuf>,
}

fn default_mode() -> String {
    "peer".into()
}

impl Default for ZenohConfig {
    fn default() -> Self {
        Self {
            mode: default_mode(),
            listen: Vec::new(),
            connect: Vec::new(),
            multicast_scouting: false,
            config_file: None,
        }
    }
}

/// A secret string (the HTTP API token). Its `Debug` never shows the value and it has no
/// `Display`, so neither `{:?}` of the config nor a tracing field can leak it; the value is
/// reachable only through [`Secret::expose`].
#[derive(Clone, Default, PartialEq, Eq, Deserialize)]
#[serde(transparent)]
pub struct Secret(String);

impl Secret {
    /// Wraps a value.
    pub fn new(value: impl Into<String>) -> Self {
        Self(value.into())
    }

    /// The value, for the one comparison that needs it.
    pub fn expose(&self) -> &str {
        &self.0
    }
}

impl std::fmt::Debug for Secret {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str("Secret(<redacted>)")
    }
}

/// The environment variable holding the HTTP API token when the config names none.
pub const TOKEN_ENV: &str = "MPMWATCH_TOKEN";

/// Shortest token accepted: a bearer token is a password, 16 random characters at least.
pub const MIN_TOKEN_LEN: usize = 16;

/// HTTP API settings.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct HttpConfig {
    /// Address and port; loopback by default (put a reverse proxy in front to expose it).
    #[serde(default = "default_bind")]
    pub bind: String,
    /// The bearer token that non-GET requests must present, written in the file. Prefer
    /// `token_env`: a file is more often copied around than an environment.
    #[serde(default)]
    pub token: Option<Secret>,
    /// The name of an environment variable holding the bearer token.
    #[serde(default)]
    pub token_env: Option<String>,
    /// Largest request body accepted, bytes; larger requests get 413.
    #[serde(default = "default_max_body")]
    pub max_body_bytes: usize,
    /// Requests per second refilled into the instance-wide token bucket; 0 turns the rate limit
    /// off. Past it requests get 429 with `Retry-After`.
    #[serde(default = "default_rate")]
    pub rate_limit_per_s: f64,
    /// Bucket size: how many requests may come at once after a quiet spell.
    #[serde(default = "default_burst")]
    pub rate_limit_burst: u32,
}

fn default_bind() -> String {
    "127.0.0.1:9464".into()
}
fn default_max_body() -> usize {
    64 * 1024
}
fn default_rate() -> f64 {
    50.0
}
fn default_burst() -> u32 {
    100
}

impl Default for HttpConfig {
    fn default() -> Self {
        Self {
            bind: default_bind(),
            token: None,
            token_env: None,
            max_body_bytes: default_max_body(),
            rate_limit_per_s: default_rate(),
            rate_limit_burst: default_burst(),
        }
    }
}

impl HttpConfig {
    /// The API token: `token` from the file, else the variable named by `token_env`, else
    /// `MPMWATCH_TOKEN`; `None` when none is set (non-GET endpoints then answer 403). `env`
    /// looks a variable up (`std::env::var` in the service, a map in tests).
    ///
    /// A `token_env` naming an unset or empty variable is an error rather than "no token": the
    /// operator meant to protect the API and should learn at start that it is not.
    pub fn resolve_token(&self, env: impl Fn(&str) -> Option<String>) -> Result<Option<Secret>, String> {
        if let Some(t) = &self.token {
            return Ok(Some(t.clone()));
        }
        let token = match &self.token_env {
            Some(name) => match env(name).filter(|v| !v.is_empty()) {
                Some(v) => v,
                None => return Err(format!("http.token_env: the environment variable {name} is not set")),
            },
            None => match env(TOKEN_ENV).filter(|v| !v.is_empty()) {
                Some(v) => v,
                None => return Ok(None),
            },
        };
        if token.chars().count() < MIN_TOKEN_LEN {
            return Err(format!("the HTTP API token must have at least {MIN_TOKEN_LEN} characters"));
        }
        Ok(Some(Secret(token)))
    }
}

/// Store settings.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct StoreConfig {
    /// SQLite file; absent means no persistence (windows start empty after a restart).
    #[serde(default)]
    pub path: Option<PathBuf>,
    /// How often closed samples are written, milliseconds (1..=1000): the most a crash loses.
    #[serde(default = "default_flush")]
    pub flush_interval_ms: u64,
    /// Cap on the database size in bytes (absent: none). Past it writes fail as on a full disk:
    /// the analyses go on and `/healthz` reports the store degraded.
    #[serde(default)]
    pub max_bytes: Option<u64>,
}

fn default_flush() -> u64 {
    500
}

impl Default for StoreConfig {
    fn default() -> Self {
        Self { path: None, flush_interval_ms: default_flush(), max_bytes: None }
    }
}

/// Ingest queue settings. Each controller has one queue between zenoh's receive thread and its
/// ingest task; a message that does not fit is dropped and counted as `queue_full`, so that
/// overload costs samples, never unbounded memory, and zenoh's receive thread never blocks
/// (a blocked receiver makes routers and publishers drop silently instead).
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct IngestConfig {
    /// Most messages waiting per controller (1..=1_000_000).
    #[serde(default = "default_queue_messages")]
    pub queue_messages: usize,
    /// Most payload bytes waiting per controller (at least 1024): the memory bound of a queue.
    /// A single message larger than this is always dropped (`queue_full`).
    #[serde(default = "default_queue_bytes")]
    pub queue_bytes: usize,
}

fn default_queue_messages() -> usize {
    256
}

fn default_queue_bytes() -> usize {
    2 << 20
}

impl Default for IngestConfig {
    fn default() -> Self {
        Self { queue_messages: default_queue_messages(), queue_bytes: default_queue_bytes() }
    }
}

/// Where the residuals come from.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum ResidualSource {
    /// `e = cv − pred`, with `pred` published by the controller (`.../pred/<tag>`).
    Pred,
    /// `e = cv − G0(mv)`, with `G0` the `[[controller.model]]` channels simulated by the service.
    Model,
}

/// One MV→CV channel of a nominal model: `y = q^-delay B(q⁻¹)/A(q⁻¹) f(u)`.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ChannelModel {
    /// MV tag (input).
    pub mv: String,
    /// CV tag (output).
    pub cv: String,
    /// Numerator in ascending powers of q⁻¹.
    pub b: Vec<f64>,
    /// Denominator in ascending powers of q⁻¹ (`[1.0]` for none).
    #[serde(default = "one")]
    pub a: Vec<f64>,
    /// Dead time, samples.
    #[serde(default)]
    pub delay: usize,
    /// Static input map: `identity` (default), `square`, `sine`, or `polynomial` with `poly`.
    #[serde(default = "identity")]
    pub map: String,
    /// Polynomial coefficients in ascending powers, for `map = "polynomial"`.
    #[serde(default)]
    pub poly: Vec<f64>,
}

fn one() -> Vec<f64> {
    vec![1.0]
}

fn identity() -> String {
    "identity".into()
}

/// One monitored controller.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ControllerConfig {
    /// Name, the second segment of its keys.
    pub id: String,
    /// Sample period in seconds; sample times are snapped to multiples of it.
    pub period: f64,
    /// MV tags (total MV `u = uc + ud`).
    pub mv: Vec<String>,
    /// Dither tags, one per MV in the same order.
    pub dither: Vec<String>,
    /// CV tags.
    pub cv: Vec<String>,
    /// Prediction tags, one per CV in the same order (residual = "pred").
    #[serde(default)]
    pub pred: Vec<String>,
    /// Residual source.
    #[serde(default = "default_residual")]
    pub residual: ResidualSource,
    /// Nominal model channels (residual = "model"); absent channels are zero.
    #[serde(default)]
    pub model: Vec<ChannelModel>,
    /// Ring-buffer length in samples: the most recent samples analysed.
    #[serde(default = "default_window")]
    pub window: usize,
    /// Least contiguous samples for an analysis; fewer gives `insufficient_data`.
    #[serde(default = "default_min_samples")]
    pub min_samples: usize,
    /// Smallest lag (eq 19's tmin).
    #[serde(default = "default_lag_min")]
    pub lag_min: usize,
    /// Largest lag (eq 19's tmax).
    #[serde(default = "default_lag_max")]
    pub lag_max: usize,
    /// KSG neighbours.
    #[serde(default = "default_k")]
    pub k: usize,
    /// Surrogates per element.
    #[serde(default = "default_surrogates")]
    pub surrogates: usize,
    /// Decision rule: `family` (one test per element over lags and statistics at `alpha`) or
    /// `paper` (μ + σ·sigma per statistic, eq 11).
    #[serde(default = "default_method")]
    pub method: Method,
    /// False-alarm rate per element and analysis (method `family`). A controller of m
    /// elements analysed on independent windows raises about m·alpha false significances per
    /// window; see docs/detection.md for false alarms per day.
    #[serde(default = "default_alpha")]
    pub alpha: f64,
    /// σ multiplier of the critical value μ + zσ (method `paper`).
    #[serde(default = "default_sigma")]
    pub sigma: f64,
    /// Also test the joint embedding of two consecutive dither lags (doubles the cost).
    #[serde(default)]
    pub joint_embedding: bool,
    /// Surrogate seed.
    #[serde(default = "default_seed")]
    pub seed: u64,
    /// Seconds between analyses (wall clock).
    #[serde(default = "default_every")]
    pub every: f64,
    /// Wall-clock seconds a row waits for a tag that has gone silent before it closes as a gap.
    /// Rows otherwise close when every tag's newest sample has passed them (per-tag
    /// watermarks), so per-tag batches of any size up to the window align without loss; a tag
    /// that returns within the window back-fills the gaps it left.
    #[serde(default = "default_grace")]
    pub grace: f64,
    /// Optional event-time bound, in samples: when non-zero, a row also closes once the newest
    /// sample is this many periods past it, whatever the other tags' watermarks (lower latency
    /// for feeds that interleave tags; a tag that lags more back-fills). 0 (default): off.
    #[serde(default)]
    pub tolerance: usize,
    /// Raise a channel's alarm after this many significant runs in a row.
    #[serde(default = "default_raise")]
    pub raise_after: u32,
    /// Clear it after this many clean runs in a row.
    #[serde(default = "default_clear")]
    pub clear_after: u32,
}

fn default_residual() -> ResidualSource {
    ResidualSource::Pred
}
fn default_window() -> usize {
    1024
}
fn default_min_samples() -> usize {
    256
}
fn default_lag_min() -> usize {
    1
}
fn default_lag_max() -> usize {
    10
}
fn default_k() -> usize {
    4
}
fn default_surrogates() -> usize {
    50
}
fn default_method() -> Method {
    Method::Family
}
fn default_alpha() -> f64 {
    0.001
}
fn default_sigma() -> f64 {
    6.0
}
fn default_seed() -> u64 {
    1
}
fn default_every() -> f64 {
    10.0
}
fn default_grace() -> f64 {
    60.0
}
fn default_raise() -> u32 {
    2
}
fn default_clear() -> u32 {
    3
}

/// Longest window, samples: bounds the memory of a controller whatever the file says.
pub const MAX_WINDOW: usize = 1_000_000;
/// Longest grace, seconds (a day).
pub const MAX_GRACE: f64 = 86_400.0;
/// Largest reorder tolerance, samples.
pub const MAX_TOLERANCE: usize = 100_000;
/// Most surrogates per element.
pub const MAX_SURROGATES: usize = 100_000;
/// Longest model dead time, samples (its filter holds that many past inputs).
pub const MAX_DELAY: usize = 100_000;
/// Shortest and longest `every`, seconds (a timer needs a non-zero, representable period).
pub const MIN_EVERY: f64 = 0.01;
/// See [`MIN_EVERY`]: one year.
pub const MAX_EVERY: f64 = 31_536_000.0;

/// Characters that zenoh key expressions reserve; none may appear in a prefix, id or tag.
const RESERVED: &[char] = &['/', '*', '$', '?', '#', ' '];

fn check_name(problems: &mut Vec<String>, key: &str, value: &str) {
    if value.is_empty() {
        problems.push(format!("{key}: must not be empty"));
    } else if let Some(c) = value.chars().find(|c| RESERVED.contains(c)) {
        problems.push(format!("{key}: {value:?} contains {c:?}, which zenoh key expressions reserve"));
    }
}

fn check_tags(problems: &mut Vec<String>, key: &str, tags: &[String]) {
    let mut seen = HashSet::new();
    for (i, t) in tags.iter().enumerate() {
        check_name(problems, &format!("{key}[{i}]"), t);
        if !seen.insert(t) {
            problems.push(format!("{key}[{i}]: tag {t:?} is listed twice"));
        }
    }
}

impl std::str::FromStr for Config {
    type Err = ConfigError;

    /// Parses and validates TOML text (messages name it `<string>`).
    fn from_str(text: &str) -> Result<Self, ConfigError> {
        Self::parse(text, "<string>")
    }
}

impl Config {
    /// Reads and validates a file.
    pub fn load(path: &Path) -> Result<Self, ConfigError> {
        let text = std::fs::read_to_string(path)
            .map_err(|source| ConfigError::Read { path: path.to_path_buf(), source })?;
        Self::parse(&text, &path.display().to_string())
    }

    /// Parses and validates TOML text; `origin` names it in messages.
    pub fn parse(text: &str, origin: &str) -> Result<Self, ConfigError> {
        let cfg: Config = toml::from_str(text)
            .map_err(|e| ConfigError::Parse { path: origin.to_string(), message: e.to_string() })?;
        let problems = cfg.problems();
        if problems.is_empty() {
            Ok(cfg)
        } else {
            Err(ConfigError::Invalid { path: origin.to_string(), problems })
        }
    }

    /// Every semantic problem, each message starting with the offending key.
    pub fn problems(&self) -> Vec<String> {
        let mut p = Vec::new();
        check_name(&mut p, "prefix", &self.prefix);
        if !["peer", "client", "router"].contains(&self.zenoh.mode.as_str()) {
            p.push(format!("zenoh.mode: {:?} is not one of peer, client, router", self.zenoh.mode));
        }
        for (key, eps) in [("zenoh.listen", &self.zenoh.listen), ("zenoh.connect", &self.zenoh.connect)] {
            for (i, e) in eps.iter().enumerate() {
                if !e.contains('/') {
                    p.push(format!("{key}[{i}]: {e:?} is not an endpoint such as tcp/127.0.0.1:7447"));
                }
            }
        }
        if let Some(f) = &self.zenoh.config_file
            && !f.exists()
        {
            p.push(format!("zenoh.config_file: {} does not exist", f.display()));
        }
        if self.http.bind.parse::<SocketAddr>().is_err() {
            p.push(format!("http.bind: {:?} is not an address:port such as 127.0.0.1:9464", self.http.bind));
        }
        if let Some(t) = &self.http.token {
            if t.expose().chars().count() < MIN_TOKEN_LEN {
                p.push(format!("http.token: must have at least {MIN_TOKEN_LEN} characters"));
            }
            if self.http.token_env.is_some() {
                p.push("http.token: set either token or token_env, not both".into());
            }
        }
        if let Some(name) = &self.http.token_env
            && (name.is_empty() || name.contains('='))
        {
            p.push(format!("http.token_env: {name:?} is not an environment variable name"));
        }
        if !(1..=(64 << 20)).contains(&self.http.max_body_bytes) {
            p.push(format!("http.max_body_bytes: {} must lie in 1..=67108864", self.http.max_body_bytes));
        }
        if !(self.http.rate_limit_per_s.is_finite() && self.http.rate_limit_per_s >= 0.0) {
            p.push(format!(
                "http.rate_limit_per_s: {} must be a number ≥ 0 (0 turns the limit off)",
                self.http.rate_limit_per_s
            ));
        }
        if self.http.rate_limit_per_s > 0.0 && self.http.rate_limit_burst == 0 {
            p.push("http.rate_limit_burst: must be at least 1 while the rate limit is on".into());
        }
        if !(1..=1000).contains(&self.store.flush_interval_ms) {
            p.push(format!(
                "store.flush_interval_ms: {} must lie in 1..=1000 (at most one second of samples may be lost)",
                self.store.flush_interval_ms
            ));
        }
        if self.store.max_bytes.is_some_and(|b| b < 16 * 1024) {
            p.push("store.max_bytes: must be at least 16384 (the empty schema takes a few pages)".into());
        }
        if !(1..=1_000_000).contains(&self.ingest.queue_messages) {
            p.push(format!("ingest.queue_messages: {} must lie in 1..=1000000", self.ingest.queue_messages));
        }
        if self.ingest.queue_bytes < 1024 {
            p.push(format!("ingest.queue_bytes: {} must be at least 1024", self.ingest.queue_bytes));
        }
        if self.controllers.is_empty() {
            p.push("controller: at least one [[controller]] table is needed".into());
        }
        let mut ids = HashSet::new();
        for (n, c) in self.controllers.iter().enumerate() {
            let key = format!("controller[{n}]");
            check_name(&mut p, &format!("{key}.id"), &c.id);
            if !ids.insert(&c.id) {
                p.push(format!("{key}.id: {:?} is used by another controller", c.id));
            }
            c.problems(&format!("{key} ({:?})", c.id), &mut p);
        }
        p
    }
}

impl ControllerConfig {
    fn problems(&self, key: &str, p: &mut Vec<String>) {
        if !(self.period.is_finite() && self.period > 0.0) {
            p.push(format!("{key}.period: {} must be a positive number of seconds", self.period));
        }
        for (name, tags) in [("mv", &self.mv), ("dither", &self.dither), ("cv", &self.cv)] {
            if tags.is_empty() {
                p.push(format!("{key}.{name}: at least one tag is needed"));
            }
            check_tags(p, &format!("{key}.{name}"), tags);
        }
        check_tags(p, &format!("{key}.pred"), &self.pred);
        if self.dither.len() != self.mv.len() {
            p.push(format!(
                "{key}.dither: {} tags for {} MVs (one dither per MV, in the same order)",
                self.dither.len(),
                self.mv.len()
            ));
        }
        match self.residual {
            ResidualSource::Pred => {
                if self.pred.len() != self.cv.len() {
                    p.push(format!(
                        "{key}.pred: {} tags for {} CVs (residual = \"pred\" needs one prediction per CV)",
                        self.pred.len(),
                        self.cv.len()
                    ));
                }
            }
            ResidualSource::Model => {
                if self.model.is_empty() {
                    p.push(format!(
                        "{key}.model: residual = \"model\" needs at least one [[controller.model]]"
                    ));
                }
                for (m, ch) in self.model.iter().enumerate() {
                    let mkey = format!("{key}.model[{m}]");
                    if !self.mv.contains(&ch.mv) {
                        p.push(format!("{mkey}.mv: {:?} is not one of the MV tags {:?}", ch.mv, self.mv));
                    }
                    if !self.cv.contains(&ch.cv) {
                        p.push(format!("{mkey}.cv: {:?} is not one of the CV tags {:?}", ch.cv, self.cv));
                    }
                    if ch.delay > MAX_DELAY {
                        p.push(format!(
                            "{mkey}.delay: {} is too long (at most {MAX_DELAY} samples)",
                            ch.delay
                        ));
                        continue;
                    }
                    if let Err(e) = channel(ch) {
                        p.push(format!("{mkey}: {e}"));
                    }
                }
                if p.is_empty() {
                    match self.nominal_model() {
                        Ok(model) if !model.is_strictly_proper() => p.push(format!(
                            "{key}.model: the model must be strictly proper (delay ≥ 1 or b[0] = 0): a \
                             residual needs the prediction before the MV moves"
                        )),
                        Ok(_) => {}
                        // e.g. a channel given twice (seen while writing the config fuzz target): it used to pass
                        // validation and stop the service at start.
                        Err(e) => p.push(format!("{key}.model: {e}")),
                    }
                }
            }
        }
        if self.window < 16 {
            p.push(format!("{key}.window: {} is too short (at least 16 samples)", self.window));
        }
        if self.window > MAX_WINDOW {
            p.push(format!("{key}.window: {} is too long (at most {MAX_WINDOW} samples)", self.window));
        }
        if self.tolerance > MAX_TOLERANCE {
            p.push(format!(
                "{key}.tolerance: {} is too large (at most {MAX_TOLERANCE} samples)",
                self.tolerance
            ));
        }
        if !(self.grace.is_finite() && (0.0..=MAX_GRACE).contains(&self.grace)) {
            p.push(format!("{key}.grace: {} must be a number of seconds in 0..={MAX_GRACE}", self.grace));
        }
        if self.surrogates > MAX_SURROGATES {
            p.push(format!("{key}.surrogates: {} is too many (at most {MAX_SURROGATES})", self.surrogates));
        }
        if self.min_samples > self.window {
            p.push(format!("{key}.min_samples: {} exceeds window {}", self.min_samples, self.window));
        }
        if self.lag_min > self.lag_max {
            p.push(format!("{key}.lag_min: {} exceeds lag_max {}", self.lag_min, self.lag_max));
        }
        if self.min_samples < self.lag_max.saturating_add(self.k.saturating_add(1).saturating_mul(4)) {
            p.push(format!(
                "{key}.min_samples: {} is too few for lag_max {} and k {} (at least lag_max + 4(k+1))",
                self.min_samples, self.lag_max, self.k
            ));
        }
        if self.k == 0 {
            p.push(format!("{key}.k: must be at least 1"));
        }
        if self.surrogates < 2 {
            p.push(format!(
                "{key}.surrogates: {} must be at least 2 (30 or more is sensible)",
                self.surrogates
            ));
        } else if self.method == Method::Family && self.surrogates < 20 {
            p.push(format!(
                "{key}.surrogates: {} is too few for method \"family\" (at least 20: its p-value rests on a tail fitted \
                 to them; or set method = \"paper\")",
                self.surrogates
            ));
        }
        if !(self.alpha > 0.0 && self.alpha < 0.5) {
            p.push(format!("{key}.alpha: {} must be between 0 and 0.5 (0.001 is the default)", self.alpha));
        }
        if !(self.sigma.is_finite() && self.sigma > 0.0) {
            p.push(format!("{key}.sigma: {} must be positive", self.sigma));
        }
        if !(self.every.is_finite() && (MIN_EVERY..=MAX_EVERY).contains(&self.every)) {
            p.push(format!(
                "{key}.every: {} must be a number of seconds in {MIN_EVERY}..={MAX_EVERY}",
                self.every
            ));
        }
        if self.raise_after == 0 {
            p.push(format!("{key}.raise_after: must be at least 1"));
        }
        if self.clear_after == 0 {
            p.push(format!("{key}.clear_after: must be at least 1"));
        }
    }

    /// The nominal model `G0` (CV rows × MV columns) of `residual = "model"`.
    pub fn nominal_model(&self) -> Result<MimoModel, String> {
        let mut rows: Vec<Vec<Option<Hammerstein>>> = vec![vec![None; self.mv.len()]; self.cv.len()];
        for ch in &self.model {
            let i = self.mv.iter().position(|t| t == &ch.mv).ok_or(format!("unknown MV {:?}", ch.mv))?;
            let j = self.cv.iter().position(|t| t == &ch.cv).ok_or(format!("unknown CV {:?}", ch.cv))?;
            if rows[j][i].is_some() {
                return Err(format!("channel {}→{} is given twice", ch.mv, ch.cv));
            }
            rows[j][i] = Some(channel(ch)?);
        }
        MimoModel::new(rows).map_err(|e| e.to_string())
    }
}

fn channel(ch: &ChannelModel) -> Result<Hammerstein, String> {
    let map = match ch.map.as_str() {
        "identity" => StaticMap::Identity,
        "square" => StaticMap::Square,
        "sine" => StaticMap::Sine,
        "polynomial" => StaticMap::Polynomial(ch.poly.clone()),
        other => return Err(format!("map {other:?} is not one of identity, square, sine, polynomial")),
    };
    if ch.b.iter().chain(&ch.a).any(|v| !v.is_finite()) {
        return Err("coefficients must be finite".into());
    }
    let tf = DiscreteTf::new(ch.b.clone(), ch.a.clone(), ch.delay).map_err(|e| e.to_string())?;
    tf.require_stable(&format!("{}→{}", ch.mv, ch.cv)).map_err(|e| e.to_string())?;
    Hammerstein::new(map, tf).map_err(|e| e.to_string())
}

#[cfg(test)]
mod tests {
    use super::*;

    const GOOD: &str = r#"
[[controller]]
id = "c1"
period = 1.0
mv = ["u1"]
dither = ["ud1"]
cv = ["y1"]
pred = ["yhat1"]
"#;

    #[test]
    fn minimal_config_takes_the_defaults() {
        let c = Config::parse(GOOD, "test").unwrap();
        assert_eq!(c.prefix, "mpm");
        assert_eq!(c.zenoh.mode, "peer");
        assert_eq!(c.http.bind, "127.0.0.1:9464");
        assert_eq!(c.controllers[0].window, 1024);
        assert_eq!(c.controllers[0].residual, ResidualSource::Pred);
    }

    #[test]
    fn every_problem_is_reported_with_its_key() {
        let text = r#"
prefix = "a/b"
[zenoh]
mode = "satellite"
[http]
bind = "nowhere"
[store]
flush_interval_ms = 5000
[[controller]]
id = "c1"
period = -1.0
mv = ["u1", "u2"]
dither = ["ud1"]
cv = ["y1"]
window = 100
min_samples = 200
surrogates = 1
"#;
        let Err(ConfigError::Invalid { problems, .. }) = Config::parse(text, "t") else { panic!() };
        let all = problems.join("\n");
        for key in [
            "prefix:",
            "zenoh.mode:",
            "http.bind:",
            "store.flush_interval_ms:",
            ".period:",
            ".dither:",
            ".pred:",
            ".min_samples:",
            ".surrogates:",
        ] {
            assert!(all.contains(key), "{key} missing from\n{all}");
        }
    }

    #[test]
    fn the_token_comes_from_the_file_a_named_variable_or_mpmwatch_token_and_never_shows() {
        fn env(vars: &[(&str, &str)]) -> impl Fn(&str) -> Option<String> {
            let vars: Vec<(String, String)> =
                vars.iter().map(|(k, v)| (k.to_string(), v.to_string())).collect();
            move |k: &str| vars.iter().find(|(n, _)| n == k).map(|(_, v)| v.clone())
        }
        let long = "0123456789abcdef0123";
        let c = Config::parse(&format!("[http]\ntoken = \"{long}\"\n{GOOD}"), "t").unwrap();
        assert_eq!(c.http.resolve_token(env(&[])).unwrap().unwrap().expose(), long);
        assert!(!format!("{c:?}").contains(long), "Debug redacts the token");
        let c = Config::parse(&format!("[http]\ntoken_env = \"API_TOKEN\"\n{GOOD}"), "t").unwrap();
        assert_eq!(
            c.http.resolve_token(env(&[("API_TOKEN", long), (TOKEN_ENV, "other-token-0123456789")])).unwrap(),
            Some(Secret::new(long))
        );
        let e = c.http.resolve_token(env(&[])).unwrap_err();
        assert!(e.contains("API_TOKEN"), "{e}");
        let c = Config::parse(GOOD, "t").unwrap();
        assert_eq!(c.http.resolve_token(env(&[])).unwrap(), None);
        assert_eq!(c.http.resolve_token(env(&[(TOKEN_ENV, long)])).unwrap(), Some(Secret::new(long)));
        assert!(c.http.resolve_token(env(&[(TOKEN_ENV, "short")])).is_err());
        let Err(ConfigError::Invalid { problems, .. }) =
            Config::parse(&format!("[http]\ntoken = \"short\"\n{GOOD}"), "t")
        else {
            panic!()
        };
        assert!(problems[0].starts_with("http.token:"), "{problems:?}");
    }

    #[test]
    fn huge_or_degenerate_numbers_are_refused_not_allocated() {
        let text = format!(
            "{GOOD}window = 1000000000000\ntolerance = 9223372036854775807\nk = 9223372036854775807\nevery = 1e-300\n"
        );
        let Err(ConfigError::Invalid { problems, .. }) = Config::parse(&text, "t") else { panic!() };
        let all = problems.join("\n");
        for key in [".window:", ".tolerance:", ".min_samples:", ".every:"] {
            assert!(all.contains(key), "{key} missing from\n{all}");
        }
        let text = format!("[http]\nmax_body_bytes = 0\nrate_limit_per_s = -1\n{GOOD}");
        let Err(ConfigError::Invalid { problems, .. }) = Config::parse(&text, "t") else { panic!() };
        assert_eq!(problems.len(), 2, "{problems:?}");
    }

    #[test]
    fn unknown_keys_are_named() {
        let Err(ConfigError::Parse { message, .. }) = Config::parse(&format!("{GOOD}windw = 3\n"), "t")
        else {
            panic!()
        };
        assert!(message.contains("windw"), "{message}");
    }

    #[test]
    fn model_channels_build_a_strictly_proper_model() {
        let text = r#"
[[controller]]
id = "c1"
period = 1.0
mv = ["u1", "u2"]
dither = ["ud1", "ud2"]
cv = ["y1"]
residual = "model"
[[controller.model]]
mv = "u1"
cv = "y1"
b = [0.0, 0.5]
a = [1.0, -0.5]
[[controller.model]]
mv = "u2"
cv = "y1"
b = [1.0]
delay = 2
map = "square"
"#;
        let c = Config::parse(text, "t").unwrap();
        let m = c.controllers[0].nominal_model().unwrap();
        assert_eq!((m.outputs(), m.inputs()), (1, 2));
        let twice = text.replace("mv = \"u2\"\ncv = \"y1\"", "mv = \"u1\"\ncv = \"y1\"");
        let Err(ConfigError::Invalid { problems, .. }) = Config::parse(&twice, "t") else { panic!() };
        assert!(problems[0].contains("given twice"), "{problems:?}");
        let bad = text.replace("delay = 2", "delay = 0");
        let Err(ConfigError::Invalid { problems, .. }) = Config::parse(&bad, "t") else { panic!() };
        assert!(problems[0].contains("strictly proper"), "{problems:?}");
    }
}
