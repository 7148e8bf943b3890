//! Faults of the online monitor, each on a real service with real zenoh sessions on 127.0.0.1
//! and the real HTTP API: a router restart, a publisher that leaves and returns, jumps of the
//! source clock, and a store that fills up. Ports come from the OS (HTTP binds port 0, zenoh
//! listens on a `free_port`), so these tests run beside other test binaries.

use crate::service_support;

use std::time::Duration;

use crate::fault_support::*;
use mpmwatch_service::{Service, run_once};
use service_support::*;

async fn status(http: u16) -> serde_json::Value {
    get_json(http, "/api/v1/controllers/c1").await.1
}

fn count(v: &serde_json::Value, key: &str) -> u64 {
    v[key].as_u64().unwrap_or_else(|| panic!("{key} missing: {v}"))
}

fn dropped(v: &serde_json::Value, reason: &str) -> u64 {
    v["dropped"][reason].as_u64().unwrap_or_else(|| panic!("dropped.{reason} missing: {v}"))
}

/// Publishes rounds of 10 toy rows until `done` holds for the controller's status.
async fn publish_until(
    p: &zenoh::Session,
    toy: &mut Toy,
    http: u16,
    what: &str,
    done: impl Fn(&serde_json::Value) -> bool,
) -> serde_json::Value {
    let deadline = tokio::time::Instant::now() + HANG_GUARD;
    loop {
        toy.publish(p, 10, true).await;
        let v = status(http).await;
        if done(&v) {
            return v;
        }
        assert!(tokio::time::Instant::now() < deadline, "gave up waiting for {what}: {v}");
        tokio::time::sleep(Duration::from_millis(50)).await;
    }
}

#[tokio::test(flavor = "multi_thread")]
async fn the_service_reconnects_after_a_router_restart() {
    let rport = free_port();
    let ep = format!("tcp/127.0.0.1:{rport}");
    let r = router(&ep).await;
    let service =
        Service::start(config(&client_config(rport, 0, None, "every = 3600"))).await.expect("service");
    let http = service.http_addr.port(); // bound on port 0: no other test can hold it
    let p = client(&ep).await;
    wait_routed(&p, http).await;
    let mut toy = Toy::new(1);
    toy.publish(&p, 100, true).await;
    let before = until("100 rows", || async {
        let v = status(http).await;
        (count(&v, "window_len") == 100).then_some(v)
    })
    .await;

    // The router goes away; the service keeps running and serving HTTP.
    r.close().await.expect("close router");
    tokio::time::sleep(Duration::from_millis(500)).await;
    let (code, _) = get_json(http, "/healthz").await;
    assert_eq!(code, 200);
    let ingested = count(&status(http).await, "ingested");
    assert_eq!(ingested, count(&before, "ingested"), "nothing can arrive without the router");

    // Same port again: both clients reconnect by themselves and samples flow again.
    let r = router_again(&ep).await;
    let after =
        publish_until(&p, &mut toy, http, "rows after the restart", |v| count(v, "window_len") >= 150).await;
    assert!(count(&after, "ingested") > ingested, "{after}");
    let _ = p.close().await;
    service.stop().await;
    let _ = r.close().await;
}

