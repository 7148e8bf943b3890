//! The real recordings of the casebook: each read from the shared data folder, given the
//! nominal model a user would have (an ARX fitted as stated per recording, or the tanks' own
//! simulation), diagnosed, and written as a table row, a JSON entry and figures.

use std::path::Path;

use anyhow::Context;
use mpmwatch_core::detect::Signal;
use mpmwatch_core::model::{Arx, ArxOrders};
use mpmwatch_diagnose::{DiagnoseInput, DiagnoseOptions, fit_pct};
use serde_json::json;

pub(super) struct RealResult {
    pub(super) row: String,
    pub(super) json: serde_json::Value,
}

pub(super) type RealCase = fn(&Path, &DiagnoseOptions, &Path) -> anyhow::Result<RealResult>;

/// Reads a headered CSV without a time column (the benchmark files); empty cells are NaN.
pub(super) fn read_plain(path: &Path) -> anyhow::Result<(Vec<String>, Vec<Vec<f64>>)> {
    let text = std::fs::read_to_string(path).with_context(|| {
        format!("cannot read {} (the real recordings live outside the repository)", path.display())
    })?;
    let mut lines = text.lines();
    let header: Vec<String> = lines
        .next()
        .unwrap_or("")
        .split(',')
        .map(|s| s.trim().trim_matches('"').to_string())
        .filter(|s| !s.is_empty())
        .collect();
    let mut cols = vec![Vec::new(); header.len()];
    for l in lines.filter(|l| !l.trim().is_empty()) {
        for (c, cell) in l.split(',').take(header.len()).enumerate() {
            cols[c].push(cell.trim().parse::<f64>().unwrap_or(f64::NAN));
        }
    }
    Ok((header, cols))
}

/// Column `name` of a [`read_plain`] file; an error names the file when the column is missing
/// or has no rows (every caller starts a simulation from its first value).
pub(super) fn column(h: &[String], c: &[Vec<f64>], name: &str, path: &Path) -> anyhow::Result<Vec<f64>> {
    let col = h
        .iter()
        .position(|n| n == name)
        .map(|k| c[k].clone())
        .with_context(|| format!("{} has no column `{name}`", path.display()))?;
    anyhow::ensure!(!col.is_empty(), "{}: column `{name}` has no rows", path.display());
    Ok(col)
}

/// A linear ARX(na, nb) model with a constant and a dead time, fitted by least squares on
/// `rows` (after the longest lag), as a user would fit a nominal model to a record.
fn arx(
    u: &[f64],
    y: &[f64],
    na: usize,
    nb: usize,
    delay: usize,
    rows: std::ops::Range<usize>,
) -> anyhow::Result<Arx> {
    let lag = na.max(delay + nb);
    let orders = ArxOrders { na, nb, delays: vec![delay] };
    Arx::fit(y, &[u], &orders, rows.start + lag..rows.end)
        .context("the nominal ARX fit failed (a value is not finite)")
}

/// [`arx`] simulated over the whole record (simulation mode, started at the first output).
fn arx_simulation(
    u: &[f64],
    y: &[f64],
    na: usize,
    nb: usize,
    delay: usize,
    rows: std::ops::Range<usize>,
) -> anyhow::Result<Vec<f64>> {
    Ok(arx(u, y, na, nb, delay, rows)?.simulate_from(&[u], y[0])?)
}

