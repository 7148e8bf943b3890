//! Blocked cross-validation of the grey-box structures in the currency of the held-out FIT:
//! each validation block simulated by a model fitted on the other rows and scored against its
//! own mean, with the one-step prediction error under the fit's noise model beside it (the
//! ranking currency on a dithered record); the linear re-fit's orders chosen that way; and
//! whether the output drifts ([`drift_gain`], [`drift_is_one_line`]), with the nominal's
//! reference then carrying the same line ([`Beside`]).

use super::{Data, Linear, Model, Orders, Reading, TREND_UNIT, fit};
use crate::fitness::fit_pct;
use crate::whiten::{ar_fit, whitened};
use mpmwatch_core::numerics::least_squares_rows;
use rayon::prelude::*;

/// FIT% on each validation block of the folds, each block against its own mean as the held-out
/// tail is scored, and their mean (the ranking score in open loop); with the RMS of the one-step
/// prediction error on each block (the ranking currency on a dithered record, see
/// [`CvScore::prediction_gain_over`]).
#[derive(Debug, Clone, PartialEq)]
pub struct CvScore {
    /// The mean of `blocks`.
    pub mean: f64,
    /// FIT% per validation block, in the folds' order.
    pub blocks: Vec<f64>,
    /// RMS of the one-step prediction error per validation block under the fit's noise model
    /// (the simulation error itself for an output-error fit), in the order of `blocks`.
    pub prediction_rms: Vec<f64>,
}

impl CvScore {
    fn of(blocks: Vec<f64>, prediction_rms: Vec<f64>) -> Self {
        // No block to score is no score (NaN fails every comparison).
        let mean =
            if blocks.is_empty() { f64::NAN } else { blocks.iter().sum::<f64>() / blocks.len() as f64 };
        CvScore { mean, blocks, prediction_rms }
    }

    /// The smallest block-by-block gain over `base` (+∞ without blocks).
    pub fn min_gain_over(&self, base: &CvScore) -> f64 {
        self.blocks.iter().zip(&base.blocks).map(|(a, b)| a - b).fold(f64::INFINITY, f64::min)
    }

    /// How much smaller the one-step prediction error is than `base`'s, percent of `base`'s
    /// RMS, averaged over the blocks (NaN without blocks). In a closed loop the disturbance
    /// dominates a simulation's error and every candidate's FIT alike; the prediction error,
    /// with the disturbance's colour removed by each fit's noise model, is the currency the
    /// fits were made in and separates candidates by what they explain of the plant.
    pub fn prediction_gain_over(&self, base: &CvScore) -> f64 {
        // A base that predicts a block perfectly leaves nothing to gain: 0 for a candidate as
        // perfect, −∞ for any other (never NaN, which no comparison would rank).
        let g: Vec<f64> = self
            .prediction_rms
            .iter()
            .zip(&base.prediction_rms)
            .map(|(a, b)| 100.0 * (b - a) / b.max(f64::MIN_POSITIVE))
            .collect();
        if g.is_empty() { f64::NAN } else { g.iter().sum::<f64>() / g.len() as f64 }
    }

    /// The score candidates are ranked by, against the nominal's `base`: the mean FIT for an
    /// output-error fit (`noise_order` 0, open loop), the prediction gain for a
    /// prediction-error fit (a dithered record).
    pub fn rank(&self, base: &CvScore, noise_order: usize) -> f64 {
        if noise_order > 0 { self.prediction_gain_over(base) } else { self.mean }
    }
}

/// RMS over `block` of the one-step prediction error of a simulation `s` of `y` under the AR
/// noise model `a` (the first `a.len()` rows of the record have no prediction and are skipped).
fn prediction_rms(s: &[f64], y: &[f64], a: &[f64], block: std::ops::Range<usize>) -> f64 {
    let e: Vec<f64> = s.iter().zip(y).map(|(a, b)| a - b).collect();
    let rows = block.start.max(a.len())..block.end;
    let n = rows.len().max(1) as f64;
    (rows.map(|t| whitened(&e, a, t).powi(2)).sum::<f64>() / n).sqrt()
}