#[tokio::test(flavor = "multi_thread")]
async fn a_publisher_that_leaves_and_returns_is_a_counted_gap() {
    let (service, zport) = start_service(|z| config_text(z, 0, None, "every = 3600")).await;
    let http = service.http_addr.port(); // bound on port 0: no other test can hold it
    let p = publisher(zport).await;
    wait_routed(&p, http).await;
    let mut toy = Toy::new(2);
    toy.publish(&p, 100, true).await;
    until("100 rows", || async { (count(&status(http).await, "window_len") == 100).then_some(()) }).await;
    p.close().await.expect("close publisher");

    // It comes back 40 samples later (its source kept time while it was away).
    tokio::time::sleep(Duration::from_millis(300)).await;
    toy.k += 40;
    let p = publisher(zport).await;
    wait_routed_again(&p, http).await;
    toy.publish(&p, 50, true).await;
    let v = until("rows after the gap", || async {
        let v = status(http).await;
        (count(&v, "window_len") == 150).then_some(v)
    })
    .await;
    assert_eq!(count(&v, "gap_rows"), 40, "the gap is counted: {v}");
    assert_eq!(count(&v, "window_contiguous"), 50, "{v}");
    assert!(count(&v, "window_contiguous") < count(&v, "window_len"), "{v}");
    assert_eq!(count(&v, "time_jumps"), 0);
    let (_, m) = get(http, "/metrics").await;
    assert!(m.contains("mpm_gap_rows_total{controller=\"c1\"} 40"), "{m}");

    // 100 more rows: the stretch after the gap (150) is still under min_samples (200), but the
    // analysis uses both stretches, each pair inside one.
    toy.publish(&p, 100, true).await;
    until("rows after the gap", || async { (count(&status(http).await, "window_len") == 250).then_some(()) })
        .await;
    let r = run_once(&service.shared, "c1").await.expect("a run");
    assert_eq!(r.status.as_str(), "ok", "{:?}", r.message);
    assert_eq!((r.n, r.segments), (250, 2));
    let _ = p.close().await;
    service.stop().await;
}

#[tokio::test(flavor = "multi_thread")]
async fn jumps_of_the_source_clock_are_counted_and_survived() {
    let (service, zport) = start_service(|z| config_text(z, 0, None, "every = 3600")).await;
    let http = service.http_addr.port(); // bound on port 0: no other test can hold it
    let p = publisher(zport).await;
    wait_routed(&p, http).await;
    let mut toy = Toy::new(3);
    toy.publish(&p, 100, true).await;
    until("100 rows", || async { (count(&status(http).await, "window_len") == 100).then_some(()) }).await;

    // A glitch: one sample stamped three hours ahead, then normal samples. It is dropped as a
    // time jump and disturbs nothing: no open row closes early, the window stays contiguous.
    p.put("mpm/c1/cv/y1", format!("{{\"t\": {}, \"v\": 1}}", toy.k as f64 + 10_800.0)).await.unwrap();
    toy.publish(&p, 50, true).await;
    let v = until("150 rows", || async {
        let v = status(http).await;
        (count(&v, "window_len") == 150).then_some(v)
    })
    .await;
    assert_eq!(dropped(&v, "time_jump"), 1, "{v}");
    assert_eq!(count(&v, "time_jumps"), 0, "{v}");
    assert_eq!(count(&v, "window_contiguous"), 150, "{v}");

    // The source clock jumps three hours ahead and stays there: after a few dropped samples the
    // new timeline is taken, and the hours in between are a gap.
    toy.k += 10_800;
    let v = publish_until(&p, &mut toy, http, "rows on the new timeline", |v| {
        count(v, "time_jumps") == 1 && count(v, "window_len") >= 200
    })
    .await;
    assert!(dropped(&v, "time_jump") > 1, "{v}");
    assert!(count(&v, "gap_rows") >= 10_000, "{v}");

    // It is set back by three hours (a clock corrected): the old window lies in the future of
    // the new timeline. After a stretch counted as late, the window restarts on the new times.
    toy.k -= 10_800;
    let late_before = dropped(&v, "late");
    let v = publish_until(&p, &mut toy, http, "rows after the jump back", |v| {
        count(v, "time_jumps") == 2 && count(v, "window_len") >= 50
    })
    .await;
    assert!(dropped(&v, "late") > late_before, "{v}");
    assert_eq!(count(&v, "window_contiguous"), count(&v, "window_len"), "{v}");
    let (_, m) = get(http, "/metrics").await;
    assert!(m.contains("mpm_time_jumps_total{controller=\"c1\"} 2"), "{m}");

    // And the analysis runs on the new timeline.
    toy.publish(&p, 200, true).await;
    until("a full window again", || async {
        (count(&status(http).await, "window_contiguous") >= 200).then_some(())
    })
    .await;
    let r = run_once(&service.shared, "c1").await.expect("a run");
    assert_eq!(r.status.as_str(), "ok", "{:?}", r.message);
    let _ = p.close().await;
    service.stop().await;
}

