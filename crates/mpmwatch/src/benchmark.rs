//! Timings of the estimation core behind `mpmwatch bench`: what one estimate, one surrogate and
//! one full 3×3 matrix cost at a given record length, on seeded synthetic data.

use std::time::Instant;

use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use rand_distr::{Distribution, StandardNormal};
use rayon::prelude::*;
use serde::Serialize;

use mpmwatch_core::detect::{MatrixOptions, Signal, analyze};
use mpmwatch_core::info::{
    Iaaft, IaaftOptions, InfoError, LaggedPair, Lags, MiOptions, SurrogateOptions, lagged_test,
    mutual_information,
};

/// What to time.
#[derive(Debug, Clone, Copy)]
pub struct BenchOptions {
    /// Record length N.
    pub n: usize,
    /// Repetitions of each single-estimate timing (the median is reported).
    pub reps: usize,
    /// Seed of the synthetic data.
    pub seed: u64,
}

impl Default for BenchOptions {
    fn default() -> Self {
        Self { n: 2048, reps: 50, seed: 1 }
    }
}

/// Measured timings, milliseconds.
#[derive(Debug, Clone, Serialize)]
pub struct BenchReport {
    /// Record length.
    pub n: usize,
    /// Neighbours.
    pub k: usize,
    /// Median time of one binary-dither (Ross path) estimate from scratch: checks, levels,
    /// sort and estimate, as a one-off call pays them.
    pub ksg_binary_ms: f64,
    /// Median time per lag of a binary-dither lag profile (lags 1–20, N pairs at every lag):
    /// the residual is sorted once and each lag only relabels it, which is how the matrix, its
    /// surrogates and the service spend their estimates.
    pub ksg_binary_per_lag_ms: f64,
    /// Median time of one continuous KSG1 estimate.
    pub ksg_continuous_ms: f64,
    /// Median time of one iAAFT surrogate of a continuous series.
    pub iaaft_ms: f64,
    /// Wall time of a 3×3 norm-of-MI matrix: binary dithers, lags 1..=20, 100 circular-shift
    /// surrogates per element, all threads.
    pub matrix_3x3_ms: f64,
    /// Wall time of `detect::analyze` on the same 3×3 data with its defaults (pairwise and
    /// joint-lag statistics, pre-whitening, partialling out the other dithers, CCF baseline):
    /// what one scheduled run of the online monitor costs.
    pub analyze_3x3_ms: f64,
    /// Rayon threads used for the matrix.
    pub threads: usize,
    /// Seed of the synthetic data.
    pub seed: u64,
}

fn median_ms(reps: usize, mut f: impl FnMut()) -> f64 {
    let mut t: Vec<f64> = (0..reps.max(1))
        .map(|_| {
            let s = Instant::now();
            f();
            s.elapsed().as_secs_f64() * 1e3
        })
        .collect();
    t.sort_by(f64::total_cmp);
    t[t.len() / 2]
}

fn ar1(rng: &mut ChaCha8Rng, n: usize, a: f64) -> Vec<f64> {
    let mut y = Vec::with_capacity(n);
    let mut prev = 0.0;
    for _ in 0..n {
        let e: f64 = StandardNormal.sample(rng);
        prev = a * prev + e;
        y.push(prev);
    }
    y
}