/// The cross-validated FIT of a model: each validation block of `folds` simulated by the model
/// fitted on the other rows and scored against its own mean, as the held-out tail is (pooled
/// over blocks, a model would be credited for following the level differences between blocks,
/// which the tail, one block, does not reward), and its one-step prediction error there.
/// `None` when a fit fails or diverges.
pub fn cv_fit(
    model: &Model<'_>,
    d: &Data<'_>,
    folds: &[(Vec<usize>, std::ops::Range<usize>)],
) -> Option<CvScore> {
    let (mut blocks, mut rms) = (Vec::with_capacity(folds.len()), Vec::with_capacity(folds.len()));
    for (fit_rows, block) in folds.iter().filter(|(_, b)| varies(&d.y[b.clone()])) {
        let f = fit(model, d, fit_rows)?;
        let s = model.simulate(&f, &d.u, d.y)?;
        blocks.push(fit_pct(&d.y[block.clone()], &s[block.clone()]));
        // A fit whose prediction-error refinement gave up has no noise model; it is whitened
        // as the nominal is, by an AR model of its error on the fit rows, so that every
        // candidate is scored in one currency.
        let noise = if f.noise.len() == d.noise_order {
            f.noise.clone()
        } else {
            let e: Vec<f64> = s.iter().zip(d.y).map(|(a, b)| a - b).collect();
            ar_fit(&e, fit_rows, d.noise_order)?
        };
        let r = prediction_rms(&s, d.y, &noise, block.clone());
        if !r.is_finite() {
            return None;
        }
        rms.push(r);
    }
    let score = CvScore::of(blocks, rms);
    score.mean.is_finite().then_some(score)
}

/// What the nominal's reference carries beside its simulation, fitted to the simulation error
/// on each fold's fit rows by least squares.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Beside {
    /// The nominal as it is.
    Nothing,
    /// A constant and a straight line in time: the level and a drift, the reference every
    /// structure with [`Orders::trend`] is measured against.
    Drift,
}

/// The nominal's FIT over the same validation blocks, scored as [`cv_fit`] scores, with what
/// `beside` adds to it, read through the instrument's range `reading` when there is one; its
/// prediction error under an AR model of order `noise_order` of its
/// simulation error, fitted on each fold's fit rows (none for 0).
pub fn nominal_cv_fit(
    s: &[f64],
    y: &[f64],
    folds: &[(Vec<usize>, std::ops::Range<usize>)],
    noise_order: usize,
    beside: Beside,
    reading: Option<Reading>,
) -> CvScore {
    let e: Vec<f64> = s.iter().zip(y).map(|(a, b)| a - b).collect();
    let ones = vec![1.0; y.len()];
    let time: Vec<f64> = (0..y.len()).map(|t| t as f64 / TREND_UNIT).collect();
    let (mut blocks, mut rms) = (Vec::new(), Vec::new());
    for (fit_rows, b) in folds.iter().filter(|(_, b)| varies(&y[b.clone()])) {
        let cols: Vec<&[f64]> = match beside {
            Beside::Nothing => Vec::new(),
            Beside::Drift => vec![&ones, &time],
        };
        let coef = if cols.is_empty() { Some(Vec::new()) } else { least_squares_rows(&cols, &e, fit_rows) };
        // A fold whose rows cannot place a line keeps the nominal as it is.
        let coef = coef.unwrap_or_else(|| vec![0.0; cols.len()]);
        let read = |v: f64| reading.map_or(v, |r| r.read(v));
        let sb: Vec<f64> = (0..y.len())
            .map(|t| read(s[t] - cols.iter().zip(&coef).map(|(c, k)| c[t] * k).sum::<f64>()))
            .collect();
        let eb: Vec<f64> = sb.iter().zip(y).map(|(a, b)| a - b).collect();
        blocks.push(fit_pct(&y[b.clone()], &sb[b.clone()]));
        let a = ar_fit(&eb, fit_rows, noise_order).unwrap_or_default();
        rms.push(prediction_rms(&sb, y, &a, b.clone()));
    }
    CvScore::of(blocks, rms)
}

