//! The MI matrix: for every dither i and residual j, the norm of MI over the lag range with its
//! surrogate threshold, the same for the joint embedding of two consecutive dither lags, and
//! the linear baselines (cross-correlation and Pearson) beside it.

use rayon::prelude::*;
use serde::Serialize;

use crate::info::correlation::{ccf, ccf_limit, family_wise_z, pearson};
use crate::info::significance::test_prepared;
use crate::info::{
    FamilyOptions, FamilyTest, InfoError, LaggedPair, Lags, MiOptions, Statistic, SurrogateOptions,
    Threshold, auto_tmax, family_test_group,
};

use super::partial::PartialPlan;
use super::pool::exchangeable_groups;
use super::verdict::{Channel, localise};
use super::whiten::{ArWhitener, drop_segment_heads};

/// A named series.
#[derive(Debug, Clone, Copy)]
pub struct Signal<'a> {
    /// The name shown in reports (a CSV column or tag).
    pub name: &'a str,
    /// The samples.
    pub values: &'a [f64],
}

/// How the lag range is chosen.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum LagChoice {
    /// `min..=max` for every element.
    Fixed(Lags),
    /// `1..=tmax` with tmax the first minimum of each residual's auto-MI, searched up to `max`.
    Auto {
        /// Largest tmax considered.
        max: usize,
    },
}

/// The decision rule of an element.
#[derive(
    Debug,
    Clone,
    Copy,
    PartialEq,
    Eq,
    Serialize,
    serde::Deserialize,
    strum::EnumString,
    strum::Display,
    strum::VariantNames,
)]
#[serde(rename_all = "snake_case")]
#[strum(serialize_all = "snake_case")]
pub enum Method {
    /// One family-wise test over lags and statistics (pairwise MI, joint-lag MI, CCF) at a
    /// stated false-alarm rate `alpha` per element ([`crate::info::family_test`]).
    Family,
    /// The paper's recipe: the norm of MI or any lag's MI above its surrogate `μ + zσ`, and the
    /// joint-lag norm likewise. Kept for comparison and for `reproduce`.
    Paper,
}

/// Options of the matrix.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct MatrixOptions {
    /// The decision rule.
    pub method: Method,
    /// False-alarm rate per element of [`Method::Family`]: the probability that an element
    /// whose submodel is right is called significant in one analysis. A matrix of m elements
    /// raises at most m·alpha false elements per analysis on average (Bonferroni: set
    /// `alpha = a / m` for a matrix-wide rate a). Default 0.01.
    pub alpha: f64,
    /// Lag range.
    pub lags: LagChoice,
    /// Estimator options.
    pub mi: MiOptions,
    /// Surrogate options (count, z, seed). Element (j, i) uses seed `seed + 1000·j + i` so that
    /// elements are independent and the whole matrix is reproducible from one seed.
    pub surrogates: SurrogateOptions,
    /// Also test the embedding of two consecutive dither lags (catches `u(t−1)·u(t−2)`).
    pub joint_embedding: bool,
    /// Family-wise false-alarm rate of the CCF baseline over an element's lags (Bonferroni);
    /// the Pearson limit uses the same rate for its single test. Default 0.05.
    pub ccf_alpha: f64,
    /// Before testing dither i against residual j, subtract from the residual what the other
    /// excited dithers explain linearly over lags 0..=tmax (see [`super::partial_out`]).
    pub partial_out: bool,
    /// Pre-whiten each residual with an AR model of at most this order (AIC) before every
    /// statistic, MI and CCF alike; `None` analyses the raw residuals as the paper does.
    /// See [`super::ArWhitener`] for why this keeps the test's level and raises its power.
    pub whiten: Option<usize>,
}

impl Default for MatrixOptions {
    fn default() -> Self {
        Self {
            method: Method::Family,
            alpha: 0.01,
            lags: LagChoice::Fixed(Lags { min: 1, max: 20 }),
            mi: MiOptions::default(),
            surrogates: SurrogateOptions::default(),
            joint_embedding: true,
            ccf_alpha: 0.05,
            partial_out: true,
            whiten: Some(10),
        }
    }
}

