//! Two tanks in cascade, the upper one overflowing at its rim: the input fills an upper tank
//! that drains with the square root of its level (Torricelli) into a lower one that drains the
//! same way, and the lower tank's level drives the rest of the dynamics (a level sensor, or a
//! process fed from that level). The process industries' level loops, and the cascaded-tanks
//! benchmark. Unlike [`super::draining_tank`], which passes the upper tank's outflow on, what
//! is measured here goes with the square of the flow through the plant, so a linear part
//! after the upper tank alone cannot follow it across a range of flows.

use crate::describe::num;
use std::collections::BTreeMap;

use mpmwatch_core::numerics::quantile;

use super::draining_tank::{SUBSTEPS, TAUS, drain, k_for};
use super::{Data, Element, map_input};
use crate::candidates::{ActsOn, Physics};

/// `h₂(t)`, the lower tank's level, from `h₁ ← clamp(h₁ + u − k₁√h₁, 0, rim)` and
/// `h₂ ← max(h₂ + k₁√h₁ − k₂√h₂, 0)`, both started settled at the first inflow; parameters
/// `[ū, k₁, rim, k₂]`, `ū` the mean training inflow (fixed; it only places the poles the
/// settling rule reads). Tried only on an input that never goes negative on the training rows.
pub struct CascadedTanks;

/// The two levels per sample from inflow `u`, the spilled part of the upper tank lost; NaN
/// throughout for an orifice or rim that is not positive, which is no tank (a simulation built
/// on it is refused as diverged).
fn levels(u: &[f64], k1: f64, rim: f64, k2: f64) -> (Vec<f64>, Vec<f64>) {
    if !(k1 > 0.0 && k2 > 0.0 && rim > 0.0) {
        return (vec![f64::NAN; u.len()], vec![f64::NAN; u.len()]);
    }
    let first = u.first().copied().unwrap_or(0.0).max(0.0);
    let mut h1 = (first / k1).powi(2).min(rim);
    let mut h2 = (k1 * h1.sqrt() / k2).powi(2);
    let mut upper = Vec::with_capacity(u.len());
    let mut lower = Vec::with_capacity(u.len());
    for &v in u {
        for _ in 0..SUBSTEPS {
            let q1 = k1 * h1.max(0.0).sqrt();
            h1 = drain(h1, v, k1, rim);
            h2 = drain(h2, q1, k2, f64::INFINITY);
        }
        upper.push(h1);
        lower.push(h2);
    }
    (upper, lower)
}

/// Time-constant pairs (samples at the mean inflow, upper then lower) tried as starts: equal
/// tanks at each of [`TAUS`]' three slower values, and one much slower than the other each way.
fn tau_pairs() -> [(f64, f64); 5] {
    let [_, fast, mid, slow] = TAUS;
    [(fast, fast), (mid, mid), (slow, slow), (mid, slow), (slow, mid)]
}

impl Element for CascadedTanks {
    fn physics(&self) -> Physics {
        Physics::Saturation
    }
    fn acts_on(&self) -> ActsOn {
        ActsOn::Input
    }
    /// An inflow: never negative on the training rows, and not always zero.
    fn identifiable(&self, d: &Data<'_>, i: usize) -> bool {
        d.u_quantile(i, 0.0) >= 0.0 && d.u_quantile(i, 1.0) > 0.0
    }
    /// Per pair of [`tau_pairs`], a rim at the unbounded upper tank's 80th and 90th training
    /// percentiles of level.
    fn starts(&self, d: &Data<'_>, i: usize) -> Vec<Vec<f64>> {
        let train = &d.u[i][d.train.clone()];
        // Positive: `identifiable` admits only an inflow that is never negative and not always
        // zero.
        let mean = train.iter().sum::<f64>() / train.len().max(1) as f64;
        let mut out = Vec::new();
        for (tau1, tau2) in tau_pairs() {
            let (k1, k2) = (k_for(mean, tau1), k_for(mean, tau2));
            let (h, _) = levels(d.u[i], k1, f64::INFINITY, k2);
            for q in [0.8, 0.9] {
                out.push(vec![mean, k1, quantile(&h[d.train.clone()], q), k2]);
            }
        }
        out
    }
    fn fixed(&self) -> usize {
        1
    }
    /// Each tank's pole at the mean inflow, `exp(−k²/(2ū))`; fuller tanks are slower, as for
    /// [`super::draining_tank::DrainingTank`].
    fn poles(&self, p: &[f64]) -> Vec<f64> {
        [p[1], p[3]].iter().map(|k| (-k * k / (2.0 * p[0])).exp()).collect()
    }
    fn signals(&self, p: &[f64], u: &[&[f64]], i: usize) -> Vec<Vec<f64>> {
        map_input(u, i, |x| levels(x, p[1], p[2], p[3]).1)
    }
    /// Where the upper tank stands at its rim.
    fn acting(&self, p: &[f64], u: &[&[f64]], i: usize, _yhat: &[f64]) -> Option<Vec<bool>> {
        Some(levels(u[i], p[1], p[2], p[3]).0.iter().map(|&h| h >= p[2]).collect())
    }
    /// The lower tank's settled level for an inflow held at `v`: `(q/k₂)²`, `q` the inflow up
    /// to the upper tank's outflow at its rim, `k₁·√rim`.
    fn map_at(&self, p: &[f64], _gamma: &[f64], v: f64) -> Option<f64> {
        let q = v.max(0.0).min(p[1] * p[2].max(0.0).sqrt());
        Some((q / p[3]).powi(2))
    }
    fn describe(&self, p: &[f64], input: &str, output: &str) -> (String, BTreeMap<String, f64>) {
        let (mean, k1, rim, k2) = (p[0], p[1], p[2], p[3]);
        let (tau1, tau2) = (2.0 * mean / (k1 * k1), 2.0 * mean / (k2 * k2));
        let cap = k1 * rim.max(0.0).sqrt();
        (
            format!(
                "{input} fills a tank that drains with the square root of its level into a second such tank, whose level drives {output} (time constants {:.1} and {:.1} samples at the mean inflow, longer when fuller); the first overflows above a level of {}, so no more than {} of {input} flows on (two tanks in cascade, the upper one overflowing)",
                tau1,
                tau2,
                num(rim),
                num(cap)
            ),
            BTreeMap::from([
                ("upper_orifice".into(), k1),
                ("rim_level".into(), rim),
                ("max_outflow".into(), cap),
                ("lower_orifice".into(), k2),
                ("upper_time_constant_samples".into(), tau1),
                ("lower_time_constant_samples".into(), tau2),
            ]),
        )
    }
}

