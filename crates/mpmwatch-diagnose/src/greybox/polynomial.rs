//! A polynomial static map on an input (a Hammerstein model): power, flow or torque that goes
//! with the square or the cube of the command (a heater driven by a voltage, a valve).

use crate::describe::num;
use std::collections::BTreeMap;

use super::{Data, Element};
use crate::candidates::{ActsOn, Physics};

/// The input and its powers up to `degree` about the input's mean, each through its own
/// numerator, the powers scaled by the input's standard deviation. Its parameters, that mean and
/// standard deviation and the input's range, are taken on the rows fitted (the training part's
/// for the reported fit, a fold's in cross-validation) and kept by the fit ([`Element::fixed`],
/// [`Element::fixed_on`]): the same fitted coefficients then mean the same map on any record,
/// and the held-out tail does not shape the regressors. Beyond the range fitted each power
/// goes on along its tangent at the edge ([`power`]): a polynomial fitted on a range is not
/// known outside it, and extrapolated as a polynomial it grows without bound, while held at its
/// edge value it bends a map that goes on curving (a heater's power past the voltages the fit
/// saw) flat (docs/diagnose-history.md, stop 68). The map is linear in its coefficients.
pub struct Polynomial {
    /// 2 (quadratic) or 3 (cubic).
    pub degree: i32,
}

/// The parameters `[mean, sd, min, max]` of `x`.
pub(super) fn centring_of(x: &[f64]) -> Vec<f64> {
    let n = x.len().max(1) as f64;
    let m = x.iter().sum::<f64>() / n;
    let sd = (x.iter().map(|v| (v - m).powi(2)).sum::<f64>() / n).sqrt().max(f64::MIN_POSITIVE);
    let lo = x.iter().copied().fold(f64::INFINITY, f64::min);
    let hi = x.iter().copied().fold(f64::NEG_INFINITY, f64::max);
    vec![m, sd, lo, hi]
}

/// The parameters `[mean, sd, min, max]` of `x` on `rows`; `None` without rows (the starts'
/// training-part parameters then stay: the whole record would let the held-out tail in).
pub(super) fn centring_on(x: &[f64], rows: &[usize]) -> Option<Vec<f64>> {
    let on: Vec<f64> = rows.iter().filter_map(|&t| x.get(t).copied()).collect();
    (!on.is_empty()).then(|| centring_of(&on))
}

/// The standardised value whose power the dynamics see for an input `v`, under `p`.
pub(super) fn standardised(p: &[f64], v: f64) -> f64 {
    let (m, sd) =
        (p.first().copied().unwrap_or(0.0), p.get(1).copied().unwrap_or(1.0).max(f64::MIN_POSITIVE));
    let (lo, hi) =
        (p.get(2).copied().unwrap_or(f64::NEG_INFINITY), p.get(3).copied().unwrap_or(f64::INFINITY));
    let v = if lo <= hi { v.clamp(lo, hi) } else { v };
    (v - m) / sd
}

/// The `k`-th power of the standardised input `v` under `p` (`[mean, sd, min, max]`): inside
/// the range its power, beyond it the power at the edge plus the tangent's slope there times
/// the distance past the edge, so the map and its slope are continuous at the edge and it
/// grows no faster than the input beyond it.
pub(crate) fn power(p: &[f64], v: f64, k: i32) -> f64 {
    let (m, sd) =
        (p.first().copied().unwrap_or(0.0), p.get(1).copied().unwrap_or(1.0).max(f64::MIN_POSITIVE));
    let z = (v - m) / sd;
    let ze = standardised(p, v);
    ze.powi(k) + f64::from(k) * ze.powi(k - 1) * (z - ze)
}

