//! A Torricelli two-tank simulation (upper tank drains into the lower one through an orifice,
//! outflow ∝ √level) that leaves the upper tank's overflow out, and its calibration on samples
//! where the measured level stays below the overflow/clip region; and the same tanks with the
//! physics the cascaded-tanks benchmark shows ([`OverflowingTanks`]), fitted on a whole record.
//! Pure.

use mpmwatch_diagnose::PhysicalModel;

/// Parameters: `dh1/dt = −k1√h1 + k4·u`, `dh2/dt = k2√h1 − k3√h2`, `y = h2 + offset`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct TwoTanks {
    /// Upper-tank outflow coefficient.
    pub k1: f64,
    /// Lower-tank inflow coefficient.
    pub k2: f64,
    /// Lower-tank outflow coefficient.
    pub k3: f64,
    /// Pump coefficient.
    pub k4: f64,
    /// Sensor offset.
    pub offset: f64,
}

impl TwoTanks {
    /// Simulates with sample time `ts` (16 Euler sub-steps per sample), both tanks started at
    /// the steady state of the first input, never overflowing.
    pub fn simulate(&self, u: &[f64], ts: f64) -> Vec<f64> {
        let u0 = u.first().copied().unwrap_or(0.0).max(0.0);
        let h1 = (self.k4 * u0 / self.k1).powi(2);
        let h2 = (self.k2 * h1.sqrt() / self.k3).powi(2);
        self.run(u, ts, [h1, h2], None).0
    }

    /// Simulates started at a measured lower-tank level `y0`, the upper tank at the level that
    /// holds the lower one steady (`k2√h1 = k3√h2`).
    pub fn simulate_from(&self, u: &[f64], ts: f64, y0: f64) -> Vec<f64> {
        self.run(u, ts, self.start_from(y0), None).0
    }

    /// As [`TwoTanks::simulate_from`], with one tank overflowing (`None`: as the nominal model),
    /// and the levels `[h1, h2]` at every sample as well as the output.
    pub fn simulate_overflowing(
        &self,
        u: &[f64],
        ts: f64,
        y0: f64,
        overflow: Option<Overflow>,
    ) -> (Vec<f64>, Vec<[f64; 2]>) {
        self.run(u, ts, self.start_from(y0), overflow)
    }

    fn start_from(&self, y0: f64) -> [f64; 2] {
        let h2 = (y0 - self.offset).max(0.0);
        [(self.k3 * h2.sqrt() / self.k2).powi(2), h2]
    }

    fn run(&self, u: &[f64], ts: f64, h: [f64; 2], overflow: Option<Overflow>) -> (Vec<f64>, Vec<[f64; 2]>) {
        self.run_with(u, ts, h, overflow.as_slice(), TORRICELLI)
    }

    /// The Euler loop behind every simulation: 16 sub-steps per sample, outflows
    /// `k·h^exponent`, every tank in `overflows` held at its rim.
    fn run_with(
        &self,
        u: &[f64],
        ts: f64,
        h: [f64; 2],
        overflows: &[Overflow],
        exponents: [f64; 2],
    ) -> (Vec<f64>, Vec<[f64; 2]>) {
        let dt = ts / 16.0;
        let [mut h1, mut h2] = h;
        let rim = |tank: usize| overflows.iter().find(|o| o.tank == tank);
        // The tank's own level cannot start above its rim.
        if let Some(o) = rim(0) {
            h1 = h1.min(o.level);
        }
        if let Some(o) = rim(1) {
            h2 = h2.min(o.level);
        }
        let outflow = |h: f64, a: f64| if a == 0.5 { h.max(0.0).sqrt() } else { h.max(0.0).powf(a) };
        let mut levels = Vec::with_capacity(u.len());
        let y = u
            .iter()
            .map(|&v| {
                levels.push([h1, h2]);
                let y = h2 + self.offset;
                for _ in 0..16 {
                    let q1 = self.k1 * outflow(h1, exponents[0]);
                    h1 = (h1 + dt * (-q1 + self.k4 * v)).max(0.0);
                    // Water above the upper tank's rim leaves it at once; the fraction `spill`
                    // of its volume falls into the lower tank, whose level it raises by the
                    // ratio of the cross-sections, A1/A2 = k2/k1 (the same orifice flow
                    // lowers h1 by q/A1 and raises h2 by q/A2).
                    let mut spilled = 0.0;
                    if let Some(o) = rim(0) {
                        let over = (h1 - o.level).max(0.0);
                        h1 -= over;
                        spilled = o.spill * over * self.k2 / self.k1;
                    }
                    h2 = (h2
                        + dt * (self.k2 * outflow(h1, exponents[0]) - self.k3 * outflow(h2, exponents[1]))
                        + spilled)
                        .max(0.0);
                    if let Some(o) = rim(1) {
                        h2 = h2.min(o.level);
                    }
                }
                y
            })
            .collect();
        (y, levels)
    }
}

