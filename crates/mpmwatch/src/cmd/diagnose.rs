//! `mpmwatch diagnose`: locate, name and fit the physics a simulation left out, and show the
//! corrected simulation on a held-out tail.

use std::path::{Path, PathBuf};

use anyhow::{Context, bail};
use mpmwatch::report::figures::{XySeries, write_xy_chart};
use mpmwatch_core::detect::{Method, Signal};
use mpmwatch_core::info::Lags;
use mpmwatch_core::io::Table;
use mpmwatch_diagnose::{
    DiagnoseInput, DiagnoseOptions, Diagnosis, Progress, Scoring, diagnose_with_progress,
};

/// Arguments of the verb (documented on the verb in `main.rs`).
#[derive(clap::Args)]
pub struct Args {
    /// CSV of the recording (first column `time`).
    #[arg(long)]
    recorded: PathBuf,
    /// CSV of the simulation on the same time axis, one column per output named as in the
    /// recording, driven by the recorded inputs.
    #[arg(long)]
    simulated: PathBuf,
    /// Recorded input (MV) columns, comma separated.
    #[arg(long, value_delimiter = ',', required = true)]
    inputs: Vec<String>,
    /// Dither columns, paired with --inputs by position (excitation i was added to input i).
    /// Without it the inputs are their own excitation (open-loop records).
    #[arg(long, value_delimiter = ',')]
    excitations: Vec<String>,
    /// Recorded output (CV) columns, comma separated; the simulation has the same names.
    #[arg(long, value_delimiter = ',', required = true)]
    outputs: Vec<String>,
    /// Where to write the JSON report (DESIGN.md §4.5).
    #[arg(long)]
    report: PathBuf,
    /// Where to write the corrected simulation (time plus one column per output).
    #[arg(long)]
    corrected: PathBuf,
    /// Fraction of the record held out at its end; the fit never sees it.
    #[arg(long, default_value_t = 0.3)]
    holdout_fraction: f64,
    /// Surrogates per MI element.
    #[arg(long, default_value_t = 40)]
    surrogates: usize,
    /// Seed of the surrogates (reported in the JSON).
    #[arg(long, default_value_t = 1)]
    seed: u64,
    /// Largest lag of the MI profile.
    #[arg(long, default_value_t = 15)]
    tmax: usize,
    /// Write figures into this folder: per output, recorded, simulated and corrected over a
    /// window of the held-out tail; for a finding, the fitted element drawn as what it is (a
    /// dead zone's or limit's map, backlash's loop, a linear change's step response beside the
    /// model's).
    #[arg(long)]
    figures: Option<PathBuf>,
    /// How hypotheses are compared in a closed loop (with --excitations). `prediction`: one-step
    /// prediction error of the corrected residual under an AR noise model (consistent in closed
    /// loop, the default); `shifted` and `projected`: the two earlier criteria, kept to compare.
    #[arg(long, value_enum, default_value_t = ScoringArg::Prediction)]
    scoring: ScoringArg,
    /// The honesty gate: a finding is reported only when its correction raises the FIT on
    /// held-back training data by at least this many points on average (never on the held-out
    /// tail). Open-loop records; a closed loop takes --closed-loop-min-gain.
    #[arg(long, value_name = "POINTS", default_value_t = DiagnoseOptions::default().min_gain_pct)]
    min_gain: f64,
    /// The honesty gate's margin, on average and with no condition on single blocks, on a
    /// closed-loop record (--excitations given and an input moving with more than its
    /// excitation), where feedback makes the FIT gain noisier: of five development findings
    /// with 0.5 to 2 points, three fell on the held-out tail.
    #[arg(long, value_name = "POINTS", default_value_t = DiagnoseOptions::default().closed_loop_min_gain_pct)]
    closed_loop_min_gain: f64,
    /// Open loop: an output may drift in a way no input carries (a sensor's drift, a slow
    /// unmeasured load), and a drift bends every re-fit. When a straight line in time added to
    /// the re-fitted linear model raises its FIT on held-back training data by this many points
    /// on average, and goes the same way fitted on either half of the training part (the slow
    /// level a nonlinear plant leaves behind a linear re-fit does not), every hypothesis and
    /// the model's reference carry one, and the finding says
    /// so; the corrected simulation holds the drift at its last training level over the
    /// held-out tail (a drift cannot be forecast). Without a drift, a disturbance with a time
    /// constant of 10 samples passes 1 point on about one record in twenty, a slower one more
    /// often; `inf` never fits one.
    #[arg(long, value_name = "POINTS", default_value_t = DiagnoseOptions::default().drift_min_gain_pct)]
    drift_min_gain: f64,
    /// How the MI matrix flags a channel. `family`: one test per element over every lag of
    /// pairwise MI, joint-lag MI and the cross-correlation, at the false-alarm rate --alpha per
    /// record. `paper`: the paper's μ + 6σ per statistic, which misses linear mismatches a
    /// cross-correlation sees.
    #[arg(long, default_value_t = DiagnoseOptions::default().locate, value_parser = super::choice::<Method>())]
    method: Method,
    /// Method `family`: the chance that a record whose every submodel is right has some channel
    /// flagged by the MI matrix, split evenly over its channels.
    #[arg(long, default_value_t = DiagnoseOptions::default().alpha)]
    alpha: f64,
}