/// Runs every timing. `progress` is told what is being timed (for a long run on a slow machine).
pub fn run(opts: &BenchOptions, mut progress: impl FnMut(&str)) -> Result<BenchReport, InfoError> {
    let n = opts.n;
    let mut rng = ChaCha8Rng::seed_from_u64(opts.seed);
    let dithers: Vec<Vec<f64>> =
        (0..3).map(|_| (0..n).map(|_| if rng.random::<bool>() { 1.0 } else { -1.0 }).collect()).collect();
    let residuals: Vec<Vec<f64>> = (0..3)
        .map(|j| {
            let v = ar1(&mut rng, n, 0.7);
            (0..n).map(|t| v[t] + if t > 0 && j == 0 { 0.3 * dithers[0][t - 1] } else { 0.0 }).collect()
        })
        .collect();
    let continuous = ar1(&mut rng, n, 0.5);
    let mi = MiOptions::default();

    progress("one binary-dither estimate");
    let mut sink = 0.0;
    let ksg_binary_ms = median_ms(opts.reps, || {
        sink += mutual_information(&dithers[0], &residuals[0], &mi).map(|e| e.nats).unwrap_or(0.0);
    });
    progress("a binary-dither lag profile, per lag");
    let lags = Lags::new(1, 20)?;
    // N + 20 samples so that every lag has N pairs, like the one-off estimate; drawn from a
    // stream of their own, so that the timings after this one see the draws they always saw.
    let mut lag_rng = ChaCha8Rng::seed_from_u64(opts.seed);
    lag_rng.set_stream(1);
    let long_dither: Vec<f64> =
        (0..n + lags.max).map(|_| if lag_rng.random::<bool>() { 1.0 } else { -1.0 }).collect();
    let long_residual: Vec<f64> = ar1(&mut lag_rng, n + lags.max, 0.7)
        .iter()
        .enumerate()
        .map(|(t, v)| v + if t > 0 { 0.3 * long_dither[t - 1] } else { 0.0 })
        .collect();
    let pair = LaggedPair::new(&long_dither, &long_residual, lags, 1, &mi)?;
    let ksg_binary_per_lag_ms = median_ms(opts.reps, || {
        sink += pair.profile_shifted(0).iter().sum::<f64>();
    }) / lags.len() as f64;
    progress("one continuous estimate");
    let ksg_continuous_ms = median_ms(opts.reps, || {
        sink += mutual_information(&continuous, &residuals[1], &mi).map(|e| e.nats).unwrap_or(0.0);
    });
    progress("one iAAFT surrogate");
    let generator = Iaaft::new(&residuals[1], IaaftOptions::default())?;
    let iaaft_ms = median_ms(opts.reps.min(20), || {
        sink += generator.generate(&mut rng).0[0];
    });
    progress("a 3x3 matrix, 20 lags, 100 surrogates per element");
    let start = Instant::now();
    let cells: Vec<(usize, usize)> = (0..3).flat_map(|j| (0..3).map(move |i| (i, j))).collect();
    let tests = cells
        .par_iter()
        .map(|&(i, j)| {
            let sur =
                SurrogateOptions { seed: opts.seed + (3 * j + i) as u64, ..SurrogateOptions::default() };
            lagged_test(&dithers[i], &residuals[j], lags, 1, &mi, &sur)
        })
        .collect::<Result<Vec<_>, _>>()?;
    let matrix_3x3_ms = start.elapsed().as_secs_f64() * 1e3;
    sink += tests.iter().map(|t| t.norm).sum::<f64>();
    progress("the default analysis of a 3x3 loop (detect::analyze)");
    let names = ["d1", "d2", "d3", "e1", "e2", "e3"];
    let d: Vec<Signal> = (0..3).map(|i| Signal { name: names[i], values: &dithers[i] }).collect();
    let r: Vec<Signal> = (0..3).map(|j| Signal { name: names[3 + j], values: &residuals[j] }).collect();
    let start = Instant::now();
    let m = analyze(&d, &r, &MatrixOptions::default())?;
    let analyze_3x3_ms = start.elapsed().as_secs_f64() * 1e3;
    sink += m.cells.len() as f64;
    std::hint::black_box(sink);
    Ok(BenchReport {
        n,
        k: mi.k,
        ksg_binary_ms,
        ksg_binary_per_lag_ms,
        ksg_continuous_ms,
        iaaft_ms,
        matrix_3x3_ms,
        analyze_3x3_ms,
        threads: rayon::current_num_threads(),
        seed: opts.seed,
    })
}

/// The industrial-scale timing: one default analysis of a 20×40 controller.
#[derive(Debug, Clone, Serialize)]
pub struct LargeReport {
    /// MVs (dithers) and CVs (residuals).
    pub shape: (usize, usize),
    /// Record length.
    pub n: usize,
    /// Wall time of `detect::analyze` with its defaults, seconds.
    pub seconds: f64,
    /// Planted mismatches found, of three.
    pub planted_found: usize,
    /// Elements flagged that were not planted.
    pub false_elements: usize,
    /// Seed of the data.
    pub seed: u64,
}

