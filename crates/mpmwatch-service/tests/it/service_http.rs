//! The HTTP API's bodies and error codes (DESIGN.md §4.4) and the zenoh queryable, on a real
//! server over loopback. Analyses are triggered directly (`scheduler::run_once`) so that the
//! states before and after a run are deterministic.

use crate::service_support::*;
use mpmwatch_service::run_once;

#[tokio::test(flavor = "multi_thread")]
async fn http_api_bodies_and_error_codes() {
    let (service, zport) = start_service(|z| config_text(z, 0, None, "every = 3600")).await;
    // Bound on port 0: the OS picked a free loopback port, which the service reports.
    let http = service.http_addr.port();
    assert!(service.http_addr.ip().is_loopback() && http != 0, "{}", service.http_addr);

    let (code, v) = get_json(http, "/healthz").await;
    assert_eq!((code, v["status"].as_str()), (200, Some("ok")));
    assert_eq!(v["controllers"], 1);

    let (code, v) = get_json(http, "/api/v1/controllers").await;
    assert_eq!(code, 200);
    assert_eq!(v[0]["id"], "c1");
    assert_eq!(v[0]["window_capacity"], 300);
    assert_eq!(v[0]["dither"], serde_json::json!(["ud1", "ud2"]));

    // Errors: JSON with a proper code.
    for (path, want) in [
        ("/api/v1/controllers/nope", 404),
        ("/api/v1/controllers/nope/matrix", 404),
        ("/api/v1/controllers/nope/alarms", 404),
        ("/api/v1/controllers/nope/profile?mv=u1&cv=y1", 404),
        ("/api/v1/controllers/c1/matrix", 503),
        ("/api/v1/controllers/c1/profile", 400),
        ("/api/v1/controllers/c1/profile?mv=u1", 400),
        ("/api/v1/controllers/c1/profile?mv=zz&cv=y1", 404),
        ("/api/v1/controllers/c1/profile?mv=u1&cv=zz", 404),
        ("/api/v1/controllers/c1/profile?mv=u1&cv=y1", 503),
        ("/api/v1/controllers/c1/alarms?limit=abc", 400),
        ("/api/v1/controllers/nope/trend?mv=u1&cv=y1", 404),
        ("/api/v1/controllers/c1/trend?mv=u1", 400),
        ("/api/v1/controllers/c1/trend?mv=zz&cv=y1", 404),
        ("/api/v1/controllers/c1/trend?mv=u1&cv=zz", 404),
        ("/no/such/path", 404),
    ] {
        let (code, v) = get_json(http, path).await;
        assert_eq!(code, want, "{path}: {v}");
        assert!(v["error"].as_str().is_some_and(|e| !e.is_empty()), "{path}: {v}");
    }

    // An analysis with too little data reports insufficient_data and is not analysed.
    let r = run_once(&service.shared, "c1").await.unwrap();
    assert_eq!(r.status.as_str(), "insufficient_data");
    let (code, v) = get_json(http, "/api/v1/controllers/c1/matrix").await;
    assert_eq!((code, v["status"].as_str()), (200, Some("insufficient_data")), "{v}");
    assert_eq!(v["needed"], 200);
    let (code, _) = get_json(http, "/api/v1/controllers/c1/profile?mv=u1&cv=y1").await;
    assert_eq!(code, 503);

    // Data in through zenoh, then a real run.
    let s = publisher(zport).await;
    wait_routed(&s, http).await;
    let mut toy = Toy::new(5);
    toy.publish(&s, 300, false).await;
    until("a full window", || async {
        let (_, v) = get_json(http, "/api/v1/controllers/c1").await;
        (v["window_len"].as_u64() == Some(300)).then_some(())
    })
    .await;
    let r = run_once(&service.shared, "c1").await.unwrap();
    assert_eq!(r.status.as_str(), "ok", "{:?}", r.message);

    let (code, m) = get_json(http, "/api/v1/controllers/c1/matrix").await;
    assert_eq!(code, 200);
    assert_eq!(m["status"], "ok");
    assert_eq!(m["n"], 300);
    assert_eq!(m["channels"].as_array().unwrap().len(), 4);
    let ch =
        m["channels"].as_array().unwrap().iter().find(|c| c["dither"] == "ud1" && c["cv"] == "y1").unwrap();
    assert_eq!(ch["significant"], true, "{ch}");
    assert_eq!(ch["verdict"], "mismatch");
    assert!(ch["norm_bits"].as_f64().unwrap() > ch["critical_bits"].as_f64().unwrap());
    let clean =
        m["channels"].as_array().unwrap().iter().find(|c| c["dither"] == "ud2" && c["cv"] == "y2").unwrap();
    assert_eq!(clean["significant"], false, "{clean}");

    for mv in ["u1", "ud1"] {
        let (code, p) = get_json(http, &format!("/api/v1/controllers/c1/profile?mv={mv}&cv=y1")).await;
        assert_eq!(code, 200, "{p}");
        assert_eq!(p["lags"], serde_json::json!([1, 2, 3]));
        assert_eq!(p["mi_bits"].as_array().unwrap().len(), 3);
        assert_eq!(p["critical_bits"].as_array().unwrap().len(), 3);
        // the effect is at lag 1
        assert!(p["mi_bits"][0].as_f64().unwrap() > p["critical_bits"][0].as_f64().unwrap(), "{p}");
    }

    // The family rule's CCF critical values and p-value come with the profile.
    let (_, p) = get_json(http, "/api/v1/controllers/c1/profile?mv=ud1&cv=y1").await;
    assert_eq!(p["ccf_critical"].as_array().map(Vec::len), Some(3), "{p}");
    assert!(p["p_value"].as_f64().unwrap() <= p["alpha"].as_f64().unwrap(), "{p}");

    let (code, a) = get_json(http, "/api/v1/controllers/c1/alarms?limit=5").await;
    assert_eq!(code, 200);
    assert_eq!(a["controller"], "c1");
    assert!(a["history"].as_array().is_some());

    let (code, page) = get(http, "/").await;
    assert_eq!(code, 200);
    assert!(page.contains("<html") && page.contains("api/v1/controllers"));
    for endpoint in ["/profile?", "/trend?", "/alarms?"] {
        assert!(page.contains(endpoint), "the page draws from {endpoint}");
    }

    let (code, metrics) = get(http, "/metrics").await;
    assert_eq!(code, 200);
    for needle in [
        r#"mpm_norm_mi_bits{controller="c1",mv="u1",dither="ud1",cv="y1"}"#,
        r#"mpm_critical_bits{controller="c1",mv="u1",dither="ud1",cv="y1"}"#,
        r#"mpm_significant{controller="c1",mv="u1",dither="ud1",cv="y1"} 1"#,
        r#"mpm_verdict{controller="c1",mv="u1",cv="y1",verdict="mismatch"} 1"#,
        r#"mpm_samples_ingested_total{controller="c1"} 2400"#,
        r#"mpm_samples_dropped_total{controller="c1",reason="late"} 0"#,
        r#"mpm_window_fill_ratio{controller="c1"} 1.0"#,
        r#"mpm_last_run_duration_seconds{controller="c1"}"#,
        r#"mpm_last_run_timestamp_seconds{controller="c1"}"#,
        r#"mpm_active_alarms{controller="c1"} 0"#,
        r#"mpm_runs_total{controller="c1",status="ok"} 1"#,
    ] {
        assert!(metrics.contains(needle), "{needle} missing from\n{metrics}");
    }

    // The latest result through the zenoh queryable.
    let replies = s.get("mpm/c1/matrix").await.unwrap();
    let reply = replies.recv_async().await.unwrap();
    let sample = reply.result().expect("a matrix reply");
    let v: serde_json::Value = serde_json::from_slice(&sample.payload().to_bytes()).unwrap();
    assert_eq!(v["status"], "ok");
    assert_eq!(v["channels"].as_array().unwrap().len(), 4);

    // The trend holds one point per ok run (the insufficient one is not a point).
    let r2 = run_once(&service.shared, "c1").await.unwrap();
    assert_eq!(r2.status.as_str(), "ok");
    let (code, t) = get_json(http, "/api/v1/controllers/c1/trend?mv=ud1&cv=y1").await;
    assert_eq!(code, 200, "{t}");
    let points = t["points"].as_array().unwrap();
    assert_eq!(points.len(), 2, "{t}");
    assert!(
        points.iter().all(|pt| pt["significant"] == true && pt["p_value"].as_f64().unwrap() <= 0.001),
        "{t}"
    );
    assert_eq!(t["alpha"], 0.001);
    let (_, t) = get_json(http, "/api/v1/controllers/c1/trend?mv=u2&cv=y2").await;
    assert_eq!(t["points"].as_array().unwrap().len(), 2);
    assert!(t["points"].as_array().unwrap().iter().all(|pt| pt["significant"] == false), "{t}");

    let _ = s.close().await;
    service.stop().await;
}