/// `--scoring` values (kept out of the library, which has no command-line types).
#[derive(Clone, Copy, clap::ValueEnum)]
enum ScoringArg {
    Prediction,
    Shifted,
    Projected,
}

impl From<ScoringArg> for Scoring {
    fn from(s: ScoringArg) -> Self {
        match s {
            ScoringArg::Prediction => Scoring::Prediction,
            ScoringArg::Shifted => Scoring::Shifted,
            ScoringArg::Projected => Scoring::Projected,
        }
    }
}

pub fn run(args: Args) -> anyhow::Result<()> {
    let rec = Table::read_csv(&args.recorded)?;
    let sim = Table::read_csv(&args.simulated)?;
    if rec.len() != sim.len() {
        bail!(
            "time axes do not match: {} has {} rows, {} has {}",
            args.recorded.display(),
            rec.len(),
            args.simulated.display(),
            sim.len()
        );
    }
    if let Some(k) =
        rec.time().iter().zip(sim.time()).position(|(a, b)| (a - b).abs() > 1e-9 * (1.0 + a.abs()))
    {
        bail!(
            "time axes do not match at row {}: {} in {} but {} in {}",
            k + 2,
            rec.time()[k],
            args.recorded.display(),
            sim.time()[k],
            args.simulated.display()
        );
    }
    if !args.excitations.is_empty() && args.excitations.len() != args.inputs.len() {
        bail!(
            "--excitations has {} columns but --inputs has {}: they pair by position",
            args.excitations.len(),
            args.inputs.len()
        );
    }
    let col = |t: &Table, name: &str, file: &Path| -> anyhow::Result<Vec<f64>> {
        let v = t.column(name).with_context(|| format!("in {}", file.display()))?;
        if let Some(k) = v.iter().position(|x| !x.is_finite()) {
            bail!(
                "column `{name}` of {} has a non-finite value ({}) at line {}",
                file.display(),
                v[k],
                k + 2
            );
        }
        Ok(v.to_vec())
    };
    let u: Vec<Vec<f64>> =
        args.inputs.iter().map(|n| col(&rec, n, &args.recorded)).collect::<Result<_, _>>()?;
    let d: Vec<Vec<f64>> =
        args.excitations.iter().map(|n| col(&rec, n, &args.recorded)).collect::<Result<_, _>>()?;
    let y: Vec<Vec<f64>> =
        args.outputs.iter().map(|n| col(&rec, n, &args.recorded)).collect::<Result<_, _>>()?;
    let s: Vec<Vec<f64>> =
        args.outputs.iter().map(|n| col(&sim, n, &args.simulated)).collect::<Result<_, _>>()?;
    let sig = |names: &[String], v: &[Vec<f64>]| -> Vec<(String, Vec<f64>)> {
        names.iter().cloned().zip(v.iter().cloned()).collect()
    };
    let (us, ds, ys, ss) =
        (sig(&args.inputs, &u), sig(&args.excitations, &d), sig(&args.outputs, &y), sig(&args.outputs, &s));
    fn view(v: &[(String, Vec<f64>)]) -> Vec<Signal<'_>> {
        v.iter().map(|(n, x)| Signal { name: n.as_str(), values: x.as_slice() }).collect()
    }
    let input = DiagnoseInput {
        time: rec.time(),
        inputs: view(&us),
        excitations: if ds.is_empty() { None } else { Some(view(&ds)) },
        outputs: view(&ys),
        simulated: view(&ss),
        physical: Vec::new(),
    };
    let opts = DiagnoseOptions {
        holdout_fraction: args.holdout_fraction,
        surrogates: args.surrogates,
        seed: args.seed,
        lags: Lags::new(1, args.tmax)?,
        scoring: args.scoring.into(),
        min_gain_pct: args.min_gain,
        closed_loop_min_gain_pct: args.closed_loop_min_gain,
        drift_min_gain_pct: args.drift_min_gain,
        locate: args.method,
        alpha: args.alpha,
        ..DiagnoseOptions::default()
    };
    // Progress on stderr, so that a long record's minutes are not silent and stdout keeps the
    // finding alone.
    let start = std::time::Instant::now();
    let elapsed = || format!("{:.0} s", start.elapsed().as_secs_f64());
    let dg = diagnose_with_progress(&input, &opts, &mut |p| match p {
        Progress::Locating { rows } => eprintln!(
            "[{}] locating: testing every input→output channel on the {rows} training rows of {} ({} held out)",
            elapsed(),
            rec.len(),
            rec.len() - rows
        ),
        Progress::Explaining { output, index, of } => eprintln!(
            "[{}] explaining {output} ({index} of {of}): fitting each candidate on every validation fold",
            elapsed()
        ),
    })?;
    write_outputs(
        &dg,
        rec.time(),
        &args.outputs,
        &y,
        &s,
        &args.report,
        &args.corrected,
        args.figures.as_deref(),
    )?;
    eprintln!("[{}] done", elapsed());
    for f in &dg.report.findings {
        println!("{} → {}: {} — {}", f.input, f.output, f.physics.name(), f.summary);
        if f.physics == mpmwatch_diagnose::Physics::Unexplained
            && let Some(best) =
                f.tried.iter().max_by(|a, b| a.validation_gain_pct.total_cmp(&b.validation_gain_pct))
        {
            println!(
                "  best candidate: {} (validation FIT gain {:+.1} points, within the training part), not reported",
                best.physics.name(),
                best.validation_gain_pct
            );
        }
    }
    if dg.report.findings.is_empty() {
        let rule = match args.method {
            Method::Family => format!("the family rule at a false-alarm rate of {} per record", args.alpha),
            Method::Paper => "the paper's 6σ rule".to_string(),
        };
        if args.excitations.is_empty() {
            println!(
                "no mismatch found (no input flagged by the MI matrix under {rule}, and no hypothesis \
                 improved the cross-validated FIT by the margin)"
            );
        } else {
            println!(
                "no mismatch found (no channel flagged by the MI matrix under {rule}, nor by the \
                 dither-projection test)"
            );
        }
    }
    for (k, v) in &dg.report.holdout.fit_before_pct {
        let after = dg.report.holdout.fit_after_pct[k];
        let gain = after - v;
        let verdict = if gain < 0.0 { ": the correction makes the held-out fit WORSE" } else { "" };
        println!("held-out FIT {k}: {v:.1} % → {after:.1} % (gain {gain:+.1} points){verdict}");
    }
    // A caution on the held-out gain of a correction; with none there is nothing extrapolated.
    if dg.report.findings.iter().any(|f| f.physics != mpmwatch_diagnose::Physics::Unexplained) {
        for b in &dg.report.holdout.beyond_training {
            println!("{}", b.sentence());
        }
    }
    Ok(())
}

