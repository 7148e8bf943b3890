//! Where the mismatch is: which input→output channels, and with a physical model which state
//! limits, the data implicate. Three tests, each against its own surrogates: the MI matrix of the
//! excitations against the residuals ([`mpmwatch_core::detect::analyze`]), the dither-projection
//! test ([`crate::projection`]) and, with a physical model, the state-limit test
//! ([`crate::physical`]). In a closed loop only what they flag is explained, so a
//! disturbance-only change, which no dither carries, yields no finding (an open-loop record's
//! grey-box step also explains what nothing flagged, see [`crate::explain`]).

use mpmwatch_core::detect::{LagChoice, MatrixOptions, MatrixResult, Signal};
use mpmwatch_core::info::SurrogateOptions;

use crate::error::DiagnoseError;
use crate::input::{DiagnoseInput, DiagnoseOptions};
use crate::nominal;
use crate::physical::{self, LimitTest};
use crate::plan::Plan;
use crate::projection::{self, DrivenMap, ProjectionOptions, ProjectionTest};
use crate::report::{ChannelReport, StateReport};

/// What the locating tests found, per testable output (in the order of [`Plan::testable`]).
pub(crate) struct Located {
    /// The MI matrix on the training part (`None` when no output is testable).
    pub matrix: Option<MatrixResult>,
    /// The dither-projection test of every element.
    pub projection: Vec<ProjectionTest>,
    /// The state-limit test of each testable output (`None`: no physical model, no limit
    /// hypothesis, too few rows, or a residual that whitens to zero).
    pub limit_tests: Vec<Option<LimitTest>>,
    /// The state-limit tests, for the report.
    pub states: Vec<StateReport>,
    /// Every element's statistics, for the report.
    pub channels: Vec<ChannelReport>,
}

impl Located {
    fn projection_of(&self, mv: usize, cv: usize) -> Option<&ProjectionTest> {
        self.projection.iter().find(|p| p.input == mv && p.output == cv)
    }

    /// The inputs of `inputs` whose element with testable output `cv` the MI matrix or the
    /// projection test flags.
    pub fn flagged(&self, cv: usize, inputs: usize) -> Vec<usize> {
        let Some(m) = &self.matrix else { return Vec::new() };
        (0..inputs)
            .filter(|&i| {
                m.cells.iter().any(|c| c.cv == cv && c.mv == i && c.significant)
                    || self.projection_of(i, cv).is_some_and(|p| p.significant)
            })
            .collect()
    }

    /// The state-limit test of testable output `cv` fired.
    pub fn limits(&self, cv: usize) -> bool {
        self.limit_tests[cv].as_ref().is_some_and(|t| t.significant)
    }

    /// Some test fired.
    pub fn any(&self) -> bool {
        self.matrix.as_ref().is_some_and(|m| m.mismatch)
            || self.projection.iter().any(|p| p.significant)
            || self.states.iter().any(|s| s.significant)
    }
}

