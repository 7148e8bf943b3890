//! The HTTP API's security on a real server over loopback: read-only without a token, bearer
//! token on every non-GET request, body size and rate limits, and no token in the logs or in
//! the config's `Debug`.

use crate::service_support;

use std::io::Write;
use std::sync::{Arc, Mutex};

use crate::fault_support::*;
use mpmwatch_service::Service;
use mpmwatch_service::config::Config;
use service_support::*;

const TOKEN: &str = "s3cret-token-0123456789abcdef";

/// A log sink shared with the tracing subscriber.
#[derive(Clone, Default)]
struct Sink(Arc<Mutex<Vec<u8>>>);

impl Write for Sink {
    fn write(&mut self, buf: &[u8]) -> std::io::Result<usize> {
        self.0.lock().unwrap().extend_from_slice(buf);
        Ok(buf.len())
    }
    fn flush(&mut self) -> std::io::Result<()> {
        Ok(())
    }
}

fn with_http(text: &str, http: &str) -> String {
    text.replace("[http]\n", &format!("[http]\n{http}\n"))
}

#[tokio::test(flavor = "multi_thread")]
async fn without_a_token_the_api_is_read_only() {
    let z = free_port();
    let cfg = config(&config_text(z, 0, None, "every = 3600"));
    assert!(cfg.http.token.is_none() && cfg.http.token_env.is_none());
    // The default bind is loopback.
    assert_eq!(Config::parse(&config_text(z, 0, None, ""), "t").unwrap().http.bind, "127.0.0.1:0");
    let default: Config = "[[controller]]\nid = \"c\"\nperiod = 1.0\nmv = [\"u\"]\ndither = [\"d\"]\ncv = [\"y\"]\npred = [\"p\"]\n"
        .parse()
        .unwrap();
    assert_eq!(default.http.bind, "127.0.0.1:9464");

    // MPMWATCH_TOKEN is not set in this test binary (the other test sets its token in the file).
    let service = Service::start(cfg).await.expect("service");
    let h = service.http_addr.port(); // bound on port 0: no other test can hold it
    let a = request(h, "GET", "/healthz", &[], b"").await;
    assert_eq!(a.status, 200);
    let a = request(h, "POST", "/api/v1/controllers/c1/run", &[], b"").await;
    assert_eq!(a.status, 403, "{a:?}");
    let msg = a.json()["error"].as_str().unwrap_or_default().to_string();
    assert!(msg.contains("token_env") && msg.contains("MPMWATCH_TOKEN"), "says how to configure one: {msg}");
    // A token presented to a service that has none changes nothing.
    let a =
        request(h, "POST", "/api/v1/controllers/c1/run", &[&format!("Authorization: Bearer {TOKEN}")], b"")
            .await;
    assert_eq!(a.status, 403);
    service.stop().await;
}

