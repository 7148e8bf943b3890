//! The power study behind `mpmwatch bench --power`: how often each decision rule finds a
//! mismatch of a given shape and size, and how often it raises one where there is none.
//!
//! Cases are residual-level: two dithers and one residual, `e = v + s·f(d1)`, where `v` is
//! coloured noise driven by unit-variance innovations (so `s` is the effect's standard deviation
//! against the noise that whitening leaves), `f` one mismatch shape acting from lag L, and d2
//! never acts. Every case therefore holds one null element (d2), and the `none` family holds
//! two. The generator draws widely on purpose: noise spectra (AR(1) of either sign, resonant
//! AR(2), a near-integrating drift), lags 1–15, and for the dynamic shape a random pole.
//!
//! Three rules decide on the same analysis: the family-wise test (the default, at `alpha`), the
//! paper's 6σ recipe on the same preprocessing, and a whitened cross-correlation with a
//! Bonferroni limit over the lags at the same `alpha` (the linear baseline an engineer would
//! reach for). p-values are kept, so the false-alarm rate at other levels is read off the same
//! run.

use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use rand_distr::{Distribution, StandardNormal};
use rayon::prelude::*;
use serde::Serialize;

use mpmwatch_core::detect::{LagChoice, MatrixOptions, Method, Signal, analyze};
use mpmwatch_core::info::{InfoError, Lags, SurrogateOptions, family_wise_z};

/// How the dither is drawn.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum DitherKind {
    /// i.i.d. ±1.
    Binary,
    /// i.i.d. uniform with unit variance.
    Uniform,
}

/// The shape of the mismatch, `f(d)` before scaling.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Shape {
    /// No mismatch.
    None,
    /// `d(t−L)`.
    Linear,
    /// `d(t−L)` through a first-order lag with a random pole in 0.3–0.8.
    LinearDynamic,
    /// `d(t−L)²` (even: invisible to a correlation).
    Quadratic,
    /// A dead zone of half-width 0.5 on `d(t−L)` (odd).
    DeadZone,
    /// `d(t−L)·d(t−L−1)` (an interaction: invisible to every pairwise statistic).
    Interaction,
}

/// The noise spectrum family.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
#[serde(rename_all = "snake_case", tag = "kind")]
pub enum Noise {
    /// `v(t) = a·v(t−1) + w(t)`.
    Ar1 {
        /// The pole.
        a: f64,
    },
    /// A resonant AR(2): poles at `r·e^{±iθ}`.
    Ar2 {
        /// Pole radius.
        r: f64,
        /// Pole angle, rad/sample.
        theta: f64,
    },
}

/// One case of the study.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct Case {
    /// Shape of the mismatch.
    pub shape: Shape,
    /// Dither distribution.
    pub dither: DitherKind,
    /// Effect standard deviation over the noise innovation's.
    pub size: f64,
    /// First lag of the effect.
    pub lag: usize,
    /// Noise spectrum.
    pub noise: Noise,
    /// Pole of the first-order lag of [`Shape::LinearDynamic`] (drawn for every case).
    pub pole: f64,
    /// Seed of the case's data (and of its surrogates).
    pub seed: u64,
}

/// The study's settings.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct PowerOptions {
    /// Record length.
    pub n: usize,
    /// Lags tested (1..=max).
    pub max_lag: usize,
    /// Level of the family-wise rule and of the CCF baseline.
    pub alpha: f64,
    /// Effect sizes.
    pub sizes: Vec<f64>,
    /// Cases per (shape, size) with a binary dither.
    pub binary_cases: usize,
    /// Cases per (shape, size) with a uniform dither.
    pub uniform_cases: usize,
    /// Cases with no mismatch, binary dithers (two null elements each).
    pub binary_nulls: usize,
    /// Cases with no mismatch, uniform dithers.
    pub uniform_nulls: usize,
    /// Base seed: case c uses `seed·1_000_000 + c`.
    pub seed: u64,
}

