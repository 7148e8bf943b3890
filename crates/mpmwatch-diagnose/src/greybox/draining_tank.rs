//! A tank that drains through an orifice and overflows at its rim: the input is an inflow that
//! fills a store whose outflow goes with the square root of its level (Torricelli), the level
//! cannot pass the rim, and only the outflow drives the rest of the dynamics. Unlike
//! [`super::storage_limit`], whose store forgets at one rate, this store's time constant grows
//! with its level, so a store fitted across a range of levels does not drift toward an
//! integrator to follow the slow high levels.

use crate::describe::num;
use std::collections::BTreeMap;

use mpmwatch_core::numerics::quantile;

use super::{Data, Element, map_input};
use crate::candidates::{ActsOn, Physics};

/// `q(t) = k·√h(t)`, the outflow of `h(t) = clamp(h(t−1) + u(t) − k·√h(t−1), 0, rim)` (unit
/// steady-state gain below the rim, started settled at the first inflow), parameters
/// `[ū, k, rim]`, `ū` the mean training inflow (fixed; it only places the pole the settling rule
/// reads). Tried only on an input that never goes negative on the training rows: an inflow.
pub struct DrainingTank;

/// Euler steps per sample. With `τ = 2√h/k` the store's time constant in samples, its pole per
/// step is `1 − 1/(4τ)` with four steps, positive down to τ = ¼ sample; with one step a sample
/// it would be `1 − 1/τ`, negative (an oscillating level) for any τ under a sample.
pub(super) const SUBSTEPS: usize = 4;

/// Time constants (samples) at the mean inflow tried as starts, from a few samples to several
/// hundred: a tank is often the slowest thing in a plant.
pub(super) const TAUS: [f64; 4] = [5.0, 25.0, 100.0, 400.0];

/// The tank's level per sample, from `u` (negative inflows count as none); NaN throughout for
/// an orifice or rim that is not positive, which is no tank (a simulation built on it is
/// refused as diverged).
fn levels(u: &[f64], k: f64, rim: f64) -> Vec<f64> {
    if !(k > 0.0 && rim > 0.0) {
        return vec![f64::NAN; u.len()];
    }
    let first = u.first().copied().unwrap_or(0.0).max(0.0);
    let mut h = (first / k).powi(2).min(rim);
    let dt = 1.0 / SUBSTEPS as f64;
    u.iter()
        .map(|&v| {
            for _ in 0..SUBSTEPS {
                h = (h + dt * (v.max(0.0) - k * h.max(0.0).sqrt())).clamp(0.0, rim);
            }
            h
        })
        .collect()
}

/// The outflow `k·√h` per sample.
fn outflow(u: &[f64], k: f64, rim: f64) -> Vec<f64> {
    levels(u, k, rim).iter().map(|h| k * h.sqrt()).collect()
}

/// The orifice coefficient whose time constant at inflow `u` is `tau` samples: the linearised
/// store `dh/dt = −(k/(2√h*))·δh` at `h* = (u/k)²` decays at `k²/(2u)` per sample.
pub(super) fn k_for(u: f64, tau: f64) -> f64 {
    (2.0 * u / tau).sqrt()
}

/// Whether input `i` is an inflow: never negative on the training rows, and not always zero.
/// The tanks are tried only on one.
pub(super) fn is_inflow(d: &Data<'_>, i: usize) -> bool {
    d.u_quantile(i, 0.0) >= 0.0 && d.u_quantile(i, 1.0) > 0.0
}

impl Element for DrainingTank {
    fn physics(&self) -> Physics {
        Physics::Saturation
    }
    fn acts_on(&self) -> ActsOn {
        ActsOn::Input
    }
    fn identifiable(&self, d: &Data<'_>, i: usize) -> bool {
        is_inflow(d, i)
    }
    /// Per time constant of [`TAUS`], a rim at the unbounded tank's 80th and 90th training
    /// percentiles of level.
    fn starts(&self, d: &Data<'_>, i: usize) -> Vec<Vec<f64>> {
        let train = &d.u[i][d.train.clone()];
        // Positive: `identifiable` admits only an inflow that is never negative and not always
        // zero. Were it not, the orifice would be 0 and every simulation refused as diverged.
        let mean = train.iter().sum::<f64>() / train.len().max(1) as f64;
        let mut out = Vec::new();
        for tau in TAUS {
            let k = k_for(mean, tau);
            let h = levels(d.u[i], k, f64::INFINITY);
            for q in [0.8, 0.9] {
                out.push(vec![mean, k, quantile(&h[d.train.clone()], q)]);
            }
        }
        out
    }
    fn fixed(&self) -> usize {
        1
    }
    /// The store's pole at the mean inflow, `exp(−k²/(2ū))`. Higher levels are slower still,
    /// up to `exp(−k/(2√rim))` at the rim, so a tank filled mostly low that spills now and then
    /// settles more slowly than the settling rule reads here (docs/diagnose-history.md, stop 52).
    fn poles(&self, p: &[f64]) -> Vec<f64> {
        vec![(-p[1] * p[1] / (2.0 * p[0])).exp()]
    }
    fn signals(&self, p: &[f64], u: &[&[f64]], i: usize) -> Vec<Vec<f64>> {
        map_input(u, i, |x| outflow(x, p[1], p[2]))
    }
    /// The square-root outflow bends the dynamics with or without the rim.
    fn idle_is_linear(&self) -> bool {
        false
    }
    /// Where the level stands at the rim.
    fn acting(&self, p: &[f64], u: &[&[f64]], i: usize, _yhat: &[f64]) -> Option<Vec<bool>> {
        Some(levels(u[i], p[1], p[2]).iter().map(|&h| h >= p[2]).collect())
    }
    /// The settled outflow for an inflow held at `v`: the inflow itself up to the rim's
    /// outflow `k·√rim`, that outflow beyond (the rest spills).
    fn map_at(&self, p: &[f64], _gamma: &[f64], v: f64) -> Option<f64> {
        Some(v.max(0.0).min(p[1] * p[2].max(0.0).sqrt()))
    }
    fn describe(&self, p: &[f64], input: &str, output: &str) -> (String, BTreeMap<String, f64>) {
        let (mean, k, rim) = (p[0], p[1], p[2]);
        let tau = 2.0 * mean / (k * k);
        let cap = k * rim.max(0.0).sqrt();
        (
            format!(
                "{input} fills a tank that drains with the square root of its level (time constant {:.1} samples at the mean inflow, longer when fuller) and overflows above a level of {}, so no more than {} of {input} flows on to {output} (a tank that overflows)",
                tau,
                num(rim),
                num(cap)
            ),
            BTreeMap::from([
                ("orifice".into(), k),
                ("rim_level".into(), rim),
                ("max_outflow".into(), cap),
                ("time_constant_samples".into(), tau),
            ]),
        )
    }
}

