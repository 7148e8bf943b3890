//! Hypotheses stated by re-running a physical nominal model: a *state* that cannot rise above a
//! rim (an overflow), with part of what overflows passed on to the next state; and an input whose
//! actuator gain is off ([`gain_terms`]).
//!
//! The generic vocabulary states every hypothesis against the linear model identified from the
//! simulation ([`super::nominal`]). That is exact for a linear simulation and close for a mildly
//! nonlinear one, but an overflow inside a strongly nonlinear model (a Torricelli tank, whose
//! time constant changes with its level) is out of its reach: measured on the cascaded-tanks
//! benchmark, the linear nominal reproduces the Torricelli simulation with only 59.6 % FIT, and no
//! clip stated against it gains a point (docs/diagnose.md). When the caller can hand over the
//! model itself ([`PhysicalModel`]), each overflow hypothesis is the model re-run with the limit
//! in place, and its correction is exact: `model with limit − model`.
//!
//! Locating: a limited state is not an input→output channel, so it has its own test. The
//! statistic is the largest fraction of the (pre-whitened) residual's variance that any
//! hypothesis' correction explains, over the whole grid; its null distribution comes from the
//! same statistic with the corrections circularly shifted against the residual (each correction
//! is a function of the inputs alone, so in an open loop the shift samples independence of
//! inputs and residual while both keep their autocorrelation). The critical value is `μ + zσ`
//! of the surrogates, z = 4 as in [`super::projection`]. Open loop only: in a closed loop the inputs
//! carry the disturbance back and a shifted correction no longer samples the null.
//!
//! Pure and deterministic: the surrogates are every circular shift between a tenth and nine
//! tenths of the rows, so no seed enters.

use rustfft::FftPlanner;
use rustfft::num_complex::Complex64;

use super::candidates::Term;
use mpmwatch_core::detect::ArWhitener;
use mpmwatch_core::info::Threshold;
use mpmwatch_core::numerics::{minus_mean, quantile};

/// A nominal model that `diagnose` can re-run with one of its states limited.
///
/// The simulation it returns must be the simulated output handed to `diagnose` for the same
/// output, sample for sample (checked).
pub trait PhysicalModel: std::fmt::Debug + Sync {
    /// A name per state, for the finding's sentence ("upper tank level").
    fn state_names(&self) -> Vec<String>;
    /// The nominal simulation of the output over the whole record.
    fn simulate(&self) -> Vec<f64>;
    /// Each state's trajectory in the nominal simulation, one value per sample.
    fn state_trajectories(&self) -> Vec<Vec<f64>>;
    /// Whether what overflows `state` can flow on into another state (so that a spill fraction
    /// means something).
    fn can_spill(&self, state: usize) -> bool;
    /// Whether the output is this state as measured (a sensor on it).
    fn is_measured(&self, state: usize) -> bool;
    /// The output simulated with `state` never above `level`, the fraction `spill` of what
    /// overflows passed on.
    fn simulate_limited(&self, state: usize, level: f64, spill: f64) -> Vec<f64>;
    /// Number of inputs the model takes (the record's inputs, in the same order; checked).
    fn inputs(&self) -> usize;
    /// The output simulated with input `input` multiplied by `ratio` before the model.
    fn simulate_scaled(&self, input: usize, ratio: f64) -> Vec<f64>;
}

/// The actuator gain ratios tried through the model ([`Term::ModelGain`]).
pub const GAIN_RATIOS: [f64; 12] = [0.5, 0.6, 0.7, 0.8, 0.9, 0.95, 1.05, 1.1, 1.25, 1.5, 1.75, 2.0];