impl Default for PowerOptions {
    fn default() -> Self {
        Self {
            n: 2048,
            max_lag: 20,
            alpha: 0.01,
            sizes: vec![0.05, 0.1, 0.2, 0.3, 0.5],
            binary_cases: 16,
            uniform_cases: 4,
            binary_nulls: 340,
            uniform_nulls: 10,
            seed: 2,
        }
    }
}

/// One element's outcome under each rule.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct Outcome {
    /// The case.
    pub case: Case,
    /// True for the element whose dither acts (d1 of a case with a shape).
    pub acts: bool,
    /// Family-wise p-value.
    pub family_p: f64,
    /// Null surrogates the family-wise test drew.
    pub family_surrogates: usize,
    /// The paper's 6σ rule.
    pub paper: bool,
    /// Largest |CCF| over the lags, whitened residual.
    pub ccf_max: f64,
    /// Samples behind the CCF (after partialling and whitening).
    pub ccf_n: usize,
}

impl Outcome {
    /// The CCF baseline's decision at `alpha` (Bonferroni over `lags`).
    pub fn ccf_at(&self, alpha: f64, lags: usize) -> bool {
        self.ccf_max > family_wise_z(alpha, lags) / (self.ccf_n as f64).sqrt()
    }
}

/// The cases of a study, in a fixed order.
pub fn cases(opts: &PowerOptions) -> Vec<Case> {
    let mut rng = ChaCha8Rng::seed_from_u64(opts.seed);
    let mut out = Vec::new();
    let mut push = |shape, dither, size, rng: &mut ChaCha8Rng| {
        let noise = match rng.random_range(0..3) {
            0 => Noise::Ar1 { a: rng.random_range(-0.5..0.95) },
            1 => Noise::Ar2 { r: rng.random_range(0.6..0.95), theta: rng.random_range(0.2..1.2) },
            _ => Noise::Ar1 { a: 0.99 },
        };
        let seed = opts.seed * 1_000_000 + out.len() as u64;
        let (lag, pole) = (rng.random_range(1..=15), rng.random_range(0.3..0.8));
        out.push(Case { shape, dither, size, lag, noise, pole, seed });
    };
    use Shape::*;
    for (dither, count, shapes) in [
        (DitherKind::Binary, opts.binary_cases, &[Linear, LinearDynamic, Interaction][..]),
        (DitherKind::Uniform, opts.uniform_cases, &[Linear, Quadratic, DeadZone, Interaction][..]),
    ] {
        for &shape in shapes {
            for &size in &opts.sizes {
                for _ in 0..count {
                    push(shape, dither, size, &mut rng);
                }
            }
        }
    }
    for (dither, count) in
        [(DitherKind::Binary, opts.binary_nulls), (DitherKind::Uniform, opts.uniform_nulls)]
    {
        for _ in 0..count {
            push(None, dither, 0.0, &mut rng);
        }
    }
    out
}

/// The two dithers and the residual of a case.
pub fn generate(case: &Case, n: usize) -> (Vec<f64>, Vec<f64>, Vec<f64>) {
    let mut rng = ChaCha8Rng::seed_from_u64(case.seed);
    let mut dither = || -> Vec<f64> {
        match case.dither {
            DitherKind::Binary => (0..n).map(|_| if rng.random::<bool>() { 1.0 } else { -1.0 }).collect(),
            DitherKind::Uniform => (0..n).map(|_| rng.random_range(-3f64.sqrt()..3f64.sqrt())).collect(),
        }
    };
    let d1 = dither();
    let d2 = dither();
    let burn = 500;
    let w: Vec<f64> = (0..n + burn).map(|_| StandardNormal.sample(&mut rng)).collect();
    let (a1, a2) = match case.noise {
        Noise::Ar1 { a } => (a, 0.0),
        Noise::Ar2 { r, theta } => (2.0 * r * theta.cos(), -r * r),
    };
    let mut v = vec![0.0; n + burn];
    for t in 2..n + burn {
        v[t] = a1 * v[t - 1] + a2 * v[t - 2] + w[t];
    }
    let v = &v[burn..];
    let f = effect(case, &d1);
    let e = v.iter().zip(&f).map(|(a, b)| a + b).collect();
    (d1, d2, e)
}