#[cfg(test)]
mod tests {
    use super::super::{Model, Orders, fit};
    use super::*;

    /// From a tank settled at an inflow of 0.1, an inflow held at `v` fills it to Torricelli's
    /// level `(v/k)²` and passes `v` on, or, past the rim, holds the level at the rim and passes
    /// `k·√rim` (closed forms). The time constant at the new inflow is `2v/k²`, 25 samples for
    /// 0.5 at k = 0.2, so 2000 samples are 80 of them and the start is forgotten to far below
    /// the 1e-9 asserted.
    #[test]
    fn a_held_inflow_settles_at_torricelli_s_level_or_spills() {
        let k = 0.2;
        let step = |v: f64| -> Vec<f64> { (0..2000).map(|t| if t < 10 { 0.1 } else { v }).collect() };
        let h = levels(&step(0.5), k, f64::INFINITY);
        assert!((h[0] - 0.25).abs() < 1e-12, "started settled at 0.1: {}", h[0]);
        assert!((h[1999] - (0.5f64 / k).powi(2)).abs() < 1e-9, "{}", h[1999]);
        let q = outflow(&step(0.5), k, 4.0);
        assert!((q[1999] - k * 2.0).abs() < 1e-12, "{}", q[1999]);
        let q = outflow(&step(0.3), k, 4.0);
        assert!((q[1999] - 0.3).abs() < 1e-9, "{}", q[1999]);
    }

    /// The time constant the starts are placed by: a small step about a settled level decays
    /// at `k²/(2u)` per sample (within 2 % for a 5 % step, the linearisation's error).
    #[test]
    fn the_store_decays_at_its_linearised_rate() {
        let (u0, tau) = (1.0, 50.0);
        let k = k_for(u0, tau);
        let mut u = vec![u0; 400];
        u[200..].fill(u0 * 1.05);
        let q = outflow(&u, k, f64::INFINITY);
        let (before, after) = (q[199], u0 * 1.05);
        let crossed = (200..400).find(|&t| (after - q[t]) < (after - before) * (-1.0f64).exp()).unwrap();
        assert!(
            ((crossed - 199) as f64 - tau).abs() < 0.02 * tau + 1.0,
            "63 % after {} samples",
            crossed - 199
        );
    }

    /// A noise-free tank of orifice 0.3 overflowing at level 9 (outflow capped at 0.9), its
    /// outflow through `x(t) = 0.8 x(t−1) + 0.4 q(t−1)`, on a staircase of inflows in
    /// [0.1, 1.3] whose high steps spill: the fit recovers the orifice, the rim and the linear
    /// coefficients (zero error at the truth; 1e-3 leaves room for the forward-difference
    /// Jacobian, as in the other elements' recovery tests).
    #[test]
    fn a_noise_free_overflowing_tank_is_recovered() {
        let u: Vec<f64> = (0..1500).map(|t| 0.1 + ((t / 60 * 7919) % 13) as f64 / 10.0).collect();
        let q = outflow(&u, 0.3, 9.0);
        assert!(q.iter().filter(|&&v| (v - 0.9).abs() < 1e-12).count() > 100, "the rim must be reached");
        let mut y = vec![0.0; u.len()];
        for t in 1..u.len() {
            y[t] = 0.8 * y[t - 1] + 0.4 * q[t - 1];
        }
        let d = Data { u: vec![&u], y: &y, train: 0..1500, nominal: None, noise_order: 0 };
        let m = Model {
            element: &DrainingTank,
            input: 0,
            orders: Orders { na: 1, nb: 1, nk: vec![1], trend: false, reading: None },
        };
        let rows: Vec<usize> = (10..1500).collect();
        let f = fit(&m, &d, &rows).unwrap();
        assert!((f.p[1] - 0.3).abs() < 1e-3 && (f.p[2] - 9.0).abs() < 1e-2, "{f:?}");
        assert!((f.theta[0] - 0.8).abs() < 1e-3 && (f.theta[1] - 0.4).abs() < 1e-3, "{f:?}");
    }
}
