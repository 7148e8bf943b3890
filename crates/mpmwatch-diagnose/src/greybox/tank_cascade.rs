//! Two tanks in cascade that drain through orifices, the upper one overflowing at its rim: the
//! input is the inflow to the upper tank, the upper tank's outflow fills the lower one, and the
//! lower tank's level drives the rest of the dynamics. Where [`super::draining_tank`] passes the
//! upper tank's outflow on to linear dynamics, whose gain is fixed, this element keeps the lower
//! tank's Torricelli law too: its settled level goes with the square of its inflow and its time
//! constant with the level, which a linear part fitted over a range of levels cannot follow
//! when the held-out rows sit at other levels.
//!
//! Two things make it a model of the tanks rather than one more element on the linear orders:
//! the levels the record starts from are fitted, from where its first outputs put them (`u0`
//! below), and the element is also tried behind a static linear part
//! ([`Element::carries_dynamics`]), since its two stores are the dynamics (what each was worth
//! is in docs/diagnose-history.md, stops 53 and 58).

use crate::describe::num;
use std::collections::BTreeMap;

use mpmwatch_core::numerics::{least_squares_rows, quantile};

use super::draining_tank::{SUBSTEPS, TAUS, is_inflow, k_for};
use super::{Data, Element, map_input};
use crate::candidates::{ActsOn, Physics};

/// `k2²·h2(t)/ū` of the cascade `dh1/dt = u − k1·√h1` (h1 held in `[0, rim]`),
/// `dh2/dt = k1·√h1 − k2·√h2` (h2 ≥ 0), integrated in [`SUBSTEPS`] Euler steps a sample;
/// parameters `[ū, u0, k1, rim, k2]`, `ū` the mean training inflow (fixed) and `u0` the inflow
/// both tanks are settled at when the record starts. The scale makes the settled signal `u²/ū`
/// below the rim, of the input's own order, whatever the orifices. Tried only on an input that
/// never goes negative on the training rows: an inflow.
///
/// Why `u0`: a tank's time constant can be a good part of the record, so the levels it starts
/// from shape the first hundreds of samples. They are what the inputs before the record left,
/// which the record does not show; settled at some inflow is the one-parameter guess a plant at
/// rest before the record makes right. It starts where the record's first outputs put it
/// ([`starting_inflow`]) and is refined by the fit. A fold that holds out the first block has
/// no fit row that depends on it, so there it stays near that start: the first block is then
/// scored with a starting level read off its own first rows, as a linear simulation copies
/// its initial conditions from the record (those rows, unlike the linear simulation's, are not
/// trimmed from the score).
pub struct TankCascade;

/// Both tanks' levels per sample, from `u` (negative inflows count as none); NaN throughout for
/// an orifice or rim that is not positive, which is no tank.
fn levels(u: &[f64], k1: f64, rim: f64, k2: f64, u0: f64) -> Vec<(f64, f64)> {
    if !(k1 > 0.0 && k2 > 0.0 && rim > 0.0) {
        return vec![(f64::NAN, f64::NAN); u.len()];
    }
    let mut h1 = (u0.max(0.0) / k1).powi(2).min(rim);
    let mut h2 = (k1 * h1.sqrt() / k2).powi(2);
    let dt = 1.0 / SUBSTEPS as f64;
    u.iter()
        .map(|&v| {
            for _ in 0..SUBSTEPS {
                let q1 = k1 * h1.max(0.0).sqrt();
                h1 = (h1 + dt * (v.max(0.0) - q1)).clamp(0.0, rim);
                h2 = (h2 + dt * (q1 - k2 * h2.max(0.0).sqrt())).max(0.0);
            }
            (h1, h2)
        })
        .collect()
}

/// The element's signal, `k2²·h2/ū`, for `[ū, k1, rim, k2]` from tanks settled at `u0`.
fn signal(u: &[f64], [mean, k1, rim, k2]: [f64; 4], u0: f64) -> Vec<f64> {
    let scale = k2 * k2 / mean;
    levels(u, k1, rim, k2, u0).iter().map(|h| scale * h.1).collect()
}

