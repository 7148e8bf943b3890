//! The casebook's benchmark-accuracy section: the physics `diagnose` names, carried to each
//! benchmark's own estimation and test data by [`mpmwatch::accuracy`], as a table and figures.

use std::path::Path;

use super::real::{column, read_plain};

use mpmwatch::accuracy::{AccuracyRow, DrivesRecord};

/// One benchmark's rows, and the figure it drew (file stem and alt text) if it draws one.
type Section = (Vec<AccuracyRow>, Option<(&'static str, &'static str, anyhow::Result<()>)>);

/// A benchmark's section from the data folder and the figures folder.
type SectionFn = fn(&Path, &Path) -> anyhow::Result<Section>;

/// The named physics on the benchmarks' own splits ([`mpmwatch::accuracy`]), as a markdown
/// section; the rows go into `json` too. A benchmark whose data cannot be read or fitted gets
/// an error row of its own; the others are still scored.
pub(super) fn benchmark_accuracy(data: &Path, figures: &Path, json: &mut Vec<AccuracyRow>) -> String {
    eprintln!("benchmark accuracy: silverbox, cascaded tanks, coupled drives");
    let mut md = String::from(
        "\n## Benchmark accuracy on the benchmarks' own splits\n\n| benchmark | model | test RMSE | NRMSE (RMSE / std of the test output) | estimation RMSE (in sample) | split | published |\n| --- | --- | --- | --- | --- | --- | --- |\n",
    );
    let mut drawn = Vec::new();
    let sections: [(&str, SectionFn); 3] =
        [("silverbox", silverbox), ("cascaded_tanks", tanks), ("coupled_drives", drives)];
    for (name, section) in sections {
        match section(data, figures) {
            Ok((rows, figure)) => {
                for r in rows {
                    md.push_str(&format!(
                        "| {} | {} | {:.3} {} | {:.2} % | {:.3} {} | {} | {} |\n",
                        r.benchmark,
                        r.model,
                        r.rmse,
                        r.unit,
                        r.nrmse_pct,
                        r.estimation_rmse,
                        r.unit,
                        r.split,
                        r.published
                    ));
                    json.push(r);
                }
                drawn.extend(figure);
            }
            Err(e) => md.push_str(&format!("| {name} | error: {e:#} | – | – | – | – | – |\n")),
        }
    }
    for (file, alt, written) in drawn {
        match written {
            Ok(()) => md.push_str(&format!("\n![{alt}](figures/{file}.png)\n")),
            Err(e) => md.push_str(&format!("\nThe figure {file}.png was not written: {e:#}\n")),
        }
    }
    md
}

fn silverbox(data: &Path, _figures: &Path) -> anyhow::Result<Section> {
    let p = data.join("silverbox/SNLS80mV.csv");
    let (h, c) = read_plain(&p)?;
    Ok((mpmwatch::accuracy::silverbox(&column(&h, &c, "V1", &p)?, &column(&h, &c, "V2", &p)?)?, None))
}

fn tanks(data: &Path, figures: &Path) -> anyhow::Result<Section> {
    let p = data.join("cascaded_tanks/dataBenchmark.csv");
    let (h, c) = read_plain(&p)?;
    let col = |n| column(&h, &c, n, &p);
    let yv = col("yVal")?;
    let rows = mpmwatch::accuracy::cascaded_tanks(&col("uEst")?, &col("yEst")?, &col("uVal")?, &yv)?;
    let figure = accuracy_figure(
        figures,
        &AccuracyFigure {
            name: "accuracy_cascaded_tanks",
            title: "Cascaded tanks, validation record (uVal/yVal)",
            ts: mpmwatch::tanks::BENCHMARK_TS,
            skip: 0,
            y_label: "level, V",
            unit: " V",
            labels: &["nominal (Torricelli)", "+ overflow (named)", "+ exponents, lower overflow"],
        },
        &yv,
        &rows.iter().collect::<Vec<_>>(),
    );
    Ok((rows, Some(("accuracy_cascaded_tanks", "cascaded tanks, validation record", figure))))
}

fn drives(data: &Path, figures: &Path) -> anyhow::Result<Section> {
    let read = |file: &str, names: &[&str]| -> anyhow::Result<Vec<Vec<f64>>> {
        let p = data.join(file);
        let (h, c) = read_plain(&p)?;
        names.iter().map(|n| column(&h, &c, n, &p)).collect()
    };
    let unif = read("ced/DATAUNIF.csv", &["u11", "z11", "u12", "z12"])?;
    let prbs = read("ced/DATAPRBS.csv", &["u1", "z1", "u2", "z2", "u3", "z3"])?;
    // The second uniform experiment first: the figure draws it.
    let tests = [
        DrivesRecord { label: "u12→z12 (uniform input)", u: &unif[2], z: &unif[3] },
        DrivesRecord { label: "u1→z1 (PRBS ±1)", u: &prbs[0], z: &prbs[1] },
        DrivesRecord { label: "u2→z2 (PRBS ±1.5)", u: &prbs[2], z: &prbs[3] },
        DrivesRecord { label: "u3→z3 (PRBS ±0.5)", u: &prbs[4], z: &prbs[5] },
    ];
    let rows = mpmwatch::accuracy::coupled_drives(&unif[0], &unif[1], &tests)?;
    // Two models, each with one row per test record in order: each model's first row.
    let on_uniform = [&rows[0], &rows[tests.len()]];
    let figure = accuracy_figure(
        figures,
        &AccuracyFigure {
            name: "accuracy_coupled_drives",
            title: "Coupled drives, test record u12→z12 (fitted on u11→z11)",
            ts: 0.02,
            skip: mpmwatch::accuracy::DRIVES_SKIP,
            y_label: "belt speed (sensor units)",
            unit: "",
            labels: &["linear", "+ |·| sensor (named)"],
        },
        &unif[3],
        &on_uniform,
    );
    Ok((rows, Some(("accuracy_coupled_drives", "coupled drives, test record u12→z12", figure))))
}

/// A benchmark's test record against the models of the accuracy table, against time: the
/// recorded output black, the first model dashed grey, the next blue, then red. `skip` is
/// where the models' scored simulations start in the record.
struct AccuracyFigure<'a> {
    name: &'a str,
    title: &'a str,
    ts: f64,
    skip: usize,
    y_label: &'a str,
    unit: &'a str,
    labels: &'a [&'a str],
}

fn accuracy_figure(
    dir: &Path,
    f: &AccuracyFigure<'_>,
    y: &[f64],
    rows: &[&AccuracyRow],
) -> anyhow::Result<()> {
    use mpmwatch::report::figures::{XySeries, write_xy_chart};
    anyhow::ensure!(rows.len() == f.labels.len(), "expected {} models, got {}", f.labels.len(), rows.len());
    let at = |s: &[f64], from: usize| -> Vec<(f64, f64)> {
        s.iter().enumerate().map(|(k, &v)| ((k + from) as f64 * f.ts, v)).collect()
    };
    let mut series = vec![XySeries::line("recorded", at(y, 0), false, (0, 0, 0), 2)];
    let styles = [(true, (150, 150, 150)), (false, (31, 119, 180)), (false, (214, 39, 40))];
    for ((row, label), (dashed, colour)) in rows.iter().zip(f.labels).zip(styles) {
        series.push(XySeries::line(
            format!("{label}: {:.3}{}", row.rmse, f.unit),
            at(&row.test_simulation, f.skip),
            dashed,
            colour,
            1,
        ));
    }
    write_xy_chart(dir, f.name, f.title, "time, s", f.y_label, &series)?;
    Ok(())
}