/// The outflow exponents of Torricelli's law, `q = k·√h`.
pub const TORRICELLI: [f64; 2] = [0.5, 0.5];

/// One tank overflowing: its level never rises above `level`; a fraction `spill` of the water
/// that overflows the upper tank (`tank` 0) falls into the lower one (`tank` 1), whatever
/// overflows the lower tank is lost. Any other `tank` overflows nowhere.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Overflow {
    /// 0: upper tank, 1: lower tank.
    pub tank: usize,
    /// The rim, in level units of the model.
    pub level: f64,
    /// Fraction of the upper tank's overflow that reaches the lower tank.
    pub spill: f64,
}

/// The Torricelli simulation of a record made of one or more runs (each started from its own
/// measured lower-tank level), as a [`PhysicalModel`]: `diagnose` can re-run it with a tank
/// overflowing.
#[derive(Debug, Clone)]
pub struct TanksRecord {
    /// The calibrated model.
    pub model: TwoTanks,
    /// Sample time, seconds.
    pub ts: f64,
    /// Each run: its pump voltages and its measured initial level.
    pub runs: Vec<(Vec<f64>, f64)>,
}

impl TanksRecord {
    fn simulate_with(&self, overflow: Option<Overflow>) -> (Vec<f64>, Vec<[f64; 2]>) {
        let mut y = Vec::new();
        let mut h = Vec::new();
        for (u, y0) in &self.runs {
            let (a, b) = self.model.simulate_overflowing(u, self.ts, *y0, overflow);
            y.extend(a);
            h.extend(b);
        }
        (y, h)
    }
}

impl PhysicalModel for TanksRecord {
    fn state_names(&self) -> Vec<String> {
        vec!["upper tank level".into(), "lower tank level".into()]
    }

    fn simulate(&self) -> Vec<f64> {
        self.simulate_with(None).0
    }

    fn state_trajectories(&self) -> Vec<Vec<f64>> {
        let h = self.simulate_with(None).1;
        (0..2).map(|k| h.iter().map(|x| x[k]).collect()).collect()
    }

    fn can_spill(&self, state: usize) -> bool {
        state == 0
    }

    fn is_measured(&self, state: usize) -> bool {
        state == 1
    }

    fn simulate_limited(&self, state: usize, level: f64, spill: f64) -> Vec<f64> {
        self.simulate_with(Some(Overflow { tank: state, level, spill })).0
    }

    fn inputs(&self) -> usize {
        1
    }

    /// The pump (the only input) `ratio` times as strong.
    fn simulate_scaled(&self, _input: usize, ratio: f64) -> Vec<f64> {
        let scaled = TanksRecord {
            runs: self.runs.iter().map(|(u, y0)| (u.iter().map(|v| v * ratio).collect(), *y0)).collect(),
            ..self.clone()
        };
        scaled.simulate_with(None).0
    }
}

/// Calibrates [`TwoTanks`] on data without overflow, and returns the simulation over the whole
/// record.
pub fn calibrate_and_simulate(u: &[f64], y: &[f64], ts: f64) -> Vec<f64> {
    calibrate(u, y, ts).simulate(u, ts)
}

/// Samples after a level at or above `0.8·max(y)` (near the top: the upper tank overflows and
/// the sensor clips at the top of its range) before which the tanks are taken to have drained
/// back to their ordinary regime: 50 samples, about three of the lower tank's time constants at
/// the benchmark's 4 s sampling.
pub const RECOVERY_SAMPLES: usize = 50;

