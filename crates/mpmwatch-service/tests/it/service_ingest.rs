//! Every kind of bad input over real zenoh is counted by reason and survived: the monitor keeps
//! ingesting good samples afterwards.

use crate::service_support::*;

#[tokio::test(flavor = "multi_thread")]
async fn bad_payloads_are_counted_by_reason_and_survived() {
    let (service, zport) = start_service(|z| config_text(z, 0, None, "every = 3600")).await;
    let http = service.http_addr.port(); // bound on port 0: no other test can hold it
    let s = publisher(zport).await;
    wait_routed(&s, http).await;

    // Good rows 0..=49, then the bad ones. The routing probes left this session before the good
    // rows and one session's samples reach the subscriber in order, so once the rows are in,
    // every probe has been counted: the snapshot cannot race a probe still in flight.
    let mut toy = Toy::new(3);
    toy.publish(&s, 50, true).await;
    let before = until("the good rows", || async {
        let (_, v) = get_json(http, "/api/v1/controllers/c1").await;
        (v["ingested"].as_u64() == Some(50 * 8)).then_some(v)
    })
    .await;
    let unknown_before = before["dropped"]["unknown_tag"].as_u64().unwrap();
    let bad: &[(&str, &[u8])] = &[
        ("mpm/c1/cv/y1", b"not json"),                                 // bad_payload
        ("mpm/c1/cv/y1", br#"{"v": 1}"#),                              // bad_payload (no t)
        ("mpm/c1/cv/y1", br#"{"t": [1, 2], "v": [1]}"#),               // bad_payload (lengths)
        ("mpm/c1/cv/y1", br#"{"t": "yesterday", "v": 1}"#),            // bad_payload (time)
        ("mpm/c1/cv/y1", &[0xff, 0xfe, 0x00]),                         // bad_payload (not UTF-8)
        ("mpm/c1/cv/y1", br#"{"t": 60, "v": null}"#),                  // non_finite
        ("mpm/c1/cv/y1", br#"{"t": 61, "v": "NaN"}"#),                 // non_finite
        ("mpm/c1/cv/y1", br#"{"t": 62, "v": "-inf"}"#),                // non_finite
        ("mpm/c1/cv/nosuch", br#"{"t": 60, "v": 1}"#),                 // unknown_tag
        ("mpm/c1/bogus/y1", br#"{"t": 60, "v": 1}"#),                  // unknown_tag (role)
        ("mpm/c1/cv/y1", br#"{"t": 70, "v": 1}"#),                     // accepted (opens slot 70)
        ("mpm/c1/cv/y1", br#"{"t": 70.2, "v": 2}"#),                   // duplicate (snaps to slot 70)
        ("mpm/c1/cv/y1", br#"{"t": 10, "v": 1}"#),                     // out_of_order (row 10 closed)
        ("mpm/c1/cv/y1", br#"{"t": -1000, "v": 1}"#),                  // late (older than the window)
        ("mpm/c1/cv/y1", br#"{"t": "2999-01-01T00:00:00Z", "v": 1}"#), // future
        ("mpm/c1/cv/y1", br#"{"t": "1970-01-01T00:01:11Z", "v": 1}"#), // accepted: RFC 3339, slot 71
    ];
    for (key, payload) in bad {
        s.put(*key, payload.to_vec()).await.unwrap();
    }
    let st = until("the bad samples to be counted", || async {
        let (_, v) = get_json(http, "/api/v1/controllers/c1").await;
        // the last message is a good one; the subscriber handles messages in order
        (v["ingested"].as_u64() == Some(50 * 8 + 2)).then_some(v)
    })
    .await;
    let d = &st["dropped"];
    assert_eq!(d["bad_payload"], 5, "{st}");
    assert_eq!(d["non_finite"], 3, "{st}");
    assert_eq!(d["unknown_tag"].as_u64().unwrap() - unknown_before, 2, "{st}");
    assert_eq!(d["duplicate"], 1, "{st}");
    assert_eq!(d["out_of_order"], 1, "{st}");
    assert_eq!(d["late"], 1, "{st}");
    assert_eq!(d["future"], 1, "{st}");
    assert_eq!(st["ingested"], 50 * 8 + 2, "{st}");

    // The same counts in Prometheus text.
    let (_, m) = get(http, "/metrics").await;
    assert!(m.contains(r#"mpm_samples_dropped_total{controller="c1",reason="bad_payload"} 5"#), "{m}");
    assert!(m.contains(r#"mpm_samples_dropped_total{controller="c1",reason="non_finite"} 3"#), "{m}");

    // Still alive and ingesting: rows 50.. complete the window further.
    let (code, _) = get(http, "/healthz").await;
    assert_eq!(code, 200);
    toy.publish(&s, 100, true).await;
    until("good samples after the bad ones", || async {
        let (_, v) = get_json(http, "/api/v1/controllers/c1").await;
        (v["ingested"].as_u64().unwrap_or(0) >= 150 * 8).then_some(())
    })
    .await;
    let _ = s.close().await;
    service.stop().await;
}
