//! Published samples to an alarm on the right channel over real zenoh on loopback, and its
//! clear once the model is fixed; the events arrive on `mpm/c1/alarm`.

use crate::service_support::*;

#[tokio::test(flavor = "multi_thread")]
async fn wrong_model_raises_the_right_alarm_and_a_fixed_model_clears_it() {
    let (service, zport) =
        start_service(|z| config_text(z, 0, None, "every = 0.3\nraise_after = 2\nclear_after = 2")).await;
    let http = service.http_addr.port(); // bound on port 0: no other test can hold it
    let pubs = publisher(zport).await;
    let alarms = pubs.declare_subscriber("mpm/c1/alarm").await.unwrap();
    wait_routed(&pubs, http).await;

    // Phase 1: the model leaves out ud1's effect on y1.
    let mut toy = Toy::new(11);
    let mut events: Vec<serde_json::Value> = Vec::new();
    let deadline = tokio::time::Instant::now() + HANG_GUARD;
    let raised = loop {
        toy.publish(&pubs, 50, false).await;
        while let Ok(Some(s)) = alarms.try_recv() {
            events.push(serde_json::from_slice(&s.payload().to_bytes()).unwrap());
        }
        if let Some(e) = events.iter().find(|e| e["event"] == "raise") {
            break e.clone();
        }
        assert!(tokio::time::Instant::now() < deadline, "no alarm raised");
        tokio::time::sleep(std::time::Duration::from_millis(100)).await;
    };
    assert_eq!(raised["channel"], "ud1→y1", "{raised}");
    assert_eq!(raised["mv"], "u1");
    assert_eq!(raised["cv"], "y1");
    assert_eq!(raised["verdict"], "mismatch");
    assert!(raised["value_bits"].as_f64().unwrap() > raised["critical_bits"].as_f64().unwrap());
    assert!(raised["time"].as_str().unwrap().contains('T'));
    let (_, st) = get_json(http, "/api/v1/controllers/c1").await;
    assert_eq!(st["active_alarms"], serde_json::json!(["ud1→y1"]));

    // Phase 2: the model is fixed; the window refills with clean residuals.
    let cleared = loop {
        toy.publish(&pubs, 50, true).await;
        while let Ok(Some(s)) = alarms.try_recv() {
            events.push(serde_json::from_slice(&s.payload().to_bytes()).unwrap());
        }
        if let Some(e) = events.iter().find(|e| e["event"] == "clear") {
            break e.clone();
        }
        assert!(tokio::time::Instant::now() < deadline, "the alarm never cleared");
        tokio::time::sleep(std::time::Duration::from_millis(100)).await;
    };
    assert_eq!(cleared["channel"], "ud1→y1");
    for e in &events {
        assert_eq!(e["channel"], "ud1→y1", "an alarm on a channel whose model is right: {e}");
    }
    let (code, body) = get_json(http, "/api/v1/controllers/c1/alarms").await;
    assert_eq!(code, 200);
    assert!(body["active"].as_array().unwrap().is_empty());
    let kinds: Vec<&str> =
        body["history"].as_array().unwrap().iter().map(|e| e["event"].as_str().unwrap()).collect();
    assert_eq!(kinds, vec!["raise", "clear"]);
    let (_, metrics) = get(http, "/metrics").await;
    assert!(metrics.contains(r#"mpm_active_alarms{controller="c1"} 0"#), "{metrics}");
    let _ = pubs.close().await;
    service.stop().await;
}