/// The runs of samples free of overflow, each at least `min_len` long: every level below
/// `0.8·max(y)` and at least [`RECOVERY_SAMPLES`] after the last level that was not.
pub fn overflow_free_runs(y: &[f64], min_len: usize) -> Vec<std::ops::Range<usize>> {
    let ymax = y.iter().fold(f64::MIN, |a, &b| a.max(b));
    let mut runs = Vec::new();
    let mut start = 0;
    for t in 0..=y.len() {
        if t == y.len() || y[t] >= 0.8 * ymax {
            if t > start && t - start >= min_len {
                runs.push(start..t);
            }
            start = t + 1 + RECOVERY_SAMPLES;
        }
    }
    runs
}

/// The calibration of [`calibrate_and_simulate`]: on every overflow-free run of the record
/// ([`overflow_free_runs`], at least 50 samples), each simulated from the measured level at its
/// start, by simulation error ([`mpmwatch_diagnose::minimize`], the coefficients searched by
/// their logarithms). A simulation run through an overflow episode would carry the model's
/// wrong upper-tank level for minutes after it, so the episodes and their recovery are left out
/// of the calibration altogether, not just masked; using every run, not only the longest, spans
/// the widest range of levels. `u` and `y` must have the same, non-zero length; otherwise a
/// fixed model (every coefficient 0.05, no offset) comes back.
pub fn calibrate(u: &[f64], y: &[f64], ts: f64) -> TwoTanks {
    const FALLBACK: TwoTanks = TwoTanks { k1: 0.05, k2: 0.05, k3: 0.05, k4: 0.05, offset: 0.0 };
    if y.is_empty() || u.len() != y.len() {
        return FALLBACK;
    }
    let mut runs = overflow_free_runs(y, RECOVERY_SAMPLES);
    if runs.iter().map(|r| r.len()).sum::<usize>() < 100 {
        runs.clear();
        runs.push(0..y.len());
    }
    let len = runs.iter().map(|r| r.len()).sum();
    let as_model =
        |x: &[f64]| TwoTanks { k1: x[0].exp(), k2: x[1].exp(), k3: x[2].exp(), k4: x[3].exp(), offset: x[4] };
    let residual = |x: &[f64]| -> Option<Vec<f64>> {
        let p = as_model(x);
        let mut r = Vec::with_capacity(len);
        for run in &runs {
            let s = p.simulate_from(&u[run.clone()], ts, y[run.start]);
            r.extend(s.iter().zip(&y[run.clone()]).map(|(a, b)| a - b));
        }
        Some(r)
    };
    let scale = mpmwatch_core::numerics::std_dev(y, 0).max(1e-12);
    // Several starts: the time scales of the two tanks and the sensor offset span an order of
    // magnitude, and a single start stops in a poor local minimum.
    let ymin = y.iter().fold(f64::MAX, |a, &b| a.min(b));
    let mut starts = Vec::new();
    for k in [0.02f64, 0.05, 0.1] {
        for k4 in [0.02f64, 0.05, 0.1] {
            for offset in [0.0, 0.5 * ymin] {
                starts.push(vec![k.ln(), k.ln(), k.ln(), k4.ln(), offset]);
            }
        }
    }
    mpmwatch_diagnose::minimize_from(&residual, &starts, len, 1e3 * scale).map_or(FALLBACK, |x| as_model(&x))
}

/// Top of the level sensor's range, volts (in the shared CSV, 47 estimation and 37 validation
/// samples sit at exactly 10.0, 48 and 39 at 9.99 or above).
pub const SENSOR_TOP: f64 = 10.0;

/// The cascaded tanks with the physics the Torricelli nominal leaves out: the upper tank's
/// overflow (the physics `diagnose` names), the sensor's top ([`SENSOR_TOP`]), and optionally
/// the refinements of [`Refinements`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct OverflowingTanks {
    /// Outflow, pump and offset coefficients.
    pub model: TwoTanks,
    /// The upper tank's rim and the fraction of its overflow that reaches the lower tank.
    pub upper: Overflow,
    /// Outflow exponents of the upper and the lower orifice ([`TORRICELLI`] unless fitted).
    pub exponents: [f64; 2],
    /// Whether the lower tank overflows at the level the sensor reads as its top.
    pub lower_overflows: bool,
    /// The upper tank's level at the start of the record it was fitted on.
    pub h1_0: f64,
}

