//! Lagged mutual information `I(x(t); y(t+τ))` over a lag range and its mean, the "norm of MI"
//! of eq 19: does the future of the residual carry information about the past dither?
//!
//! Every lag uses the same sample pairs count, `N − τmax − (w − 1)`, so the estimates at
//! different lags have the same bias and can be averaged and compared with one threshold.
//!
//! A record with gaps is given as contiguous *segments* laid end to end
//! ([`LaggedPair::segmented`]): a time t is then used only when `x(t−w+1)..` and `y(t+τmax)`
//! lie in the same segment, so no pair straddles a gap, and every lag still uses the same
//! times.
//!
//! With an embedding width `w > 1`, X at time t is the vector `(x(t), x(t−1), …, x(t−w+1))`.
//! An interaction term such as `c·u(t−1)·u(t−2)` driven by an i.i.d. dither is invisible to
//! every pairwise statistic, because each factor alone is independent of the product; the
//! pair of consecutive lags sees it (DESIGN.md §2.4).

use serde::Serialize;

use super::discrete::{Levels, ross_sorted};
use super::estimator::{Estimator, MiOptions, mutual_information, robust_std, scaled};
use super::ksg::ksg1;
use super::{InfoError, validate};

/// An inclusive range of non-negative lags, in samples.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
pub struct Lags {
    /// Smallest lag (eq 19's tmin; 1 by default: the dither acts on later residuals).
    pub min: usize,
    /// Largest lag (eq 19's tmax).
    pub max: usize,
}

impl Lags {
    /// The range `min..=max`; errors when `min > max`.
    pub fn new(min: usize, max: usize) -> Result<Self, InfoError> {
        if min > max {
            return Err(InfoError::InvalidParameter {
                name: "lags",
                value: format!("{min}..={max}"),
                reason: "the smallest lag exceeds the largest",
            });
        }
        Ok(Self { min, max })
    }

    /// The lags in order.
    pub fn iter(&self) -> impl Iterator<Item = usize> + use<> {
        self.min..=self.max
    }

    /// Number of lags.
    pub fn len(&self) -> usize {
        self.max - self.min + 1
    }

    /// Never true: a range holds at least one lag.
    pub fn is_empty(&self) -> bool {
        false
    }
}

/// MI against lag for one (x, y) pair.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct LaggedProfile {
    /// The lags, in samples.
    pub lags: Vec<usize>,
    /// `I(x(t); y(t+τ))` in nats, one per lag.
    pub nats: Vec<f64>,
    /// Sample pairs per lag.
    pub n_pairs: usize,
    /// The estimator used.
    pub estimator: Estimator,
    /// Embedding width w.
    pub embedding: usize,
}

impl LaggedProfile {
    /// The norm of MI (eq 19): the mean over the lag range, in nats.
    pub fn norm(&self) -> f64 {
        norm_of(&self.nats)
    }
}

/// Mean of a profile (eq 19).
pub fn norm_of(profile: &[f64]) -> f64 {
    profile.iter().sum::<f64>() / profile.len() as f64
}

enum Path {
    /// X discrete: the residual sorted once; each lag and each circular shift only relabels.
    Discrete {
        levels: Levels,
        order: Vec<u32>,
        classes: usize,
    },
    Continuous,
}

/// One (x, y) pair prepared for repeated lagged estimates: the profile itself and its
/// surrogates (circular shifts of x, or a replacement x) share the preparation.
pub struct LaggedPair<'a> {
    x: &'a [f64],
    /// y as the estimator sees it (standardised on the continuous path).
    y: std::borrow::Cow<'a, [f64]>,
    /// Standard deviation x is divided by on the continuous path (1 when not standardising).
    x_scale: f64,
    lags: Lags,
    width: usize,
    k: usize,
    n_pairs: usize,
    path: Path,
    /// Mean and population spread of x and of y, for the correlation profile (a circular shift
    /// or an iAAFT surrogate of x keeps x's values, hence both).
    moments: [(f64, f64); 2],
    /// For records in segments: whether time `t0 + s` is used (`None`: every time is).
    used: Option<Vec<bool>>,
}

