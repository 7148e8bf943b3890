//! `mpmwatch casebook`: the diagnosis proof. Concealed simulated cases (one hidden effect each,
//! from `mpmwatch_sim::scenarios`) and the real recordings in the shared data folder, each
//! diagnosed; `DIR/casebook.md` (tables and figures) and `DIR/casebook.json`.

use std::path::{Path, PathBuf};

use anyhow::Context;
use mpmwatch::report::figures::{BeforeAfter, write_before_after_chart};
use mpmwatch_core::detect::Signal;
use mpmwatch_core::model::{Arx, ArxOrders};
use mpmwatch_diagnose::{DiagnoseInput, DiagnoseOptions, Physics, diagnose_numbered, fit_pct};
use mpmwatch_sim::scenarios::{casebook_specs, run as run_case, wide_specs};
use serde_json::json;

/// Arguments of the verb (documented on the verb in `main.rs`).
#[derive(clap::Args)]
pub struct Args {
    /// Output folder.
    #[arg(long)]
    out: PathBuf,
    /// Samples per simulated case.
    #[arg(long, default_value_t = 3000)]
    n: usize,
    /// Base seed of the simulated cases (case k uses seed + k).
    #[arg(long, default_value_t = 100)]
    seed: u64,
    /// Folder of the real recordings (see its README).
    #[arg(long, default_value = "../shared/data")]
    data: PathBuf,
    /// Skip the real recordings.
    #[arg(long)]
    simulated_only: bool,
    /// Run only the simulated cases whose name contains one of these (comma-separated, e.g.
    /// `c09,abs_sensor`); the rates then cover those cases only.
    #[arg(long, value_delimiter = ',')]
    only: Vec<String>,
    /// Skip the simulated cases (only the real recordings).
    #[arg(long, conflicts_with = "simulated_only")]
    real_only: bool,
    /// Instead of the casebook's 28 fixed cases, COUNT cases drawn by the wide generator: each
    /// with its own plant, PI tuning, disturbance spectrum, dither level, effect, channel, size
    /// and concealment ratio (0.1–0.8). Case k uses seed + k.
    #[arg(long, value_name = "COUNT", value_parser = clap::builder::RangedU64ValueParser::<usize>::new().range(1..))]
    wide: Option<usize>,
}

