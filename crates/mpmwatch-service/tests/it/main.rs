//! Integration tests of mpmwatch-service against a real zenoh session, HTTP socket and SQLite store on loopback.
//! One test binary per crate, each test file a module, so the dependencies link once.

mod fault_support;
mod service_alarm;
mod service_faults;
mod service_historian;
mod service_http;
mod service_ingest;
mod service_security;
mod service_support;
mod service_tls;