/// Writes the JSON report, the corrected CSV and (optionally) one figure per output.
#[allow(clippy::too_many_arguments)]
pub fn write_outputs(
    dg: &Diagnosis,
    time: &[f64],
    names: &[String],
    y: &[Vec<f64>],
    s: &[Vec<f64>],
    report: &Path,
    corrected: &Path,
    figures: Option<&Path>,
) -> anyhow::Result<()> {
    std::fs::write(report, serde_json::to_string_pretty(&dg.report)?)
        .with_context(|| format!("writing {}", report.display()))?;
    let mut t = Table::new(time.to_vec());
    for (n, c) in names.iter().zip(&dg.corrected) {
        t.push_column(n.clone(), c.clone())?;
    }
    let f = std::fs::File::create(corrected).with_context(|| format!("writing {}", corrected.display()))?;
    t.write_csv(std::io::BufWriter::new(f))?;
    if let Some(dir) = figures {
        for (j, n) in names.iter().enumerate() {
            output_figure(
                dir,
                &format!("diagnose_{n}"),
                &format!("{n}: recorded, nominal, corrected"),
                time,
                &y[j],
                &s[j],
                &dg.corrected[j],
                dg.report.holdout.start_index,
            )?;
            if let Some(Some(c)) = dg.curves.get(j) {
                element_figure(
                    dir,
                    &format!("diagnose_{n}_element"),
                    &format!("{n}: the fitted {}", c.physics.name()),
                    c,
                )?;
            }
        }
    }
    Ok(())
}

