//! The time of one MI estimate at N = 2048, k = 4, as the minimum over 200 batches of 20
//! estimates: on a shared VM whose speed moves from one second to the next, the minimum is the
//! steadiest figure to compare two builds by (run both alternately; criterion's mean moves
//! with the neighbours). The data are the criterion bench's (`benches/common`, seed 1).
//!
//! Run: `cargo run --release -p mpmwatch-core --example estimate_time -- continuous|binary`.

#[path = "../benches/common/mod.rs"]
mod common;

use std::time::Instant;

use mpmwatch_core::info::{MiOptions, mutual_information};

fn main() {
    let which = std::env::args().nth(1).unwrap_or_else(|| "continuous".into());
    let (dither, residual, continuous, _) = common::estimator_data(2048);
    let x = match which.as_str() {
        "continuous" => &continuous,
        "binary" => &dither,
        other => {
            eprintln!("unknown estimate '{other}': give continuous or binary");
            std::process::exit(2);
        }
    };
    let opts = MiOptions::default();
    let mut best = f64::INFINITY;
    let mut nats = 0.0;
    for _ in 0..200 {
        let t = Instant::now();
        for _ in 0..20 {
            nats = mutual_information(std::hint::black_box(x), std::hint::black_box(&residual), &opts)
                .expect("valid data")
                .nats;
        }
        best = best.min(t.elapsed().as_secs_f64() / 20.0);
    }
    println!(
        "{which}: {:.1} µs per estimate (minimum of 200 batches of 20); estimate {nats:.6} nats",
        best * 1e6
    );
}