pub fn run(args: Args) -> anyhow::Result<()> {
    let fig = args.out.join("figures");
    std::fs::create_dir_all(&fig).with_context(|| format!("creating {}", fig.display()))?;
    let opts = DiagnoseOptions::default();
    let mut specs = match (args.real_only, args.wide) {
        (true, _) => Vec::new(),
        (false, Some(count)) => wide_specs(count, args.n, args.seed),
        (false, None) => casebook_specs(args.n, args.seed),
    };
    if !args.only.is_empty() {
        specs.retain(|s| args.only.iter().any(|o| s.name.contains(o.as_str())));
    }
    let mut rows = Vec::new();
    let mut md = String::from("# Diagnosis casebook\n\n");
    md.push_str(&format!(
        "Simulated concealed cases{}: {} samples each, seeds {}..{}, 30 % held out, MI with {} surrogates (seed {}), lags 1..={}.\n\n",
        if args.wide.is_some() { " (wide generator: every plant, loop, disturbance and effect drawn)" } else { "" },
        args.n,
        args.seed,
        (args.seed + specs.len() as u64).saturating_sub(1),
        opts.surrogates,
        opts.seed,
        opts.lags.max
    ));
    md.push_str("The CCF column: any lag of the linear cross-correlation of the true channel's dither with its residual beyond the family-wise (Bonferroni, α = 0.05 over the lags) limit of the MI matrix's baseline.\n\n");
    md.push_str("| case | true effect | effect/disturbance variance | channel found | physics named | held-out FIT before → after | did the CCF see it? |\n| --- | --- | --- | --- | --- | --- | --- |\n");
    let (mut named, mut chan, mut total, mut false_alarms, mut quiet, mut fell) = (0, 0, 0, 0, 0, 0);
    let mut fit_items = Vec::new();
    for (k, spec) in specs.iter().enumerate() {
        eprintln!("[{}/{}] {} (seed {})", k + 1, specs.len(), spec.name, spec.seed);
        let rec = run_case(spec)?;
        let dg = diagnose_numbered(&rec.u, &rec.d, &rec.y, &rec.s, &opts)?;
        let (ci, cj) = spec.channel;
        let truth_in = format!("u{}", ci + 1);
        let truth_out = format!("y{}", cj + 1);
        let finding = dg
            .report
            .findings
            .iter()
            .find(|f| f.physics != Physics::Unexplained)
            .or(dg.report.findings.first());
        let found_channel =
            finding.map(|f| format!("{}→{}", f.input, f.output)).unwrap_or_else(|| "none".into());
        let physics = finding.map(|f| f.physics.name().to_string()).unwrap_or_else(|| "none".into());
        let ccf = dg
            .report
            .channels
            .iter()
            .find(|c| c.input == truth_in && c.output == truth_out)
            .is_some_and(|c| c.ccf_significant);
        let y = &truth_out;
        let (fb, fa) = (dg.report.holdout.fit_before_pct[y], dg.report.holdout.fit_after_pct[y]);
        let right_channel = finding.is_some_and(|f| f.input == truth_in && f.output == truth_out);
        let right_physics =
            finding.is_some_and(|f| f.physics.name() == spec.effect.physics() && right_channel);
        let success = if spec.effect.is_mismatch() { right_physics } else { dg.report.findings.is_empty() };
        fit_items.push(BeforeAfter {
            label: spec.name.split('_').next().unwrap_or_default().to_string(),
            before: fb,
            after: fa,
            success,
        });
        case_figure(
            &fig,
            spec.name.as_str(),
            cj,
            &rec.y[cj],
            &rec.s[cj],
            &dg.corrected[cj],
            dg.report.holdout.start_index,
        )?;
        let reported = finding.is_some_and(|f| f.physics != Physics::Unexplained);
        fell += usize::from(reported && fa < fb);
        if spec.effect.is_mismatch() {
            total += 1;
            named += usize::from(right_physics);
            chan += usize::from(right_channel);
        } else if dg.report.findings.is_empty() {
            quiet += 1;
        } else {
            false_alarms += 1;
        }
        md.push_str(&format!(
            "| {} ({}×{}, {} dither) | {} on u{}→y{}: {} | {:.2} | {} | {} | {:.1} → {:.1} | {} |\n",
            spec.name,
            spec.size,
            spec.size,
            if spec.excitation == mpmwatch_sim::Excitation::Prbs { "binary" } else { "uniform" },
            spec.effect.physics(),
            ci + 1,
            cj + 1,
            spec.describe(rec.strength).replace('|', "\\|"),
            rec.effect_ratio,
            found_channel,
            physics,
            fb,
            fa,
            if ccf { "yes" } else { "no" }
        ));
        rows.push(json!({
            "case": spec, "true_effect": spec.effect.physics(), "strength": rec.strength,
            "description": spec.describe(rec.strength), "effect_ratio": rec.effect_ratio,
            "channel_found": found_channel, "physics_named": physics, "right_channel": right_channel,
            "right_physics": right_physics, "ccf_saw_it": ccf, "holdout_fit_before_pct": fb,
            "holdout_fit_after_pct": fa, "report": dg.report,
        }));
    }
    let rates = json!({
        "mismatch_cases": total,
        "physics_named_right": named,
        "physics_rate": named as f64 / total.max(1) as f64,
        "channel_right": chan,
        "channel_rate": chan as f64 / total.max(1) as f64,
        "null_cases_quiet": quiet,
        "null_cases_with_findings": false_alarms,
        "reported_findings_whose_held_out_fit_fell": fell,
    });
    md.push_str(&format!(
        "\n**Measured:** physics named right in {named}/{total} mismatch cases ({:.0} %, target ≥ 90 %); right channel in {chan}/{total} ({:.0} %, target ≥ 95 %); findings in {false_alarms} of {} disturbance-only and no-change cases (target 0); reported findings whose held-out FIT fell: {fell} (target 0).\n\n",
        100.0 * named as f64 / total.max(1) as f64,
        100.0 * chan as f64 / total.max(1) as f64,
        false_alarms + quiet
    ));
    if !fit_items.is_empty() {
        write_before_after_chart(
            &fig,
            "casebook_fit",
            "held-out FIT per case, before (grey) → after the fitted correction",
            "held-out FIT [%]",
            &fit_items,
        )?;
        md.push_str("![held-out FIT before and after, per case](figures/casebook_fit.png)\n\n");
        md.push_str("Triangle: physics named right (null cases: no finding); cross: wrong physics, or a finding on a null case. Green: FIT rose; red: it fell.\n\n");
        md.push_str("Each case's held-out tail (last 200 samples of the output that carries the effect; recorded, simulated, corrected): ");
        let links: Vec<String> = specs
            .iter()
            .map(|s| {
                format!("[{}](figures/case_{}.png)", s.name.split('_').next().unwrap_or_default(), s.name)
            })
            .collect();
        md.push_str(&links.join(" · "));
        md.push_str(".\n\n");
    }
    let mut real = Vec::new();
    let mut accuracy = Vec::new();
    if !args.simulated_only {
        md.push_str("## Real recordings\n\n| recording | simulation | channel | physics named | parameters | held-out FIT before → after | figure |\n| --- | --- | --- | --- | --- | --- | --- |\n");
        for (name, f) in
            [("silverbox", silverbox as RealCase), ("ced", ced), ("tclab", tclab), ("cascaded_tanks", tanks)]
        {
            eprintln!("real recording: {name}");
            match f(&args.data, &opts, &fig) {
                Ok(r) => {
                    md.push_str(&r.row);
                    real.push(r.json);
                }
                Err(e) => {
                    md.push_str(&format!("| {name} | – | – | – | error: {e:#} | – | – |\n"));
                    real.push(json!({"recording": name, "error": format!("{e:#}")}));
                }
            }
        }
        md.push_str(&benchmark_accuracy(&args.data, &fig, &mut accuracy));
        md.push_str("\nData: Silverbox and cascaded tanks from the nonlinear system-identification benchmarks (Wigren & Schoukens; Schoukens, Mattsson, Wigren & Noël 2016, CC BY-SA 4.0), coupled electric drives (Wigren & Schoukens, Uppsala University 2017), TCLab (BSD-3).\n");
    }
    std::fs::write(args.out.join("casebook.md"), md)?;
    let out = json!({"rates": rates, "simulated": rows, "real": real, "benchmark_accuracy": accuracy,
                     "seed": args.seed, "n": args.n});
    std::fs::write(args.out.join("casebook.json"), serde_json::to_string_pretty(&out)?)?;
    eprintln!("{}", serde_json::to_string(&rates)?);
    Ok(())
}

