//! Integration tests of the mpmwatch binary and its library half: the CLI verbs, reproduce, the casebook's real recordings and physical models, and the service run as a process (restart, soak, scale-out).
//! One test binary per crate, each test file a module, so the dependencies link once.

mod accuracy;
mod cli;
#[path = "../../../mpmwatch-core/tests/it/common.rs"]
mod common;
mod diagnose_explore;
mod diagnose_paper;
mod diagnose_physical;
mod diagnose_real;
mod diagnose_report;
#[path = "../../../mpmwatch-service/tests/it/fault_support.rs"]
mod fault_support;
mod reproduce;
mod serve_process;
mod service_config;
mod service_restart;
mod service_scaleout;
mod service_soak;
#[path = "../../../mpmwatch-service/tests/it/service_support.rs"]
mod service_support;
mod shared_data;
mod sim_cli;