impl<'a> LaggedPair<'a> {
    /// Checks the inputs and prepares the estimator path chosen by `opts` for x.
    pub fn new(
        x: &'a [f64],
        y: &'a [f64],
        lags: Lags,
        width: usize,
        opts: &MiOptions,
    ) -> Result<Self, InfoError> {
        if width == 0 || width > super::ksg::MAX_X_DIM {
            return Err(InfoError::InvalidParameter {
                name: "embedding",
                value: width.to_string(),
                reason: "the embedding width must be between 1 and 4",
            });
        }
        validate::same_length("x", x.len(), "y", y.len())?;
        validate::finite("x", x)?;
        validate::finite("y", y)?;
        validate::not_constant("x", x)?;
        validate::not_constant("y", y)?;
        let n_pairs = x.len().saturating_sub(lags.max + width - 1);
        validate::neighbours(&format!("lagged MI up to lag {}", lags.max), n_pairs, opts.k)?;
        let path = match opts.discrete_levels(x)? {
            Some(levels) => {
                let classes = levels.count().pow(width as u32);
                if classes > u16::MAX as usize {
                    return Err(InfoError::TooManyLevels {
                        series: "x (embedded)".into(),
                        levels: classes,
                        max: u16::MAX as usize,
                    });
                }
                let mut order: Vec<u32> = (0..y.len() as u32).collect();
                order.sort_unstable_by(|&a, &b| y[a as usize].total_cmp(&y[b as usize]));
                Path::Discrete { levels, order, classes }
            }
            None => Path::Continuous,
        };
        let continuous = matches!(path, Path::Continuous);
        let y = scaled(y, continuous && opts.standardize);
        let x_scale = if continuous && opts.standardize { robust_std(x).unwrap_or(1.0) } else { 1.0 };
        let moments = [x, &y[..]].map(|v| (crate::numerics::mean(v), crate::numerics::std_dev(v, 0)));
        Ok(Self { x, y, x_scale, lags, width, k: opts.k, n_pairs, path, moments, used: None })
    }

    /// [`LaggedPair::new`] for a record of contiguous segments of lengths `segments` laid end to
    /// end (summing to the series' length): times whose pairs would straddle a segment boundary
    /// are skipped at every lag. One segment is [`LaggedPair::new`].
    pub fn segmented(
        x: &'a [f64],
        y: &'a [f64],
        lags: Lags,
        width: usize,
        opts: &MiOptions,
        segments: &[usize],
    ) -> Result<Self, InfoError> {
        if segments.iter().sum::<usize>() != x.len() {
            return Err(InfoError::InvalidParameter {
                name: "segments",
                value: format!("{} samples in segments", segments.iter().sum::<usize>()),
                reason: "the segment lengths must add up to the series' length",
            });
        }
        let mut pair = Self::new(x, y, lags, width, opts)?;
        if segments.len() > 1 {
            let mut id = Vec::with_capacity(x.len());
            for (k, &len) in segments.iter().enumerate() {
                id.extend(std::iter::repeat_n(k, len));
            }
            let t0 = width - 1;
            let used: Vec<bool> = (t0..t0 + pair.n_pairs).map(|t| id[t - t0] == id[t + lags.max]).collect();
            pair.n_pairs = used.iter().filter(|&&u| u).count();
            validate::neighbours(
                &format!("lagged MI up to lag {} within segments", lags.max),
                pair.n_pairs,
                opts.k,
            )?;
            pair.used = Some(used);
        }
        Ok(pair)
    }

    /// Whether time `t0 + s` (s counted from the first usable time) is used.
    fn uses(&self, s: usize) -> bool {
        self.used.as_ref().is_none_or(|u| u[s])
    }

