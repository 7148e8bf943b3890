//! The time of one MI estimate at N = 2048, k = 4, as the minimum over 200 batches of 20
//! estimates: on a shared VM whose speed moves from one second to the next, the minimum is the
//! steadiest figure to compare two builds by (run both alternately; criterion's mean moves
//! with the neighbours). The data are the criterion bench's (`benches/common`, seed 1).
//!
//! `per-lag` times a binary-dither lag profile (lags 1–20, 2048 pairs at every lag, from
//! 2068 samples of the same kind) and divides by the lags: the residual is sorted once and each
//! lag only relabels it, as the matrix and its surrogates do.
//!
//! Run: `cargo run --release -p mpmwatch-core --example estimate_time -- continuous|binary|per-lag`.

#[path = "../benches/common/mod.rs"]
mod common;

use std::time::Instant;

use mpmwatch_core::info::{LaggedPair, Lags, MiOptions, mutual_information};

fn main() {
    let which = std::env::args().nth(1).unwrap_or_else(|| "continuous".into());
    if which == "per-lag" {
        per_lag();
        return;
    }
    let (dither, residual, continuous, _) = common::estimator_data(2048);
    let x = match which.as_str() {
        "continuous" => &continuous,
        "binary" => &dither,
        other => {
            eprintln!("unknown estimate '{other}': give continuous, binary or per-lag");
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

fn per_lag() {
    let lags = Lags::new(1, 20).expect("valid lags");
    let (dither, residual, _, _) = common::estimator_data(2048 + lags.max);
    let pair = LaggedPair::new(&dither, &residual, lags, 1, &MiOptions::default()).expect("valid data");
    let mut best = f64::INFINITY;
    let mut sum = 0.0;
    for _ in 0..200 {
        let t = Instant::now();
        sum = std::hint::black_box(&pair).profile_shifted(0).iter().sum::<f64>();
        best = best.min(t.elapsed().as_secs_f64() / lags.len() as f64);
    }
    println!("per-lag: {:.1} µs per lag (minimum of 200 profiles of 20 lags); sum {sum:.6} nats", best * 1e6);
}