impl Element for Polynomial {
    fn physics(&self) -> Physics {
        if self.degree == 2 { Physics::Quadratic } else { Physics::Cubic }
    }
    fn acts_on(&self) -> ActsOn {
        ActsOn::Input
    }
    fn starts(&self, d: &Data<'_>, i: usize) -> Vec<Vec<f64>> {
        vec![centring_of(&d.u[i][d.train.clone()])]
    }
    fn fixed(&self) -> usize {
        4
    }
    fn fixed_on(&self, d: &Data<'_>, i: usize, rows: &[usize]) -> Option<Vec<f64>> {
        centring_on(d.u[i], rows)
    }
    fn signals(&self, p: &[f64], u: &[&[f64]], i: usize) -> Vec<Vec<f64>> {
        let x = u[i];
        let mut out: Vec<Vec<f64>> = u.iter().map(|x| x.to_vec()).collect();
        for k in 2..=self.degree {
            out.push(x.iter().map(|&v| power(p, v, k)).collect());
        }
        out
    }
    /// What the dynamics see of an input `v`, in the input's units: `v` plus each power's
    /// steady-state contribution over the input's own gain (`None` when that gain is zero).
    fn map_from_gains(&self, p: &[f64], dc: &[f64], i: usize, v: f64) -> Option<f64> {
        let powers = (self.degree - 1) as usize;
        let first = dc.len().checked_sub(powers)?;
        let gain = *dc.get(i)?;
        if gain == 0.0 || !gain.is_finite() {
            return None;
        }
        Some(v + (2..=self.degree).zip(&dc[first..]).map(|(k, g)| g / gain * power(p, v, k)).sum::<f64>())
    }
    fn describe(&self, p: &[f64], input: &str, output: &str) -> (String, BTreeMap<String, f64>) {
        let what = if self.degree == 2 { "square" } else { "cube" };
        let (lo, hi) = (p.get(2).copied().unwrap_or(f64::NAN), p.get(3).copied().unwrap_or(f64::NAN));
        (
            format!(
                "{output} responds to the {what} of {input}'s deviation, not only to {input} (a static polynomial map on the input, fitted for {input} in [{}, {}] and continued along its tangent beyond it)",
                num(lo),
                num(hi)
            ),
            BTreeMap::from([("fitted_range_low".to_string(), lo), ("fitted_range_high".to_string(), hi)]),
        )
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Inside the training range the powers are those of the standardised input; beyond it
    /// they go on along their tangent at the edge, while the input itself passes unchanged.
    /// Exact up to rounding (1e-12): the tangent is `z_e^k + k z_e^(k−1) (z − z_e)`.
    #[test]
    fn powers_go_on_along_their_tangent_beyond_the_training_range() {
        let train = [-1.0, 0.0, 1.0, 2.0];
        let p = centring_of(&train);
        assert_eq!(p, vec![0.5, 1.25f64.sqrt(), -1.0, 2.0]);
        let el = Polynomial { degree: 3 };
        let u = [0.5, 2.0, 5.0, -4.0];
        let sig = el.signals(&p, &[&u], 0);
        assert_eq!(sig[0], u.to_vec());
        let z = |v: f64| (v - 0.5) / 1.25f64.sqrt();
        let tangent = |edge: f64, v: f64, k: i32| {
            z(edge).powi(k) + f64::from(k) * z(edge).powi(k - 1) * (z(v) - z(edge))
        };
        let want2 = [0.0, z(2.0).powi(2), tangent(2.0, 5.0, 2), tangent(-1.0, -4.0, 2)];
        let want3 = [0.0, z(2.0).powi(3), tangent(2.0, 5.0, 3), tangent(-1.0, -4.0, 3)];
        for (got, want) in sig[1].iter().zip(want2).chain(sig[2].iter().zip(want3)) {
            assert!((got - want).abs() < 1e-12, "{got} against {want}");
        }
        // Beyond the top the square rises with the tangent's slope 2·z(2), not the square's.
        assert!(sig[1][2] < z(5.0).powi(2) && sig[1][2] > z(2.0).powi(2));
    }
}
