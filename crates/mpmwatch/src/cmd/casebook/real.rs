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
        physical: vec![physical],
        ..DiagnoseInput::open_loop(
            &time,
            Signal { name: "u", values: &u },
            Signal { name: "y", values: &y },
            &s,
        )
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
    silverbox_window(data, opts, fig, "silverbox", 30_000..40_000)
}

/// Silverbox, the odd multisine that follows the arrow head in SNLS80mV, samples 60 000..70 000,
/// against the same ARX(2,3) fitted on the arrow's low amplitudes: another experiment on the
/// same circuit, first diagnosed at stop 74 (docs/diagnose-history.md).
pub(super) fn silverbox_multisine(
    data: &Path,
    opts: &DiagnoseOptions,
    fig: &Path,
) -> anyhow::Result<RealResult> {
    silverbox_window(data, opts, fig, "silverbox_multisine", 60_000..70_000)
}

/// The Silverbox's linear ARX(2,3), fitted on SNLS80mV's samples 2 000..10 000 (the arrow
/// head's low amplitudes), simulated from the record's start up to the end of window `w`, which
/// is diagnosed.
fn silverbox_window(
    data: &Path,
    opts: &DiagnoseOptions,
    fig: &Path,
    name: &str,
    w: std::ops::Range<usize>,
) -> anyhow::Result<RealResult> {
    let p = data.join("silverbox/SNLS80mV.csv");
    let (h, c) = read_plain(&p)?;
    let (v1, v2) = (column(&h, &c, "V1", &p)?, column(&h, &c, "V2", &p)?);
    anyhow::ensure!(
        v1.len().min(v2.len()) >= w.end,
        "{}: {} rows, where the window {name} ends at row {}",
        p.display(),
        v1.len().min(v2.len()),
        w.end
    );
    let (u_all, y_all) = (&v1[..w.end], &v2[..w.end]);
    let s_all = arx_simulation(u_all, y_all, 2, 3, 0, 2_000..10_000)?;
    let (u, y, s) = (u_all[w.clone()].to_vec(), y_all[w.clone()].to_vec(), s_all[w].to_vec());
    let time: Vec<f64> = (0..u.len()).map(|k| k as f64 / 610.35).collect();
    real_case(
        name,
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
    ced_on(data, opts, fig, "ced", "DATAPRBS.csv", "u1", "z1")
}

/// The drives' PRBS ±1.5 experiment (`u2 → z2`) against the same calibrated ARX(3,3): first
/// diagnosed at stop 74.
pub(super) fn ced_u2z2(data: &Path, opts: &DiagnoseOptions, fig: &Path) -> anyhow::Result<RealResult> {
    ced_on(data, opts, fig, "ced_u2z2", "DATAPRBS.csv", "u2", "z2")
}

/// The drives' PRBS ±0.5 experiment (`u3 → z3`) against the same calibrated ARX(3,3): first
/// diagnosed at stop 74.
pub(super) fn ced_u3z3(data: &Path, opts: &DiagnoseOptions, fig: &Path) -> anyhow::Result<RealResult> {
    ced_on(data, opts, fig, "ced_u3z3", "DATAPRBS.csv", "u3", "z3")
}

/// The drives' first uniform-input experiment (`u11 → z11`, the speed changing sign) against
/// the ARX(3,3) calibrated on the second: first diagnosed at stop 74.
pub(super) fn ced_u11z11(data: &Path, opts: &DiagnoseOptions, fig: &Path) -> anyhow::Result<RealResult> {
    ced_on(data, opts, fig, "ced_u11z11", "DATAUNIF.csv", "u11", "z11")
}

/// One experiment of the coupled drives (`file`, columns `uc → yc`) against the linear
/// ARX(3,3) calibrated on `u12 → z12` of DATAUNIF.csv, simulated from the experiment's first
/// speed.
fn ced_on(
    data: &Path,
    opts: &DiagnoseOptions,
    fig: &Path,
    name: &str,
    file: &str,
    uc: &str,
    yc: &str,
) -> anyhow::Result<RealResult> {
    let pu = data.join("ced/DATAUNIF.csv");
    let (hu, cu) = read_plain(&pu)?;
    let (ucal, ycal) = (column(&hu, &cu, "u12", &pu)?, column(&hu, &cu, "z12", &pu)?);
    let p = data.join("ced").join(file);
    let (h, c) = read_plain(&p)?;
    let (u, y) = (column(&h, &c, uc, &p)?, column(&h, &c, yc, &p)?);
    let s = arx(&ucal, &ycal, 3, 3, 1, 0..ucal.len())?.simulate_from(&[&u], y[0])?;
    let time: Vec<f64> = (0..u.len()).map(|k| k as f64 * 0.02).collect();
    real_case(
        name,
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
    tclab_on(data, opts, fig, "tclab", "T1")
}

/// The same sine test read at the neighbouring sensor, temperature 2, which heater 1 warms
/// through the board: first diagnosed at stop 74.
pub(super) fn tclab_t2(data: &Path, opts: &DiagnoseOptions, fig: &Path) -> anyhow::Result<RealResult> {
    tclab_on(data, opts, fig, "tclab_t2", "T2")
}

/// The TCLab sine test's heater 1 against temperature column `yc`, with a linear first-order
/// ARX(1,1) (one sample of dead time) fitted on the record's first 70 %.
fn tclab_on(
    data: &Path,
    opts: &DiagnoseOptions,
    fig: &Path,
    name: &str,
    yc: &str,
) -> anyhow::Result<RealResult> {
    let p = data.join("tclab/tclab_sine_test_5min_period.csv");
    let (h, c) = read_plain(&p)?;
    let (time, u, y) = (column(&h, &c, "Time", &p)?, column(&h, &c, "Q1", &p)?, column(&h, &c, yc, &p)?);
    let n = time.len();
    let s = arx_simulation(&u, &y, 1, 1, 1, 0..(n * 7 / 10))?;
    real_case(name, "linear first-order ARX(1,1)", time, u, y, s, "say what it finds", None, opts, fig)
}

/// Cascaded tanks: a Torricelli two-tank simulation without overflow, calibrated on the
/// estimation record's samples below the overflow level.
pub(super) fn cascaded_tanks(data: &Path, opts: &DiagnoseOptions, fig: &Path) -> anyhow::Result<RealResult> {
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
pub(super) fn cascaded_tanks_arx(
    data: &Path,
    opts: &DiagnoseOptions,
    fig: &Path,
) -> anyhow::Result<RealResult> {
    tanks_arx_on(data, opts, fig, "cascaded_tanks_arx", ("uEst", "yEst"), ("uVal", "yVal"))
}

/// The same with the records' roles swapped: the ARX fitted on the validation record, the
/// estimation record diagnosed; first diagnosed at stop 74.
pub(super) fn cascaded_tanks_arx_swapped(
    data: &Path,
    opts: &DiagnoseOptions,
    fig: &Path,
) -> anyhow::Result<RealResult> {
    tanks_arx_on(data, opts, fig, "cascaded_tanks_arx_swapped", ("uVal", "yVal"), ("uEst", "yEst"))
}

/// The cascaded tanks' ARX(2,2,1), fitted by least squares on the record of columns `fitted`,
/// run from its first level on the record of columns `diagnosed`, which is diagnosed.
fn tanks_arx_on(
    data: &Path,
    opts: &DiagnoseOptions,
    fig: &Path,
    name: &str,
    fitted: (&str, &str),
    diagnosed: (&str, &str),
) -> anyhow::Result<RealResult> {
    let p = data.join("cascaded_tanks/dataBenchmark.csv");
    let (h, c) = read_plain(&p)?;
    let (uf, yf) = (column(&h, &c, fitted.0, &p)?, column(&h, &c, fitted.1, &p)?);
    let (u, y) = (column(&h, &c, diagnosed.0, &p)?, column(&h, &c, diagnosed.1, &p)?);
    let s = arx(&uf, &yf, 2, 2, 1, 0..uf.len())?.simulate_from(&[&u], y[0])?;
    let time: Vec<f64> = (0..u.len()).map(|k| k as f64 * mpmwatch::tanks::BENCHMARK_TS).collect();
    let model = format!(
        "linear ARX(2,2,1) fitted on {}→{}, run on {}→{}",
        fitted.0, fitted.1, diagnosed.0, diagnosed.1
    );
    real_case(name, &model, time, u, y, s, "saturation", None, opts, fig)
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