/// The mismatch's contribution to the residual: `f(d1)` scaled to standard deviation `size`.
pub fn effect(case: &Case, d1: &[f64]) -> Vec<f64> {
    let n = d1.len();
    let l = case.lag;
    let at = |t: usize, k: usize| if t >= k { d1[t - k] } else { 0.0 };
    let mut f: Vec<f64> = match case.shape {
        Shape::None => vec![0.0; n],
        Shape::Linear => (0..n).map(|t| at(t, l)).collect(),
        Shape::LinearDynamic => {
            let p = case.pole;
            let mut y = vec![0.0; n];
            for t in 0..n {
                y[t] = if t > 0 { p * y[t - 1] } else { 0.0 } + at(t, l);
            }
            y
        }
        Shape::Quadratic => (0..n).map(|t| at(t, l).powi(2)).collect(),
        Shape::DeadZone => (0..n).map(|t| at(t, l).signum() * (at(t, l).abs() - 0.5).max(0.0)).collect(),
        Shape::Interaction => (0..n).map(|t| at(t, l) * at(t, l + 1)).collect(),
    };
    let m = mpmwatch_core::numerics::mean(&f);
    let sd = mpmwatch_core::numerics::std_dev(&f, 0);
    if sd > 0.0 {
        f.iter_mut().for_each(|x| *x = case.size * (*x - m) / sd);
    }
    f
}

/// Analyses one case under the family rule and the paper's, and returns its elements.
pub fn run_case(case: &Case, opts: &PowerOptions) -> Result<[Outcome; 2], InfoError> {
    let (d1, d2, e) = generate(case, opts.n);
    let d = [Signal { name: "d1", values: &d1 }, Signal { name: "d2", values: &d2 }];
    let r = [Signal { name: "e", values: &e }];
    let base = MatrixOptions {
        lags: LagChoice::Fixed(Lags::new(1, opts.max_lag)?),
        alpha: opts.alpha,
        ccf_alpha: opts.alpha,
        surrogates: SurrogateOptions { seed: case.seed, ..SurrogateOptions::default() },
        ..MatrixOptions::default()
    };
    let family = analyze(&d, &r, &base)?;
    let paper = analyze(&d, &r, &MatrixOptions { method: Method::Paper, ..base })?;
    let outcome = |mv: usize| -> Outcome {
        let c = family.cell(mv, 0).expect("both dithers are excited");
        let ccf_max = c.ccf.values.iter().fold(0.0f64, |m, v| m.max(v.abs()));
        Outcome {
            case: *case,
            acts: mv == 0 && case.shape != Shape::None,
            family_p: c.decision.p_value,
            family_surrogates: c.family.as_ref().map_or(0, |f| f.surrogates),
            paper: paper.cell(mv, 0).is_some_and(|c| c.significant),
            ccf_max,
            ccf_n: c.ccf.n,
        }
    };
    Ok([outcome(0), outcome(1)])
}

/// Runs every case; `progress(done, total)` after each.
pub fn run(opts: &PowerOptions, progress: impl Fn(usize, usize) + Sync) -> Result<Vec<Outcome>, InfoError> {
    let all = cases(opts);
    let done = std::sync::atomic::AtomicUsize::new(0);
    let out: Vec<[Outcome; 2]> = all
        .par_iter()
        .map(|c| {
            let r = run_case(c, opts);
            progress(done.fetch_add(1, std::sync::atomic::Ordering::Relaxed) + 1, all.len());
            r
        })
        .collect::<Result<_, _>>()?;
    Ok(out.into_iter().flatten().collect())
}

