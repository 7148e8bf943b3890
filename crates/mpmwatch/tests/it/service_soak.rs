//! Bounded memory under overload: the monitor runs as a child process (`mpmwatch serve`, so its
//! resident memory is its own), an in-process load generator publishes as fast as it can into
//! small ingest queues for about 25 s, and the test checks that
//!
//! * every sample sent is accounted for: ingested, or dropped with a reason (`queue_full`
//!   counts messages, so it is multiplied by the batch); nothing vanishes on the way;
//! * the overload was real: `queue_full` drops happened;
//! * the queues, windows and pending rows never exceed their configured sizes;
//! * the resident memory stays under a bound argued from the configuration, and does not keep
//!   growing from the first third of the run to the end.
//!
//! No wall-clock performance is asserted: a slow machine only drops more.

use std::time::{Duration, Instant};

use crate::serve_process::serve;
use crate::service_support::*;
use mpmwatch::loadgen::{self, LoadgenOptions};

const CONTROLLERS: usize = 4;
const BATCH: usize = 200;
const QUEUE_MESSAGES: usize = 16;
const QUEUE_BYTES: usize = 256 * 1024;
const WINDOW: usize = 1024;

fn rss_kib(pid: u32) -> Option<u64> {
    let s = std::fs::read_to_string(format!("/proc/{pid}/status")).ok()?;
    s.lines().find(|l| l.starts_with("VmRSS:"))?.split_whitespace().nth(1)?.parse().ok()
}

/// The value of one Prometheus sample line `name{labels} value`.
fn metric(text: &str, name_and_labels: &str) -> f64 {
    text.lines()
        .find(|l| l.starts_with(name_and_labels) && l[name_and_labels.len()..].starts_with(' '))
        .and_then(|l| l.rsplit(' ').next())
        .and_then(|v| v.parse().ok())
        .unwrap_or_else(|| panic!("{name_and_labels} not in /metrics"))
}

fn sum_metric(text: &str, prefix: &str) -> f64 {
    text.lines()
        .filter(|l| l.starts_with(prefix))
        .filter_map(|l| l.rsplit(' ').next()?.parse::<f64>().ok())
        .sum()
}