/// Every actuator-gain hypothesis of `model` on each of its inputs, with its correction
/// (`scaled − nominal`, `nominal` the model's simulation) over the whole record. A gain is the one input-side class stated through
/// the model as well: under a strongly nonlinear model (a tank's level grows with the square of
/// its inflow) a gain error is not a gain of the linear nominal, and the generic classes name it
/// something else (measured: a dead zone for a 20 % weaker pump, `crates/mpmwatch/tests/it/diagnose_physical.rs`).
pub fn gain_terms(model: &dyn PhysicalModel, nominal: &[f64]) -> Vec<(Term, Vec<f64>)> {
    let mut out = Vec::new();
    for input in 0..model.inputs() {
        for &ratio in &GAIN_RATIOS {
            let sc = model.simulate_scaled(input, ratio);
            if sc.len() != nominal.len() || sc.iter().any(|v| !v.is_finite()) {
                continue;
            }
            out.push((
                Term::ModelGain { input, ratio },
                sc.iter().zip(nominal).map(|(a, b)| a - b).collect(),
            ));
        }
    }
    out
}

/// The levels tried per state: quantiles of the state's nominal trajectory on the training rows
/// (a limit above the trajectory's maximum changes nothing).
pub const LEVEL_QUANTILES: [f64; 10] = [0.5, 0.6, 0.7, 0.75, 0.8, 0.85, 0.9, 0.95, 0.98, 0.995];

/// The spill fractions tried where a state can spill.
pub const SPILLS: [f64; 6] = [0.0, 0.2, 0.4, 0.6, 0.8, 1.0];

/// Every limit hypothesis of `model` with its correction (`limited − nominal`, `nominal` the
/// model's simulation) over the whole record; `rows` are the training rows the grid is built on.
pub fn limit_terms(
    model: &dyn PhysicalModel,
    nominal: &[f64],
    rows: std::ops::Range<usize>,
) -> Vec<(Term, Vec<f64>)> {
    let mut out = Vec::new();
    for (state, x) in model.state_trajectories().iter().enumerate() {
        let end = rows.end.min(x.len());
        if rows.start >= end {
            continue;
        }
        let mut levels: Vec<f64> =
            LEVEL_QUANTILES.iter().map(|&q| quantile(&x[rows.start..end], q)).collect();
        levels.dedup_by(|a, b| (*a - *b).abs() <= 1e-12 * b.abs().max(1.0));
        let spills_tried = model.can_spill(state);
        let spills: &[f64] = if spills_tried { &SPILLS } else { &[0.0] };
        let measured = model.is_measured(state);
        for &level in &levels {
            for &spill in spills {
                let lim = model.simulate_limited(state, level, spill);
                if lim.len() != nominal.len() || lim.iter().any(|v| !v.is_finite()) {
                    continue;
                }
                let c: Vec<f64> = lim.iter().zip(nominal).map(|(a, b)| a - b).collect();
                out.push((Term::StateLimit { state, level, spill, measured, spills: spills_tried }, c));
            }
        }
    }
    out
}

/// The locating test of the limit hypotheses of one output (see the module documentation).
#[derive(Debug, Clone, PartialEq)]
pub struct LimitTest {
    /// The largest whitened R² over the hypotheses.
    pub r2: f64,
    /// Surrogate statistics of `r2`.
    pub threshold: Threshold,
    /// `r2` above the critical value.
    pub significant: bool,
}

