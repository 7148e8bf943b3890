//! A storage that overflows: the input fills a first-order store (a tank, a buffer, a heated
//! mass) whose level cannot pass a limit (a rim, a relief), and only the capped level drives
//! the rest of the dynamics. Unlike an actuator limit, what is capped is the input's memory, not
//! its present value, so a long high input saturates where a short one does not.

use crate::describe::num;
use std::collections::BTreeMap;

use mpmwatch_core::numerics::quantile;

use super::{Data, Element, map_input};
use crate::candidates::{ActsOn, Physics};

/// `clamp(s, lo, hi)` of `s(t) = a·s(t−1) + (1 − a)·u(t)` (unit steady-state gain, started at
/// the first input), parameters `[a, lo, hi]`; a limit outside the store's range is inactive.
pub struct StorageLimit;

/// Poles of the store tried as starts: from a few samples to about two hundred. A limit
/// placed on a faster store's range than the fit ends on can lie beyond the slower store's,
/// where it binds on no row and has no gradient to come back by.
const POLES: [f64; 4] = [0.8, 0.93, 0.98, 0.995];

fn store(u: &[f64], a: f64, lo: f64, hi: f64) -> Vec<f64> {
    let mut s = u.first().copied().unwrap_or(0.0);
    u.iter()
        .map(|&v| {
            s = (a * s + (1.0 - a) * v).clamp(lo, hi);
            s
        })
        .collect()
}

impl Element for StorageLimit {
    fn physics(&self) -> Physics {
        Physics::Saturation
    }
    fn acts_on(&self) -> ActsOn {
        ActsOn::Input
    }
    /// Per pole of [`POLES`], an upper limit at the uncapped store's 80th and 90th training
    /// percentiles and a lower one at its 10th and 20th, the other side beyond the data.
    fn starts(&self, d: &Data<'_>, i: usize) -> Vec<Vec<f64>> {
        let (lo, hi) = (d.u_quantile(i, 0.0), d.u_quantile(i, 1.0));
        let r = (hi - lo).max(f64::MIN_POSITIVE);
        let mut out = Vec::new();
        for a in POLES {
            let s = store(d.u[i], a, f64::NEG_INFINITY, f64::INFINITY);
            let train = &s[d.train.clone()];
            for q in [0.8, 0.9] {
                out.push(vec![a, lo - r, quantile(train, q)]);
                out.push(vec![a, quantile(train, 1.0 - q), hi + r]);
            }
        }
        out
    }
    /// The store's own pole `a`: a store that never forgets is as slow as an integrator.
    fn poles(&self, p: &[f64]) -> Vec<f64> {
        vec![p[0]]
    }
    fn signals(&self, p: &[f64], u: &[&[f64]], i: usize) -> Vec<Vec<f64>> {
        let (lo, hi) = (p[1].min(p[2]), p[1].max(p[2]));
        // A pole outside [0, 1) is no store (at 1 it never forgets, below 0 it alternates):
        // the NaN makes the simulation built on it refused as diverged.
        let a = if (0.0..1.0).contains(&p[0]) { p[0] } else { f64::NAN };
        map_input(u, i, |x| store(x, a, lo, hi))
    }
    /// Where the store's level is held at a limit (the clamp returns the limit itself).
    fn acting(&self, p: &[f64], u: &[&[f64]], i: usize, _yhat: &[f64]) -> Option<Vec<bool>> {
        let (lo, hi) = (p[1].min(p[2]), p[1].max(p[2]));
        Some(store(u[i], p[0], lo, hi).iter().map(|&s| s == lo || s == hi).collect())
    }
    /// The store's level for an input held at `v`, once it has settled: the cap itself (the
    /// store has unit gain). A swept loop would show the memory too, but its shape would depend
    /// on how fast the figure's sweep runs against the fitted time constant, which the
    /// description states instead.
    fn map_at(&self, p: &[f64], _gamma: &[f64], v: f64) -> Option<f64> {
        Some(v.clamp(p[1].min(p[2]), p[1].max(p[2])))
    }
    fn describe(&self, p: &[f64], input: &str, output: &str) -> (String, BTreeMap<String, f64>) {
        let (lo, hi) = (p[1].min(p[2]), p[1].max(p[2]));
        let memory = if p[0] > 0.0 {
            format!("time constant {:.1} samples", -1.0 / p[0].ln())
        } else {
            "no memory".to_string()
        };
        (
            format!(
                "{input} fills a store ({memory}) whose level cannot leave [{}, {}], and only that level reaches {output} (a storage that overflows: a tank's rim, a relief)",
                num(lo),
                num(hi)
            ),
            BTreeMap::from([("pole".into(), p[0]), ("lower".into(), lo), ("upper".into(), hi)]),
        )
    }
}

