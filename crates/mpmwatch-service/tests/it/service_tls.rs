//! Zenoh over mutually authenticated TLS with access control, using the shipped examples in
//! `deploy/tls/` (only their paths and port replaced): a throwaway CA and certificates are made
//! at test time, a real TLS router runs in-process on 127.0.0.1, the service connects to it as
//! a client through `[zenoh] config_file`, and a publisher with the gateway's certificate feeds
//! it. A client without a certificate, one whose certificate another CA signed, and a plain TCP
//! client are all refused; a client with a valid certificate but an unknown name (CN) connects
//! and is silenced by the access-control rules.

use crate::service_support;

use std::path::{Path, PathBuf};
use std::time::Duration;

use crate::fault_support::*;
use mpmwatch_service::Service;
use rcgen::{
    BasicConstraints, CertificateParams, DnType, ExtendedKeyUsagePurpose, IsCa, Issuer, KeyPair,
    KeyUsagePurpose,
};
use service_support::*;

/// Writes `<name>.pem` and `<name>-key.pem`, signed by `issuer`, into `dir`.
fn leaf(dir: &Path, issuer: &Issuer<'_, KeyPair>, name: &str, sans: &[&str]) {
    let key = KeyPair::generate().unwrap();
    let mut p = CertificateParams::new(sans.iter().map(|s| s.to_string()).collect::<Vec<_>>()).unwrap();
    p.distinguished_name.push(DnType::CommonName, name);
    p.extended_key_usages = vec![ExtendedKeyUsagePurpose::ServerAuth, ExtendedKeyUsagePurpose::ClientAuth];
    p.key_usages = vec![KeyUsagePurpose::DigitalSignature, KeyUsagePurpose::KeyEncipherment];
    let cert = p.signed_by(&key, issuer).unwrap();
    std::fs::write(dir.join(format!("{name}.pem")), cert.pem()).unwrap();
    std::fs::write(dir.join(format!("{name}-key.pem")), key.serialize_pem()).unwrap();
}

/// A CA (its certificate written as `<file>`) and its issuer.
fn ca(dir: &Path, file: &str, cn: &str) -> Issuer<'static, KeyPair> {
    let key = KeyPair::generate().unwrap();
    let mut p = CertificateParams::new(Vec::<String>::new()).unwrap();
    p.is_ca = IsCa::Ca(BasicConstraints::Unconstrained);
    p.distinguished_name.push(DnType::CommonName, cn);
    p.key_usages =
        vec![KeyUsagePurpose::KeyCertSign, KeyUsagePurpose::CrlSign, KeyUsagePurpose::DigitalSignature];
    let cert = p.self_signed(&key).unwrap();
    std::fs::write(dir.join(file), cert.pem()).unwrap();
    Issuer::new(p, key)
}

/// A deploy/tls example with its paths pointing into `dir` and its endpoints at `port`.
fn example(name: &str, dir: &Path, port: u16, out: &str) -> PathBuf {
    let text =
        std::fs::read_to_string(Path::new(env!("CARGO_MANIFEST_DIR")).join("../../deploy/tls").join(name))
            .expect("deploy example");
    let d = format!("{}/", dir.display());
    let text = text
        .replace("/etc/zenoh/tls/", &d)
        .replace("/etc/mpmwatch/tls/", &d)
        .replace("/etc/historian-gw/tls/", &d)
        .replace("tls/0.0.0.0:7447", &format!("tls/127.0.0.1:{port}"))
        .replace("tls/zenoh-router.example:7447", &format!("tls/127.0.0.1:{port}"));
    let path = dir.join(out);
    std::fs::write(&path, text).unwrap();
    path
}

/// A client session from a json5 file, or the error that refused it (within a hang guard).
async fn open_file(path: &Path) -> Result<zenoh::Session, String> {
    let cfg = zenoh::Config::from_file(path).map_err(|e| e.to_string())?;
    match tokio::time::timeout(Duration::from_secs(30), zenoh::open(cfg)).await {
        Ok(r) => r.map_err(|e| e.to_string()),
        Err(_) => Err("timed out".into()),
    }
}

