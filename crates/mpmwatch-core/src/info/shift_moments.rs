//! The exact mean and standard deviation of the lagged cross-correlation over every circular
//! shift a surrogate may take, by FFT.
//!
//! Why: the family test standardises each statistic by its null mean and spread. Estimated from
//! 30 calibration surrogates, a spread is off by about 13 % (1/√58), and the maximum over 20
//! noisily standardised lags needs a higher critical value than the lags themselves would: power
//! lost exactly where a linear mismatch is decided. For a circular-shift surrogate the
//! cross-correlation at every admissible shift is one circular cross-correlation per lag, so its
//! moments over the whole shift distribution cost a few FFTs and carry no sampling error.
//!
//! At shift s and lag τ the statistic is `Σ_{t∈T} (x((t+s) mod N) − x̄)(y(t+τ) − ȳ) / (|T|·σx·σy)`
//! over the used times T ([`super::LaggedPair`]); with `a_τ(t) = y(t+τ) − ȳ` on T and 0 elsewhere
//! and `b = x − x̄`, the sum is the circular cross-correlation `(a_τ ⋆ b)(s)`, the inverse FFT of
//! `conj(A_τ)·B`. The admissible shifts are those [`super::draw_shift`] accepts: inside the
//! bounds and changing more than a tenth of the samples, whose count of unchanged samples is the
//! circular autocorrelation of each level's indicator (every shift in the bounds, for a
//! continuous dither). The family test uses these moments for continuous dithers too, whose MI
//! statistics have iAAFT surrogates: given the residual, the correlation's null is still its
//! distribution over the dither's circular shifts.

use rustfft::FftPlanner;
use rustfft::num_complex::Complex64;

