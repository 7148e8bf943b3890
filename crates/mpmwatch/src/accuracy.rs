//! Benchmark-grade accuracy: the physics a diagnosis names, carried to a benchmark's own
//! estimation and test splits and scored in the benchmark's units beside the linear model of
//! the same orders, so that the figures compare with published ones. Pure.

use serde::Serialize;

use mpmwatch_diagnose::{DiagnoseError, GreyBox, Structure};

/// One model on one benchmark's test split.
#[derive(Debug, Clone, Serialize)]
pub struct AccuracyRow {
    /// Benchmark.
    pub benchmark: &'static str,
    /// The model.
    pub model: String,
    /// Root-mean-square simulation error on the test split, in `unit`.
    pub rmse: f64,
    /// The same on the estimation split (in sample): far below `rmse` means the model does not
    /// carry to the test data.
    pub estimation_rmse: f64,
    /// Unit of `rmse`.
    pub unit: &'static str,
    /// RMSE over the test output's standard deviation, percent.
    pub nrmse_pct: f64,
    /// Estimation and test samples, as the benchmark defines them.
    pub split: String,
    /// What the literature is reported to reach on the same split (quoted, not re-derived).
    pub published: &'static str,
    /// The model's simulation of the test split (the scored samples), for a figure.
    #[serde(skip)]
    pub test_simulation: Vec<f64>,
}

fn rmse(y: &[f64], s: &[f64], skip: usize) -> (f64, f64) {
    let n = (y.len() - skip) as f64;
    let e = (y[skip..].iter().zip(&s[skip..]).map(|(a, b)| (a - b).powi(2)).sum::<f64>() / n).sqrt();
    let m = y[skip..].iter().sum::<f64>() / n;
    let sd = (y[skip..].iter().map(|v| (v - m).powi(2)).sum::<f64>() / n).sqrt();
    (e, 100.0 * e / sd)
}

/// Silverbox (`SNLS80mV`, `V1` in, `V2` out): the models are fitted on the odd multisines
/// (samples 40 000..127 000) and simulated on the arrow head (samples 0..40 000, the first 100
/// left out of the score as the simulation's start-up), whose last part reaches amplitudes
/// above any in the estimation part. Linear dynamics with `na` = 2 poles and `nb` = 3 taps (a
/// mass–spring–damper sampled at 610 Hz), alone and with a force in the cube of the output fed
/// back.
pub fn silverbox(v1: &[f64], v2: &[f64]) -> Result<Vec<AccuracyRow>, DiagnoseError> {
    const EST: std::ops::Range<usize> = 40_000..127_000;
    const TEST: std::ops::Range<usize> = 0..40_000;
    if v1.len() < EST.end || v2.len() < EST.end {
        return Err(DiagnoseError::Invalid {
            what: "Silverbox record".into(),
            reason: format!("{} samples, the benchmark's split needs {}", v1.len().min(v2.len()), EST.end),
        });
    }
    let (ue, ye) = (&v1[EST], &v2[EST]);
    let (ut, yt) = (&v1[TEST], &v2[TEST]);
    let mut rows = Vec::new();
    for (structure, name, published) in [
        (
            Structure::Linear,
            "linear, 2 poles, 3 taps",
            "best linear approximation ≈ 13 % NRMSE (normalisation not stated; not checked here)",
        ),
        (
            Structure::CubicStiffness,
            "linear + cubic stiffness fed back (named by `diagnose`)",
            "with a cubic term ≈ 1 % NRMSE (not checked here)",
        ),
    ] {
        let fitted = GreyBox { structure, na: 2, nb: 3, nk: vec![0] }.fit(&[ue], ye, 0..ye.len())?;
        let s = fitted.simulate(&[ut], yt).ok_or_else(|| DiagnoseError::Invalid {
            what: format!("{name} on the arrow head"),
            reason: "the simulation diverges".into(),
        })?;
        let (e, nrmse_pct) = rmse(yt, &s, 100);
        let se = fitted.simulate(&[ue], ye).unwrap_or_else(|| vec![f64::NAN; ye.len()]);
        let (ee, _) = rmse(ye, &se, 100);
        rows.push(AccuracyRow {
            benchmark: "silverbox",
            model: name.into(),
            rmse: 1e3 * e,
            estimation_rmse: 1e3 * ee,
            unit: "mV",
            nrmse_pct,
            split: "estimation 40 000..127 000 (multisines), test 100..40 000 (arrow head)".into(),
            published,
            test_simulation: s[100..].to_vec(),
        });
    }
    Ok(rows)
}

