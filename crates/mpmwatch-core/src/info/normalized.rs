//! Normalised mutual information on [0, 1], for reading an estimate before the surrogate test.

use super::InfoError;
use super::discrete::Levels;
use super::entropy::{kozachenko_leonenko, plug_in};
use super::estimator::MiOptions;

/// Joe's linear-correlation-like measure (eq 9), `sqrt(1 − exp(−2I))` with I in nats. For a
/// bivariate Gaussian it equals |ρ|. Negative estimates (independence plus noise) map to 0.
pub fn joe(mi_nats: f64) -> f64 {
    (1.0 - (-2.0 * mi_nats.max(0.0)).exp()).sqrt()
}

/// Estévez's normalisation (eq 10), `I / min(H(X), H(Y))`, with plug-in entropy for a discrete
/// series (X as `opts` decides; Y when it has at most `opts.max_levels` values) and
/// Kozachenko–Leonenko for a continuous one.
///
/// A differential entropy depends on the scale of the variable and can be ≤ 0, in which case
/// the ratio is meaningless: the function returns `None` then, rather than a misleading number.
pub fn estevez(mi_nats: f64, x: &[f64], y: &[f64], opts: &MiOptions) -> Result<Option<f64>, InfoError> {
    let hx = match opts.discrete_levels(x)? {
        Some(l) => plug_in(&l),
        None => kozachenko_leonenko(x, opts.k)?,
    };
    let hy = match Levels::of(y, opts.max_levels) {
        Some(l) => plug_in(&l),
        None => kozachenko_leonenko(y, opts.k)?,
    };
    let h = hx.min(hy);
    Ok((h > 0.0).then(|| mi_nats / h))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn joe_is_rho_for_gaussians() {
        for rho in [0.0f64, 0.3, 0.6, 0.9] {
            let i = -0.5 * (1.0 - rho * rho).ln();
            assert!((joe(i) - rho).abs() < 1e-12);
        }
        assert_eq!(joe(-0.01), 0.0);
    }

    #[test]
    fn estevez_of_a_copy_of_a_binary_series_is_one() {
        // I(X; X) = H(X) for a discrete X: the ratio is exactly 1 with plug-in entropies.
        let x: Vec<f64> = (0..64).map(|i| if (i * 5) % 7 < 3 { 1.0 } else { -1.0 }).collect();
        let l = Levels::of(&x, 2).unwrap();
        let h = plug_in(&l);
        let r = estevez(h, &x, &x, &MiOptions::default()).unwrap().unwrap();
        assert!((r - 1.0).abs() < 1e-12);
    }
}