    /// The dither series.
    pub fn x(&self) -> &'a [f64] {
        self.x
    }

    /// Sample pairs per lag.
    pub fn n_pairs(&self) -> usize {
        self.n_pairs
    }

    /// Series length.
    pub fn len(&self) -> usize {
        self.x.len()
    }

    /// Never true: validation rejects empty series.
    pub fn is_empty(&self) -> bool {
        self.x.is_empty()
    }

    /// The lag range.
    pub fn lags(&self) -> Lags {
        self.lags
    }

    /// True when the discrete-X path is in use.
    pub fn is_discrete(&self) -> bool {
        matches!(self.path, Path::Discrete { .. })
    }

    /// The estimator in use.
    pub fn estimator(&self) -> Estimator {
        if self.is_discrete() { Estimator::Ross } else { Estimator::Ksg1 }
    }

    /// The observed profile.
    pub fn profile(&self) -> LaggedProfile {
        LaggedProfile {
            lags: self.lags.iter().collect(),
            nats: self.profile_shifted(0),
            n_pairs: self.n_pairs,
            estimator: self.estimator(),
            embedding: self.width,
        }
    }

    /// The profile with x circularly shifted by `shift` samples: `x_s(t) = x((t + shift) mod N)`.
    pub fn profile_shifted(&self, shift: usize) -> Vec<f64> {
        match &self.path {
            Path::Discrete { levels, order, classes } => {
                self.discrete_profile(levels, order, *classes, shift)
            }
            Path::Continuous => {
                if shift == 0 {
                    self.continuous_profile(self.x)
                } else {
                    let n = self.x.len();
                    let xs: Vec<f64> = (0..n).map(|t| self.x[(t + shift) % n]).collect();
                    self.continuous_profile(&xs)
                }
            }
        }
    }

    /// The profile with x replaced by `x_new` (an iAAFT surrogate, which has x's values and
    /// hence its scale), always by KSG1 since a surrogate of a continuous series is continuous.
    pub fn profile_with_x(&self, x_new: &[f64]) -> Vec<f64> {
        debug_assert_eq!(x_new.len(), self.x.len());
        self.continuous_profile(x_new)
    }

    /// Cross-correlation of x(t) with y(t+τ) over the same sample pairs as the MI profile, with
    /// x circularly shifted by `shift` (0 for the observed series). A circular shift keeps x's
    /// mean and spread, so they are taken once over the whole series.
    pub fn linear_profile_shifted(&self, shift: usize) -> Vec<f64> {
        let n = self.x.len();
        self.correlations(|t| self.x[(t + shift) % n])
    }

    /// [`Self::linear_profile_shifted`] with x replaced by `x_new` (an iAAFT surrogate).
    pub fn linear_profile_with_x(&self, x_new: &[f64]) -> Vec<f64> {
        debug_assert_eq!(x_new.len(), self.x.len());
        self.correlations(|t| x_new[t])
    }

    /// Per lag, the exact mean and standard deviation of [`Self::linear_profile_shifted`] over
    /// every shift in `bounds` that [`super::draw_shift`] may return (`None` when no shift is
    /// admissible). On the continuous path too: whatever the surrogates of the MI statistics,
    /// the correlation's null given the residual is its distribution over the dither's circular
    /// shifts, and every shift in the bounds changes a continuous series. See
    /// [`super::shift_moments`].
    pub fn linear_shift_moments(&self, bounds: (usize, usize)) -> Option<Vec<(f64, f64)>> {
        let labels = match &self.path {
            Path::Discrete { levels, .. } => Some(&levels.labels[..]),
            Path::Continuous => None,
        };
        super::shift_moments::ccf_shift_moments(
            self.x,
            &self.y,
            labels,
            &self.times(),
            self.lags.iter(),
            self.moments,
            bounds,
        )
    }

    /// The times used, `t0 + s` for the used s (all of `t0..t0 + span` without segments).
    fn times(&self) -> Vec<usize> {
        let t0 = self.width - 1;
        match &self.used {
            None => (t0..t0 + self.n_pairs).collect(),
            Some(u) => u.iter().enumerate().filter(|(_, u)| **u).map(|(s, _)| t0 + s).collect(),
        }
    }

    fn correlations(&self, x_at: impl Fn(usize) -> f64) -> Vec<f64> {
        let [(mx, sx), (my, sy)] = self.moments;
        let times = self.times();
        let np = times.len();
        let xc: Vec<f64> = times.iter().map(|&t| x_at(t) - mx).collect();
        self.lags
            .iter()
            .map(|tau| {
                let s: f64 = xc.iter().zip(&times).map(|(a, &t)| a * (self.y[t + tau] - my)).sum();
                s / (np as f64 * sx * sy)
            })
            .collect()
    }

    fn continuous_profile(&self, x: &[f64]) -> Vec<f64> {
        let x: Vec<f64> = x.iter().map(|v| v / self.x_scale).collect();
        let t0 = self.width - 1;
        let np = self.n_pairs;
        if self.used.is_none() {
            let cols: Vec<&[f64]> = (0..self.width).map(|d| &x[t0 - d..t0 - d + np]).collect();
            return self
                .lags
                .iter()
                .map(|tau| ksg1(&cols, &self.y[t0 + tau..t0 + tau + np], self.k))
                .collect();
        }
        let times = self.times();
        let cols: Vec<Vec<f64>> =
            (0..self.width).map(|d| times.iter().map(|&t| x[t - d]).collect()).collect();
        let refs: Vec<&[f64]> = cols.iter().map(Vec::as_slice).collect();
        self.lags
            .iter()
            .map(|tau| {
                let y: Vec<f64> = times.iter().map(|&t| self.y[t + tau]).collect();
                ksg1(&refs, &y, self.k)
            })
            .collect()
    }

    fn discrete_profile(&self, levels: &Levels, order: &[u32], classes: usize, shift: usize) -> Vec<f64> {
        let n = self.x.len();
        let t0 = self.width - 1;
        let np = self.used.as_ref().map_or(self.n_pairs, Vec::len);
        let base = levels.count();
        // The embedded label of every time from the first usable one, once for all lags.
        let label: Vec<u16> = (0..n)
            .map(|t| {
                let mut l = 0usize;
                for d in 0..self.width.min(t + 1) {
                    l = l * base + levels.labels[(t - d + shift) % n] as usize;
                }
                l as u16
            })
            .collect();
        let mut ys = Vec::with_capacity(np);
        let mut labels = Vec::with_capacity(np);
        self.lags
            .iter()
            .map(|tau| {
                let (lo, hi) = (t0 + tau, t0 + tau + np);
                ys.clear();
                labels.clear();
                for &j in order {
                    let j = j as usize;
                    if j >= lo && j < hi && self.uses(j - lo) {
                        ys.push(self.y[j]);
                        labels.push(label[j - tau]);
                    }
                }
                ross_sorted(&ys, &labels, classes, self.k)
            })
            .collect()
    }
}

