//! The config parser and validator on arbitrary text: a config or an error naming the problem,
//! never a panic; a config that validates builds its controllers (nominal models included).
#![no_main]
use libfuzzer_sys::fuzz_target;
use mpmwatch_service::config::Config;
use mpmwatch_service::Controller;

fuzz_target!(|data: &[u8]| {
    let Ok(text) = std::str::from_utf8(data) else { return };
    match text.parse::<Config>() {
        Ok(cfg) => {
            // A validated config must never fail (or panic) later, at start.
            for c in &cfg.controllers {
                Controller::new(c.clone()).expect("a validated controller builds");
            }
            let _ = cfg.http.resolve_token(|_| None);
            let _ = format!("{cfg:?}");
        }
        Err(e) => assert!(!e.to_string().is_empty()),
    }
});