/// Runs the locating tests on the training part.
pub(crate) fn locate(
    input: &DiagnoseInput<'_>,
    opts: &DiagnoseOptions,
    plan: &Plan<'_>,
) -> Result<Located, DiagnoseError> {
    let (n_train, split, residuals, testable, ctxs) =
        (plan.n_train, &plan.split, &plan.residuals, &plan.testable, &plan.ctxs);
    let matrix = if testable.is_empty() {
        None
    } else {
        let d: Vec<Signal<'_>> =
            plan.exc.iter().map(|e| Signal { name: e.name, values: &e.values[..n_train] }).collect();
        let r: Vec<Signal<'_>> = testable
            .iter()
            .map(|&j| Signal { name: input.outputs[j].name, values: &residuals[j][..n_train] })
            .collect();
        let mo = MatrixOptions {
            method: opts.locate,
            alpha: opts.alpha / (plan.exc.len() * testable.len()) as f64,
            lags: LagChoice::Fixed(opts.lags),
            surrogates: SurrogateOptions {
                count: opts.surrogates,
                seed: opts.seed,
                ..SurrogateOptions::default()
            },
            ..MatrixOptions::default()
        };
        Some(mpmwatch_core::detect::analyze(&d, &r, &mo)?)
    };
    let mut limit_tests: Vec<Option<LimitTest>> = vec![None; testable.len()];
    let mut states = Vec::new();
    for (cv, &j) in testable.iter().enumerate() {
        if input.physical.get(j).copied().flatten().is_none() {
            continue;
        }
        let ctx = &ctxs[cv];
        let k = plan.limits[cv];
        limit_tests[cv] = physical::limit_test(
            &residuals[j],
            &ctx.physical_terms[..k],
            split.train.clone(),
            ProjectionOptions::default().z,
        );
        if let Some(t) = &limit_tests[cv] {
            states.push(StateReport {
                output: input.outputs[j].name.to_string(),
                states: ctx.state_names.clone(),
                hypotheses: k,
                r2: t.r2,
                critical: t.threshold.critical,
                significant: t.significant,
            });
        }
    }
    let projection = if testable.is_empty() {
        Vec::new()
    } else {
        let exc_tr: Vec<&[f64]> = plan.exc.iter().map(|e| &e.values[..n_train]).collect();
        let u_tr: Vec<&[f64]> = plan.u_all.iter().map(|u| &u[..n_train]).collect();
        let map = DrivenMap::fit(&u_tr, &exc_tr, split.train.clone());
        let r_tr: Vec<&[f64]> = testable.iter().map(|&j| &residuals[j][..n_train]).collect();
        let models: Vec<&nominal::NominalArx> = ctxs.iter().map(|c| &c.model).collect();
        let has: Vec<Vec<bool>> = ctxs.iter().map(|c| c.has_channel.clone()).collect();
        let po = ProjectionOptions { surrogates: opts.surrogates, seed: opts.seed, ..Default::default() };
        projection::projection_tests(&exc_tr, &map, &r_tr, &models, &has, split.train.clone(), &po)
    };
    let mut located = Located { matrix, projection, limit_tests, states, channels: Vec::new() };
    located.channels = channel_reports(input, testable, &located);
    Ok(located)
}

/// Every element's statistics for the report: the MI norm against its critical value (the
/// pairwise MI's, or the joint embedding's where only that was significant), the verdict, the
/// CCF baseline and the projection test.
fn channel_reports(input: &DiagnoseInput<'_>, testable: &[usize], located: &Located) -> Vec<ChannelReport> {
    let Some(m) = &located.matrix else { return Vec::new() };
    let proj = |mv: usize, cv: usize| located.projection_of(mv, cv);
    let mut channels = Vec::new();
    for c in &m.cells {
        let j = testable[c.cv];
        let bits = std::f64::consts::LN_2;
        let (norm, thr) = if c.pairwise.significant || c.joint.is_none() {
            (c.pairwise.norm, c.pairwise.threshold.critical)
        } else {
            let jt = c.joint.as_ref().map(|j| (j.norm, j.threshold.critical)).unwrap_or_default();
            if c.significant { jt } else { (c.pairwise.norm, c.pairwise.threshold.critical) }
        };
        let verdict =
            m.channels.iter().find(|ch| ch.mv_index == c.mv && ch.cv_index == c.cv).map(|ch| ch.verdict);
        let p = proj(c.mv, c.cv);
        channels.push(ChannelReport {
            input: input.inputs[c.mv].name.to_string(),
            output: input.outputs[j].name.to_string(),
            norm_mi_bits: norm / bits,
            threshold_bits: thr / bits,
            significant: c.significant,
            verdict: verdict
                .and_then(|v| serde_json::to_value(v).ok().and_then(|v| v.as_str().map(str::to_string)))
                .unwrap_or_default(),
            ccf_significant: c.ccf.significant,
            projection_r2: p.map_or(0.0, |p| p.r2),
            projection_critical: p.map_or(0.0, |p| p.threshold.critical),
            projection_significant: p.is_some_and(|p| p.significant),
        });
    }
    channels
}
