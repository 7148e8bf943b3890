//! The zenoh payload decoder and the key parser on arbitrary bytes: an error or samples, never
//! a panic; a decoded batch never holds more samples than the limit, whatever it claims; and a
//! controller fed the bytes counts every sample as accepted or dropped.
#![no_main]
use libfuzzer_sys::fuzz_target;
use mpmwatch_service::Controller;
use mpmwatch_service::payload::{self, MAX_BATCH, Role};

const CONFIG: &str = r#"
[[controller]]
id = "c1"
period = 0.5
mv = ["u1"]
dither = ["ud1"]
cv = ["y1"]
pred = ["p1"]
window = 64
min_samples = 32
lag_max = 3
tolerance = 2
"#;

fuzz_target!(|data: &[u8]| {
    if let Ok(s) = payload::decode(data) {
        assert!(s.len() <= MAX_BATCH);
        assert!(s.iter().all(|x| x.t.is_finite()));
    }
    if let Ok(key) = std::str::from_utf8(data) {
        let _ = payload::parse_key("mpm", key);
    }
    // The same bytes through a controller, twice (the second sees the state the first left).
    let cfg = mpmwatch_service::config::Config::parse(CONFIG, "fuzz").expect("config");
    let mut c = Controller::new(cfg.controllers[0].clone()).expect("controller");
    for role in [Role::Cv, Role::Cv] {
        let n = payload::decode(data).map(|s| s.len() as u64).unwrap_or(1);
        let o = c.ingest(role, "y1", data);
        let dropped: u64 = o.dropped.iter().map(|d| d.1).sum();
        assert_eq!(o.accepted + dropped, n, "every sample counted once");
        assert!(c.pending() <= 64);
    }
});