impl OverflowingTanks {
    /// Simulates from the upper level [`OverflowingTanks::h1_0`] and the lower level that reads
    /// `y0`; the output clipped at [`SENSOR_TOP`].
    pub fn simulate(&self, u: &[f64], ts: f64, y0: f64) -> Vec<f64> {
        let mut overflows = vec![self.upper];
        if self.lower_overflows {
            overflows.push(Overflow { tank: 1, level: SENSOR_TOP - self.model.offset, spill: 0.0 });
        }
        let h = [self.h1_0, (y0 - self.model.offset).max(0.0)];
        let (y, _) = self.model.run_with(u, ts, h, &overflows, self.exponents);
        y.into_iter().map(|v| v.min(SENSOR_TOP)).collect()
    }
}

/// Physics beyond the upper tank's overflow that [`calibrate_overflowing`] may fit. The
/// cascaded-tanks benchmark's structure (both) was chosen on its estimation record alone by
/// `scripts/tanks_structure.py` (docs/diagnose.md, "Benchmark accuracy").
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct Refinements {
    /// Each orifice's outflow exponent fitted (a real orifice is not Torricelli's ideal one).
    pub exponents: bool,
    /// The lower tank overflows at the level the sensor reads as its top: water above it is
    /// lost, so the level comes down as soon as the inflow falls, which a clipped sensor alone
    /// would not show.
    pub lower_overflow: bool,
}

/// The model with the physics the nominal leaves out, the upper tank's overflow and the
/// sensor's top ([`SENSOR_TOP`]), plus `refine`, fitted on the whole record `u`, `y` by
/// simulation error ([`mpmwatch_diagnose::minimize`]): the model's five coefficients, the rim,
/// the spill fraction, the upper tank's initial level (the lower tank's is the measured level
/// less the offset) and, with `refine.exponents`, the two exponents within [`EXPONENT_RANGE`].
/// Coefficients and the rim are searched by their logarithms and the spill fraction by its
/// logit, so that they stay positive and the fraction within (0, 1); an exponent outside its
/// range is a point the model refuses, and a negative initial level counts as 0. Started from
/// `start` (the overflow-free calibration) with the rim at 60 % and 80 % of the level the
/// start's upper tank reaches and spill fractions ¼ and ¾, and with `refine.exponents` also
/// from the fit without them (exponents ½); the fit with the least error wins. `u` and `y` must
/// have the same length; otherwise, or when empty, `start` comes back unchanged with no spill.
pub fn calibrate_overflowing(
    u: &[f64],
    y: &[f64],
    ts: f64,
    start: &TwoTanks,
    refine: Refinements,
) -> OverflowingTanks {
    let as_model = |x: &[f64]| OverflowingTanks {
        model: TwoTanks { k1: x[0].exp(), k2: x[1].exp(), k3: x[2].exp(), k4: x[3].exp(), offset: x[4] },
        upper: Overflow { tank: 0, level: x[5].exp(), spill: 1.0 / (1.0 + (-x[6]).exp()) },
        h1_0: x[7].max(0.0),
        exponents: if refine.exponents { [x[8], x[9]] } else { TORRICELLI },
        lower_overflows: refine.lower_overflow,
    };
    let residual = |x: &[f64]| -> Option<Vec<f64>> {
        let m = as_model(x);
        if m.exponents.iter().any(|a| !EXPONENT_RANGE.contains(a)) {
            return None;
        }
        Some(m.simulate(u, ts, y[0]).iter().zip(y).map(|(a, b)| a - b).collect())
    };
    let unchanged = |h1_0: f64| OverflowingTanks {
        model: *start,
        upper: Overflow { tank: 0, level: f64::INFINITY, spill: 0.0 },
        exponents: TORRICELLI,
        lower_overflows: false,
        h1_0,
    };
    if y.is_empty() || u.len() != y.len() {
        return unchanged(0.0);
    }
    let (_, h) = start.simulate_overflowing(u, ts, y[0], None);
    let top = h.iter().fold(0.0f64, |m, h| m.max(h[0]));
    let h1_0 = h.first().map_or(1.0, |h| h[0]);
    let scale = mpmwatch_core::numerics::std_dev(y, 0).max(1e-12);
    let as_start = |m: &TwoTanks, rim: f64, spill: f64, h1_0: f64| {
        let mut x0 = vec![
            m.k1.ln(),
            m.k2.ln(),
            m.k3.ln(),
            m.k4.ln(),
            m.offset,
            rim.max(1e-3).ln(),
            (spill / (1.0 - spill)).ln(),
            h1_0,
        ];
        if refine.exponents {
            x0.extend(TORRICELLI);
        }
        x0
    };
    let mut starts: Vec<Vec<f64>> = [(0.6, 0.25), (0.6, 0.75), (0.8, 0.25), (0.8, 0.75)]
        .iter()
        .map(|&(rim, spill)| as_start(start, rim * top, spill, h1_0))
        .collect();
    // With the exponents free the search has more ways to wander off from a poor start, so it
    // also starts from the Torricelli fit (a continuation: the same structure, exponents ½).
    if refine.exponents {
        let m = calibrate_overflowing(u, y, ts, start, Refinements { exponents: false, ..refine });
        starts.push(as_start(&m.model, m.upper.level, m.upper.spill.clamp(1e-3, 1.0 - 1e-3), m.h1_0));
    }
    mpmwatch_diagnose::minimize_from(&residual, &starts, y.len(), 1e3 * scale)
        .map_or_else(|| unchanged(h1_0), |x| as_model(&x))
}

