//! Property tests: the public estimators never panic, whatever the input — NaN, infinities,
//! constant, tiny, huge, short — and every error names its problem; finite inputs of any scale
//! give finite estimates.

use mpmwatch_core::info::{
    InfoError, Lags, MiOptions, SurrogateOptions, XKind, lagged_profile, lagged_test, mutual_information,
};
use proptest::prelude::*;

fn any_value() -> impl Strategy<Value = f64> {
    prop_oneof![
        4 => -1e3f64..1e3,
        1 => Just(f64::NAN),
        1 => Just(f64::INFINITY),
        1 => Just(f64::NEG_INFINITY),
        1 => -1e-300f64..1e-300,
        1 => prop_oneof![Just(1e300), Just(-1e300), Just(f64::MAX), Just(f64::MIN_POSITIVE), Just(0.0)],
    ]
}

fn scale() -> impl Strategy<Value = f64> {
    prop_oneof![Just(1e-300), Just(1e-150), Just(1e-12), Just(1.0), Just(1e12), Just(1e150), Just(1e300)]
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 200, ..ProptestConfig::default() })]

    #[test]
    fn arbitrary_input_never_panics(
        x in prop::collection::vec(any_value(), 0..40),
        y in prop::collection::vec(any_value(), 0..40),
        k in 0usize..6,
        kind in prop_oneof![Just(XKind::Auto), Just(XKind::Continuous), Just(XKind::Discrete)],
    ) {
        let opts = MiOptions { k, x_kind: kind, ..MiOptions::default() };
        match mutual_information(&x, &y, &opts) {
            Ok(e) => prop_assert!(!e.nats.is_nan(), "NaN estimate for finite input"),
            Err(e) => prop_assert!(!e.to_string().is_empty()),
        }
        if let Ok(lags) = Lags::new(1, 3) {
            let _ = lagged_profile(&x, &y, lags, &opts);
            let sur = SurrogateOptions { count: 3, ..SurrogateOptions::default() };
            let _ = lagged_test(&x, &y, lags, 1, &opts, &sur);
        }
    }

    /// Continuous inputs are standardised, so the estimate does not depend on units: the same
    /// record in any scale from 1e-300 to 1e300 gives the same number (to rounding of the
    /// standardised values, far below 1e-6).
    #[test]
    fn finite_input_of_any_scale_gives_the_same_estimate(
        base in prop::collection::vec(-1.0f64..1.0, 30..60),
        noise in prop::collection::vec(-1.0f64..1.0, 60),
        sx in scale(),
        sy in scale(),
    ) {
        let n = base.len();
        let x: Vec<f64> = base.iter().map(|v| v * sx).collect();
        let y: Vec<f64> = (0..n).map(|t| (base[t] + 0.3 * noise[t]) * sy).collect();
        let reference = {
            let y1: Vec<f64> = (0..n).map(|t| base[t] + 0.3 * noise[t]).collect();
            mutual_information(&base, &y1, &MiOptions::default())
        };
        match (mutual_information(&x, &y, &MiOptions::default()), reference) {
            (Ok(e), Ok(r)) => prop_assert!(
                (e.nats - r.nats).abs() < 1e-6,
                "{} at scales {sx:e}, {sy:e} against {} at scale 1", e.nats, r.nats
            ),
            // Constant base data are constant at every scale.
            (Err(InfoError::Constant { .. }), Err(InfoError::Constant { .. })) => {}
            (a, b) => prop_assert!(false, "scaled {a:?} against unscaled {b:?}"),
        }
    }
}
