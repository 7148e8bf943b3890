//! The estimators on arbitrary doubles (NaN, infinities, subnormals, huge values, any length):
//! an error or a number, never a panic.
#![no_main]
use libfuzzer_sys::fuzz_target;
use mpmwatch_core::info::{Lags, MiOptions, SurrogateOptions, XKind, lagged_test, mutual_information};

fuzz_target!(|data: &[u8]| {
    if data.len() < 2 {
        return;
    }
    let k = 1 + (data[0] % 6) as usize;
    let kind = [XKind::Auto, XKind::Continuous, XKind::Discrete][(data[1] % 3) as usize];
    let values: Vec<f64> =
        data[2..].chunks_exact(8).map(|c| f64::from_le_bytes(c.try_into().unwrap())).collect();
    let half = values.len() / 2;
    let (x, y) = values.split_at(half);
    let opts = MiOptions { k, x_kind: kind, ..MiOptions::default() };
    let _ = mutual_information(x, &y[..half], &opts);
    let sur = SurrogateOptions { count: 3, ..SurrogateOptions::default() };
    let _ = lagged_test(x, &y[..half], Lags { min: 1, max: 2 }, 1, &opts, &sur);
});
