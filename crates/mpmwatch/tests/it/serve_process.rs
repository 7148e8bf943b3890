//! `mpmwatch serve` as a child process on loopback ports.
//!
//! The HTTP server binds port 0 and the child says which port it got (its line
//! `mpmwatch: serving on http://…/`), so no other test can hold it. The zenoh port comes from
//! `free_port`, free when picked but open to a test running in parallel until the child binds
//! it; zenoh then fails to listen and the child exits. So the start watches the child until it
//! serves, and when it has exited starts it again on a fresh zenoh port, a bounded number of
//! times, instead of waiting out the hang guard.

use std::io::{BufRead, BufReader};
use std::path::Path;
use std::process::{Child, Command, Stdio};
use std::sync::mpsc;
use std::time::Duration;

use crate::fault_support::free_port;
use crate::service_support::HANG_GUARD;

/// Starts on fresh ports; each failed start is a port race lost, rare, so three is plenty.
const ATTEMPTS: usize = 3;

/// What the child prints once it serves, before its address.
const SERVING: &str = "mpmwatch: serving on http://";

/// A running `mpmwatch serve`; killed (SIGKILL) and reaped when dropped, panics included.
pub struct Served {
    /// The child process.
    pub child: Child,
    /// Its zenoh listening port.
    pub zenoh: u16,
    /// Its HTTP port.
    pub http: u16,
}

impl Served {
    /// Kills the child now (`kill -9`: no shutdown, no final flush) and reaps it.
    pub fn kill(&mut self) {
        let _ = self.child.kill();
        let _ = self.child.wait();
    }
}

impl Drop for Served {
    fn drop(&mut self) {
        self.kill();
    }
}

/// Writes `config(zenoh_port, http_bind)` to `path` (`http_bind` is `0`: the OS picks), starts
/// `mpmwatch serve --config path`, and returns once the child serves. Its stderr is copied to
/// the test's when `show_stderr`, else discarded; the last lines are kept for the panic message
/// when every start fails.
pub async fn serve(path: &Path, config: impl Fn(u16, u16) -> String, show_stderr: bool) -> Served {
    let mut last_words = Vec::new();
    for _ in 0..ATTEMPTS {
        let zenoh = free_port();
        std::fs::write(path, config(zenoh, 0)).expect("write the config");
        let child = Command::new(env!("CARGO_BIN_EXE_mpmwatch"))
            .args(["serve", "--config"])
            .arg(path)
            .env("RUST_LOG", "warn")
            .stdout(Stdio::null())
            .stderr(Stdio::piped())
            .spawn()
            .expect("start mpmwatch serve");
        let mut served = Served { child, zenoh, http: 0 };
        let (port_tx, port_rx) = mpsc::channel();
        let (words_tx, words_rx) = mpsc::channel();
        let stderr = served.child.stderr.take().expect("piped stderr");
        // Drains the pipe for the child's whole life, so it never blocks on a full pipe.
        std::thread::spawn(move || {
            for line in BufReader::new(stderr).lines().map_while(Result::ok) {
                if show_stderr {
                    eprintln!("{line}");
                }
                if let Some(port) = line.strip_prefix(SERVING).and_then(|a| a.split(['/', ' ']).next()) {
                    let _ = port_tx.send(port.rsplit(':').next().and_then(|p| p.parse::<u16>().ok()));
                }
                let _ = words_tx.send(line);
            }
        });
        match serving(&mut served.child, &port_rx).await {
            Some(http) => {
                served.http = http;
                return served;
            }
            None => {
                // The reader may still hold the lines the child wrote as it exited.
                tokio::time::sleep(Duration::from_millis(200)).await;
                last_words = words_rx.try_iter().collect();
            }
        }
    }
    let tail = last_words[last_words.len().saturating_sub(5)..].join("\n");
    panic!("mpmwatch serve exited before serving, {ATTEMPTS} times on fresh ports; its last words:\n{tail}");
}

/// The HTTP port the child reports once it serves; `None` if it exits first.
async fn serving(child: &mut Child, port: &mpsc::Receiver<Option<u16>>) -> Option<u16> {
    let deadline = tokio::time::Instant::now() + HANG_GUARD;
    loop {
        if let Ok(p) = port.try_recv() {
            return Some(p.expect("a port in the child's serving line"));
        }
        if child.try_wait().expect("the child's status").is_some() {
            return None;
        }
        assert!(tokio::time::Instant::now() < deadline, "mpmwatch serve never said it serves");
        tokio::time::sleep(Duration::from_millis(50)).await;
    }
}

/// The retry itself: a first start on a zenoh port another socket holds exits, and the second,
/// on a fresh port, serves.
#[tokio::test(flavor = "multi_thread")]
async fn a_start_on_a_taken_zenoh_port_is_retried_on_a_fresh_one() {
    let held = std::net::TcpListener::bind("127.0.0.1:0").expect("a loopback port");
    let taken = held.local_addr().expect("its address").port();
    let starts = std::cell::Cell::new(0);
    let dir = std::env::temp_dir().join(format!("mpmwatch-retry-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let config = |zenoh: u16, http: u16| {
        starts.set(starts.get() + 1);
        let zenoh = if starts.get() == 1 { taken } else { zenoh };
        crate::service_support::config_text(zenoh, http, None, "every = 3600")
    };
    let served = serve(&dir.join("retry.toml"), config, false).await;
    assert_eq!(starts.get(), 2, "one failed start, one that serves");
    assert_ne!(served.zenoh, taken);
    let (code, _) = crate::service_support::get_json(served.http, "/healthz").await;
    assert_eq!(code, 200);
    drop(served);
    let _ = std::fs::remove_dir_all(&dir);
}