/// The inflow the tanks were settled at when the record started, for the tanks `tanks`
/// (`[ū, k1, rim, k2]`): the one whose settled signal, `u0²/ū` whatever the orifices, reads as
/// the record's first [`STARTING_ROWS`] outputs through the scale and offset that fit the
/// training output by least squares (with the tanks started at `ū`), within the training
/// inputs' range; `ū` when the fit gives no positive scale. A reading above the upper tank's
/// spill (`k1·√rim`) is not capped there, though every inflow past it starts the tanks alike.
fn starting_inflow(d: &Data<'_>, i: usize, tanks: [f64; 4]) -> f64 {
    let (lo, hi) = (d.u_quantile(i, 0.0), d.u_quantile(i, 1.0));
    let mean = tanks[0];
    let x = signal(d.u[i], tanks, mean);
    let ones = vec![1.0; d.y.len()];
    let rows: Vec<usize> = d.train.clone().collect();
    let Some(c) = least_squares_rows(&[&x, &ones], d.y, &rows).filter(|c| c[0] > 0.0) else {
        return mean;
    };
    let first = &d.y[..STARTING_ROWS.min(d.y.len())];
    let y0 = first.iter().sum::<f64>() / first.len().max(1) as f64;
    (mean * ((y0 - c[1]) / c[0]).max(0.0)).sqrt().clamp(lo, hi)
}

/// Outputs averaged for the level the record starts at: a few, so that noise on one row does
/// not set it, and few enough that even a fast tank has hardly moved.
const STARTING_ROWS: usize = 5;

impl Element for TankCascade {
    fn physics(&self) -> Physics {
        Physics::Saturation
    }
    fn acts_on(&self) -> ActsOn {
        ActsOn::Input
    }
    fn identifiable(&self, d: &Data<'_>, i: usize) -> bool {
        is_inflow(d, i)
    }
    /// Per time constant of the single tank's [`TAUS`] (both tanks alike), a rim at the
    /// unbounded upper tank's 80th and 90th training percentiles of level, and the starting
    /// inflow [`starting_inflow`] reads for them.
    fn starts(&self, d: &Data<'_>, i: usize) -> Vec<Vec<f64>> {
        let train = &d.u[i][d.train.clone()];
        let mean = train.iter().sum::<f64>() / train.len().max(1) as f64;
        let mut out = Vec::new();
        for tau in TAUS {
            let k = k_for(mean, tau);
            let h1: Vec<f64> = levels(d.u[i], k, f64::INFINITY, k, mean).iter().map(|h| h.0).collect();
            for q in [0.8, 0.9] {
                let rim = quantile(&h1[d.train.clone()], q);
                let u0 = starting_inflow(d, i, [mean, k, rim, k]);
                out.push(vec![mean, u0, k, rim, k]);
            }
        }
        out
    }
    fn fixed(&self) -> usize {
        1
    }
    fn carries_dynamics(&self) -> bool {
        true
    }
    /// Both tanks' poles at the mean inflow, `exp(−k²/(2ū))`.
    fn poles(&self, p: &[f64]) -> Vec<f64> {
        vec![(-p[2] * p[2] / (2.0 * p[0])).exp(), (-p[4] * p[4] / (2.0 * p[0])).exp()]
    }
    fn signals(&self, p: &[f64], u: &[&[f64]], i: usize) -> Vec<Vec<f64>> {
        map_input(u, i, |x| signal(x, [p[0], p[2], p[3], p[4]], p[1]))
    }
    /// The square-root outflow bends the dynamics with or without the rim.
    fn idle_is_linear(&self) -> bool {
        false
    }
    /// Where the upper level stands at the rim.
    fn acting(&self, p: &[f64], u: &[&[f64]], i: usize, _yhat: &[f64]) -> Option<Vec<bool>> {
        Some(levels(u[i], p[2], p[3], p[4], p[1]).iter().map(|h| h.0 >= p[3]).collect())
    }
    /// The settled signal for an inflow held at `v`: `v²/ū` up to the rim's outflow `k1·√rim`,
    /// that outflow's beyond.
    fn map_at(&self, p: &[f64], _gamma: &[f64], v: f64) -> Option<f64> {
        Some(v.max(0.0).min(p[2] * p[3].max(0.0).sqrt()).powi(2) / p[0])
    }
    fn describe(&self, p: &[f64], input: &str, output: &str) -> (String, BTreeMap<String, f64>) {
        let (mean, k1, rim, k2) = (p[0], p[2], p[3], p[4]);
        let (tau1, tau2) = (2.0 * mean / (k1 * k1), 2.0 * mean / (k2 * k2));
        let cap = k1 * rim.max(0.0).sqrt();
        (
            format!(
                "{input} fills a tank that drains with the square root of its level into a second one (time constants {:.1} and {:.1} samples at the mean inflow, longer when fuller); the first overflows above a level of {}, so no more than {} of {input} flows on to {output} (a tank that overflows)",
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
                ("starting_inflow".into(), p[1]),
            ]),
        )
    }
}

