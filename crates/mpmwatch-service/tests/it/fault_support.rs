//! Helpers of the fault and security tests: free loopback ports, raw HTTP requests with any
//! method, headers and body, in-process zenoh routers and client sessions.
#![allow(dead_code)]

use std::time::Duration;

use tokio::io::{AsyncReadExt, AsyncWriteExt};

/// A port free on 127.0.0.1 now (the OS picks it; tests on this machine run in parallel with
/// other test binaries, so fixed ports could collide). Free now, not later: another test can
/// take it before the caller binds it, so an HTTP server binds port 0 instead and reports its
/// port (`Service::http_addr`); this is for what must be known before the start (a zenoh
/// listener the publisher connects to).
pub fn free_port() -> u16 {
    std::net::TcpListener::bind("127.0.0.1:0")
        .and_then(|l| l.local_addr())
        .map(|a| a.port())
        .expect("free port")
}

/// An HTTP answer.
#[derive(Debug)]
pub struct Answer {
    /// Status code.
    pub status: u16,
    /// Header lines, lower-cased names.
    pub headers: Vec<(String, String)>,
    /// Body.
    pub body: String,
}

impl Answer {
    /// A header's value.
    pub fn header(&self, name: &str) -> Option<&str> {
        self.headers.iter().find(|(n, _)| n == name).map(|(_, v)| v.as_str())
    }

    /// The body as JSON.
    pub fn json(&self) -> serde_json::Value {
        serde_json::from_str(&self.body).unwrap_or_else(|e| panic!("not JSON ({e}): {}", self.body))
    }
}

/// Sends `head` (request line and headers, without the blank line) and `body` raw.
pub async fn raw(port: u16, head: &str, body: &[u8]) -> Answer {
    let mut s = tokio::net::TcpStream::connect(("127.0.0.1", port)).await.expect("connect http");
    s.write_all(format!("{head}\r\nHost: 127.0.0.1\r\nConnection: close\r\n\r\n").as_bytes()).await.unwrap();
    // The server may answer (413) and close before reading a large body: ignore write errors.
    let _ = s.write_all(body).await;
    let mut buf = Vec::new();
    let _ = s.read_to_end(&mut buf).await;
    let text = String::from_utf8_lossy(&buf).to_string();
    let status: u16 = text.split_whitespace().nth(1).and_then(|c| c.parse().ok()).expect("status line");
    let (head, body) = text.split_once("\r\n\r\n").unwrap_or((&text, ""));
    let headers = head
        .lines()
        .skip(1)
        .filter_map(|l| l.split_once(':'))
        .map(|(n, v)| (n.trim().to_ascii_lowercase(), v.trim().to_string()))
        .collect::<Vec<_>>();
    let body = if headers.iter().any(|(n, v)| n == "transfer-encoding" && v.contains("chunked")) {
        dechunk(body)
    } else {
        body.to_string()
    };
    Answer { status, headers, body }
}

fn dechunk(mut s: &str) -> String {
    let mut out = String::new();
    while let Some((len, rest)) = s.split_once("\r\n") {
        let n = usize::from_str_radix(len.trim(), 16).unwrap_or(0);
        if n == 0 || rest.len() < n {
            break;
        }
        out.push_str(&rest[..n]);
        s = rest.get(n + 2..).unwrap_or("");
    }
    out
}

/// `METHOD path` with extra header lines and a body (Content-Length set).
pub async fn request(port: u16, method: &str, path: &str, headers: &[&str], body: &[u8]) -> Answer {
    let mut head = format!("{method} {path} HTTP/1.1\r\nContent-Length: {}", body.len());
    for h in headers {
        head.push_str("\r\n");
        head.push_str(h);
    }
    raw(port, &head, body).await
}

/// An in-process zenoh router listening on `endpoint` (e.g. `tcp/127.0.0.1:PORT`).
pub async fn router(endpoint: &str) -> zenoh::Session {
    let mut c = zenoh::Config::default();
    c.insert_json5("mode", "\"router\"").unwrap();
    c.insert_json5("scouting/multicast/enabled", "false").unwrap();
    c.insert_json5("listen/endpoints", &format!("[\"{endpoint}\"]")).unwrap();
    zenoh::open(c).await.expect("router session")
}

/// A router on `endpoint`, retried while the port is still held by a closed predecessor.
pub async fn router_again(endpoint: &str) -> zenoh::Session {
    for _ in 0..100 {
        let mut c = zenoh::Config::default();
        c.insert_json5("mode", "\"router\"").unwrap();
        c.insert_json5("scouting/multicast/enabled", "false").unwrap();
        c.insert_json5("listen/endpoints", &format!("[\"{endpoint}\"]")).unwrap();
        if let Ok(s) = zenoh::open(c).await {
            return s;
        }
        tokio::time::sleep(Duration::from_millis(100)).await;
    }
    panic!("could not restart the router on {endpoint}");
}

/// A client session connected to the router at `endpoint`.
pub async fn client(endpoint: &str) -> zenoh::Session {
    let mut c = zenoh::Config::default();
    c.insert_json5("mode", "\"client\"").unwrap();
    c.insert_json5("scouting/multicast/enabled", "false").unwrap();
    c.insert_json5("connect/endpoints", &format!("[\"{endpoint}\"]")).unwrap();
    zenoh::open(c).await.expect("client session")
}

/// `c1` of the toy loop through a router as a client, with `extra` lines in the controller.
pub fn client_config(
    router_port: u16,
    http_port: u16,
    store: Option<&std::path::Path>,
    extra: &str,
) -> String {
    super::service_support::config_text(0, http_port, store, extra)
        .replace("mode = \"peer\"", "mode = \"client\"")
        .replace("listen = [\"tcp/127.0.0.1:0\"]", &format!("connect = [\"tcp/127.0.0.1:{router_port}\"]"))
}

/// Like `wait_routed`, for a publisher that comes after another: probes on an unknown tag until
/// the monitor's count of them grows.
pub async fn wait_routed_again(session: &zenoh::Session, http_port: u16) {
    let probes = |v: serde_json::Value| v["dropped"]["unknown_tag"].as_u64().unwrap_or(0);
    let before = probes(super::service_support::get_json(http_port, "/api/v1/controllers/c1").await.1);
    super::service_support::until("the new publisher's samples to reach the monitor", || async {
        session.put("mpm/c1/cv/probe", r#"{"t": 0, "v": 0}"#).await.unwrap();
        let (_, v) = super::service_support::get_json(http_port, "/api/v1/controllers/c1").await;
        (probes(v) > before).then_some(())
    })
    .await;
    super::service_support::settle_probes(http_port).await;
}