/// Runs the test of [`LimitTest`] on `rows` of the residual `r` with the corrections of
/// [`limit_terms`], critical value `μ + zσ` over every circular shift between a tenth and nine
/// tenths of the rows; `None` when there are too few rows or no hypothesis.
pub fn limit_test(
    r: &[f64],
    terms: &[(Term, Vec<f64>)],
    rows: std::ops::Range<usize>,
    z: f64,
) -> Option<LimitTest> {
    if rows.len() < 200 || terms.is_empty() {
        return None;
    }
    // Whitening is a filter, and a filter commutes with a circular shift (up to its few edge
    // samples), so each column is whitened once and the whitened columns are shifted.
    let w = ArWhitener::fit(&r[rows.clone()], 10);
    let wr = minus_mean(&w.apply(&r[rows.clone()]));
    let m = wr.len();
    let syy: f64 = wr.iter().map(|v| v * v).sum();
    if syy <= 0.0 {
        return None;
    }
    // Every circular cross-correlation of the whitened residual with a whitened column at once,
    // by FFT: `xc[s] = Σ_t wr[t]·c[(t + s) mod m] = IFFT(conj(FFT(wr))·FFT(c))[s]`, so the cost
    // is O(K·m log m) for K columns, not O(K·m²).
    let mut planner = FftPlanner::new();
    let forward = planner.plan_fft_forward(m);
    let inverse = planner.plan_fft_inverse(m);
    let spectrum = |x: &[f64]| -> Vec<Complex64> {
        let mut b: Vec<Complex64> = x.iter().map(|&v| Complex64::new(v, 0.0)).collect();
        forward.process(&mut b);
        b
    };
    let fr = spectrum(&wr);
    // best[s]: the largest R² over the columns at shift s.
    let mut best = vec![0.0f64; m];
    for (_, c) in terms {
        let wc = minus_mean(&w.apply(&c[rows.clone()]));
        let sxx: f64 = wc.iter().map(|v| v * v).sum();
        if sxx <= 0.0 {
            continue;
        }
        let fc = spectrum(&wc);
        let mut xc: Vec<Complex64> = fr.iter().zip(&fc).map(|(a, b)| a.conj() * b).collect();
        inverse.process(&mut xc);
        for (b, x) in best.iter_mut().zip(&xc) {
            let sxy = x.re / m as f64;
            *b = b.max(sxy * sxy / (sxx * syy));
        }
    }
    let r2 = best[0];
    // Shifts of at least a tenth of the rows each way, so that a slow correction is moved well
    // past its own correlation time; every such shift, so the critical value carries no seed.
    let sur = &best[m / 10..=m - m / 10];
    let threshold = Threshold::of(sur, z);
    Some(LimitTest { r2, significant: r2 > threshold.critical, threshold })
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::{Rng, SeedableRng};
    use rand_chacha::ChaCha8Rng;
    use rand_distr::{Distribution, StandardNormal};

    /// A staircase: random levels held for 50–150 samples (not periodic, so no shift realigns it).
    fn staircase(n: usize, seed: u64) -> Vec<f64> {
        let mut rng = ChaCha8Rng::seed_from_u64(seed);
        let mut x = Vec::new();
        while x.len() < n {
            let v: f64 = rng.random_range(-1.0..1.0);
            x.extend(std::iter::repeat_n(v, rng.random_range(50..150)));
        }
        x.truncate(n);
        x
    }

    fn term() -> Term {
        Term::StateLimit { state: 0, level: 1.0, spill: 0.0, measured: false, spills: false }
    }

    /// A residual that is an affine function of the correction: after the same whitening both
    /// are the same series up to scale, so R² = 1 (closed form), far above every shifted value.
    #[test]
    fn a_correction_that_is_the_residual_explains_all_of_it() {
        let c = staircase(2000, 3);
        let r: Vec<f64> = c.iter().map(|v| 2.0 * v + 1.0).collect();
        let t = limit_test(&r, &[(term(), c)], 0..2000, 4.0).unwrap();
        assert!((t.r2 - 1.0).abs() < 1e-9 && t.significant, "{t:?}");
    }

    /// A residual independent of the correction (slow AR(1) noise, pole 0.9): with one column,
    /// `m·R²` of two independent whitened series is close to χ²(1), and the shifts give
    /// μ ≈ 1/m, σ ≈ √2/m, so μ + 4σ ≈ 6.7/m, exceeded with probability ≈ 1 % per record. Over
    /// 20 seeded records the expected count is 0.2 and two or more false alarms have probability
    /// below 2 %; three or more, below 0.1 %.
    #[test]
    fn an_independent_residual_is_seldom_significant() {
        let c = staircase(2000, 4);
        let mut alarms = 0;
        for seed in 0..20 {
            let mut rng = ChaCha8Rng::seed_from_u64(100 + seed);
            let mut x = 0.0;
            let r: Vec<f64> = (0..2000)
                .map(|_| {
                    let e: f64 = StandardNormal.sample(&mut rng);
                    x = 0.9 * x + e;
                    x
                })
                .collect();
            let t = limit_test(&r, &[(term(), c.clone())], 0..2000, 4.0).unwrap();
            alarms += usize::from(t.significant);
        }
        assert!(alarms <= 2, "{alarms} false alarms in 20");
    }
}