/// The named physics on the benchmarks' own splits ([`mpmwatch::accuracy`]), as a markdown
/// section; the rows go into `json` too.
fn benchmark_accuracy(
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

/// The held-out tail of one simulated case: its last 200 samples (at most the tail) of output
/// `j`, recorded, simulated and corrected, against the sample index.
fn case_figure(
    dir: &Path,
    name: &str,
    j: usize,
    y: &[f64],
    s: &[f64],
    c: &[f64],
    holdout: usize,
) -> anyhow::Result<()> {
    let time: Vec<f64> = (0..y.len()).map(|k| k as f64).collect();
    crate::cmd::diagnose::output_figure(
        dir,
        &format!("case_{name}"),
        &format!("{name}: y{}", j + 1),
        &time,
        y,
        s,
        c,
        holdout,
    )
}

struct RealResult {
    row: String,
    json: serde_json::Value,
}

type RealCase = fn(&Path, &DiagnoseOptions, &Path) -> anyhow::Result<RealResult>;

/// Reads a headered CSV without a time column (the benchmark files); empty cells are NaN.
fn read_plain(path: &Path) -> anyhow::Result<(Vec<String>, Vec<Vec<f64>>)> {
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

fn column(h: &[String], c: &[Vec<f64>], name: &str, path: &Path) -> anyhow::Result<Vec<f64>> {
    h.iter()
        .position(|n| n == name)
        .map(|k| c[k].clone())
        .with_context(|| format!("{} has no column `{name}`", path.display()))
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
fn silverbox(data: &Path, opts: &DiagnoseOptions, fig: &Path) -> anyhow::Result<RealResult> {
    let p = data.join("silverbox/SNLS80mV.csv");
    let (h, c) = read_plain(&p)?;
    let (v1, v2) = (column(&h, &c, "V1", &p)?, column(&h, &c, "V2", &p)?);
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
fn ced(data: &Path, opts: &DiagnoseOptions, fig: &Path) -> anyhow::Result<RealResult> {
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
fn tclab(data: &Path, opts: &DiagnoseOptions, fig: &Path) -> anyhow::Result<RealResult> {
    let p = data.join("tclab/tclab_sine_test_5min_period.csv");
    let (h, c) = read_plain(&p)?;
    let (time, u, y) = (column(&h, &c, "Time", &p)?, column(&h, &c, "Q1", &p)?, column(&h, &c, "T1", &p)?);
    let n = time.len();
    let s = arx_simulation(&u, &y, 1, 1, 1, 0..(n * 7 / 10))?;
    real_case("tclab", "linear first-order ARX(1,1)", time, u, y, s, "say what it finds", None, opts, fig)
}

/// Cascaded tanks: a Torricelli two-tank simulation without overflow, calibrated on the
/// estimation record's samples below the overflow level.
fn tanks(data: &Path, opts: &DiagnoseOptions, fig: &Path) -> anyhow::Result<RealResult> {
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