#[tokio::test(flavor = "multi_thread")]
async fn non_get_needs_the_token_bodies_and_rates_are_limited_and_logs_keep_it_secret() {
    let sink = Sink::default();
    let writer = sink.clone();
    tracing_subscriber::fmt()
        .with_env_filter(tracing_subscriber::EnvFilter::new("trace,zenoh=warn"))
        .with_writer(move || writer.clone())
        .with_ansi(false)
        .try_init()
        .expect("this binary's only subscriber");

    let z = free_port();
    let text = with_http(
        &config_text(z, 0, None, "every = 3600"),
        &format!(
            "token = \"{TOKEN}\"\nmax_body_bytes = 1024\nrate_limit_per_s = 1000\nrate_limit_burst = 1000"
        ),
    );
    let cfg = config(&text);
    let debug = format!("{cfg:?} {:?}", cfg.http);
    assert!(!debug.contains(TOKEN), "Debug of the config shows the token: {debug}");
    assert!(debug.contains("redacted"));
    tracing::info!(config = ?cfg, "the config as a tracing field");
    let service = Service::start(cfg).await.expect("service");
    let h = service.http_addr.port(); // bound on port 0: no other test can hold it

    // GET stays open; non-GET needs the right bearer token.
    assert_eq!(request(h, "GET", "/api/v1/controllers", &[], b"").await.status, 200);
    let run = "/api/v1/controllers/c1/run";
    let a = request(h, "POST", run, &[], b"").await;
    assert_eq!(a.status, 401, "{a:?}");
    assert_eq!(a.header("www-authenticate"), Some("Bearer"));
    assert!(a.json()["error"].is_string());
    let wrong = format!("Authorization: Bearer {}x", &TOKEN[..TOKEN.len() - 1]);
    assert_eq!(request(h, "POST", run, &[&wrong], b"").await.status, 401);
    assert_eq!(request(h, "POST", run, &["Authorization: Basic Zm9vOmJhcg=="], b"").await.status, 401);
    assert_eq!(request(h, "DELETE", "/api/v1/controllers/c1", &[], b"").await.status, 401);
    let auth = format!("Authorization: Bearer {TOKEN}");
    let a = request(h, "POST", run, &[&auth], b"").await;
    assert_eq!(a.status, 200, "{a:?}");
    assert_eq!(a.json()["status"], "insufficient_data");
    assert_eq!(request(h, "POST", "/api/v1/controllers/nope/run", &[&auth], b"").await.status, 404);

    // Body limit: a declared length over it, and a chunked body that grows over it.
    let big = vec![b'x'; 4096];
    let a = request(h, "POST", run, &[&auth], &big).await;
    assert_eq!(a.status, 413, "{a:?}");
    assert!(a.json()["error"].as_str().unwrap().contains("max_body_bytes"));
    let mut chunked = Vec::new();
    for _ in 0..4 {
        chunked.extend_from_slice(b"400\r\n");
        chunked.extend_from_slice(&[b'y'; 1024]);
        chunked.extend_from_slice(b"\r\n");
    }
    chunked.extend_from_slice(b"0\r\n\r\n");
    let a = raw(h, &format!("POST {run} HTTP/1.1\r\n{auth}\r\nTransfer-Encoding: chunked"), &chunked).await;
    assert_eq!(a.status, 413, "{a:?}");
    assert_eq!(request(h, "POST", run, &[&auth], &[b' '; 100]).await.status, 200, "a small body is fine");
    service.stop().await;

    // Rate limit: a bucket of 3 at 1 per second; the fourth request at once gets 429.
    let (service, _) = start_service(|z| {
        with_http(
            &config_text(z, 0, None, "every = 3600"),
            &format!("token = \"{TOKEN}\"\nrate_limit_per_s = 1\nrate_limit_burst = 3"),
        )
    })
    .await;
    let h = service.http_addr.port(); // bound on port 0: no other test can hold it
    for _ in 0..3 {
        assert_eq!(request(h, "GET", "/healthz", &[], b"").await.status, 200);
    }
    let a = request(h, "GET", "/healthz", &[], b"").await;
    assert_eq!(a.status, 429, "{a:?}");
    assert_eq!(a.header("retry-after"), Some("1"));
    assert!(a.json()["error"].as_str().unwrap().contains("rate"));
    tokio::time::sleep(std::time::Duration::from_millis(1100)).await;
    assert_eq!(request(h, "GET", "/healthz", &[], b"").await.status, 200, "the bucket refills");
    service.stop().await;

    let logs = String::from_utf8_lossy(&sink.0.lock().unwrap()).to_string();
    assert!(logs.contains("bearer token"), "the refusals are logged: {logs}");
    assert!(!logs.contains(TOKEN), "the token leaked into the logs");
}

#[tokio::test(flavor = "multi_thread")]
async fn a_token_env_naming_an_unset_variable_stops_the_start() {
    let (z, h) = (free_port(), free_port());
    let text =
        with_http(&config_text(z, h, None, "every = 3600"), "token_env = \"MPMWATCH_TEST_UNSET_VARIABLE\"");
    let Err(e) = Service::start(config(&text)).await else { panic!("started without its token") };
    assert!(e.to_string().contains("MPMWATCH_TEST_UNSET_VARIABLE"), "{e}");
}