#[tokio::test(flavor = "multi_thread")]
async fn overload_is_dropped_and_counted_and_memory_stays_bounded() {
    let opts = LoadgenOptions {
        controllers: CONTROLLERS,
        batch: BATCH,
        rate: 0.0,
        duration: Duration::from_secs(25),
        wait_subscribers: Duration::from_secs(60),
        ..LoadgenOptions::default()
    };
    let dir = std::env::temp_dir().join(format!("mpmwatch-soak-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let text = |zport: u16, http: u16| {
        let text = format!(
            "[zenoh]\nmode = \"peer\"\nlisten = [\"tcp/127.0.0.1:{zport}\"]\n[http]\nbind = \"127.0.0.1:{http}\"\n\
             [ingest]\nqueue_messages = {QUEUE_MESSAGES}\nqueue_bytes = {QUEUE_BYTES}\n\n{}",
            opts.controller_toml(&format!(
                "window = {WINDOW}\nmin_samples = 600\nlag_max = 5\nsurrogates = 10\nmethod = \"paper\"\nevery = 5"
            ))
        );
        config(&text); // valid before the child sees it
        text
    };
    let child = serve(&dir.join("soak.toml"), text, false).await;
    let (zport, http, pid) = (child.zenoh, child.http, child.child.id());
    let rss_start = rss_kib(pid).expect("child RSS");

    let session = publisher(zport).await;
    let sampler = tokio::spawn(async move {
        // (seconds since start, RSS KiB, largest queue length and bytes seen in /metrics)
        let mut samples: Vec<(f64, u64, f64, f64)> = Vec::new();
        let t0 = Instant::now();
        while t0.elapsed() < Duration::from_secs(25) {
            tokio::time::sleep(Duration::from_millis(500)).await;
            let (_, m) = get(http, "/metrics").await;
            let q = (0..CONTROLLERS)
                .map(|i| metric(&m, &format!("mpm_ingest_queue_messages{{controller=\"lg{i:03}\"}}")))
                .fold(0.0, f64::max);
            let b = (0..CONTROLLERS)
                .map(|i| metric(&m, &format!("mpm_ingest_queue_bytes{{controller=\"lg{i:03}\"}}")))
                .fold(0.0, f64::max);
            samples.push((t0.elapsed().as_secs_f64(), rss_kib(pid).unwrap_or(0), q, b));
        }
        samples
    });
    let sent = loadgen::run(&session, &opts).await.expect("loadgen");
    let samples = sampler.await.unwrap();
    assert_eq!(sent.unmatched_keys, 0, "{sent:?}");
    assert_eq!(sent.put_errors, 0, "{sent:?}");

    // Accounting: wait until the monitor has handled everything sent (the queues drain).
    let expected = sent.samples as f64;
    let accounted = |m: &str| {
        let ingested = sum_metric(m, "mpm_samples_ingested_total{");
        let full = sum_metric(m, "mpm_samples_dropped_total{") - other_drops(m);
        (ingested, full, other_drops(m))
    };
    let m = until("every sent sample to be accounted for", || async {
        let (_, m) = get(http, "/metrics").await;
        let (ingested, full, other) = accounted(&m);
        (ingested + other + full * BATCH as f64 == expected).then_some(m)
    })
    .await;
    let (ingested, full, other) = accounted(&m);
    eprintln!(
        "sent {expected} samples in {} messages ({:.0}/s): ingested {ingested}, other drops {other}, \
         queue_full {full} messages; RSS {rss_start} KiB at start, samples {samples:?}",
        sent.messages, sent.samples_per_s
    );
    assert!(full > 0.0, "no queue_full drop: the generator did not overload the monitor");
    assert!(ingested > 0.0, "nothing ingested");

    // Queues, windows and pending rows within their configured sizes.
    for (_, _, q, b) in &samples {
        assert!(*q <= QUEUE_MESSAGES as f64, "queue length {q} > {QUEUE_MESSAGES}");
        assert!(*b <= QUEUE_BYTES as f64, "queue bytes {b} > {QUEUE_BYTES}");
    }
    let (_, st) = get_json(http, "/api/v1/controllers").await;
    for c in st.as_array().unwrap() {
        assert!(c["window_len"].as_u64().unwrap() <= WINDOW as u64, "{c}");
        // Rows wait for every tag's watermark, at most a window of them (then the oldest
        // closes early, counted in overflow_rows).
        assert!(c["pending_rows"].as_u64().unwrap() <= WINDOW as u64, "{c}");
    }

    // Memory. The bound: the queues' payloads (CONTROLLERS × QUEUE_BYTES), counted four times
    // over for zenoh's receive buffers, the decoded JSON and the allocator's slack; the windows
    // (CONTROLLERS × WINDOW rows of 12 values, < 1 MiB); the analysis (a few MiB per run);
    // and 64 MiB for zenoh's and tokio's fixed buffers and thread stacks.
    let bound_kib = rss_start + (4 * CONTROLLERS * QUEUE_BYTES / 1024) as u64 + 64 * 1024;
    let peak = samples.iter().map(|s| s.1).max().unwrap();
    assert!(peak <= bound_kib, "peak RSS {peak} KiB > bound {bound_kib} KiB (start {rss_start} KiB)");
    // Flat: from the first third of the run to the end it grows by less than 16 MiB, far less
    // than the tens of MiB per second an unbounded queue would take at this rate.
    let third = samples.iter().find(|s| s.0 >= 8.0).map(|s| s.1).unwrap();
    let last = samples.last().unwrap().1;
    assert!(last <= third + 16 * 1024, "RSS grew from {third} KiB to {last} KiB");

    let _ = session.close().await;
    drop(child);
    let _ = std::fs::remove_dir_all(&dir);
}

/// Drops for every reason but `queue_full` (which counts messages, not samples).
fn other_drops(m: &str) -> f64 {
    m.lines()
        .filter(|l| l.starts_with("mpm_samples_dropped_total{") && !l.contains("reason=\"queue_full\""))
        .filter_map(|l| l.rsplit(' ').next()?.parse::<f64>().ok())
        .sum()
}