/// The named physics element drawn as what it is (`{name}.png`): its fitted map (or loop, or a
/// linear change's step response), beside what the nominal assumes in its place (dashed).
pub fn element_figure(
    dir: &Path,
    name: &str,
    title: &str,
    c: &mpmwatch_diagnose::ElementCurve,
) -> anyhow::Result<()> {
    let series = [
        XySeries::line(c.baseline_label.clone(), c.baseline.clone(), true, (120, 120, 120), 2),
        XySeries::line(c.label.clone(), c.points.clone(), false, (31, 119, 180), 3),
    ];
    write_xy_chart(dir, name, title, &c.x_label, &c.y_label, &series)?;
    Ok(())
}

/// Samples drawn in an output figure: a window a reader can follow cycle by cycle (at 610 Hz
/// that is 0.33 s of Silverbox, about 15 periods; a whole long record drawn at once, or every
/// k-th sample of it, is a blur).
const FIGURE_WINDOW: usize = 200;

/// A figure of recorded, simulated (nominal) and corrected output over a window of at most
/// [`FIGURE_WINDOW`] consecutive samples from the start of the held-out tail, which no fit saw:
/// plain lines, the nominal dashed.
#[allow(clippy::too_many_arguments)]
pub fn output_figure(
    dir: &Path,
    name: &str,
    title: &str,
    time: &[f64],
    y: &[f64],
    s: &[f64],
    c: &[f64],
    holdout_start: usize,
) -> anyhow::Result<()> {
    let n = time.len();
    let start =
        if n.saturating_sub(holdout_start) >= 2 { holdout_start } else { n.saturating_sub(FIGURE_WINDOW) };
    let end = (start + FIGURE_WINDOW).min(n);
    let pts = |v: &[f64]| -> Vec<(f64, f64)> { (start..end).map(|k| (time[k], v[k])).collect() };
    let series = [
        XySeries::line("recorded", pts(y), false, (120, 120, 120), 4),
        XySeries::line("nominal simulation", pts(s), true, (214, 39, 40), 2),
        XySeries::line("corrected", pts(c), false, (31, 119, 180), 2),
    ];
    let title = format!("{title} (held-out samples {start}..{end})");
    write_xy_chart(dir, name, &title, "time [s]", "output", &series)?;
    Ok(())
}