/// The outflow exponents [`calibrate_overflowing`] admits: wide around Torricelli's ½ (laminar
/// flow gives 1), fixed before the benchmark was first fitted. The benchmark's upper exponent
/// ends at its top (docs/diagnose.md, "Benchmark accuracy").
pub const EXPONENT_RANGE: std::ops::RangeInclusive<f64> = 0.05..=3.0;

/// Sample time of the cascaded-tanks benchmark, seconds.
pub const BENCHMARK_TS: f64 = 4.0;

/// The cascaded-tanks benchmark as the casebook diagnoses it: the model calibrated on the
/// estimation record (`ue`, `ye`), then both records simulated, each from its own measured
/// initial level (the only recorded output the simulation sees); diagnosed as one record whose
/// tail is the validation record.
pub fn benchmark_record(ue: &[f64], ye: &[f64], uv: &[f64], yv: &[f64]) -> TanksRecord {
    TanksRecord {
        model: calibrate(ue, ye, BENCHMARK_TS),
        ts: BENCHMARK_TS,
        runs: vec![(ue.to_vec(), ye[0]), (uv.to_vec(), yv[0])],
    }
}

/// The diagnosis settings of the benchmark record, on top of `base`: the tanks answer over tens
/// of samples (time constants of minutes at 4 s), so the MI profile needs lags to 40 to see the
/// input's effect at all; 45 % held out, i.e. the validation record but its first 102 samples.
pub fn benchmark_options(base: &mpmwatch_diagnose::DiagnoseOptions) -> mpmwatch_diagnose::DiagnoseOptions {
    mpmwatch_diagnose::DiagnoseOptions {
        lags: mpmwatch_core::info::Lags { min: 1, max: 40 },
        holdout_fraction: 0.45,
        ..base.clone()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const M: TwoTanks = TwoTanks { k1: 0.052, k2: 0.043, k3: 0.047, k4: 0.049, offset: -0.8 };

    fn input() -> Vec<f64> {
        (0..600).map(|t| if (t / 100) % 2 == 0 { 6.0 } else { 1.0 }).collect()
    }

    /// Without an overflow the model is the plain Torricelli Euler step (the reference loop is the
    /// calibration's model as first written, kept here independent of `run`): equal to the bit.
    #[test]
    fn without_overflow_it_is_the_plain_torricelli_model() {
        let u = input();
        let (y, _) = M.simulate_overflowing(&u, 4.0, 3.0, None);
        let h2s = 3.0 - M.offset;
        let (mut h1, mut h2) = ((M.k3 * h2s.sqrt() / M.k2).powi(2), h2s);
        let dt = 4.0 / 16.0;
        for (t, &v) in u.iter().enumerate() {
            assert_eq!(y[t], h2 + M.offset, "sample {t}");
            for _ in 0..16 {
                let q1 = M.k1 * h1.max(0.0).sqrt();
                h1 = (h1 + dt * (-q1 + M.k4 * v)).max(0.0);
                h2 = (h2 + dt * (M.k2 * h1.sqrt() - M.k3 * h2.max(0.0).sqrt())).max(0.0);
            }
        }
        assert_eq!(y, M.simulate_from(&u, 4.0, 3.0));
    }

    /// Noise-free levels of a plant with every refinement (exponents 0.6 and 0.45; each
    /// overflow changing the output by more than 0.05 V on more than 50 samples) are fitted
    /// back from the overflow-free calibration, as on the benchmark. The structure is the
    /// plant's, so the least-squares optimum has zero error: 1 mV (0.02 % of the output's
    /// ≈ 5 V range) leaves room for the solver's stopping rule only. The parameters that do not
    /// depend on the upper level's scale must come back too: the exponents within 0.01 and the
    /// offset within 10 mV. (The upper level itself is not identifiable: `k1`, `k2`, `k4`, the
    /// rim and the initial level trade off against its scale.)
    #[test]
    fn the_overflowing_fit_recovers_a_refined_plant() {
        let steps = [2.0, 3.0, 1.4, 4.5, 2.4, 1.8, 3.3, 1.2, 2.7, 2.2];
        let u: Vec<f64> = (0..600).map(|t| steps[t / 60]).collect();
        let plant = OverflowingTanks {
            model: M,
            upper: Overflow { tank: 0, level: 8.0, spill: 0.5 },
            exponents: [0.6, 0.45],
            lower_overflows: true,
            h1_0: 3.0,
        };
        let y = plant.simulate(&u, 4.0, 3.0);
        let no_upper = OverflowingTanks { upper: Overflow { level: 1e3, ..plant.upper }, ..plant }
            .simulate(&u, 4.0, 3.0);
        let no_lower = OverflowingTanks { lower_overflows: false, ..plant }.simulate(&u, 4.0, 3.0);
        let differ = |s: &[f64]| s.iter().zip(&y).filter(|(a, b)| (*a - *b).abs() > 0.05).count();
        assert!(differ(&no_upper) > 50 && differ(&no_lower) > 50, "both overflows must act on the record");
        let start = calibrate(&u, &y, 4.0);
        let fitted =
            calibrate_overflowing(&u, &y, 4.0, &start, Refinements { exponents: true, lower_overflow: true });
        let s = fitted.simulate(&u, 4.0, y[0]);
        let rmse = (s.iter().zip(&y).map(|(a, b)| (a - b).powi(2)).sum::<f64>() / y.len() as f64).sqrt();
        assert!(rmse < 1e-3, "{rmse} V, {fitted:?}");
        assert!(
            (fitted.exponents[0] - 0.6).abs() < 0.01
                && (fitted.exponents[1] - 0.45).abs() < 0.01
                && (fitted.model.offset - M.offset).abs() < 0.01,
            "{fitted:?}"
        );
    }

    /// With a rim the upper level never exceeds it; the whole overflow falling into the lower
    /// tank keeps its level above the run where all of it is lost, and with the rim above every
    /// level reached nothing changes.
    #[test]
    fn the_upper_tank_never_rises_above_its_rim() {
        let u = input();
        let (_, h) = M.simulate_overflowing(&u, 4.0, 3.0, None);
        let top = h.iter().map(|x| x[0]).fold(0.0, f64::max);
        let rim = 0.7 * top;
        let run = |spill| M.simulate_overflowing(&u, 4.0, 3.0, Some(Overflow { tank: 0, level: rim, spill }));
        let (lost, hl) = run(0.0);
        let (kept, _) = run(1.0);
        assert!(hl.iter().all(|x| x[0] <= rim));
        assert!(kept.iter().zip(&lost).all(|(a, b)| a >= b));
        assert!(kept.iter().zip(&lost).any(|(a, b)| a > b));
        let high =
            M.simulate_overflowing(&u, 4.0, 3.0, Some(Overflow { tank: 0, level: 2.0 * top, spill: 0.5 }));
        assert_eq!(high.0, M.simulate_from(&u, 4.0, 3.0));
    }
}
