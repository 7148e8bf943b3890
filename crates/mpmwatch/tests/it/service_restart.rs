//! Restart with the windows restored from the SQLite store: the real binary is killed with
//! SIGKILL (no shutdown flush) and started again on the same store.

use std::time::Duration;

use crate::serve_process::serve;
use crate::service_support::*;

async fn window_len(http: u16) -> Option<u64> {
    // Not listening yet (starting, or restored rows still loading): try again later.
    tokio::net::TcpStream::connect(("127.0.0.1", http)).await.ok()?;
    let (code, v) = get_json(http, "/api/v1/controllers/c1").await;
    (code == 200).then(|| v["window_len"].as_u64()).flatten()
}

#[tokio::test(flavor = "multi_thread")]
async fn windows_survive_kill_9() {
    let dir = std::env::temp_dir().join(format!("mpmwatch-restart-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    let store = dir.join("store.sqlite");
    let cfg = |z: u16, h: u16| config_text(z, h, Some(&store), "every = 3600");

    let mut first = serve(&dir.join("first.toml"), cfg, true).await;
    let (z1, h1) = (first.zenoh, first.http);
    until("the first instance's HTTP", || window_len(h1)).await;
    let s = publisher(z1).await;
    wait_routed(&s, h1).await;
    let mut toy = Toy::new(9);
    toy.publish(&s, 250, true).await;
    until("250 rows in the window", || async { (window_len(h1).await == Some(250)).then_some(()) }).await;
    // More than the flush interval (100 ms), so the rows are on disk.
    tokio::time::sleep(Duration::from_millis(1500)).await;
    first.kill(); // kill -9: no shutdown, no final flush
    let _ = s.close().await;

    let second = serve(&dir.join("second.toml"), cfg, true).await;
    let (z2, h2) = (second.zenoh, second.http);
    let restored = until("the second instance's HTTP", || window_len(h2)).await;
    assert_eq!(restored, 250, "window not restored");
    let (_, v) = get_json(h2, "/api/v1/controllers/c1").await;
    assert_eq!(v["window_contiguous"], 250);

    // It continues where it stopped: the next rows extend the window, old ones are refused.
    let s = publisher(z2).await;
    wait_routed(&s, h2).await;
    toy.publish(&s, 50, true).await;
    until("the window to continue", || async { (window_len(h2).await == Some(300)).then_some(()) }).await;
    s.put("mpm/c1/cv/y1", r#"{"t": 100, "v": 1}"#).await.unwrap();
    let v = until("the old sample to be refused", || async {
        let (_, v) = get_json(h2, "/api/v1/controllers/c1").await;
        (v["dropped"]["out_of_order"].as_u64() == Some(1)).then_some(v)
    })
    .await;
    assert_eq!(v["window_contiguous"], 300);
    let _ = s.close().await;
    drop(second);
    let _ = std::fs::remove_dir_all(&dir);
}

/// `kill -9` while samples are still arriving: every row the first instance had accepted a
/// margin before the kill is restored, and nothing it never had. The margin is ten flush
/// intervals (100 ms each), generous for a loaded machine; the bound it checks is the store's
/// contract: what a crash loses is at most the rows closed since the last flush.
#[tokio::test(flavor = "multi_thread")]
async fn kill_9_mid_ingest_loses_at_most_the_last_flush_interval() {
    let dir = std::env::temp_dir().join(format!("mpmwatch-midkill-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    let store = dir.join("store.sqlite");
    let cfg = |z: u16, h: u16| {
        config_text(z, h, Some(&store), "every = 3600").replace("window = 300\n", "window = 5000\n")
    };

    let mut first = serve(&dir.join("first.toml"), cfg, true).await;
    let (z1, h1) = (first.zenoh, first.http);
    until("the first instance's HTTP", || window_len(h1)).await;
    let s = publisher(z1).await;
    wait_routed(&s, h1).await;

    // A publisher that keeps going until told to stop (the kill happens while it runs).
    let (stop_tx, mut stop_rx) = tokio::sync::watch::channel(false);
    let feeder = tokio::spawn(async move {
        let mut toy = Toy::new(11);
        while !*stop_rx.borrow_and_update() {
            toy.publish(&s, 10, true).await;
            tokio::time::sleep(Duration::from_millis(20)).await;
        }
        let _ = s.close().await;
        toy.k
    });
    until("ingestion under way", || async { window_len(h1).await.filter(|&n| n >= 300) }).await;
    // Rows accepted now must be on disk after ten flush intervals; ingestion goes on meanwhile.
    let seen = window_len(h1).await.expect("first instance");
    tokio::time::sleep(Duration::from_millis(1000)).await;
    let before_kill = window_len(h1).await.expect("first instance");
    assert!(before_kill > seen, "ingestion must still be running at the kill");
    first.kill();
    let _ = stop_tx.send(true);
    let published = feeder.await.unwrap() as u64;

    let second = serve(&dir.join("second.toml"), cfg, true).await;
    let h2 = second.http;
    let restored = until("the second instance's HTTP", || window_len(h2)).await;
    eprintln!("accepted {seen} rows 1 s before the kill, {before_kill} just before it; {restored} restored");
    assert!(restored >= seen, "lost rows accepted a second before the kill: {restored} < {seen}");
    assert!(restored <= published, "restored rows that were never published");
    let (_, v) = get_json(h2, "/api/v1/controllers/c1").await;
    assert_eq!(v["window_contiguous"].as_u64(), Some(restored), "restored rows are contiguous");
    drop(second);
    let _ = std::fs::remove_dir_all(&dir);
}
