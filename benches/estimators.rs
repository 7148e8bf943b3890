//! Criterion benchmarks of the estimation core (filled in with the estimators).
fn main() {}