#[cfg(test)]
mod tests {
    use super::super::{Model, Orders, fit};
    use super::*;

    /// An inflow held at `v` settles the lower tank at `(v/k₂)²`, the upper at `(v/k₁)²`; past
    /// the rim the upper holds at the rim and the lower settles at `(k₁√rim/k₂)²` (closed
    /// forms). Both time constants at the new inflow are `2v/k²`, at most 50 samples here, so
    /// 3000 samples are 60 of the slower and the start is forgotten far below the 1e-6 asserted.
    #[test]
    fn a_held_inflow_settles_both_levels_or_spills() {
        let (k1, k2) = (0.2, 0.1);
        let step = |v: f64| -> Vec<f64> { (0..3000).map(|t| if t < 10 { 0.1 } else { v }).collect() };
        let (h1, h2) = levels(&step(0.25), k1, f64::INFINITY, k2);
        assert!((h2[0] - 1.0).abs() < 1e-12, "started settled at 0.1: {}", h2[0]);
        assert!((h1[2999] - (0.25f64 / k1).powi(2)).abs() < 1e-6, "{}", h1[2999]);
        assert!((h2[2999] - (0.25f64 / k2).powi(2)).abs() < 1e-6, "{}", h2[2999]);
        let (h1, h2) = levels(&step(0.25), k1, 1.0, k2);
        assert!((h1[2999] - 1.0).abs() < 1e-12, "{}", h1[2999]);
        assert!((h2[2999] - (k1 / k2).powi(2)).abs() < 1e-6, "{}", h2[2999]);
        let p = [0.25, k1, 1.0, k2];
        assert_eq!(CascadedTanks.map_at(&p, &[], 0.25), Some((k1 / k2).powi(2)));
        assert_eq!(CascadedTanks.map_at(&p, &[], 0.1), Some(1.0));
    }

    /// The settling rule reads one pole per tank, `exp(−k²/(2ū))` (orifices 0.2 and 0.1 at a
    /// mean inflow of 0.5: time constants of 25 and 100 samples), and the element acts where
    /// the upper tank stands at its rim: on a held inflow of 0.5 past a rim of 4 (below the
    /// unbounded level of 6.25) from the first sample on, below a rim of 7 nowhere.
    #[test]
    fn one_pole_per_tank_and_the_rim_acts_where_the_upper_tank_spills() {
        let poles = CascadedTanks.poles(&[0.5, 0.2, 4.0, 0.1]);
        assert!((poles[0] - (-1.0f64 / 25.0).exp()).abs() < 1e-12, "{poles:?}");
        assert!((poles[1] - (-1.0f64 / 100.0).exp()).abs() < 1e-12, "{poles:?}");
        let u = vec![0.5; 200];
        let at = |rim: f64| CascadedTanks.acting(&[0.5, 0.2, rim, 0.1], &[&u], 0, &[]).unwrap();
        assert!(at(4.0).iter().all(|&a| a));
        assert!(at(7.0).iter().all(|&a| !a));
    }

    /// A noise-free cascade (orifices 0.3 and 0.2, rim 4, so at most 0.6 flows on) read as
    /// `y(t) = 0.5·h₂(t−1) + 1`, on a staircase of inflows in [0.1, 1.3] whose high steps
    /// spill: the fit recovers both orifices, the rim and the linear coefficients (zero error
    /// at the truth; 1e-3 leaves room for the forward-difference Jacobian, as in the other
    /// elements' recovery tests).
    #[test]
    fn a_noise_free_cascade_is_recovered() {
        let u: Vec<f64> = (0..1500).map(|t| 0.1 + ((t / 60 * 7919) % 13) as f64 / 10.0).collect();
        let (h1, h2) = levels(&u, 0.3, 4.0, 0.2);
        assert!(h1.iter().filter(|&&h| h >= 4.0).count() > 100, "the rim must be reached");
        let mut y = vec![1.0; u.len()];
        for t in 1..u.len() {
            y[t] = 0.5 * h2[t - 1] + 1.0;
        }
        let d = Data { u: vec![&u], y: &y, train: 0..1500, nominal: None, noise_order: 0 };
        let m = Model {
            element: &CascadedTanks,
            input: 0,
            orders: Orders { na: 0, nb: 1, nk: vec![1], trend: false },
        };
        let rows: Vec<usize> = (10..1500).collect();
        let f = fit(&m, &d, &rows).unwrap();
        assert!((f.p[1] - 0.3).abs() < 1e-3 && (f.p[2] - 4.0).abs() < 1e-2, "{f:?}");
        assert!((f.p[3] - 0.2).abs() < 1e-3, "{f:?}");
        assert!((f.theta[0] - 0.5).abs() < 1e-3, "{f:?}");
    }
}