#[tokio::test(flavor = "multi_thread")]
async fn the_service_receives_over_mtls_and_others_are_refused() {
    // RUST_LOG=zenoh_link_tls=debug shows the handshakes when this test fails.
    let _ = tracing_subscriber::fmt()
        .with_env_filter(tracing_subscriber::EnvFilter::from_default_env())
        .with_test_writer()
        .try_init();
    let dir = std::env::temp_dir().join(format!("mpmwatch-tls-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    let issuer = ca(&dir, "ca.pem", "mpmwatch test CA");
    leaf(&dir, &issuer, "router", &["localhost", "127.0.0.1"]);
    for cn in ["mpmwatch", "historian-gw", "intruder"] {
        leaf(&dir, &issuer, cn, &[cn]);
    }
    let rogue_dir = dir.join("rogue");
    std::fs::create_dir_all(&rogue_dir).unwrap();
    let rogue = ca(&rogue_dir, "ca.pem", "another CA");
    leaf(&rogue_dir, &rogue, "historian-gw", &["historian-gw"]);
    // The router's files are named router.pem / router-key.pem in the example.
    let port = free_port();
    let router_cfg = example("zenoh-router-tls.json5", &dir, port, "router.json5");
    let router = open_file(&router_cfg).await.expect("TLS router");

    let monitor_cfg = example("zenoh-mpmwatch-tls.json5", &dir, port, "mpmwatch.json5");
    let text = config_text(0, 0, None, "every = 3600").replace("mode = \"peer\"\n", "").replace(
        "listen = [\"tcp/127.0.0.1:0\"]",
        &format!("config_file = {:?}", monitor_cfg.display().to_string()),
    );
    let service = Service::start(config(&text)).await.expect("service over TLS");
    let http = service.http_addr.port(); // bound on port 0: no other test can hold it

    // The gateway's certificate: data flows to the service over TLS.
    let publisher_cfg = example("zenoh-publisher-tls.json5", &dir, port, "publisher.json5");
    let p = open_file(&publisher_cfg).await.expect("publisher over TLS");
    wait_routed(&p, http).await;
    let mut toy = Toy::new(6);
    toy.publish(&p, 50, true).await;
    until("50 rows over TLS", || async {
        let (_, v) = get_json(http, "/api/v1/controllers/c1").await;
        (v["window_len"] == 50).then_some(())
    })
    .await;

    // No client certificate: the mTLS handshake fails and the session does not open.
    let no_cert = std::fs::read_to_string(&publisher_cfg)
        .unwrap()
        .lines()
        .filter(|l| !l.contains("connect_private_key") && !l.contains("connect_certificate"))
        .collect::<Vec<_>>()
        .join("\n")
        .replace("enable_mtls: true", "enable_mtls: false");
    let no_cert_path = dir.join("no-cert.json5");
    std::fs::write(&no_cert_path, no_cert).unwrap();
    let Err(e) = open_file(&no_cert_path).await else { panic!("a client without a certificate was let in") };
    eprintln!("no certificate: {e}");

    // A certificate with the right name from another CA: refused too.
    let rogue_cfg = std::fs::read_to_string(&publisher_cfg).unwrap().replace(
        &format!("{}/historian-gw", dir.display()),
        &format!("{}/historian-gw", rogue_dir.display()),
    );
    let rogue_path = dir.join("rogue.json5");
    std::fs::write(&rogue_path, rogue_cfg).unwrap();
    let Err(e) = open_file(&rogue_path).await else { panic!("a certificate of another CA was accepted") };
    eprintln!("other CA: {e}");

    // Plain TCP to the TLS port: refused.
    let mut c = zenoh::Config::default();
    c.insert_json5("mode", "\"client\"").unwrap();
    c.insert_json5("scouting/multicast/enabled", "false").unwrap();
    c.insert_json5("connect/endpoints", &format!("[\"tcp/127.0.0.1:{port}\"]")).unwrap();
    let plain = tokio::time::timeout(Duration::from_secs(30), zenoh::open(c)).await;
    assert!(!matches!(plain, Ok(Ok(_))), "plain TCP must not get a session");

    // A valid certificate with an unknown name: it connects, but access control drops its puts.
    let intruder_cfg = std::fs::read_to_string(&publisher_cfg).unwrap().replace("historian-gw", "intruder");
    let intruder_path = dir.join("intruder.json5");
    std::fs::write(&intruder_path, intruder_cfg).unwrap();
    let intruder = open_file(&intruder_path).await.expect("the intruder's TLS session opens");
    let (_, before) = get_json(http, "/api/v1/controllers/c1").await;
    for k in 0..20 {
        intruder.put("mpm/c1/cv/probe", format!("{{\"t\": {k}, \"v\": 0}}")).await.unwrap();
        intruder.put("mpm/c1/cv/y1", format!("{{\"t\": {}, \"v\": 0}}", 1000 + k)).await.unwrap();
        tokio::time::sleep(Duration::from_millis(100)).await;
    }
    // The gateway's next samples still arrive, and behind them nothing of the intruder's.
    toy.publish(&p, 10, true).await;
    let after = until("the gateway's next rows", || async {
        let (_, v) = get_json(http, "/api/v1/controllers/c1").await;
        (v["window_len"] == 60).then_some(v)
    })
    .await;
    assert_eq!(after["dropped"]["unknown_tag"], before["dropped"]["unknown_tag"], "{after}");
    assert_eq!(
        after["ingested"].as_u64().unwrap(),
        before["ingested"].as_u64().unwrap() + 80,
        "only the gateway's 80 samples: {after}"
    );

    let _ = intruder.close().await;
    let _ = p.close().await;
    service.stop().await;
    let _ = router.close().await;
    let _ = std::fs::remove_dir_all(&dir);
}