/// One lagged MI test as reported: the profile against lag, per-lag critical values, the norm
/// and its threshold. Values in nats.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct ElementTest {
    /// Lags of the profile.
    pub lags: Vec<usize>,
    /// MI against lag, nats.
    pub profile: Vec<f64>,
    /// Per-lag critical values, nats.
    pub lag_critical: Vec<f64>,
    /// Norm of MI (eq 19), nats.
    pub norm: f64,
    /// Surrogate statistics of the norm.
    pub threshold: Threshold,
    /// Empirical p-value of the norm.
    pub p_value: f64,
    /// Norm above its critical value.
    pub norm_significant: bool,
    /// The lag whose MI exceeds its own critical value by the most, if any does.
    pub peak_lag: Option<usize>,
    /// Norm above its critical value, or MI above the per-lag critical value at some lag.
    pub significant: bool,
    /// Surrogate method used.
    pub method: crate::info::SurrogateMethod,
    /// Surrogate seed.
    pub seed: u64,
}

impl ElementTest {
    /// The norm of MI averages over the lag range, so an effect confined to one lag of twenty
    /// is diluted twentyfold and can stay under the norm's critical value while towering over
    /// its own lag's (measured: 0.146 nats at lag 2 against a per-lag critical value of 0.08,
    /// norm 0.032 against 0.040). The paper reads its figures the same way, by violations of
    /// the per-lag limit, so an element is significant on either count. With z = 6 the extra
    /// per-lag tests add a negligible false-alarm probability.
    fn from(t: crate::info::LaggedTest) -> Self {
        let peak_lag = t
            .profile
            .nats
            .iter()
            .zip(&t.lag_critical)
            .zip(&t.profile.lags)
            .filter(|((v, c), _)| v > c)
            .max_by(|a, b| (a.0.0 - a.0.1).total_cmp(&(b.0.0 - b.0.1)))
            .map(|(_, &lag)| lag);
        Self {
            norm_significant: t.significant,
            peak_lag,
            significant: t.significant || peak_lag.is_some(),
            lags: t.profile.lags,
            profile: t.profile.nats,
            lag_critical: t.lag_critical,
            norm: t.norm,
            threshold: t.threshold,
            p_value: t.p_value,
            method: t.method,
            seed: t.seed,
        }
    }
}

impl ElementTest {
    /// One MI statistic's view of a family-wise test: its profile with the family-wise critical
    /// value per lag, its norm against the calibration surrogates' norms (shown, not decided
    /// on), and `significant` when the family is and this statistic holds its maximum.
    fn from_family(t: &FamilyTest, statistic: Statistic, z: f64) -> Self {
        let p = t.profiles.iter().find(|p| p.statistic == statistic).expect("the statistic was tested");
        let holds_max = t.significant && t.argmax.0 == statistic;
        Self {
            lags: t.lags.clone(),
            profile: p.values.clone(),
            lag_critical: p.critical.clone(),
            norm: p.norm,
            threshold: Threshold {
                mean: p.norm_mean,
                std: p.norm_std,
                critical: p.norm_mean + z * p.norm_std,
            },
            p_value: t.p_value,
            norm_significant: false,
            peak_lag: holds_max.then_some(t.argmax.1),
            significant: holds_max,
            method: t.method,
            seed: t.seed,
        }
    }
}

/// The linear baselines of one element.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct CcfBaseline {
    /// Lags of the CCF (the same range as the MI profile).
    pub lags: Vec<usize>,
    /// Cross-correlation of dither(t) with residual(t+τ).
    pub values: Vec<f64>,
    /// ± control limit z/√N, z family-wise over the lags (Bonferroni).
    pub limit: f64,
    /// The z of that limit.
    pub z: f64,
    /// Samples behind the CCF (after partialling out and whitening trimmed the start).
    pub n: usize,
    /// Any |CCF| above the limit.
    pub significant: bool,
    /// Pearson r at lag 0.
    pub pearson_r: f64,
    /// Its Fisher-transform limit.
    pub pearson_limit: f64,
}

/// The evidence that decided an element (or, when none did, the strongest).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Evidence {
    /// The norm of MI over the lag range (paper).
    NormMi,
    /// MI at one lag.
    LagMi,
    /// The joint-lag MI (its norm under the paper's rule, one lag under the family rule).
    JointMi,
    /// The cross-correlation at one lag (family rule).
    Ccf,
}