#[tokio::test(flavor = "multi_thread")]
async fn a_full_store_degrades_health_and_analysis_goes_on() {
    let dir = std::env::temp_dir().join(format!("mpmwatch-full-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    let store = dir.join("store.sqlite");
    // A cap of 16 KiB: the empty schema nearly fills it, as a full disk would.
    let (service, zport) = start_service(|z| {
        config_text(z, 0, Some(&store), "every = 3600")
            .replace("flush_interval_ms = 100", "flush_interval_ms = 100\nmax_bytes = 16384")
    })
    .await;
    let http = service.http_addr.port(); // bound on port 0: no other test can hold it
    let (_, h) = get_json(http, "/healthz").await;
    assert_eq!(h["status"], "ok", "{h}");
    assert_eq!(h["store"]["ok"], true, "{h}");

    let p = publisher(zport).await;
    wait_routed(&p, http).await;
    let mut toy = Toy::new(4);
    toy.publish(&p, 250, false).await;
    let h = until("the store fault in /healthz", || async {
        let (_, h) = get_json(http, "/healthz").await;
        (h["status"] == "degraded").then_some(h)
    })
    .await;
    assert_eq!(h["store"]["ok"], false, "{h}");
    let err = h["store"]["error"].as_str().unwrap_or_default();
    assert!(err.contains("full"), "the error says why: {h}");
    let (_, m) = get(http, "/metrics").await;
    assert!(m.contains("mpm_store_ok 0"), "{m}");
    let errors: u64 = m
        .lines()
        .find(|l| l.starts_with("mpm_store_errors_total{op=\"flush\"}"))
        .and_then(|l| l.rsplit(' ').next())
        .and_then(|n| n.parse().ok())
        .unwrap_or(0);
    assert!(errors >= 1, "{m}");

    // Ingestion and analysis go on without persistence.
    until("250 rows", || async { (count(&status(http).await, "window_len") == 250).then_some(()) }).await;
    let r = run_once(&service.shared, "c1").await.expect("a run");
    assert_eq!(r.status.as_str(), "ok", "{:?}", r.message);

    // Space comes back: the rows kept for retry are written and health recovers.
    service.shared.store.as_ref().unwrap().limit_size(1 << 30).unwrap();
    let h = until("the store to recover", || async {
        let (_, h) = get_json(http, "/healthz").await;
        (h["status"] == "ok").then_some(h)
    })
    .await;
    assert_eq!(h["store"]["ok"], true, "{h}");
    let saved = service.shared.store.as_ref().unwrap().load_rows("c1", 1000).unwrap();
    assert_eq!(saved.len(), 250, "the rows that failed to write were written on recovery");
    let _ = p.close().await;
    service.stop().await;
    let _ = std::fs::remove_dir_all(&dir);
}

/// The start helper's retry: the first zenoh port it is handed is held by another listener, so
/// that start fails; the next port is free, and the service started there serves.
#[tokio::test(flavor = "multi_thread")]
async fn a_start_on_a_taken_zenoh_port_is_tried_again_on_a_fresh_one() {
    let held = std::net::TcpListener::bind("127.0.0.1:0").unwrap();
    let taken = held.local_addr().unwrap().port();
    let mut handed = vec![taken];
    let ports = || handed.pop().unwrap_or_else(free_port);
    let (service, zport) = start_service_on(ports, |z| config_text(z, 0, None, "every = 3600")).await;
    assert_ne!(zport, taken);
    let (code, h) = get_json(service.http_addr.port(), "/healthz").await;
    assert_eq!(code, 200, "{h}");
    service.stop().await;
    drop(held);
}