/// How much a drift term adds to the re-fitted linear model `linear` (its orders and score,
/// from [`linear_orders`]): the same orders with [`Orders::trend`], scored on the same folds,
/// its mean FIT over `linear`'s, in points. `None` when the fit fails. The re-fit, not the
/// nominal, is the reference: a nominal whose slow dynamics are wrong leaves an error that
/// follows a line, which the re-fitted dynamics explain from the inputs and a drift need not.
/// Compared on the mean, not block by block: the middle block, which the line interpolates,
/// gains nothing from a ramp and loses a little to the line's noise; the outer blocks, which
/// it extrapolates as it will the held-out tail, carry the test.
pub fn drift_gain(
    d: &Data<'_>,
    folds: &[(Vec<usize>, std::ops::Range<usize>)],
    linear: &(Orders, CvScore),
) -> Option<f64> {
    let orders = Orders { trend: true, ..linear.0.clone() };
    let with = cv_fit(&Model { element: &Linear, input: 0, orders }, d, folds)?;
    Some(with.mean - linear.1.mean)
}

/// Whether a validation block's output moves at all: a constant block (a stuck sensor, a level
/// held at its rim) has no FIT (−∞ for any error), so it is left out of every score alike.
fn varies(y: &[f64]) -> bool {
    y.first().is_some_and(|&f| y.iter().any(|&v| v != f))
}

/// The best linear orders by blocked cross-validation: dead times input by input, by the
/// simulation error on the training rows (the same rows for every dead time compared; on a
/// dithered record the one-step prediction error under the fit's noise model) of a [`fit`] at
/// two poles and two taps, then poles and taps by cross-validation ([`CvScore::rank`] against
/// `base`). Every dead time up to [`DEAD_TIME_FLOOR`] is scored, then the grid of
/// [`dead_time_grid`] past it on to [`max_dead_time`], whose best replaces the first only when
/// it simulates better on the rows past the longest. The dead time is judged on
/// a fit by simulation error, not on the equation-error fit alone, which coloured noise and a
/// slow pole bias (docs/diagnose-history.md, "The dead-time search of the linear re-fit").
pub fn linear_orders(
    d: &Data<'_>,
    folds: &[(Vec<usize>, std::ops::Range<usize>)],
    base: &CvScore,
    trend: bool,
) -> Option<(Orders, CvScore)> {
    let lin = Linear;
    let longest = max_dead_time(folds);
    // The dead times compared are scored on the same rows: from the folds' first row (after the
    // warm-up) and past the longest one's initial rows, which a simulation copies from the
    // record (zero error there would favour the longer dead times).
    let rows_past = |k: usize| -> Vec<usize> {
        let first = folds.first().map_or(d.train.start, |f| f.1.start).max(d.train.start + k + 2);
        (first..d.train.end).collect()
    };
    let (near_rows, far_rows) = (rows_past(DEAD_TIME_FLOOR.min(longest)), rows_past(longest));
    let sim_err = |orders: &Orders, rows: &[usize]| -> f64 {
        let m = Model { element: &lin, input: 0, orders: orders.clone() };
        fit(&m, d, rows).and_then(|f| m.simulate(&f, &d.u, d.y).map(|s| (f, s))).map_or(
            f64::INFINITY,
            |(f, s)| {
                let e: Vec<f64> = s.iter().zip(d.y).map(|(a, b)| a - b).collect();
                let sse: f64 = rows.iter().map(|&t| whitened(&e, &f.noise, t).powi(2)).sum();
                // A NaN would rank first under `total_cmp`; it is no fit.
                if sse.is_nan() { f64::INFINITY } else { sse }
            },
        )
    };
    let mut nk = vec![1usize; d.u.len()];
    for i in 0..d.u.len() {
        let error_at = |k: usize, nk: &[usize], rows: &[usize]| -> f64 {
            let mut o = Orders { na: 2, nb: 2, nk: nk.to_vec(), trend, reading: None };
            o.nk[i] = k;
            sim_err(&o, rows)
        };
        let argmin = |ks: &[usize], e: &[f64]| -> usize {
            (0..ks.len()).min_by(|&a, &b| e[a].total_cmp(&e[b])).map_or(1, |a| ks[a])
        };
        let near: Vec<usize> = (0..=DEAD_TIME_FLOOR.min(longest)).collect();
        let errors: Vec<f64> = near.par_iter().map(|&k| error_at(k, &nk, &near_rows)).collect();
        let mut best = argmin(&near, &errors);
        // Past the floor, a dead time replaces the floor range's best only when it simulates
        // better than that one on the same rows (those past the longest): a minimum inside the
        // floor's range is otherwise kept as it was found.
        if longest > DEAD_TIME_FLOOR {
            let grid: Vec<usize> =
                dead_time_grid(longest).into_iter().filter(|&k| k > DEAD_TIME_FLOOR).collect();
            let errors: Vec<f64> = grid.par_iter().map(|&k| error_at(k, &nk, &far_rows)).collect();
            let at = grid.iter().position(|&k| k == argmin(&grid, &errors)).unwrap_or(0);
            // Between the best grid point's neighbours every dead time is tried.
            let lo = if at == 0 { DEAD_TIME_FLOOR + 1 } else { grid[at - 1] };
            let fine: Vec<usize> = (lo..=grid[(at + 1).min(grid.len() - 1)]).collect();
            let errors: Vec<f64> = fine.par_iter().map(|&k| error_at(k, &nk, &far_rows)).collect();
            let far = argmin(&fine, &errors);
            let far_error = errors[fine.iter().position(|&k| k == far).unwrap_or(0)];
            if far_error < error_at(best, &nk, &far_rows) {
                best = far;
            }
        }
        nk[i] = best;
    }
    ranked_linear(d, folds, base, &Orders { na: 1, nb: 1, nk, trend, reading: None }).into_iter().next()
}

