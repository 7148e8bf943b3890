//! `mpmwatch analyze`: the MI matrix of a recording, with thresholds, verdicts, the CCF
//! baseline, JSON and figures.

use std::path::PathBuf;
use std::time::Instant;

use anyhow::{Context, bail};
use mpmwatch::report::{figures, summarise};
use mpmwatch_core::detect::{Evidence, LagChoice, MatrixOptions, Method, Signal, Verdict, analyze};
use mpmwatch_core::info::{Lags, MiOptions, SurrogateOptions, Units};
use mpmwatch_core::io::Table;
use serde_json::json;

/// Arguments of the verb (documented on the verb in `main.rs`).
#[derive(clap::Args)]
pub struct Args {
    /// CSV recording with a `time` column.
    file: PathBuf,
    /// Dither columns, comma separated (one per excited MV).
    #[arg(long, value_delimiter = ',', required = true)]
    dither: Vec<String>,
    /// Residual columns (CV minus model prediction), comma separated.
    #[arg(long, value_delimiter = ',', conflicts_with_all = ["output", "simulated"])]
    residual: Vec<String>,
    /// Measured CV columns; residuals are these minus the same-named columns of --simulated.
    #[arg(long, value_delimiter = ',', requires = "simulated")]
    output: Vec<String>,
    /// CSV of the nominal model's simulation on the same time axis.
    #[arg(long, requires = "output")]
    simulated: Option<PathBuf>,
    /// Smallest lag (eq 19's tmin).
    #[arg(long, default_value_t = 1)]
    tmin: usize,
    /// Largest lag. Without it, each residual's tmax is the first minimum of its auto-MI,
    /// searched up to --tmax-search.
    #[arg(long)]
    tmax: Option<usize>,
    /// Upper bound of the automatic tmax search.
    #[arg(long, default_value_t = 30)]
    tmax_search: usize,
    /// Nearest neighbours of the KSG estimator.
    #[arg(long, default_value_t = 4)]
    k: usize,
    /// Decision rule. `family`: one test per element over every lag of pairwise MI, joint-lag
    /// MI and the cross-correlation, with false-alarm rate --alpha. `paper`: the paper's
    /// μ + zσ per statistic (eq 11), about a one-in-a-billion test per lag at z = 6.
    #[arg(long, default_value_t = Method::Family, value_parser = super::choice::<Method>())]
    method: Method,
    /// False-alarm rate per element (method `family`): the chance that a right submodel is
    /// called significant in one analysis. A matrix of m elements averages m·alpha false
    /// elements per analysis; use alpha/m for a matrix-wide rate.
    #[arg(long, default_value_t = 0.01)]
    alpha: f64,
    /// Surrogates per element. Method `family`: the most drawn after 30 calibration
    /// surrogates; a clearly null or clearly significant element stops early.
    #[arg(long, default_value_t = 100)]
    surrogates: usize,
    /// Multiplier of the surrogate standard deviation in the critical value (eq 11; method
    /// `paper`).
    #[arg(long, default_value_t = 6.0)]
    z: f64,
    /// Seed of the surrogates (reported in the output).
    #[arg(long, default_value_t = 0)]
    seed: u64,
    /// Skip the joint embedding of two consecutive dither lags (halves the run time; misses
    /// interaction terms such as u(t-1)·u(t-2)).
    #[arg(long)]
    no_joint: bool,
    /// Analyse the raw residuals, as the paper does, instead of pre-whitening each with its
    /// own AR model (order by AIC up to --whiten-order). Whitening removes the coloured
    /// disturbance that buries the dither's contribution; the test's level is unchanged.
    #[arg(long)]
    no_whiten: bool,
    /// Test each dither against the residual as it is, instead of first subtracting what the
    /// other dithers explain linearly (over lags 0..tmax). Subtracting keeps the test's level
    /// and finds a wrong channel hidden under a louder one.
    #[arg(long)]
    no_partial: bool,
    /// Largest AR order of the pre-whitening filter.
    #[arg(long, default_value_t = 10)]
    whiten_order: usize,
    /// Units of printed values and figures.
    #[arg(long, default_value_t = Units::Bits, value_parser = super::choice::<Units>())]
    units: Units,
    /// Print the full result as one JSON object.
    #[arg(long)]
    json: bool,
    /// Write figures (SVG and PNG) into this folder.
    #[arg(long)]
    figures: Option<PathBuf>,
}