#[cfg(test)]
mod tests {
    use super::super::{Model, Orders, fit};
    use super::*;

    /// Without limits the store is a first-order filter of unit gain: a unit step reaches
    /// `1 − aᵗ` after t samples (the closed form).
    #[test]
    fn the_store_is_a_unit_gain_first_order_filter() {
        let mut u = vec![0.0; 40];
        u[1..].fill(1.0);
        let s = store(&u, 0.9, f64::NEG_INFINITY, f64::INFINITY);
        for (t, v) in s.iter().enumerate() {
            let truth = if t == 0 { 0.0 } else { 1.0 - 0.9f64.powi(t as i32) };
            assert!((v - truth).abs() < 1e-12, "t={t}: {v} against {truth}");
        }
    }

    /// A noise-free plant with a store of pole 0.9 capped at 0.6, feeding
    /// `x(t) = 0.7 x(t−1) + 0.5 s(t−1)`, on a staircase whose long high steps fill the store to
    /// its cap and whose short ones do not: the fit recovers the pole, the cap and the linear
    /// coefficients (the simulation error is zero at the truth; 1e-3 leaves room for the
    /// forward-difference Jacobian, as in the other elements' recovery tests).
    #[test]
    fn a_noise_free_overflowing_store_is_recovered() {
        let u: Vec<f64> = (0..1500)
            .map(|t| {
                let level = ((t / 37 * 7919) % 41) as f64 / 20.0 - 1.0;
                if (t / 37) % 3 == 0 { 1.0 } else { level }
            })
            .collect();
        let s = store(&u, 0.9, f64::NEG_INFINITY, 0.6);
        assert!(s.iter().filter(|&&v| v == 0.6).count() > 100, "the cap must be active");
        let mut y = vec![0.0; u.len()];
        for t in 1..u.len() {
            y[t] = 0.7 * y[t - 1] + 0.5 * s[t - 1];
        }
        let d = Data { u: vec![&u], y: &y, train: 0..1500, nominal: None, noise_order: 0 };
        let m = Model {
            element: &StorageLimit,
            input: 0,
            orders: Orders { na: 1, nb: 1, nk: vec![1], trend: false, reading: None },
        };
        let rows: Vec<usize> = (10..1500).collect();
        let f = fit(&m, &d, &rows).unwrap();
        let upper = f.p[1].max(f.p[2]);
        assert!((f.p[0] - 0.9).abs() < 1e-3 && (upper - 0.6).abs() < 1e-3, "{f:?}");
        assert!((f.theta[0] - 0.7).abs() < 1e-3 && (f.theta[1] - 0.5).abs() < 1e-3, "{f:?}");
        // Its figure is the settled level against a held input: the input itself up to the
        // cap, the cap beyond (the fitted cap's 1e-3 carried into the map).
        let c = m.curve(&f, &d, "u", "y").unwrap();
        for &(v, w) in &c.points {
            assert!((w - v.min(0.6)).abs() < 1e-3, "{v}: {w}");
        }
    }
}
