//! Criterion benchmarks of the estimation core at N = 2048, k = 4 (the figures the README
//! quotes come from `mpmwatch bench`, which times the same operations without criterion).
//!
//! Run: `cargo bench --bench estimators`.

mod common;

use criterion::{Criterion, black_box, criterion_group, criterion_main};
use mpmwatch_core::info::{
    Iaaft, IaaftOptions, Lags, MiOptions, SurrogateOptions, lagged_test, mutual_information,
};

fn estimators(c: &mut Criterion) {
    let (dither, residual, continuous, mut rng) = common::estimator_data(2048);
    let opts = MiOptions::default();
    c.bench_function("ksg_binary_2048", |b| {
        b.iter(|| mutual_information(black_box(&dither), black_box(&residual), &opts).unwrap())
    });
    c.bench_function("ksg_continuous_2048", |b| {
        b.iter(|| mutual_information(black_box(&continuous), black_box(&residual), &opts).unwrap())
    });
    let generator = Iaaft::new(&residual, IaaftOptions::default()).unwrap();
    c.bench_function("iaaft_surrogate_2048", |b| b.iter(|| generator.generate(&mut rng)));
    let lags = Lags::new(1, 20).unwrap();
    let sur = SurrogateOptions::default();
    let mut group = c.benchmark_group("element");
    group.sample_size(10);
    group.bench_function("binary_20_lags_100_surrogates_2048", |b| {
        b.iter(|| lagged_test(&dither, &residual, lags, 1, &opts, &sur).unwrap())
    });
    group.finish();
}

criterion_group!(benches, estimators);
criterion_main!(benches);