/// The linear structures at the dead times, drift term and range of `at` (its poles and taps
/// are not read): one to three poles and one to three taps, each scored by blocked
/// cross-validation on `folds`, best first by [`CvScore::rank`] against `base` less a tenth of
/// a point per pole and tap (one more must earn it). A structure that cannot be fitted is left
/// out; a score that is not a number ranks last.
pub fn ranked_linear(
    d: &Data<'_>,
    folds: &[(Vec<usize>, std::ops::Range<usize>)],
    base: &CvScore,
    at: &Orders,
) -> Vec<(Orders, CvScore)> {
    let mut scored: Vec<(Orders, CvScore)> = (1..=3)
        .flat_map(|na| (1..=3).map(move |nb| (na, nb)))
        .collect::<Vec<_>>()
        .into_par_iter()
        .filter_map(|(na, nb)| {
            let orders = Orders { na, nb, ..at.clone() };
            let m = Model { element: &Linear, input: 0, orders: orders.clone() };
            cv_fit(&m, d, folds).map(|v| (orders, v))
        })
        .collect();
    let score = |(o, v): &(Orders, CvScore)| {
        let s = v.rank(base, d.noise_order) - 0.1 * (o.na + o.nb) as f64;
        if s.is_nan() { f64::NEG_INFINITY } else { s }
    };
    // Scored on every core, then sorted stably in the order listed, so that a tie goes as it
    // would on one thread.
    scored.sort_by(|a, b| score(b).total_cmp(&score(a)));
    scored
}

/// Whether the drift the re-fitted linear model `linear` (its orders, from [`linear_orders`])
/// takes on is one straight line over the training part: fitted with a drift term on each half
/// of the validation rows of `folds`, the drift's simulated rise ([`Model::drift_over`]) goes
/// on both halves the way it goes over all the rows. A line no input carries rises on both
/// halves, by amounts a half-record's fit leaves noisy (on a development ramp one half kept
/// 6 % of the whole's rate, docs/diagnose-history.md, stop 56), so only the direction is
/// asked; the slow level a nonlinearity leaves the linear re-fit to follow (a tank that fills
/// and overflows) rises on one half and falls, or stays flat, on the other. A fit that fails,
/// or a drift of exactly zero, says no.
pub fn drift_is_one_line(
    d: &Data<'_>,
    folds: &[(Vec<usize>, std::ops::Range<usize>)],
    linear: &Orders,
) -> bool {
    let m = Model { element: &Linear, input: 0, orders: Orders { trend: true, ..linear.clone() } };
    let rows: Vec<usize> = folds.iter().flat_map(|f| f.1.clone()).collect();
    // Only the direction is compared, so the rise over each part stands for its rate.
    let rise = |r: &[usize]| fit(&m, d, r).and_then(|f| m.drift_over(&f, &d.u, d.y, r));
    let (half_a, half_b) = rows.split_at(rows.len() / 2);
    match (rise(&rows), rise(half_a), rise(half_b)) {
        (Some(all), Some(a), Some(b)) => a * all > 0.0 && b * all > 0.0,
        _ => false,
    }
}