#[allow(clippy::too_many_arguments)]
fn real_case(
    name: &str,
    model: &str,
    time: Vec<f64>,
    u: Vec<f64>,
    y: Vec<f64>,
    s: Vec<f64>,
    expected: &str,
    physical: Option<&dyn mpmwatch_diagnose::PhysicalModel>,
    opts: &DiagnoseOptions,
    fig: &Path,
) -> anyhow::Result<RealResult> {
    let input = DiagnoseInput {
        time: &time,
        inputs: vec![Signal { name: "u", values: &u }],
        excitations: None,
        outputs: vec![Signal { name: "y", values: &y }],
        simulated: vec![Signal { name: "y", values: &s }],
        physical: vec![physical],
    };
    let dg = mpmwatch_diagnose::diagnose(&input, opts)?;
    crate::cmd::diagnose::output_figure(
        fig,
        &format!("real_{name}"),
        &format!("{name}: recorded, nominal, corrected"),
        &time,
        &y,
        &s,
        &dg.corrected[0],
        dg.report.holdout.start_index,
    )?;
    if let Some(Some(c)) = dg.curves.first() {
        crate::cmd::diagnose::element_figure(
            fig,
            &format!("real_{name}_element"),
            &format!("{name}: the fitted {}", c.physics.name()),
            c,
        )?;
    }
    let f = dg.report.findings.first();
    let (fb, fa) = (dg.report.holdout.fit_before_pct["y"], dg.report.holdout.fit_after_pct["y"]);
    let physics = f.map_or("none".to_string(), |f| f.physics.name().to_string());
    let params = f.map_or(String::new(), |f| {
        f.parameters
            .iter()
            .filter(|(k, _)| *k != "intercept")
            .map(|(k, v)| format!("{k} = {v:.4}"))
            .collect::<Vec<_>>()
            .join(", ")
    });
    let row = format!(
        "| {name} | {model} | {} | {physics} (expected: {expected}) | {params} | {fb:.1} → {fa:.1} | ![{name}](figures/real_{name}.png) |\n",
        f.map_or("none".into(), |f| format!("{}→{}", f.input, f.output)),
    );
    Ok(RealResult {
        row,
        json: json!({"recording": name, "simulation": model, "expected": expected, "physics_named": physics,
                     "holdout_fit_before_pct": fb, "holdout_fit_after_pct": fa, "whole_record_fit_before_pct": fit_pct(&y, &s),
                     "report": dg.report}),
    })
}

/// Silverbox, the arrow-head part of SNLS80mV (samples 0..40 000, amplitude growing): a linear
/// ARX(2,3) fitted on the low-amplitude samples 2 000..10 000, simulated over the whole arrow,
/// diagnosed on its last 10 000 samples (the largest amplitudes, where the cubic term shows).
pub(super) fn silverbox(data: &Path, opts: &DiagnoseOptions, fig: &Path) -> anyhow::Result<RealResult> {
    let p = data.join("silverbox/SNLS80mV.csv");
    let (h, c) = read_plain(&p)?;
    let (v1, v2) = (column(&h, &c, "V1", &p)?, column(&h, &c, "V2", &p)?);
    anyhow::ensure!(
        v1.len().min(v2.len()) >= 40_000,
        "{}: {} rows, where the arrow head takes the first 40 000",
        p.display(),
        v1.len().min(v2.len())
    );
    let (u_all, y_all) = (&v1[..40_000], &v2[..40_000]);
    let s_all = arx_simulation(u_all, y_all, 2, 3, 0, 2_000..10_000)?;
    let w = 30_000..40_000;
    let (u, y, s) = (u_all[w.clone()].to_vec(), y_all[w.clone()].to_vec(), s_all[w].to_vec());
    let time: Vec<f64> = (0..u.len()).map(|k| k as f64 / 610.35).collect();
    real_case(
        "silverbox",
        "linear ARX(2,3) fitted on low-amplitude samples",
        time,
        u,
        y,
        s,
        "cubic",
        None,
        opts,
        fig,
    )
}

/// Coupled electric drives: a linear ARX(3,3) model of the belt speed, calibrated on the
/// uniform-input experiment's second record (`u12 → z12`, input mostly positive, so the speed
/// seldom changes sign and the |·| sensor hardly matters there), simulated on the PRBS ±1
/// experiment (`u1 → z1`), where the speed does change sign.
pub(super) fn ced(data: &Path, opts: &DiagnoseOptions, fig: &Path) -> anyhow::Result<RealResult> {
    let pu = data.join("ced/DATAUNIF.csv");
    let (hu, cu) = read_plain(&pu)?;
    let (uc, yc) = (column(&hu, &cu, "u12", &pu)?, column(&hu, &cu, "z12", &pu)?);
    let p = data.join("ced/DATAPRBS.csv");
    let (h, c) = read_plain(&p)?;
    let (u, y) = (column(&h, &c, "u1", &p)?, column(&h, &c, "z1", &p)?);
    let s = arx(&uc, &yc, 3, 3, 1, 0..uc.len())?.simulate_from(&[&u], y[0])?;
    let time: Vec<f64> = (0..u.len()).map(|k| k as f64 * 0.02).collect();
    real_case(
        "ced",
        "linear ARX(3,3) calibrated on DATAUNIF u12→z12",
        time,
        u,
        y,
        s,
        "abs_sensor",
        None,
        opts,
        fig,
    )
}