/// A proportion with its 95 % Wilson interval.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct Rate {
    /// Successes.
    pub k: usize,
    /// Trials.
    pub n: usize,
    /// Lower end of the interval.
    pub low: f64,
    /// Upper end.
    pub high: f64,
}

impl Rate {
    /// `k` of `n` with Wilson's score interval at 95 %.
    pub fn of(k: usize, n: usize) -> Self {
        if n == 0 {
            return Self { k, n, low: 0.0, high: 1.0 };
        }
        let (z, nf, p) = (1.959_963_984_540_054, n as f64, k as f64 / n as f64);
        let centre = (p + z * z / (2.0 * nf)) / (1.0 + z * z / nf);
        let half = z / (1.0 + z * z / nf) * (p * (1.0 - p) / nf + z * z / (4.0 * nf * nf)).sqrt();
        Self { k, n, low: (centre - half).max(0.0), high: (centre + half).min(1.0) }
    }

    /// k / n.
    pub fn value(&self) -> f64 {
        if self.n == 0 { 0.0 } else { self.k as f64 / self.n as f64 }
    }
}

/// Detection rates of one (shape, dither, size) cell of the study.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct PowerRow {
    /// Shape.
    pub shape: Shape,
    /// Dither.
    pub dither: DitherKind,
    /// Effect size.
    pub size: f64,
    /// The family-wise rule at the study's alpha.
    pub family: Rate,
    /// The paper's 6σ rule.
    pub paper: Rate,
    /// The whitened Bonferroni CCF at the study's alpha.
    pub ccf: Rate,
}

/// False alarms of the null elements at one level.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct NullRow {
    /// The level.
    pub alpha: f64,
    /// The family-wise rule at that level.
    pub family: Rate,
    /// The CCF baseline at that level.
    pub ccf: Rate,
}

/// The study's tables.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct PowerSummary {
    /// Settings.
    pub options: PowerOptions,
    /// Detection rates.
    pub power: Vec<PowerRow>,
    /// False alarms at several levels (the p-values of one run read at each).
    pub nulls: Vec<NullRow>,
    /// The paper's rule on the null elements (it has no level to set).
    pub paper_nulls: Rate,
    /// Mean null surrogates drawn by the family-wise test: on null elements, on acting ones.
    pub mean_surrogates: (f64, f64),
}

/// Tabulates outcomes.
pub fn summarise(opts: &PowerOptions, out: &[Outcome]) -> PowerSummary {
    let lags = opts.max_lag;
    let mut keys: Vec<(Shape, DitherKind, u64)> = Vec::new();
    for o in out.iter().filter(|o| o.acts) {
        let k = (o.case.shape, o.case.dither, o.case.size.to_bits());
        if !keys.contains(&k) {
            keys.push(k);
        }
    }
    let rate = |sel: &[&Outcome], f: &dyn Fn(&Outcome) -> bool| {
        Rate::of(sel.iter().filter(|o| f(o)).count(), sel.len())
    };
    let power = keys
        .iter()
        .map(|&(shape, dither, bits)| {
            let sel: Vec<&Outcome> = out
                .iter()
                .filter(|o| {
                    o.acts
                        && o.case.shape == shape
                        && o.case.dither == dither
                        && o.case.size.to_bits() == bits
                })
                .collect();
            PowerRow {
                shape,
                dither,
                size: f64::from_bits(bits),
                family: rate(&sel, &|o| o.family_p <= opts.alpha),
                paper: rate(&sel, &|o| o.paper),
                ccf: rate(&sel, &|o| o.ccf_at(opts.alpha, lags)),
            }
        })
        .collect();
    let nulls: Vec<&Outcome> = out.iter().filter(|o| !o.acts).collect();
    let mean_of =
        |v: Vec<usize>| if v.is_empty() { 0.0 } else { v.iter().sum::<usize>() as f64 / v.len() as f64 };
    PowerSummary {
        options: opts.clone(),
        power,
        nulls: [0.05, 0.01, 0.001]
            .iter()
            .map(|&a| NullRow {
                alpha: a,
                family: rate(&nulls, &|o| o.family_p <= a),
                ccf: rate(&nulls, &|o| o.ccf_at(a, lags)),
            })
            .collect(),
        paper_nulls: rate(&nulls, &|o| o.paper),
        mean_surrogates: (
            mean_of(nulls.iter().map(|o| o.family_surrogates).collect()),
            mean_of(out.iter().filter(|o| o.acts).map(|o| o.family_surrogates).collect()),
        ),
    }
}