/// `folds` with every validation block starting at `start` or later (a block that would be
/// empty is dropped); the fit rows are kept.
pub fn starting_at(
    folds: &[(Vec<usize>, std::ops::Range<usize>)],
    start: usize,
) -> Vec<(Vec<usize>, std::ops::Range<usize>)> {
    folds
        .iter()
        .map(|(fit, b)| (fit.clone(), b.start.max(start)..b.end))
        .filter(|(_, b)| !b.is_empty())
        .collect()
}

/// Dead times up to this many samples are always searched, each one.
pub const DEAD_TIME_FLOOR: usize = 20;

/// The longest dead time searched, in samples: a quarter of the shortest validation block, and
/// at least [`DEAD_TIME_FLOOR`]. A record sampled fast against its plant carries dead times of
/// tens or hundreds of samples (a process logged every second), which a fixed bound would
/// leave a nonlinear element to imitate; a quarter of a block still leaves each block three
/// quarters of its rows driven by its own inputs.
pub fn max_dead_time(folds: &[(Vec<usize>, std::ops::Range<usize>)]) -> usize {
    let block = folds.iter().map(|f| f.1.len()).min().unwrap_or(0);
    (block / 4).max(DEAD_TIME_FLOOR)
}

/// Each dead time up to [`DEAD_TIME_FLOOR`], then steps of a tenth of the dead time up to
/// `longest` (included); [`linear_orders`] scores the points past the floor, then every dead
/// time between the best of them and its neighbours, on the assumption that a response's
/// error changes little while its start moves by a tenth.
fn dead_time_grid(longest: usize) -> Vec<usize> {
    let mut grid: Vec<usize> = (0..=DEAD_TIME_FLOOR.min(longest)).collect();
    let mut k = DEAD_TIME_FLOOR;
    while k < longest {
        k = (k + k.div_ceil(10)).min(longest);
        grid.push(k);
    }
    grid
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Every dead time to the floor, then steps of a tenth up to the longest, which is
    /// included; the longest follows a quarter of the shortest block, never below the floor.
    #[test]
    fn the_dead_time_grid_widens_with_the_blocks() {
        assert_eq!(dead_time_grid(20), (0..=20).collect::<Vec<_>>());
        let g = dead_time_grid(100);
        assert_eq!(&g[21..], &[22, 25, 28, 31, 35, 39, 43, 48, 53, 59, 65, 72, 80, 88, 97, 100]);
        assert!(g.windows(2).all(|w| w[1] > w[0] && w[1] - w[0] <= w[0].div_ceil(10).max(1)));
        let folds = |len: usize| vec![(Vec::new(), 0..len), (Vec::new(), len..3 * len)];
        assert_eq!(max_dead_time(&folds(693)), 173);
        assert_eq!(max_dead_time(&folds(60)), DEAD_TIME_FLOOR);
    }

    /// Three blocks of 700 rows, each fold fitted on the other two, as the plan cuts a training
    /// part of 2100.
    fn three_folds() -> Vec<(Vec<usize>, std::ops::Range<usize>)> {
        (0..3)
            .map(|k| {
                let block = 700 * k..700 * (k + 1);
                let fit = (0..2100).filter(|t| !block.contains(t)).collect();
                (fit, block)
            })
            .collect()
    }

    /// The drift tests' plant: `x(t) = 0.9 x(t−1) + 0.1 u(t−1)` driven by a ±1 staircase held
    /// 37 samples, `n` rows; returns `(u, x)`.
    fn staircase_plant(n: usize) -> (Vec<f64>, Vec<f64>) {
        let u: Vec<f64> = (0..n).map(|t| if (t / 37 * 7919) % 11 < 5 { 1.0 } else { -1.0 }).collect();
        let mut x = vec![0.0; n];
        for t in 1..n {
            x[t] = 0.9 * x[t - 1] + 0.1 * u[t - 1];
        }
        (u, x)
    }

    /// A ramp over the record is one line; a level that rises on one half and falls on the
    /// other (what a store that fills and overflows can leave behind a linear re-fit) is not.
    /// A first-order plant on a ±1 staircase held 37 samples, white measurement noise uniform
    /// on ±0.1, ten seeds each: every ramp passes; a level that peaks at 70 % of the record and
    /// falls back by a fifth never does, nor its mirror image in time (a short rise, then a
    /// long fall), which only the first half's direction rejects.
    #[test]
    fn a_drift_must_be_one_line_over_the_record() {
        use rand::{Rng, SeedableRng};
        let n = 2100;
        let folds = three_folds();
        let (u, x) = staircase_plant(n);
        let orders = Orders { na: 1, nb: 1, nk: vec![1], trend: false, reading: None };
        let one_line = |level: &dyn Fn(f64) -> f64, seed: u64| {
            let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(seed);
            let y: Vec<f64> = (0..n)
                .map(|t| x[t] + level(t as f64 / n as f64) + 0.2 * (rng.random::<f64>() - 0.5))
                .collect();
            let d = Data { u: vec![&u], y: &y, train: 0..n, nominal: None, noise_order: 0 };
            drift_is_one_line(&d, &folds, &orders)
        };
        for seed in 1..=10 {
            assert!(one_line(&|s| 1.3 * s, seed), "a ramp read as no line (seed {seed})");
            assert!(
                !one_line(&|s| 1.3 * (std::f64::consts::PI * s / 1.4).sin(), seed),
                "a rise and fall read as a line (seed {seed})"
            );
            assert!(
                !one_line(&|s| 1.3 * (std::f64::consts::PI * (1.0 - s) / 1.4).sin(), seed),
                "a fall and rise read as a line (seed {seed})"
            );
        }
    }

    /// The drift test against both of its cases, on a plant the re-fit's structure holds,
    /// `x(t) = 0.9 x(t−1) + 0.1 u(t−1)` driven by a ±1 staircase. A ramp of 1.3 over the 2100
    /// rows (about the output's standard deviation), under white noise of standard deviation
    /// 0.2, gains a drift term 35 to 37 points on every seed (1–10): without it the re-fit's
    /// constant misses an outer block's level by a block and a half's worth of ramp (0.65),
    /// and its dynamics bend to follow the ramp. Without a ramp, under a disturbance of pole
    /// 0.9 and standard deviation 0.5 (a time constant of 10 samples against blocks of 700),
    /// it gains a point on 4 of the 60 seeds 1001–1060 (4 of 1001–1100): the decision's
    /// false-alarm rate, about 5 %, asserted at 8 of 60, three binomial standard deviations
    /// above the 3 that 5 % expects. Slower disturbances read as a drift more often: within a
    /// block of 700 rows they are one. A false drift names nothing by itself: every structure
    /// and the nominal's reference then carry the same line (docs/diagnose-history.md, stop 51).
    #[test]
    fn a_drift_is_told_from_a_faster_disturbance() {
        const NSEEDS: u64 = 60;
        use rand::{Rng, SeedableRng};
        let n = 2100;
        let folds = three_folds();
        let (u, x) = staircase_plant(n);
        let uniform = |rng: &mut rand_chacha::ChaCha8Rng| (rng.random::<f64>() - 0.5) * 12f64.sqrt();
        let gain = |y: &[f64]| {
            let d = Data { u: vec![&u], y, train: 0..n, nominal: None, noise_order: 0 };
            let orders = Orders { na: 1, nb: 1, nk: vec![1], trend: false, reading: None };
            let v =
                cv_fit(&Model { element: &Linear, input: 0, orders: orders.clone() }, &d, &folds).unwrap();
            drift_gain(&d, &folds, &(orders, v)).unwrap()
        };
        let ramps: Vec<f64> = (1..=10)
            .map(|seed| {
                let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(seed);
                let y: Vec<f64> =
                    (0..n).map(|t| x[t] + 1.3 * t as f64 / n as f64 + 0.2 * uniform(&mut rng)).collect();
                gain(&y)
            })
            .collect();
        let nulls: Vec<f64> = (1001..=1000 + NSEEDS)
            .map(|seed| {
                let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(seed);
                let mut v = 0.0;
                let y: Vec<f64> = (0..n)
                    .map(|t| {
                        v = 0.9 * v + 0.5 * (1.0f64 - 0.81).sqrt() * uniform(&mut rng);
                        x[t] + v
                    })
                    .collect();
                gain(&y)
            })
            .collect();
        assert!(ramps.iter().all(|&g| g >= 1.0), "{ramps:?}");
        let false_alarms = nulls.iter().filter(|&&g| g >= 1.0).count();
        assert!(false_alarms <= 8, "{false_alarms} of {NSEEDS} disturbances read as a drift");
    }

    /// Each block is scored against its own mean: a simulation that only follows the blocks'
    /// levels earns FIT 0 on every block (pooled, it would earn the share of the variance the
    /// level differences carry); the gate's smallest gain is the worst block's.
    #[test]
    fn blocks_are_scored_against_their_own_means() {
        let y: Vec<f64> =
            (0..60).map(|t| (t / 20) as f64 * 10.0 + if t % 2 == 0 { 1.0 } else { -1.0 }).collect();
        let s: Vec<f64> = (0..60).map(|t| (t / 20) as f64 * 10.0).collect();
        let folds: Vec<(Vec<usize>, std::ops::Range<usize>)> =
            (0..3).map(|k| (Vec::new(), 20 * k..20 * (k + 1))).collect();
        let score = nominal_cv_fit(&s, &y, &folds, 0, Beside::Nothing, None);
        assert_eq!(score.blocks, vec![0.0, 0.0, 0.0]);
        assert_eq!(score.mean, 0.0);
        assert!(fit_pct(&y, &s) > 80.0);
        let other = CvScore::of(vec![5.0, -2.0, 3.0], vec![1.0, 3.0, 2.0]);
        assert_eq!(other.mean, 2.0);
        assert_eq!(other.min_gain_over(&score), -2.0);
        // A constant block has no FIT (−∞ for any error) and is left out.
        let mut flat = y.clone();
        flat[20..40].iter_mut().for_each(|v| *v = 10.0);
        assert_eq!(nominal_cv_fit(&s, &flat, &folds, 0, Beside::Nothing, None).blocks, vec![0.0, 0.0]);
        assert!(CvScore::of(Vec::new(), Vec::new()).mean.is_nan());
        // The prediction currency: per block the share of the base's RMS removed, averaged
        // (an output-error score's RMS is its simulation error's: ±1 about the levels here).
        assert_eq!(score.prediction_rms, vec![1.0, 1.0, 1.0]);
        let base = CvScore::of(vec![0.0; 3], vec![2.0, 4.0, 2.0]);
        assert_eq!(other.prediction_gain_over(&base), (50.0 + 25.0 + 0.0) / 3.0);
        assert!(CvScore::of(Vec::new(), Vec::new()).prediction_gain_over(&base).is_nan());
        // A base that predicts perfectly: nothing to gain for a perfect candidate, an unbounded
        // loss (−∞, which ranks last) for any other, never NaN.
        let perfect = CvScore::of(vec![0.0], vec![0.0]);
        assert_eq!(CvScore::of(vec![0.0], vec![0.0]).prediction_gain_over(&perfect), 0.0);
        let worse = CvScore::of(vec![0.0], vec![1.0]).prediction_gain_over(&perfect);
        assert_eq!(worse, f64::NEG_INFINITY);
    }
}
