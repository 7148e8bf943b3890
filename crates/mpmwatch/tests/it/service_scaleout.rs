//! Scale-out: one zenoh router on loopback (an in-process session in router mode), two monitor
//! instances as its clients, each configured with half of the controllers, and one publisher
//! (also a client) sending all of them. Each instance must see exactly its own controllers'
//! samples: every sample of its controllers ingested once (none lost, none doubled), nothing of
//! the other half (no `unknown_tag` drops, no foreign controller in its API or metrics).

use std::time::Duration;

use crate::fault_support::free_port;
use crate::service_support::*;
use mpmwatch::loadgen::{self, LoadgenOptions};
use mpmwatch_service::Service;

const CONTROLLERS: usize = 4;

fn instance(router: u16, http: u16, share: &LoadgenOptions) -> String {
    format!(
        "[zenoh]\nmode = \"client\"\nconnect = [\"tcp/127.0.0.1:{router}\"]\n[http]\nbind = \"127.0.0.1:{http}\"\n\n{}",
        share.controller_toml(
            "window = 512\nmin_samples = 200\nlag_max = 3\nsurrogates = 10\nmethod = \"paper\"\nevery = 3600"
        )
    )
}

async fn router(port: u16) -> zenoh::Session {
    let mut c = zenoh::Config::default();
    c.insert_json5("mode", "\"router\"").unwrap();
    c.insert_json5("scouting/multicast/enabled", "false").unwrap();
    c.insert_json5("listen/endpoints", &format!("[\"tcp/127.0.0.1:{port}\"]")).unwrap();
    zenoh::open(c).await.expect("router session")
}

async fn client(router: u16) -> zenoh::Session {
    let mut c = zenoh::Config::default();
    c.insert_json5("mode", "\"client\"").unwrap();
    c.insert_json5("scouting/multicast/enabled", "false").unwrap();
    c.insert_json5("connect/endpoints", &format!("[\"tcp/127.0.0.1:{router}\"]")).unwrap();
    zenoh::open(c).await.expect("publisher session")
}

#[tokio::test(flavor = "multi_thread")]
async fn two_instances_behind_one_router_each_see_only_their_half() {
    let port = free_port();
    let all = LoadgenOptions {
        controllers: CONTROLLERS,
        batch: 10,
        rate: 200.0,
        duration: Duration::from_secs(3),
        wait_subscribers: HANG_GUARD,
        ..LoadgenOptions::default()
    };
    let half_a = LoadgenOptions { controllers: CONTROLLERS / 2, ..all.clone() };
    let half_b = LoadgenOptions { first: CONTROLLERS / 2, controllers: CONTROLLERS / 2, ..all.clone() };
    let ids = |o: &LoadgenOptions| (0..o.controllers).map(|i| o.id(i)).collect::<Vec<_>>();
    let (ids_a, ids_b) = (ids(&half_a), ids(&half_b));
    assert_eq!([ids_a.clone(), ids_b.clone()].concat(), ids(&all));

    let router = router(port).await;
    let a = Service::start(config(&instance(port, 0, &half_a))).await.unwrap();
    let b = Service::start(config(&instance(port, 0, &half_b))).await.unwrap();
    // Bound on port 0: no other test can hold them.
    let (http_a, http_b) = (a.http_addr.port(), b.http_addr.port());
    let publisher = client(port).await;
    // loadgen waits until every key (all four controllers) has a subscriber through the router.
    let sent = loadgen::run(&publisher, &all).await.expect("loadgen");
    assert_eq!(sent.unmatched_keys, 0, "{sent:?}");
    assert_eq!(sent.put_errors, 0, "{sent:?}");
    let per_controller = sent.rows_per_controller * sent.tags_per_controller as u64;
    assert_eq!(per_controller * CONTROLLERS as u64, sent.samples);

    for (http, mine, theirs) in [(http_a, &ids_a, &ids_b), (http_b, &ids_b, &ids_a)] {
        let list = until("every sample of this instance's controllers", || async {
            let (_, v) = get_json(http, "/api/v1/controllers").await;
            let done = v.as_array().unwrap().iter().all(|c| c["ingested"].as_u64() == Some(per_controller));
            done.then_some(v)
        })
        .await;
        let listed: Vec<&str> = list.as_array().unwrap().iter().map(|c| c["id"].as_str().unwrap()).collect();
        assert_eq!(listed, mine.iter().map(String::as_str).collect::<Vec<_>>(), "instance on {http}");
        for c in list.as_array().unwrap() {
            // exactly once: any doubled sample would show as a duplicate, any lost one as fewer
            assert_eq!(c["ingested"].as_u64(), Some(per_controller), "{c}");
            for (reason, n) in c["dropped"].as_object().unwrap() {
                assert_eq!(n.as_u64(), Some(0), "{http}: {} dropped {n} as {reason}", c["id"]);
            }
        }
        for other in theirs {
            let (code, _) = get(http, &format!("/api/v1/controllers/{other}")).await;
            assert_eq!(code, 404, "{other} must not be known to the instance on {http}");
            let (_, m) = get(http, "/metrics").await;
            assert!(!m.contains(&format!("controller=\"{other}\"")), "{other} in the metrics of {http}");
        }
    }
    // Stay a moment longer: nothing else arrives late (e.g. a second copy through the router).
    tokio::time::sleep(Duration::from_millis(500)).await;
    for http in [http_a, http_b] {
        let (_, v) = get_json(http, "/api/v1/controllers").await;
        for c in v.as_array().unwrap() {
            assert_eq!(c["ingested"].as_u64(), Some(per_controller), "{c}");
            assert_eq!(c["dropped"]["duplicate"].as_u64(), Some(0), "{c}");
        }
    }
    let _ = publisher.close().await;
    a.stop().await;
    b.stop().await;
    let _ = router.close().await;
}