pub fn run(args: Args) -> anyhow::Result<()> {
    let table = Table::read_csv(&args.file)?;
    let dithers: Vec<&[f64]> = args
        .dither
        .iter()
        .map(|d| table.column(d).with_context(|| format!("--dither in {}", args.file.display())))
        .collect::<Result<_, _>>()?;
    let (residual_names, residuals): (Vec<String>, Vec<Vec<f64>>) = if !args.residual.is_empty() {
        let r = args
            .residual
            .iter()
            .map(|e| {
                Ok(table
                    .column(e)
                    .with_context(|| format!("--residual in {}", args.file.display()))?
                    .to_vec())
            })
            .collect::<anyhow::Result<_>>()?;
        (args.residual.clone(), r)
    } else if let Some(sim_path) = &args.simulated {
        let sim = Table::read_csv(sim_path)?;
        if sim.len() != table.len() {
            bail!(
                "{} has {} rows, {} has {}: they must share the time axis",
                sim_path.display(),
                sim.len(),
                args.file.display(),
                table.len()
            );
        }
        if let Some(r) = (0..table.len())
            .find(|&r| (sim.time()[r] - table.time()[r]).abs() > 1e-9 * table.time()[r].abs().max(1.0))
        {
            bail!(
                "time differs at row {}: {} has {}, {} has {}",
                r + 2,
                args.file.display(),
                table.time()[r],
                sim_path.display(),
                sim.time()[r]
            );
        }
        let r = args
            .output
            .iter()
            .map(|y| {
                let meas = table.column(y).with_context(|| format!("--output in {}", args.file.display()))?;
                let pred = sim.column(y).with_context(|| format!("--output in {}", sim_path.display()))?;
                Ok(meas.iter().zip(pred).map(|(a, b)| a - b).collect())
            })
            .collect::<anyhow::Result<_>>()?;
        (args.output.iter().map(|y| format!("e_{y}")).collect(), r)
    } else {
        bail!(
            "give the residuals (--residual e1,e2) or the outputs and a simulation (--output y1,y2 --simulated SIM.csv)"
        );
    };

    let lags = match args.tmax {
        Some(tmax) => LagChoice::Fixed(Lags::new(args.tmin, tmax)?),
        None => LagChoice::Auto { max: args.tmax_search },
    };
    let opts = MatrixOptions {
        method: args.method,
        alpha: args.alpha,
        lags,
        mi: MiOptions { k: args.k, ..MiOptions::default() },
        surrogates: SurrogateOptions {
            count: args.surrogates,
            z: args.z,
            seed: args.seed,
            ..SurrogateOptions::default()
        },
        joint_embedding: !args.no_joint,
        ccf_alpha: 0.05,
        partial_out: !args.no_partial,
        whiten: (!args.no_whiten).then_some(args.whiten_order),
    };
    let d: Vec<Signal> =
        args.dither.iter().zip(&dithers).map(|(n, v)| Signal { name: n, values: v }).collect();
    let r: Vec<Signal> =
        residual_names.iter().zip(&residuals).map(|(n, v)| Signal { name: n, values: v }).collect();
    eprintln!(
        "analysing {} dither(s) x {} residual(s), {} samples, {}, up to {} surrogates per element (seed {}){}...",
        d.len(),
        r.len(),
        table.len(),
        match args.method {
            Method::Family => format!("family-wise test at alpha = {} per element", args.alpha),
            Method::Paper => format!("the paper's rule at z = {}", args.z),
        },
        args.surrogates,
        args.seed,
        if args.no_joint { "" } else { ", with joint-lag embedding" }
    );
    let start = Instant::now();
    let m = analyze(&d, &r, &opts)?;
    eprintln!("done in {:.1} s", start.elapsed().as_secs_f64());
    let summary = summarise(&m);
    if let Some(dir) = &args.figures {
        let files = figures::write_matrix_figures(dir, &m, args.units)?;
        eprintln!("wrote {} figure files to {}", files.len(), dir.display());
    }
    if args.json {
        println!(
            "{}",
            json!({ "mismatch": m.mismatch, "channels": summary, "matrix": m, "units_of_matrix": "nats" })
        );
        return Ok(());
    }
    let u = args.units;
    let unit = if u == Units::Bits { "bits" } else { "nats" };
    println!("{}", if m.mismatch { "MISMATCH detected" } else { "no mismatch detected" });
    println!(
        "{:<10} {:<12} {:>11} {:>9} {:<22} {:>10} {:>10}  verdict",
        "input",
        "output",
        format!("MI ({unit})"),
        "p-value",
        "strongest evidence",
        "value",
        "critical"
    );
    for ch in &m.channels {
        let Some(c) = m.cell(ch.mv_index, ch.cv_index) else { continue };
        let dec = &c.decision;
        let (what, scale): (String, fn(Units, f64) -> f64) = match dec.evidence {
            Evidence::NormMi => (format!("norm of MI ({unit})"), |u, v| u.from_nats(v)),
            Evidence::LagMi => (format!("MI, lag {} ({unit})", dec.lag.unwrap_or(0)), |u, v| u.from_nats(v)),
            Evidence::JointMi => (format!("joint MI ({unit})"), |u, v| u.from_nats(v)),
            Evidence::Ccf => (format!("CCF, lag {}", dec.lag.unwrap_or(0)), |_, v| v),
        };
        println!(
            "{:<10} {:<12} {:>11.5} {:>9.2e} {:<22} {:>10.5} {:>10.5}  {}",
            ch.mv,
            ch.cv,
            u.from_nats(c.pairwise.norm),
            dec.p_value,
            what,
            scale(u, dec.value),
            scale(u, dec.critical),
            match ch.verdict {
                Verdict::Mismatch => "MISMATCH",
                Verdict::ImplicatedByFeedback => "implicated by feedback",
                Verdict::Clean => "clean",
            }
        );
    }
    for s in summary.iter().filter(|s| s.significant) {
        println!("  {} -> {}: {}", s.input, s.output, s.reason);
    }
    let not_excited: Vec<&str> =
        m.dithers.iter().zip(&m.excited).filter(|(_, e)| !**e).map(|(n, _)| n.as_str()).collect();
    if !not_excited.is_empty() {
        println!("not excited (constant dither): {}", not_excited.join(", "));
    }
    Ok(())
}
