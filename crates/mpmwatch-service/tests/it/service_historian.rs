//! A historian's way of publishing, under the default alignment: one message per tag holding
//! 100–1000 samples, tags in a different order every round, one tag's batch held back and
//! published after its own next batch (so its rows first close as gaps and are then
//! back-filled), and a few bad messages. Every sample is ingested or counted by reason, the
//! window ends whole, and the alarm rises on the planted channel only.

use crate::service_support::*;
use rand::seq::SliceRandom;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use zenoh::qos::CongestionControl;

/// The shared test config without `tolerance` or `grace`: the defaults decide.
fn historian_config(zport: u16, http: u16) -> String {
    config_text(zport, http, None, "every = 0.5")
        .replace("window = 300\nmin_samples = 200\n", "window = 2048\nmin_samples = 1024\n")
}

/// A put that waits rather than lets zenoh drop under congestion (its default for `put`): a
/// historian gateway must not lose batches, and the test counts every sample.
async fn put(s: &zenoh::Session, key: &str, payload: String) {
    s.put(key, payload).congestion_control(CongestionControl::Block).await.unwrap();
}

#[tokio::test(flavor = "multi_thread")]
async fn per_tag_batches_with_a_back_fill_lose_nothing_and_raise_the_right_alarm() {
    let text = historian_config(0, 0);
    assert!(text.contains("window = 2048") && !text.contains("tolerance") && !text.contains("grace"));
    let (service, zport) = start_service(|z| historian_config(z, 0)).await;
    let http = service.http_addr.port(); // bound on port 0: no other test can hold it
    let s = publisher(zport).await;
    let alarms = s.declare_subscriber("mpm/c1/alarm").await.unwrap();
    wait_routed(&s, http).await;
    let (_, st) = get_json(http, "/api/v1/controllers/c1").await;
    let unknown_before = st["dropped"]["unknown_tag"].as_u64().unwrap();

    let mut rng = ChaCha8Rng::seed_from_u64(17);
    let mut toy = Toy::new(5);
    let mut sent = 0u64;
    let mut held: Option<(String, String)> = None;
    let mut held_rows = 0u64;
    for round in 0..8 {
        let n = rng.random_range(100..=1000);
        if round == 3 {
            held_rows = n as u64;
        }
        let mut batches = toy.batch(n, false);
        batches.shuffle(&mut rng);
        for (leaf, t, v) in batches {
            let payload = serde_json::json!({"t": t, "v": v}).to_string();
            sent += t.len() as u64;
            // Round 3's y2 batch comes late: after round 4's batches of every tag.
            if round == 3 && leaf == "cv/y2" {
                held = Some((leaf, payload));
                continue;
            }
            put(&s, &format!("mpm/c1/{leaf}"), payload).await;
        }
        if round == 4
            && let Some((leaf, payload)) = held.take()
        {
            put(&s, &format!("mpm/c1/{leaf}"), payload).await;
        }
        if round == 5 {
            put(&s, "mpm/c1/cv/y1", "not json".into()).await;
            put(&s, "mpm/c1/cv/nosuch", r#"{"t": [1, 2], "v": [1, 2]}"#.into()).await;
            put(&s, "mpm/c1/cv/y1", r#"{"t": 1e6, "v": "NaN"}"#.into()).await;
        }
    }
    // Accounted: ingested, or dropped per sample (bad_payload counts messages, and the probes
    // were unknown tags before the count started).
    let st = until("every sample ingested or counted", || async {
        let (_, v) = get_json(http, "/api/v1/controllers/c1").await;
        let dropped: u64 = v["dropped"]
            .as_object()?
            .iter()
            .filter(|(k, _)| *k != "bad_payload")
            .map(|(_, n)| n.as_u64().unwrap_or(0))
            .sum();
        (v["ingested"].as_u64()? + dropped - unknown_before >= sent + 3).then_some(v)
    })
    .await;
    assert_eq!(st["ingested"], sent, "{st}");
    let d = &st["dropped"];
    assert_eq!(d["bad_payload"], 1, "{st}");
    assert_eq!(d["non_finite"], 1, "{st}");
    assert_eq!(d["unknown_tag"].as_u64().unwrap() - unknown_before, 2, "{st}");
    for reason in ["duplicate", "out_of_order", "late", "future", "time_jump", "queue_full"] {
        assert_eq!(d[reason], 0, "{reason}: {st}");
    }
    assert_eq!(st["overflow_rows"], 0, "{st}");
    // y2's next batch moved its watermark past the held rows: they closed as a gap, and the
    // late batch filled every one of them.
    assert_eq!(st["gap_rows"], held_rows, "{st}");
    assert_eq!(st["backfilled_rows"], held_rows, "{st}");
    assert_eq!(st["window_len"], 2048, "{st}");
    assert_eq!(st["window_contiguous"], 2048, "{st}");

    let raised = until("the alarm", || async {
        let mut found = None;
        while let Ok(Some(sample)) = alarms.try_recv() {
            let e: serde_json::Value = serde_json::from_slice(&sample.payload().to_bytes()).unwrap();
            assert_eq!(e["channel"], "ud1→y1", "an alarm on a channel whose model is right: {e}");
            found = Some(e);
        }
        found
    })
    .await;
    assert_eq!(raised["event"], "raise");
    let _ = s.close().await;
    service.stop().await;
}