/// The decision on one element, the same shape under either rule.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct Decision {
    /// The rule applied.
    pub method: Method,
    /// Significant at the rule's level.
    pub significant: bool,
    /// The p-value: of the family's maximum (family), or the norm's empirical one (paper).
    pub p_value: f64,
    /// The false-alarm rate tested at (family only).
    pub alpha: Option<f64>,
    /// Which statistic decided.
    pub evidence: Evidence,
    /// At which lag, when the statistic is one lag's.
    pub lag: Option<usize>,
    /// Its value: nats for MI, the absolute correlation for the CCF.
    pub value: f64,
    /// Its critical value, same units.
    pub critical: f64,
}

/// Element (j, i) of the matrix: dither i against residual j.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Cell {
    /// Dither (MV) index.
    pub mv: usize,
    /// Residual (CV) index.
    pub cv: usize,
    /// Pairwise lagged test.
    pub pairwise: ElementTest,
    /// Joint embedding of two consecutive dither lags, when enabled.
    pub joint: Option<ElementTest>,
    /// Linear baselines.
    pub ccf: CcfBaseline,
    /// The family-wise test (method `family`).
    pub family: Option<FamilyTest>,
    /// The decision.
    pub decision: Decision,
    /// `decision.significant`.
    pub significant: bool,
    /// The element of eq 21: the pairwise norm when significant, else 0 (nats). When only the
    /// joint statistic is significant, the joint norm.
    pub value: f64,
}

/// The whole analysis.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct MatrixResult {
    /// Dither names, by MV index.
    pub dithers: Vec<String>,
    /// Residual names, by CV index.
    pub residuals: Vec<String>,
    /// Whether each dither carries any excitation (not constant).
    pub excited: Vec<bool>,
    /// Cells in row-major order (cv, then mv), excited dithers only.
    pub cells: Vec<Cell>,
    /// One verdict per tested channel.
    pub channels: Vec<Channel>,
    /// True when any element is significant (Proposition 1: ΔG ≠ 0).
    pub mismatch: bool,
    /// Sample count.
    pub n: usize,
    /// Surrogates per element.
    pub surrogates: usize,
    /// z of the MI critical values (method `paper`).
    pub z: f64,
    /// The decision rule.
    pub method: Method,
    /// Its false-alarm rate per element (method `family`).
    pub alpha: Option<f64>,
    /// Base seed.
    pub seed: u64,
    /// Per residual: the whitening AR model (order 0 and ratio 1 when whitening is off).
    pub whitening: Vec<ArWhitener>,
}

impl MatrixResult {
    /// The cell of dither `mv` against residual `cv`, if that dither was excited.
    pub fn cell(&self, mv: usize, cv: usize) -> Option<&Cell> {
        self.cells.iter().find(|c| c.mv == mv && c.cv == cv)
    }
}

