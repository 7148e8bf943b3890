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

/// One real row of the casebook: a record of the shared data and the nominal a user would give
/// it. Each row's name ([`ROWS`]) is its table key, its JSON `recording` and its figures' stem.
pub(super) enum Row {
    /// A window of SNLS80mV (rows), against a linear ARX(2,3) fitted on the arrow head's low
    /// amplitudes, samples 2 000..10 000, simulated from the record's start.
    Silverbox(std::ops::Range<usize>),
    /// One experiment of the coupled drives (file, input and speed columns) against a linear
    /// ARX(3,3) calibrated on `u12 → z12` of DATAUNIF.csv (input mostly positive, so the speed
    /// seldom changes sign and the |·| sensor hardly matters there), simulated from the
    /// experiment's first speed.
    Ced { file: &'static str, u: &'static str, y: &'static str },
    /// The TCLab sine test (heater 1 swept 0–100 %, period 5 min) against one temperature
    /// column, with a linear first-order ARX(1,1) (one sample of dead time) fitted on the
    /// record's first 70 % (the training part).
    Tclab { y: &'static str },
    /// The cascaded tanks as one record (estimation, then validation) against a Torricelli
    /// two-tank simulation without overflow, calibrated below the overflow level and handed to
    /// `diagnose` as a physical model, so that it can re-run the model with a tank overflowing.
    Tanks,
    /// The cascaded tanks as a user with a linear model meets them, through the CSV verb's path
    /// (no physical model): an ARX(2,2,1) fitted by least squares on the `fitted` record's
    /// (input, level) columns, run from its first level on the `diagnosed` record's.
    TanksArx { fitted: (&'static str, &'static str), diagnosed: (&'static str, &'static str) },
}

/// The real rows, in the casebook's order. The rows after `cascaded_tanks_arx` are other
/// experiments on the same systems, first diagnosed at stop 74 (docs/diagnose-history.md).
pub(super) const ROWS: [(&str, Row); 11] = [
    // The arrow head's last 10 000 samples, its largest amplitudes, where the cubic term shows.
    ("silverbox", Row::Silverbox(30_000..40_000)),
    // The PRBS ±1 experiment, where the speed changes sign.
    ("ced", Row::Ced { file: "DATAPRBS.csv", u: "u1", y: "z1" }),
    ("tclab", Row::Tclab { y: "T1" }),
    ("cascaded_tanks", Row::Tanks),
    ("cascaded_tanks_arx", Row::TanksArx { fitted: ("uEst", "yEst"), diagnosed: ("uVal", "yVal") }),
    // The odd multisine that follows the arrow head.
    ("silverbox_multisine", Row::Silverbox(60_000..70_000)),
    // PRBS ±1.5.
    ("ced_u2z2", Row::Ced { file: "DATAPRBS.csv", u: "u2", y: "z2" }),
    // PRBS ±0.5.
    ("ced_u3z3", Row::Ced { file: "DATAPRBS.csv", u: "u3", y: "z3" }),
    // The first uniform-input experiment, the speed changing sign.
    ("ced_u11z11", Row::Ced { file: "DATAUNIF.csv", u: "u11", y: "z11" }),
    // The neighbouring sensor, which heater 1 warms through the board.
    ("tclab_t2", Row::Tclab { y: "T2" }),
    // The records' roles swapped.
    ("cascaded_tanks_arx_swapped", Row::TanksArx { fitted: ("uVal", "yVal"), diagnosed: ("uEst", "yEst") }),
];

/// Real row `row`, named `name`: its record read, its nominal built, diagnosed.
pub(super) fn run(
    name: &str,
    row: &Row,
    data: &Path,
    opts: &DiagnoseOptions,
    fig: &Path,
) -> anyhow::Result<RealResult> {
    match row {
        Row::Silverbox(w) => silverbox(data, opts, fig, name, w.clone()),
        Row::Ced { file, u, y } => ced(data, opts, fig, name, file, u, y),
        Row::Tclab { y } => tclab(data, opts, fig, name, y),
        Row::Tanks => tanks(data, opts, fig, name),
        Row::TanksArx { fitted, diagnosed } => tanks_arx(data, opts, fig, name, *fitted, *diagnosed),
    }
}

/// [`Row::Silverbox`]: the diagnosed window `w`.
fn silverbox(
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

/// [`Row::Ced`]: columns `uc → yc` of `file`.
fn ced(
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

/// [`Row::Tclab`]: heater 1 against temperature column `yc`.
fn tclab(
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

/// [`Row::Tanks`].
fn tanks(data: &Path, opts: &DiagnoseOptions, fig: &Path, name: &str) -> anyhow::Result<RealResult> {
    let p = data.join("cascaded_tanks/dataBenchmark.csv");
    let (h, c) = read_plain(&p)?;
    let (ue, ye) = (column(&h, &c, "uEst", &p)?, column(&h, &c, "yEst", &p)?);
    let (uv, yv) = (column(&h, &c, "uVal", &p)?, column(&h, &c, "yVal", &p)?);
    let record = mpmwatch::tanks::benchmark_record(&ue, &ye, &uv, &yv);
    let s = mpmwatch_diagnose::PhysicalModel::simulate(&record);
    let u: Vec<f64> = ue.iter().chain(&uv).copied().collect();
    let y: Vec<f64> = ye.iter().chain(&yv).copied().collect();
    let time: Vec<f64> = (0..u.len()).map(|k| k as f64 * record.ts).collect();
    let opts = mpmwatch::tanks::benchmark_options(opts);
    real_case(
        name,
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

/// [`Row::TanksArx`], diagnosed with the casebook's settings (the last 30 % held out).
fn tanks_arx(
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