/// A 20×40 controller: binary dithers, AR(1) residuals (poles 0.3–0.9), three planted
/// mismatches of `0.35·d(t−2) + 0.25·d(t−2)·d(t−3)` on (cv 3, mv 0), (cv 17, mv 7) and
/// (cv 31, mv 15); lags 1–20; the default analysis.
pub fn run_large(n: usize, seed: u64) -> Result<LargeReport, InfoError> {
    let (mvs, cvs) = (20, 40);
    let planted = [(3usize, 0usize), (17, 7), (31, 15)];
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let dithers: Vec<Vec<f64>> =
        (0..mvs).map(|_| (0..n).map(|_| if rng.random::<bool>() { 1.0 } else { -1.0 }).collect()).collect();
    let residuals: Vec<Vec<f64>> = (0..cvs)
        .map(|j| {
            let a = rng.random_range(0.3..0.9);
            let mut v = ar1(&mut rng, n, a);
            for &(cv, mv) in &planted {
                if cv == j {
                    let d = &dithers[mv];
                    for t in 3..n {
                        v[t] += 0.35 * d[t - 2] + 0.25 * d[t - 2] * d[t - 3];
                    }
                }
            }
            v
        })
        .collect();
    let dn: Vec<String> = (0..mvs).map(|i| format!("d{}", i + 1)).collect();
    let rn: Vec<String> = (0..cvs).map(|j| format!("e{}", j + 1)).collect();
    let d: Vec<Signal> = dithers.iter().zip(&dn).map(|(v, name)| Signal { name, values: v }).collect();
    let r: Vec<Signal> = residuals.iter().zip(&rn).map(|(v, name)| Signal { name, values: v }).collect();
    let start = Instant::now();
    let m = analyze(&d, &r, &MatrixOptions::default())?;
    let seconds = start.elapsed().as_secs_f64();
    let flagged: Vec<(usize, usize)> =
        m.cells.iter().filter(|c| c.significant).map(|c| (c.cv, c.mv)).collect();
    Ok(LargeReport {
        shape: (mvs, cvs),
        n,
        seconds,
        planted_found: planted.iter().filter(|p| flagged.contains(p)).count(),
        false_elements: flagged.iter().filter(|f| !planted.contains(f)).count(),
        seed,
    })
}

/// Why the diagnosis timing could not run.
#[derive(Debug, thiserror::Error)]
pub enum DiagnoseBenchError {
    /// The generated record.
    #[error("generating the record: {0}")]
    Sim(#[from] mpmwatch_sim::SimError),
    /// The diagnosis itself.
    #[error("diagnosing the record: {0}")]
    Diagnose(#[from] mpmwatch_diagnose::DiagnoseError),
    /// The one-thread pool.
    #[error("building a one-thread pool: {0}")]
    Pool(#[from] rayon::ThreadPoolBuildError),
}

/// One open-loop grey-box diagnosis timed on one thread and on every thread of the process.
#[derive(Debug, Clone, Serialize)]
pub struct DiagnoseTiming {
    /// The generated physical case.
    pub case: &'static str,
    /// Record length.
    pub n: usize,
    /// Seed of the case.
    pub seed: u64,
    /// Wall time on one thread, seconds.
    pub one_thread_s: f64,
    /// Threads of the process's pool.
    pub threads: usize,
    /// Wall time on every thread, seconds.
    pub all_threads_s: f64,
    /// What was named (the first finding's physics, `none` without one).
    pub named: &'static str,
    /// Whether both runs reported the same findings and held-out FITs, as they must: the
    /// candidates' scores come back in one order whichever thread fitted them.
    pub same: bool,
}

/// [`DiagnoseTiming`] for the Duffing oscillator of `mpmwatch_sim::physical_cases` at `seed`,
/// `n` samples, against its least-squares ARX nominal (the `diagnose` verb's open-loop path:
/// every element on every order set, scored by blocked cross-validation).
pub fn run_diagnosis(n: usize, seed: u64) -> Result<DiagnoseTiming, DiagnoseBenchError> {
    use mpmwatch_diagnose::{DiagnoseInput, DiagnoseOptions, diagnose};
    use mpmwatch_sim::physical_cases::{PhysicalCase, run};
    let case = PhysicalCase::Duffing;
    let r = run(case, n, seed)?;
    let time: Vec<f64> = (0..n).map(|k| k as f64).collect();
    let input = DiagnoseInput::open_loop(
        &time,
        Signal { name: "u1", values: &r.u },
        Signal { name: "y1", values: &r.y },
        &r.s,
    );
    let opts = DiagnoseOptions::default();
    let timed = || {
        let start = Instant::now();
        diagnose(&input, &opts).map(|d| (start.elapsed().as_secs_f64(), d))
    };
    let one = rayon::ThreadPoolBuilder::new().num_threads(1).build()?;
    let (one_thread_s, a) = one.install(timed)?;
    let (all_threads_s, b) = timed()?;
    let named = a.report.findings.first().map_or("none", |f| f.physics.name());
    Ok(DiagnoseTiming {
        case: case.name(),
        n,
        seed,
        one_thread_s,
        threads: rayon::current_num_threads(),
        all_threads_s,
        named,
        // Compared as JSON, where a NaN reads as `null` on both sides.
        same: serde_json::to_string(&a.report).ok() == serde_json::to_string(&b.report).ok()
            && a.corrected == b.corrected,
    })
}