#[cfg(test)]
mod tests {
    use super::super::{Model, Orders, fit};
    use super::*;

    /// From tanks settled at an inflow of 0.1, an inflow held at `v` fills the upper tank to
    /// Torricelli's level `(v/k1)²` and the lower one to `(v/k2)²`, so the signal settles at
    /// `v²/ū`; past the rim the upper level holds at the rim and the lower tank settles at
    /// `(k1·√rim/k2)²` (closed forms). The slower tank's time constant at the new inflow is
    /// `2v/k²`, 25 samples for 0.5 at k = 0.2, so 3000 samples are 120 of them and the start is
    /// forgotten to far below the 1e-9 asserted.
    #[test]
    fn a_held_inflow_settles_at_torricelli_s_levels_or_spills() {
        let (k1, k2, mean) = (0.3, 0.2, 0.4);
        let step = |v: f64| -> Vec<f64> { (0..3000).map(|t| if t < 10 { 0.1 } else { v }).collect() };
        let h = levels(&step(0.5), k1, f64::INFINITY, k2, 0.1);
        assert!((h[0].0 - (0.1f64 / k1).powi(2)).abs() < 1e-12, "started settled: {:?}", h[0]);
        assert!((h[0].1 - (0.1f64 / k2).powi(2)).abs() < 1e-12, "started settled: {:?}", h[0]);
        assert!((h[2999].0 - (0.5f64 / k1).powi(2)).abs() < 1e-9, "{:?}", h[2999]);
        assert!((h[2999].1 - (0.5f64 / k2).powi(2)).abs() < 1e-9, "{:?}", h[2999]);
        let p = [mean, 0.1, k1, 2.0, k2];
        let s = TankCascade.signals(&p, &[&step(0.3)], 0);
        assert!((s[0][2999] - 0.09 / mean).abs() < 1e-9, "{}", s[0][2999]);
        let cap = k1 * 2f64.sqrt();
        let h = levels(&step(0.5), k1, 2.0, k2, 0.1);
        assert!(
            (h[2999].0 - 2.0).abs() < 1e-12 && (h[2999].1 - (cap / k2).powi(2)).abs() < 1e-9,
            "{:?}",
            h[2999]
        );
        assert_eq!(TankCascade.map_at(&p, &[], 0.5), Some(cap * cap / mean));
        assert_eq!(TankCascade.map_at(&p, &[], 0.3), Some(0.09 / mean));
    }

    /// A noise-free cascade (orifices 0.3 and 0.25, the upper tank overflowing at level 9,
    /// both settled at an inflow of 0.7 when the record starts), read through `y = 2·s + 1`,
    /// on a staircase of inflows in [0.1, 1.3] whose high steps spill: the fit recovers the
    /// orifices, the rim and the output's scale and offset (zero error at the truth, whose
    /// starting level the first outputs give exactly; 1e-2 leaves room for the
    /// forward-difference Jacobian through two tanks, as in the other elements' recovery
    /// tests).
    #[test]
    fn a_noise_free_overflowing_cascade_is_recovered() {
        let u: Vec<f64> = (0..1500).map(|t| 0.1 + ((t / 60 * 7919) % 13) as f64 / 10.0).collect();
        let mean = u.iter().sum::<f64>() / u.len() as f64;
        let p = [mean, 0.7, 0.3, 9.0, 0.25];
        assert!(
            levels(&u, 0.3, 9.0, 0.25, 0.7).iter().filter(|h| h.0 >= 9.0).count() > 100,
            "the rim must be reached"
        );
        let s = TankCascade.signals(&p, &[&u], 0).remove(0);
        let y: Vec<f64> = s.iter().map(|v| 2.0 * v + 1.0).collect();
        let d = Data { u: vec![&u], y: &y, train: 0..1500, nominal: None, noise_order: 0 };
        let m = Model {
            element: &TankCascade,
            input: 0,
            orders: Orders { na: 0, nb: 1, nk: vec![0], trend: false, reading: None },
        };
        let rows: Vec<usize> = (10..1500).collect();
        let f = fit(&m, &d, &rows).unwrap();
        assert!((f.p[2] - 0.3).abs() < 1e-2 && (f.p[4] - 0.25).abs() < 1e-2, "{f:?}");
        assert!((f.p[3] - 9.0).abs() < 0.1, "{f:?}");
        assert!((f.theta[0] - 2.0).abs() < 1e-2 && (f.theta[1] - 1.0).abs() < 1e-2, "{f:?}");
    }
}