fn check_signals(kind: &str, s: &[Signal<'_>], n: usize) -> Result<(), InfoError> {
    if s.is_empty() {
        return Err(InfoError::InvalidParameter {
            name: "signals",
            value: kind.to_string(),
            reason: "at least one is needed",
        });
    }
    for sig in s {
        crate::info::validate::same_length(sig.name, sig.values.len(), "the first dither", n)?;
        crate::info::validate::finite(sig.name, sig.values)?;
    }
    Ok(())
}

/// Computes the MI matrix, its thresholds, the baselines and the verdicts.
pub fn analyze(
    dithers: &[Signal<'_>],
    residuals: &[Signal<'_>],
    opts: &MatrixOptions,
) -> Result<MatrixResult, InfoError> {
    let n = dithers.first().map_or(0, |d| d.values.len());
    analyze_segments(dithers, residuals, &[n], opts)
}

/// [`analyze`] on a record with gaps, given as contiguous segments of lengths `segments` laid
/// end to end in every signal. Partialling-out, whitening and every lagged statistic stay inside
/// a segment: a regression row, an AR prediction or a lagged pair that would reach across a gap
/// is skipped, so the data before a gap count without a pair ever straddling it.
pub fn analyze_segments(
    dithers: &[Signal<'_>],
    residuals: &[Signal<'_>],
    segments: &[usize],
    opts: &MatrixOptions,
) -> Result<MatrixResult, InfoError> {
    let n = dithers.first().map_or(0, |d| d.values.len());
    check_signals("dithers", dithers, n)?;
    check_signals("residuals", residuals, n)?;
    if segments.iter().sum::<usize>() != n || segments.contains(&0) {
        return Err(InfoError::InvalidParameter {
            name: "segments",
            value: format!("{segments:?}"),
            reason: "the segment lengths must be positive and add up to the signals' length",
        });
    }
    for r in residuals {
        crate::info::validate::not_constant(r.name, r.values)?;
    }
    let excited: Vec<bool> =
        dithers.iter().map(|d| crate::info::validate::not_constant(d.name, d.values).is_ok()).collect();
    if !excited.iter().any(|&e| e) {
        return Err(InfoError::Constant { series: "every dither".into(), value: dithers[0].values[0] });
    }
    let whitening: Vec<ArWhitener> = residuals
        .iter()
        .map(|r| match opts.whiten {
            Some(max) => ArWhitener::fit_segments(r.values, segments, max),
            None => ArWhitener { coefficients: Vec::new(), variance_ratio: 1.0 },
        })
        .collect();
    // The automatic tmax reads the memory of the raw residual (Abarbanel's rule on what the
    // dither drives); whitening spreads an effect over `order` further lags, so they are added.
    let lags: Vec<Lags> = residuals
        .iter()
        .zip(&whitening)
        .map(|(r, w)| match opts.lags {
            LagChoice::Fixed(l) => Ok(l),
            LagChoice::Auto { max } => {
                Lags::new(1, (auto_tmax(r.values, max, opts.mi.k)? + w.order()).min(max))
            }
        })
        .collect::<Result<_, _>>()?;
    let pairs: Vec<(usize, usize)> = (0..residuals.len())
        .flat_map(|j| (0..dithers.len()).map(move |i| (j, i)))
        .filter(|&(_, i)| excited[i])
        .collect();
    let several = excited.iter().filter(|&&e| e).count() > 1;
    let dither_values: Vec<&[f64]> = dithers.iter().map(|d| d.values).collect();
    let cut_of = |j: usize| if opts.partial_out && several { lags[j].max } else { 0 };
    let mut cuts: Vec<usize> = (0..residuals.len()).map(cut_of).filter(|&c| c > 0).collect();
    cuts.sort_unstable();
    cuts.dedup();
    let plans: Vec<(usize, PartialPlan)> =
        cuts.par_iter().map(|&c| (c, PartialPlan::new(&dither_values, &excited, c, segments))).collect();
    let plan_of = |cut: usize| plans.iter().find(|(c, _)| *c == cut).map(|(_, p)| p);
    let fits: Vec<Option<Vec<f64>>> = (0..residuals.len())
        .into_par_iter()
        .map(|j| plan_of(cut_of(j)).and_then(|p| p.fit(residuals[j].values)))
        .collect();
    // Partial out the other dithers, then whiten what is left with an AR model fitted to it
    // (the per-residual whitener is reported; the per-element refit differs only by the removed
    // dither-driven part).
    let prepared: Vec<Prepared> = pairs
        .par_iter()
        .map(|&(j, i)| {
            let (cleaned, d_clean, segs1) = match plan_of(cut_of(j)) {
                Some(plan) => (
                    plan.partial_out(residuals[j].values, fits[j].as_deref(), i),
                    plan.on_rows(dithers[i].values),
                    plan.segments().to_vec(),
                ),
                None => (residuals[j].values.to_vec(), dithers[i].values.to_vec(), segments.to_vec()),
            };
            let w = match opts.whiten {
                Some(max) => ArWhitener::fit_segments(&cleaned, &segs1, max),
                None => ArWhitener { coefficients: Vec::new(), variance_ratio: 1.0 },
            };
            let (residual, segments) = w.apply_segments(&cleaned, &segs1);
            let (dither, _) = drop_segment_heads(&d_clean, &segs1, w.order());
            Prepared { mv: i, cv: j, dither, residual, segments }
        })
        .collect();
    // Under the family rule the elements of one residual whose dithers are alike share their
    // surrogates (see `pool`); the paper's rule keeps one set per element, as published.
    let excited_idx: Vec<usize> = (0..dithers.len()).filter(|&i| excited[i]).collect();
    let dither_groups = match opts.method {
        Method::Family => exchangeable_groups(&dither_values, &excited_idx, &opts.mi),
        Method::Paper => excited_idx.iter().map(|&i| vec![i]).collect(),
    };
    let groups: Vec<Vec<&Prepared>> = (0..residuals.len())
        .flat_map(|j| {
            let prepared = &prepared;
            dither_groups.iter().map(move |g| {
                g.iter().filter_map(|&i| prepared.iter().find(|p| p.cv == j && p.mv == i)).collect()
            })
        })
        .collect();
    let mut cells: Vec<Cell> = groups
        .par_iter()
        .map(|g| group_cells(g, dithers, residuals, lags[g[0].cv], opts))
        .collect::<Result<Vec<_>, _>>()?
        .into_iter()
        .flatten()
        .collect();
    cells.sort_by_key(|c| (c.cv, c.mv));
    let channels = localise(&cells, &excited, dithers, residuals);
    Ok(MatrixResult {
        dithers: dithers.iter().map(|d| d.name.to_string()).collect(),
        residuals: residuals.iter().map(|r| r.name.to_string()).collect(),
        mismatch: cells.iter().any(|c| c.significant),
        excited,
        cells,
        channels,
        n,
        surrogates: opts.surrogates.count,
        z: opts.surrogates.z,
        method: opts.method,
        alpha: (opts.method == Method::Family).then_some(opts.alpha),
        seed: opts.surrogates.seed,
        whitening,
    })
}

/// One element's series after partialling-out and whitening.
struct Prepared {
    mv: usize,
    cv: usize,
    dither: Vec<f64>,
    residual: Vec<f64>,
    segments: Vec<usize>,
}

/// The cells of one group of elements of a residual: under the family rule tested together on
/// shared surrogates, under the paper's rule one by one.
fn group_cells(
    group: &[&Prepared],
    dithers: &[Signal<'_>],
    residuals: &[Signal<'_>],
    lags: Lags,
    opts: &MatrixOptions,
) -> Result<Vec<Cell>, InfoError> {
    let seed_of = |e: &Prepared| opts.surrogates.seed + 1000 * e.cv as u64 + e.mv as u64;
    let built = group
        .iter()
        .map(|e| {
            let pair = LaggedPair::segmented(&e.dither, &e.residual, lags, 1, &opts.mi, &e.segments)?;
            let pair2 = if opts.joint_embedding {
                Some(LaggedPair::segmented(&e.dither, &e.residual, lags, 2, &opts.mi, &e.segments)?)
            } else {
                None
            };
            Ok((pair, pair2))
        })
        .collect::<Result<Vec<_>, InfoError>>()?;
    let mut family: Vec<Option<FamilyTest>> = match opts.method {
        Method::Paper => vec![None; group.len()],
        Method::Family => {
            let sur = SurrogateOptions { seed: seed_of(group[0]), ..opts.surrogates };
            let fo = FamilyOptions { alpha: opts.alpha, surrogates: sur, ..FamilyOptions::default() };
            let elements: Vec<_> = built.iter().map(|(p, j)| (p, j.as_ref())).collect();
            family_test_group(&elements, &fo)?.into_iter().map(Some).collect()
        }
    };
    group
        .iter()
        .zip(&built)
        .zip(family.iter_mut())
        .map(|((e, (pair, pair2)), family)| {
            let d = Signal { name: dithers[e.mv].name, values: &e.dither };
            let r = Signal { name: residuals[e.cv].name, values: &e.residual };
            let sur = SurrogateOptions { seed: seed_of(e), ..opts.surrogates };
            cell(&d, &r, e.mv, e.cv, (pair, pair2.as_ref()), family.take(), &e.segments, &sur, opts)
        })
        .collect()
}

#[allow(clippy::too_many_arguments)]
fn cell(
    d: &Signal<'_>,
    r: &Signal<'_>,
    mv: usize,
    cv: usize,
    (pair, pair2): (&LaggedPair<'_>, Option<&LaggedPair<'_>>),
    family: Option<FamilyTest>,
    segments: &[usize],
    sur: &SurrogateOptions,
    opts: &MatrixOptions,
) -> Result<Cell, InfoError> {
    let lags = pair.lags();
    // With gaps, the CCF over the pair set (which never straddles one); without, the whole
    // record's 1/N form, as before.
    let (ccf_values, n_ccf) = if segments.len() > 1 {
        (pair.linear_profile_shifted(0), pair.n_pairs())
    } else {
        (ccf(d.values, r.values, lags.min as i64..=lags.max as i64)?, d.values.len())
    };
    let z = family_wise_z(opts.ccf_alpha, lags.len());
    let limit = ccf_limit(n_ccf, z);
    let p = pearson(d.values, r.values, family_wise_z(opts.ccf_alpha, 1))?;
    let ccf = CcfBaseline {
        lags: lags.iter().collect(),
        significant: ccf_values.iter().any(|v| v.abs() > limit),
        values: ccf_values,
        limit,
        z,
        n: n_ccf,
        pearson_r: p.r,
        pearson_limit: p.limit,
    };
    let (pairwise, joint, family, decision) = match family {
        None => {
            let pairwise = ElementTest::from(test_prepared(pair, sur)?);
            let joint = match pair2 {
                Some(p2) => Some(ElementTest::from(test_prepared(
                    p2,
                    &SurrogateOptions { seed: sur.seed ^ 0x5eed, ..*sur },
                )?)),
                None => None,
            };
            let decision = paper_decision(&pairwise, joint.as_ref());
            (pairwise, joint, None, decision)
        }
        Some(t) => {
            let pairwise = ElementTest::from_family(&t, Statistic::Mi, opts.surrogates.z);
            let joint =
                pair2.is_some().then(|| ElementTest::from_family(&t, Statistic::JointMi, opts.surrogates.z));
            let decision = family_decision(&t);
            (pairwise, joint, Some(t), decision)
        }
    };
    let value = if !decision.significant {
        0.0
    } else if decision.evidence == Evidence::JointMi {
        joint.as_ref().map_or(0.0, |j| j.norm)
    } else {
        pairwise.norm
    };
    Ok(Cell { mv, cv, pairwise, joint, ccf, family, significant: decision.significant, decision, value })
}

fn paper_decision(pairwise: &ElementTest, joint: Option<&ElementTest>) -> Decision {
    let base = Decision {
        method: Method::Paper,
        significant: pairwise.significant || joint.is_some_and(|j| j.significant),
        p_value: pairwise.p_value,
        alpha: None,
        evidence: Evidence::NormMi,
        lag: None,
        value: pairwise.norm,
        critical: pairwise.threshold.critical,
    };
    if pairwise.norm_significant {
        base
    } else if let Some(lag) = pairwise.peak_lag
        && let Some(k) = pairwise.lags.iter().position(|&l| l == lag)
    {
        Decision {
            evidence: Evidence::LagMi,
            lag: Some(lag),
            value: pairwise.profile[k],
            critical: pairwise.lag_critical[k],
            ..base
        }
    } else if let Some(j) = joint.filter(|j| j.significant) {
        Decision {
            evidence: Evidence::JointMi,
            value: j.norm,
            critical: j.threshold.critical,
            p_value: j.p_value,
            ..base
        }
    } else {
        base
    }
}

fn family_decision(t: &FamilyTest) -> Decision {
    let (statistic, lag) = t.argmax;
    let profile =
        t.profiles.iter().find(|p| p.statistic == statistic).expect("the argmax names a tested statistic");
    let k = t.lags.iter().position(|&l| l == lag).expect("the argmax lag is in the range");
    let evidence = match statistic {
        Statistic::Mi => Evidence::LagMi,
        Statistic::JointMi => Evidence::JointMi,
        Statistic::Ccf => Evidence::Ccf,
    };
    let (value, critical) = match statistic {
        Statistic::Ccf => (profile.values[k].abs(), profile.mean[k].abs() + t.critical_z * profile.std[k]),
        _ => (profile.values[k], profile.critical[k]),
    };
    Decision {
        method: Method::Family,
        significant: t.significant,
        p_value: t.p_value,
        alpha: Some(t.alpha),
        evidence,
        lag: Some(lag),
        value,
        critical,
    }
}