/// MI against lag, `I(x(t); y(t+τ))` for τ in `lags`, with embedding width 1.
pub fn lagged_profile(
    x: &[f64],
    y: &[f64],
    lags: Lags,
    opts: &MiOptions,
) -> Result<LaggedProfile, InfoError> {
    Ok(LaggedPair::new(x, y, lags, 1, opts)?.profile())
}

/// The lag where the residual's own memory has died out: the first local minimum of its
/// auto-MI `I(y(t); y(t+τ))` for τ = 1..=`max_lag` (Abarbanel's rule, which the paper cites
/// for choosing tmax), or `max_lag` when the auto-MI keeps falling.
pub fn auto_tmax(y: &[f64], max_lag: usize, k: usize) -> Result<usize, InfoError> {
    if max_lag < 2 {
        return Err(InfoError::InvalidParameter {
            name: "max_lag",
            value: max_lag.to_string(),
            reason: "automatic tmax needs at least 2 candidate lags",
        });
    }
    let n = y.len().saturating_sub(max_lag);
    validate::neighbours("automatic tmax", n, k)?;
    let opts = MiOptions { x_kind: super::estimator::XKind::Continuous, ..MiOptions::with_k(k) };
    let mut prev = f64::INFINITY;
    for tau in 1..=max_lag {
        let now = mutual_information(&y[..n], &y[tau..tau + n], &opts)?.nats;
        if now > prev {
            return Ok(tau - 1);
        }
        prev = now;
    }
    Ok(max_lag)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn discrete_profile_equals_direct_estimates() {
        let n = 600;
        let x: Vec<f64> = (0..n).map(|i| if (i * 7 + i / 5) % 3 == 0 { 1.0 } else { -1.0 }).collect();
        let y: Vec<f64> = (0..n)
            .map(|t| if t >= 2 { 0.5 * x[t - 2] } else { 0.0 } + ((t * 7919) % 1009) as f64 / 1009.0)
            .collect();
        let lags = Lags::new(0, 4).unwrap();
        let opts = MiOptions::default();
        let pair = LaggedPair::new(&x, &y, lags, 1, &opts).unwrap();
        assert!(pair.is_discrete());
        let prof = pair.profile();
        let np = n - 4;
        for (i, tau) in lags.iter().enumerate() {
            let direct = mutual_information(&x[..np], &y[tau..tau + np], &opts).unwrap().nats;
            assert!((prof.nats[i] - direct).abs() < 1e-12, "lag {tau}");
        }
        // Shifted: same as estimating on an explicitly rotated x.
        let s = 123;
        let xs: Vec<f64> = (0..n).map(|t| x[(t + s) % n]).collect();
        let shifted = pair.profile_shifted(s);
        for (i, tau) in lags.iter().enumerate() {
            let direct = mutual_information(&xs[..np], &y[tau..tau + np], &opts).unwrap().nats;
            assert!((shifted[i] - direct).abs() < 1e-12, "shifted lag {tau}");
        }
        // The dependence sits at lag 2.
        let best = prof.nats.iter().cloned().enumerate().max_by(|a, b| a.1.total_cmp(&b.1)).unwrap().0;
        assert_eq!(prof.lags[best], 2);
    }

    #[test]
    fn segments_skip_the_pairs_that_straddle_a_gap() {
        use crate::info::estimator::XKind;
        // Two segments (300 + 250); each estimate must equal the direct one on the times whose
        // window t..t+τmax lies inside one segment.
        let n = 550;
        let x: Vec<f64> = (0..n).map(|i| if (i * 11 + i / 3) % 5 < 2 { 1.0 } else { -1.0 }).collect();
        let y: Vec<f64> = (0..n)
            .map(|t| if t >= 1 { 0.4 * x[t - 1] } else { 0.0 } + ((t * 7919) % 1009) as f64 / 1009.0)
            .collect();
        let lags = Lags::new(1, 3).unwrap();
        // Unstandardised, so that the continuous path's scale (taken over the whole series)
        // and the direct estimate's (over the used times) cannot differ.
        let continuous = MiOptions { x_kind: XKind::Continuous, standardize: false, ..MiOptions::default() };
        for opts in [MiOptions::default(), continuous] {
            let pair = LaggedPair::segmented(&x, &y, lags, 1, &opts, &[300, 250]).unwrap();
            let times: Vec<usize> = (0..297).chain(300..547).collect();
            assert_eq!(pair.n_pairs(), times.len());
            let prof = pair.profile();
            let xs: Vec<f64> = times.iter().map(|&t| x[t]).collect();
            for (i, tau) in lags.iter().enumerate() {
                let ys: Vec<f64> = times.iter().map(|&t| y[t + tau]).collect();
                let direct = mutual_information(&xs, &ys, &opts).unwrap().nats;
                assert!((prof.nats[i] - direct).abs() < 1e-9, "lag {tau}: {} vs {direct}", prof.nats[i]);
            }
            let r = pair.linear_profile_shifted(0);
            let direct_r = crate::info::correlation::pearson(
                &xs,
                &times.iter().map(|&t| y[t + 1]).collect::<Vec<_>>(),
                2.0,
            )
            .unwrap()
            .r;
            // The profile normalises by the whole series' moments, Pearson by the used times':
            // 544 of 550 samples, so the two differ by well under 0.01 here.
            assert!((r[0] - direct_r).abs() < 0.01, "{} vs {direct_r}", r[0]);
        }
        assert!(LaggedPair::segmented(&x, &y, lags, 1, &MiOptions::default(), &[300, 200]).is_err());
    }

    #[test]
    fn too_short_for_the_lags_is_an_error() {
        let x = [1.0, -1.0, 1.0, -1.0, 1.0, 1.0];
        let y = [0.1, 0.2, 0.3, 0.5, 0.4, 0.0];
        let err = LaggedPair::new(&x, &y, Lags::new(1, 3).unwrap(), 1, &MiOptions::default()).err().unwrap();
        assert!(matches!(err, InfoError::TooFewSamples { .. }), "{err}");
        assert!(Lags::new(3, 1).is_err());
    }
}
