//! Helpers of the service tests: configs, a publisher session on loopback, a minimal HTTP
//! client, and a seeded toy loop whose model can be wrong or right.
#![allow(dead_code)]

use std::time::Duration;

use mpmwatch_service::config::Config;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use tokio::io::{AsyncReadExt, AsyncWriteExt};

/// A guard against hangs only (never a performance assertion): generous on a loaded machine.
pub const HANG_GUARD: Duration = Duration::from_secs(240);

/// A two-MV, two-CV controller `c1` on the given ports. `extra` is appended to the controller
/// table (e.g. `every = 0.3`).
pub fn config_text(zenoh_port: u16, http_port: u16, store: Option<&std::path::Path>, extra: &str) -> String {
    let store =
        store.map(|p| format!("[store]\npath = {:?}\nflush_interval_ms = 100\n", p.display().to_string()));
    format!(
        r#"
prefix = "mpm"
[zenoh]
mode = "peer"
listen = ["tcp/127.0.0.1:{zenoh_port}"]
multicast_scouting = false
[http]
bind = "127.0.0.1:{http_port}"
{}
[[controller]]
id = "c1"
period = 1.0
mv = ["u1", "u2"]
dither = ["ud1", "ud2"]
cv = ["y1", "y2"]
pred = ["p1", "p2"]
window = 300
min_samples = 200
lag_min = 1
lag_max = 3
surrogates = 30
{extra}
"#,
        store.unwrap_or_default()
    )
}

/// A service started from the config `text(zenoh_port)`, its zenoh listener on a port
/// [`free_port`](crate::fault_support::free_port) has just picked, and that port. Another
/// process can take a picked port before the service binds it (the HTTP port has no such race:
/// it is bound on port 0), so a start that fails is tried again on a fresh port, three times
/// in all; the panic quotes the last error.
pub async fn start_service(text: impl Fn(u16) -> String) -> (mpmwatch_service::Service, u16) {
    start_service_on(crate::fault_support::free_port, text).await
}

/// [`start_service`] with the zenoh ports drawn from `ports`.
pub async fn start_service_on(
    mut ports: impl FnMut() -> u16,
    text: impl Fn(u16) -> String,
) -> (mpmwatch_service::Service, u16) {
    let mut last = String::new();
    for _ in 0..3 {
        let zenoh_port = ports();
        match mpmwatch_service::Service::start(config(&text(zenoh_port))).await {
            Ok(service) => return (service, zenoh_port),
            Err(e) => last = e.to_string(),
        }
    }
    panic!("the service did not start on three fresh zenoh ports: {last}");
}

/// Parses a test config.
pub fn config(text: &str) -> Config {
    Config::parse(text, "test").expect("test config")
}

/// A peer session that connects to the monitor's endpoint.
pub async fn publisher(zenoh_port: u16) -> zenoh::Session {
    let mut c = zenoh::Config::default();
    c.insert_json5("mode", "\"peer\"").unwrap();
    c.insert_json5("scouting/multicast/enabled", "false").unwrap();
    c.insert_json5("listen/endpoints", "[]").unwrap();
    c.insert_json5("connect/endpoints", &format!("[\"tcp/127.0.0.1:{zenoh_port}\"]")).unwrap();
    zenoh::open(c).await.expect("publisher session")
}

/// `GET path` on 127.0.0.1:port; returns the status code and the body.
pub async fn get(port: u16, path: &str) -> (u16, String) {
    let mut s = tokio::net::TcpStream::connect(("127.0.0.1", port)).await.expect("connect http");
    s.write_all(format!("GET {path} HTTP/1.1\r\nHost: 127.0.0.1\r\nConnection: close\r\n\r\n").as_bytes())
        .await
        .unwrap();
    let mut buf = Vec::new();
    s.read_to_end(&mut buf).await.unwrap();
    let text = String::from_utf8_lossy(&buf).to_string();
    let status: u16 = text.split_whitespace().nth(1).and_then(|c| c.parse().ok()).expect("status line");
    let (head, body) = text.split_once("\r\n\r\n").unwrap_or((&text, ""));
    let body = if head.to_ascii_lowercase().contains("transfer-encoding: chunked") {
        dechunk(body)
    } else {
        body.into()
    };
    (status, body)
}

fn dechunk(mut s: &str) -> String {
    let mut out = String::new();
    while let Some((len, rest)) = s.split_once("\r\n") {
        let n = usize::from_str_radix(len.trim(), 16).unwrap_or(0);
        if n == 0 {
            break;
        }
        out.push_str(&rest[..n]);
        s = &rest[n + 2..];
    }
    out
}

/// `GET` and parse JSON.
pub async fn get_json(port: u16, path: &str) -> (u16, serde_json::Value) {
    let (c, b) = get(port, path).await;
    (c, serde_json::from_str(&b).unwrap_or_else(|e| panic!("{path}: not JSON ({e}): {b}")))
}

