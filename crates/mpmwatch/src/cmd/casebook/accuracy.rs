//! The casebook's benchmark-accuracy section: the physics `diagnose` names, carried to each
//! benchmark's own estimation and test data by [`mpmwatch::accuracy`], as a table and figures.

use std::path::Path;

use super::real::{column, read_plain};

/// The named physics on the benchmarks' own splits ([`mpmwatch::accuracy`]), as a markdown
/// section; the rows go into `json` too.
pub(super) fn benchmark_accuracy(
    data: &Path,
    figures: &Path,
    json: &mut Vec<mpmwatch::accuracy::AccuracyRow>,
) -> String {
    eprintln!("benchmark accuracy: silverbox, cascaded tanks, coupled drives");
    let mut md = String::from(
        "\n## Benchmark accuracy on the benchmarks' own splits\n\n| benchmark | model | test RMSE | NRMSE (RMSE / std of the test output) | estimation RMSE (in sample) | split | published |\n| --- | --- | --- | --- | --- | --- | --- |\n",
    );
    let rows = (|| -> anyhow::Result<(Vec<mpmwatch::accuracy::AccuracyRow>, [anyhow::Result<()>; 2])> {
        let p = data.join("silverbox/SNLS80mV.csv");
        let (h, c) = read_plain(&p)?;
        let mut rows = mpmwatch::accuracy::silverbox(&column(&h, &c, "V1", &p)?, &column(&h, &c, "V2", &p)?)?;
        let p = data.join("cascaded_tanks/dataBenchmark.csv");
        let (h, c) = read_plain(&p)?;
        let col = |n| column(&h, &c, n, &p);
        let yv = col("yVal")?;
        let tanks = mpmwatch::accuracy::cascaded_tanks(&col("uEst")?, &col("yEst")?, &col("uVal")?, &yv)?;
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
            &tanks.iter().collect::<Vec<_>>(),
        );
        rows.extend(tanks);
        let p = data.join("ced/DATAUNIF.csv");
        let (h, c) = read_plain(&p)?;
        let unif: Vec<Vec<f64>> =
            ["u11", "z11", "u12", "z12"].iter().map(|n| column(&h, &c, n, &p)).collect::<Result<_, _>>()?;
        let p = data.join("ced/DATAPRBS.csv");
        let (h, c) = read_plain(&p)?;
        let prbs: Vec<Vec<f64>> = ["u1", "z1", "u2", "z2", "u3", "z3"]
            .iter()
            .map(|n| column(&h, &c, n, &p))
            .collect::<Result<_, _>>()?;
        let tests = [
            ("u12→z12", &unif[2][..], &unif[3][..]),
            ("u1→z1", &prbs[0][..], &prbs[1][..]),
            ("u2→z2", &prbs[2][..], &prbs[3][..]),
            ("u3→z3", &prbs[4][..], &prbs[5][..]),
        ];
        let drives = mpmwatch::accuracy::coupled_drives(&unif[0], &unif[1], &tests)?;
        // The uniform test record: the first of each model's rows.
        let on_uniform: Vec<_> = drives.iter().filter(|r| r.split.contains("u12→z12")).collect();
        let drives_figure = accuracy_figure(
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
        rows.extend(drives);
        Ok((rows, [figure, drives_figure]))
    })();
    match rows {
        Ok((rows, figures_written)) => {
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
            let names = [
                ("cascaded tanks, validation record", "accuracy_cascaded_tanks"),
                ("coupled drives, test record u12→z12", "accuracy_coupled_drives"),
            ];
            for (written, (alt, file)) in figures_written.into_iter().zip(names) {
                match written {
                    Ok(()) => md.push_str(&format!("\n![{alt}](figures/{file}.png)\n")),
                    Err(e) => md.push_str(&format!("\nThe figure {file}.png was not written: {e:#}\n")),
                }
            }
        }
        Err(e) => md.push_str(&format!("| – | error: {e:#} | – | – | – | – | – |\n")),
    }
    md
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
    rows: &[&mpmwatch::accuracy::AccuracyRow],
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