/// Per lag, the mean and standard deviation of the cross-correlation over the admissible shifts
/// in `bounds` (inclusive). `labels` are x's discrete levels (the shifts that leave more than 90 %
/// of them unchanged are not admissible), `None` for a continuous x (every shift in the bounds
/// is admissible: no shift reproduces a continuous series), `times` the used times, `moments`
/// the (mean, spread) of x and of y that the statistic is normalised by. Returns `None` when no
/// shift is admissible (a dither periodic in every shift), in which case the caller keeps
/// sampled moments.
pub(crate) fn ccf_shift_moments(
    x: &[f64],
    y: &[f64],
    labels: Option<&[u16]>,
    times: &[usize],
    lags: impl Iterator<Item = usize>,
    moments: [(f64, f64); 2],
    bounds: (usize, usize),
) -> Option<Vec<(f64, f64)>> {
    let n = x.len();
    let mut planner = FftPlanner::new();
    let forward = planner.plan_fft_forward(n);
    let inverse = planner.plan_fft_inverse(n);
    let spectrum = |v: &mut Vec<Complex64>| forward.process(v);
    // Unchanged samples per shift: Σ over levels of each indicator's circular autocorrelation.
    let labels = labels.unwrap_or_default();
    let levels = labels.iter().copied().max().map_or(0, |m| m as usize + 1);
    let mut same = vec![0.0; n];
    for level in 0..levels {
        let mut ind: Vec<Complex64> =
            labels.iter().map(|&l| Complex64::new(f64::from(u8::from(l as usize == level)), 0.0)).collect();
        spectrum(&mut ind);
        let mut power: Vec<Complex64> = ind.iter().map(|c| Complex64::new(c.norm_sqr(), 0.0)).collect();
        inverse.process(&mut power);
        for (s, c) in same.iter_mut().zip(&power) {
            *s += c.re / n as f64;
        }
    }
    let admissible: Vec<usize> =
        (bounds.0..=bounds.1).filter(|&s| same[s % n].round() * 10.0 < (n * 9) as f64).collect();
    if admissible.is_empty() {
        return None;
    }
    let [(mx, sx), (my, sy)] = moments;
    let mut b: Vec<Complex64> = x.iter().map(|&v| Complex64::new(v - mx, 0.0)).collect();
    spectrum(&mut b);
    let scale = 1.0 / (times.len() as f64 * sx * sy * n as f64);
    let m = admissible.len() as f64;
    Some(
        lags.map(|tau| {
            let mut a = vec![Complex64::new(0.0, 0.0); n];
            for &t in times {
                a[t] = Complex64::new(y[t + tau] - my, 0.0);
            }
            spectrum(&mut a);
            let mut c: Vec<Complex64> = a.iter().zip(&b).map(|(a, b)| a.conj() * b).collect();
            inverse.process(&mut c);
            let values = admissible.iter().map(|&s| c[s % n].re * scale);
            let (sum, sum_sq) = values.fold((0.0, 0.0), |(s, q), v| (s + v, q + v * v));
            let mean = sum / m;
            (mean, ((sum_sq / m - mean * mean).max(0.0) * m / (m - 1.0).max(1.0)).sqrt())
        })
        .collect(),
    )
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::info::significance::stream;
    use rand::Rng;

    /// A binary dither (its levels given) and a continuous one (none: every shift in the
    /// bounds is admissible), each against the statistic computed at every admissible shift.
    #[test]
    fn moments_equal_those_of_every_shift_computed_directly() {
        for continuous in [false, true] {
            check_against_direct(continuous);
        }
    }

    fn check_against_direct(continuous: bool) {
        let n = 257;
        let mut rng = stream(5, 0);
        let labels: Vec<u16> = (0..n).map(|_| u16::from(rng.random::<bool>())).collect();
        let x: Vec<f64> = if continuous {
            (0..n).map(|_| rng.random::<f64>() - 0.5).collect()
        } else {
            labels.iter().map(|&l| if l == 1 { 0.5 } else { -0.5 }).collect()
        };
        let y: Vec<f64> = (0..n).map(|_| rng.random::<f64>()).collect();
        let times: Vec<usize> = (0..n - 6).filter(|t| t % 7 != 3).collect();
        let stats = |v: &[f64]| (crate::numerics::mean(v), crate::numerics::std_dev(v, 0));
        let moments = [stats(&x), stats(&y)];
        let bounds = (30, 220);
        let levels = (!continuous).then_some(&labels[..]);
        let got = ccf_shift_moments(&x, &y, levels, &times, 1..=5, moments, bounds).unwrap();
        for (k, tau) in (1..=5).enumerate() {
            let values: Vec<f64> = (bounds.0..=bounds.1)
                .filter(|&s| (0..n).filter(|&t| x[(t + s) % n] == x[t]).count() * 10 < n * 9)
                .map(|s| {
                    let sum: f64 = times
                        .iter()
                        .map(|&t| (x[(t + s) % n] - moments[0].0) * (y[t + tau] - moments[1].0))
                        .sum();
                    sum / (times.len() as f64 * moments[0].1 * moments[1].1)
                })
                .collect();
            let (mean, std) = (crate::numerics::mean(&values), crate::numerics::std_dev(&values, 1));
            assert!(
                (got[k].0 - mean).abs() < 1e-12 && (got[k].1 - std).abs() < 1e-12,
                "lag {tau}: {:?} vs {mean} {std}",
                got[k]
            );
        }
    }

    #[test]
    fn a_dither_periodic_in_every_admissible_shift_has_no_moments() {
        let n = 40;
        let labels: Vec<u16> = (0..n).map(|t| (t % 2) as u16).collect();
        let x: Vec<f64> = labels.iter().map(|&l| f64::from(l)).collect();
        let y: Vec<f64> = (0..n).map(|t| (t as f64).sin()).collect();
        let times: Vec<usize> = (0..n - 3).collect();
        assert!(
            ccf_shift_moments(&x, &y, Some(&labels), &times, 1..=3, [(0.5, 0.5), (0.0, 1.0)], (10, 10))
                .is_none()
        );
    }
}