/// Cascaded tanks (`dataBenchmark`): the Torricelli model calibrated on the estimation record's
/// overflow-free runs (the nominal the diagnosis starts from); the same model with the physics
/// `diagnose` names, the upper tank's overflow, plus the sensor's top at 10 V; and that model
/// with the refinements chosen on the estimation record alone (fitted outflow exponents, the
/// lower tank overflowing at the sensor's top; `scripts/tanks_structure.py`). The last two are
/// fitted on the whole estimation record; all three are simulated on the validation record from
/// its first measured level and scored over all of it in volts. The corrected models' upper tank
/// starts the validation at the level fitted for the estimation record's start (an assumption:
/// both experiments start from about the same state, their first levels 5.2 and 5.0 V); the
/// nominal's starts at the level that holds the measured one steady. The upper tank's rim is
/// not printed: the upper level's scale is not identifiable from the lower level alone.
pub fn cascaded_tanks(
    ue: &[f64],
    ye: &[f64],
    uv: &[f64],
    yv: &[f64],
) -> Result<Vec<AccuracyRow>, DiagnoseError> {
    use crate::tanks::{BENCHMARK_TS, OverflowingTanks, Refinements, calibrate, calibrate_overflowing};
    if ue.len() != ye.len() || uv.len() != yv.len() || ue.len() < 100 || uv.is_empty() {
        return Err(DiagnoseError::Invalid {
            what: "cascaded-tanks records".into(),
            reason: format!(
                "estimation {}/{} and validation {}/{} samples (input/output): they must pair up, ≥ 100",
                ue.len(),
                ye.len(),
                uv.len(),
                yv.len()
            ),
        });
    }
    let nominal = calibrate(ue, ye, BENCHMARK_TS);
    let named = calibrate_overflowing(ue, ye, BENCHMARK_TS, &nominal, Refinements::default());
    let refined = calibrate_overflowing(
        ue,
        ye,
        BENCHMARK_TS,
        &nominal,
        Refinements { exponents: true, lower_overflow: true },
    );
    let split = "estimation uEst/yEst, test uVal/yVal (1024 samples each, all scored)";
    let row = |model: String, s: &[f64], s_est: &[f64], published| {
        let (e, nrmse_pct) = rmse(yv, s, 0);
        let (estimation_rmse, _) = rmse(ye, s_est, 0);
        AccuracyRow {
            benchmark: "cascaded_tanks",
            model,
            rmse: e,
            estimation_rmse,
            unit: "V",
            nrmse_pct,
            split: split.into(),
            published,
            test_simulation: s.to_vec(),
        }
    };
    let on_both =
        |m: &OverflowingTanks| (m.simulate(uv, BENCHMARK_TS, yv[0]), m.simulate(ue, BENCHMARK_TS, ye[0]));
    let upper = |m: &OverflowingTanks| {
        format!(
            "the upper tank's overflow ({:.0} % spills into the lower tank) and the sensor's 10 V top",
            100.0 * m.upper.spill
        )
    };
    let (s_named, s_named_est) = on_both(&named);
    let (s_refined, s_refined_est) = on_both(&refined);
    Ok(vec![
        row(
            "Torricelli two tanks, no overflow".into(),
            &nominal.simulate_from(uv, BENCHMARK_TS, yv[0]),
            &nominal.simulate_from(ue, BENCHMARK_TS, ye[0]),
            "best black-box ≈ 0.34 V (not checked here)",
        ),
        row(
            format!("with {}", upper(&named)),
            &s_named,
            &s_named_est,
            "grey-box with overflow 0.18 V (not checked here)",
        ),
        row(
            format!(
                "with {}, outflow exponents {:.2} and {:.2} fitted, the lower tank overflowing at the sensor's top",
                upper(&refined),
                refined.exponents[0],
                refined.exponents[1]
            ),
            &s_refined,
            &s_refined_est,
            "grey-box with overflow 0.18 V (not checked here)",
        ),
    ])
}