/// TCLab sine test (heater 1 swept sinusoidally 0–100 %, period 5 min): temperature 1 against a
/// linear first-order ARX(1,1) model fitted on the first 70 % (the training part).
pub(super) fn tclab(data: &Path, opts: &DiagnoseOptions, fig: &Path) -> anyhow::Result<RealResult> {
    let p = data.join("tclab/tclab_sine_test_5min_period.csv");
    let (h, c) = read_plain(&p)?;
    let (time, u, y) = (column(&h, &c, "Time", &p)?, column(&h, &c, "Q1", &p)?, column(&h, &c, "T1", &p)?);
    let n = time.len();
    let s = arx_simulation(&u, &y, 1, 1, 1, 0..(n * 7 / 10))?;
    real_case("tclab", "linear first-order ARX(1,1)", time, u, y, s, "say what it finds", None, opts, fig)
}

/// Cascaded tanks: a Torricelli two-tank simulation without overflow, calibrated on the
/// estimation record's samples below the overflow level.
pub(super) fn tanks(data: &Path, opts: &DiagnoseOptions, fig: &Path) -> anyhow::Result<RealResult> {
    let p = data.join("cascaded_tanks/dataBenchmark.csv");
    let (h, c) = read_plain(&p)?;
    let (ue, ye) = (column(&h, &c, "uEst", &p)?, column(&h, &c, "yEst", &p)?);
    let (uv, yv) = (column(&h, &c, "uVal", &p)?, column(&h, &c, "yVal", &p)?);
    // The simulation handed to `diagnose` is the model's own, so that it can re-run the model
    // with a tank overflowing.
    let record = mpmwatch::tanks::benchmark_record(&ue, &ye, &uv, &yv);
    let s = mpmwatch_diagnose::PhysicalModel::simulate(&record);
    let u: Vec<f64> = ue.iter().chain(&uv).copied().collect();
    let y: Vec<f64> = ye.iter().chain(&yv).copied().collect();
    let time: Vec<f64> = (0..u.len()).map(|k| k as f64 * record.ts).collect();
    let opts = mpmwatch::tanks::benchmark_options(opts);
    real_case(
        "cascaded_tanks",
        "Torricelli two tanks, no overflow (the model itself handed to `diagnose`)",
        time,
        u,
        y,
        s,
        "saturation",
        Some(&record),
        &opts,
        fig,
    )
}

/// Cascaded tanks as a user with a linear model meets them, through the CSV verb's path (no
/// physical model): an ARX(2,2,1) fitted by least squares on the estimation record, run on the
/// validation record from its first level, which is diagnosed with the casebook's settings
/// (the last 30 % held out).
pub(super) fn tanks_arx(data: &Path, opts: &DiagnoseOptions, fig: &Path) -> anyhow::Result<RealResult> {
    let p = data.join("cascaded_tanks/dataBenchmark.csv");
    let (h, c) = read_plain(&p)?;
    let (ue, ye) = (column(&h, &c, "uEst", &p)?, column(&h, &c, "yEst", &p)?);
    let (u, y) = (column(&h, &c, "uVal", &p)?, column(&h, &c, "yVal", &p)?);
    let s = arx(&ue, &ye, 2, 2, 1, 0..ue.len())?.simulate_from(&[&u], y[0])?;
    let time: Vec<f64> = (0..u.len()).map(|k| k as f64 * mpmwatch::tanks::BENCHMARK_TS).collect();
    real_case(
        "cascaded_tanks_arx",
        "linear ARX(2,2,1) fitted on the estimation record, run on the validation record",
        time,
        u,
        y,
        s,
        "saturation",
        None,
        opts,
        fig,
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A file with a header and no rows, or without the column asked for, is an error naming
    /// the file and the column, not a panic on the first sample.
    #[test]
    fn a_missing_or_empty_column_is_an_error_naming_it() {
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("empty.csv");
        std::fs::write(&p, "\"uEst\",\"yEst\"\n\n").unwrap();
        let (h, c) = read_plain(&p).unwrap();
        let e = column(&h, &c, "yEst", &p).unwrap_err().to_string();
        assert!(e.contains("empty.csv") && e.contains("`yEst` has no rows"), "{e}");
        let e = column(&h, &c, "uVal", &p).unwrap_err().to_string();
        assert!(e.contains("has no column `uVal`"), "{e}");
        std::fs::write(&p, "uEst,yEst\n1,2\n").unwrap();
        let (h, c) = read_plain(&p).unwrap();
        assert_eq!(column(&h, &c, "yEst", &p).unwrap(), vec![2.0]);
    }
}