impl PowerSummary {
    /// The tables as Markdown.
    pub fn markdown(&self) -> String {
        let o = &self.options;
        let pct = |r: &Rate| format!("{}/{}", r.k, r.n);
        let mut s = format!(
            "N = {}, lags 1–{}, alpha = {} (family-wise rule and CCF baseline), seed {}.\n\n\
             | shape | dither | size | family | paper (6σ) | whitened CCF |\n| --- | --- | --- | --- | --- | --- |\n",
            o.n, o.max_lag, o.alpha, o.seed
        );
        for r in &self.power {
            s += &format!(
                "| {:?} | {:?} | {} | {} | {} | {} |\n",
                r.shape,
                r.dither,
                r.size,
                pct(&r.family),
                pct(&r.paper),
                pct(&r.ccf)
            );
        }
        s += "\nFalse alarms on the null elements (95 % Wilson interval):\n\n| level | family | CCF |\n| --- | --- | --- |\n";
        for r in &self.nulls {
            s += &format!(
                "| {} | {} ({:.2}–{:.2} %) | {} ({:.2}–{:.2} %) |\n",
                r.alpha,
                pct(&r.family),
                100.0 * r.family.low,
                100.0 * r.family.high,
                pct(&r.ccf),
                100.0 * r.ccf.low,
                100.0 * r.ccf.high
            );
        }
        s += &format!(
            "| paper, 6σ | {} ({:.2}–{:.2} %) | |\n\nSurrogates drawn after calibration by the family-wise test, mean: {:.0} on null \
             elements, {:.0} on acting ones (at most {}).\n",
            pct(&self.paper_nulls),
            100.0 * self.paper_nulls.low,
            100.0 * self.paper_nulls.high,
            self.mean_surrogates.0,
            self.mean_surrogates.1,
            SurrogateOptions::default().count
        );
        s
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn wilson_interval_matches_a_published_value() {
        // Wilson (1927) / Newcombe (1998) example: 81 of 263 gives 0.2553–0.3662.
        let r = Rate::of(81, 263);
        assert!((r.low - 0.2553).abs() < 5e-4 && (r.high - 0.3662).abs() < 5e-4, "{r:?}");
    }

    #[test]
    fn generated_effects_have_the_asked_size_and_lag() {
        let opts = PowerOptions::default();
        let all = cases(&opts);
        for shape in
            [Shape::Linear, Shape::LinearDynamic, Shape::Quadratic, Shape::DeadZone, Shape::Interaction]
        {
            let case = all.iter().find(|c| c.shape == shape).expect("every shape is drawn");
            let (d1, _, _) = generate(case, opts.n);
            let f = effect(case, &d1);
            let sd = mpmwatch_core::numerics::std_dev(&f, 0);
            assert!((sd - case.size).abs() < 1e-9 * case.size, "{shape:?}: sd {sd}");
            // Nothing acts before the effect's lag: f(t) is its mean there.
            assert!(f[..case.lag].iter().all(|x| (x - f[0]).abs() < 1e-12), "{shape:?}");
        }
        // A linear effect is exactly the scaled, lagged dither.
        let case = all.iter().find(|c| c.shape == Shape::Linear).unwrap();
        let (d1, _, _) = generate(case, opts.n);
        let f = effect(case, &d1);
        let r = mpmwatch_core::info::ccf(&d1, &f, case.lag as i64..=case.lag as i64).unwrap()[0];
        assert!(r > 0.99, "{r}");
    }
}