/// Start-up samples of each coupled-drives record left out of the score.
pub const DRIVES_SKIP: usize = 10;

/// One test record of the coupled electric drives.
#[derive(Debug, Clone, Copy)]
pub struct DrivesRecord<'a> {
    /// Which record, for the table (e.g. `u12→z12 (uniform input)`).
    pub label: &'a str,
    /// Input.
    pub u: &'a [f64],
    /// Belt speed as the sensor reads it.
    pub z: &'a [f64],
}

/// Coupled electric drives (CE8, Wigren & Schoukens 2017): linear dynamics with 3 poles, 3 taps
/// and one sample of dead time (the casebook's nominal orders), alone and followed by the
/// direction-blind speed sensor `diagnose` names (`|x|` with a zero offset), fitted by
/// simulation error on the first uniform-input experiment (`u11 → z11`, all of it) and
/// simulated on each test record from its first measured speeds, the first [`DRIVES_SKIP`]
/// samples left out of the score as the start-up. Two rows per test record (linear, then the
/// sensor), models in that order. The casebook passes the second uniform experiment and the
/// three PRBS experiments, which the casebook's own CED case also uses (it calibrates on
/// `u12 → z12` and diagnoses `u1 → z1`), so these test records are not untouched.
pub fn coupled_drives(
    u_est: &[f64],
    z_est: &[f64],
    tests: &[DrivesRecord<'_>],
) -> Result<Vec<AccuracyRow>, DiagnoseError> {
    let bad = |what: &str, u: &[f64], z: &[f64]| {
        (u.len() != z.len() || u.len() <= 4 * DRIVES_SKIP).then(|| DiagnoseError::Invalid {
            what: format!("coupled-drives record {what}"),
            reason: format!(
                "{} input and {} speed samples: they must pair up, > {}",
                u.len(),
                z.len(),
                4 * DRIVES_SKIP
            ),
        })
    };
    if let Some(e) = bad("u11/z11", u_est, z_est) {
        return Err(e);
    }
    if let Some(e) = tests.iter().find_map(|r| bad(r.label, r.u, r.z)) {
        return Err(e);
    }
    let mut rows = Vec::new();
    for (structure, name) in [
        (Structure::Linear, "linear, 3 poles, 3 taps"),
        (Structure::AbsSensor, "the same + absolute-value speed sensor (named by `diagnose`)"),
    ] {
        let fitted = GreyBox { structure, na: 3, nb: 3, nk: vec![1] }.fit(&[u_est], z_est, 0..z_est.len())?;
        let s_est = fitted.simulate(&[u_est], z_est).unwrap_or_else(|| vec![f64::NAN; z_est.len()]);
        let (estimation_rmse, _) = rmse(z_est, &s_est, DRIVES_SKIP);
        for r in tests {
            let s = fitted.simulate(&[r.u], r.z).ok_or_else(|| DiagnoseError::Invalid {
                what: format!("{name} on {}", r.label),
                reason: "the simulation diverges".into(),
            })?;
            let (e, nrmse_pct) = rmse(r.z, &s, DRIVES_SKIP);
            rows.push(AccuracyRow {
                benchmark: "coupled_drives",
                model: name.into(),
                rmse: e,
                estimation_rmse,
                unit: "(sensor units)",
                nrmse_pct,
                split: format!(
                    "estimation u11→z11, test {}; samples {DRIVES_SKIP}..{} scored",
                    r.label,
                    r.z.len()
                ),
                published: "none quoted (not available offline)",
                test_simulation: s[DRIVES_SKIP..].to_vec(),
            });
        }
    }
    Ok(rows)
}