/// Polls `f` every 100 ms until it returns `Some`, within the hang guard.
pub async fn until<T, F, Fut>(what: &str, mut f: F) -> T
where
    F: FnMut() -> Fut,
    Fut: std::future::Future<Output = Option<T>>,
{
    let deadline = tokio::time::Instant::now() + HANG_GUARD;
    loop {
        if let Some(v) = f().await {
            return v;
        }
        assert!(tokio::time::Instant::now() < deadline, "gave up waiting for {what}");
        tokio::time::sleep(Duration::from_millis(100)).await;
    }
}

/// Publishes probes on an unknown tag until the monitor counts one: then its subscription is
/// known to the publisher's session and later samples reach it. Returns once the count has
/// settled, so a caller that reads it as a baseline is not overtaken by a probe still queued.
pub async fn wait_routed(session: &zenoh::Session, http_port: u16) {
    until("the publisher's samples to reach the monitor", || async {
        session.put("mpm/c1/cv/probe", r#"{"t": 0, "v": 0}"#).await.unwrap();
        let (_, v) = get_json(http_port, "/api/v1/controllers/c1").await;
        (v["dropped"]["unknown_tag"].as_u64().unwrap_or(0) > 0).then_some(())
    })
    .await;
    settle_probes(http_port).await;
}

/// Waits until the monitor's `unknown_tag` count holds still for 500 ms: a probe sent just
/// before the first one was counted may still sit in the ingest queue (seen once under load:
/// a baseline one short).
pub async fn settle_probes(http_port: u16) {
    let count = || async {
        let (_, v) = get_json(http_port, "/api/v1/controllers/c1").await;
        v["dropped"]["unknown_tag"].as_u64().unwrap_or(0)
    };
    let deadline = tokio::time::Instant::now() + HANG_GUARD;
    let mut last = count().await;
    loop {
        tokio::time::sleep(Duration::from_millis(500)).await;
        let now = count().await;
        if now == last {
            return;
        }
        assert!(tokio::time::Instant::now() < deadline, "gave up waiting for the probes to settle");
        last = now;
    }
}

/// The toy loop: y1(t) = ud1(t−1) + n1, y2(t) = 0.5·ud2(t−1) + n2 with ±1 dithers. The right
/// model predicts both terms; the wrong one leaves ud1's out of p1 (mismatch on ud1→y1 only).
pub struct Toy {
    rng: ChaCha8Rng,
    prev: [f64; 2],
    /// Next sample index.
    pub k: usize,
}

impl Toy {
    /// Seeded.
    pub fn new(seed: u64) -> Self {
        Self { rng: ChaCha8Rng::seed_from_u64(seed), prev: [0.0; 2], k: 0 }
    }

    /// `n` samples as (tag key leaf, times, values) batches of the ten roles' tags.
    pub fn batch(&mut self, n: usize, model_right: bool) -> Vec<(String, Vec<f64>, Vec<f64>)> {
        let mut cols: Vec<(String, Vec<f64>, Vec<f64>)> =
            ["mv/u1", "mv/u2", "dither/ud1", "dither/ud2", "cv/y1", "cv/y2", "pred/p1", "pred/p2"]
                .iter()
                .map(|k| (k.to_string(), Vec::new(), Vec::new()))
                .collect();
        for _ in 0..n {
            let t = self.k as f64;
            let ud: [f64; 2] = [self.sign(), self.sign()];
            let noise: [f64; 2] = [self.rng.random::<f64>() - 0.5, self.rng.random::<f64>() - 0.5];
            let y = [self.prev[0] + noise[0], 0.5 * self.prev[1] + noise[1]];
            let p = [if model_right { self.prev[0] } else { 0.0 }, 0.5 * self.prev[1]];
            let vals = [1.0 + ud[0], ud[1], ud[0], ud[1], y[0], y[1], p[0], p[1]];
            for (c, v) in cols.iter_mut().zip(vals) {
                c.1.push(t);
                c.2.push(v);
            }
            self.prev = ud;
            self.k += 1;
        }
        cols
    }

    fn sign(&mut self) -> f64 {
        if self.rng.random::<bool>() { 1.0 } else { -1.0 }
    }

    /// Publishes `n` samples in interleaved batches of 10 per tag.
    pub async fn publish(&mut self, s: &zenoh::Session, n: usize, model_right: bool) {
        for _ in 0..n / 10 {
            for (leaf, t, v) in self.batch(10, model_right) {
                let payload = serde_json::json!({"t": t, "v": v}).to_string();
                s.put(format!("mpm/c1/{leaf}"), payload).await.unwrap();
            }
        }
    }
}
