//! `mpmwatch mi`: one mutual-information estimate between two columns of a CSV file.

use std::path::PathBuf;

use anyhow::Context;
use mpmwatch_core::info::joe;
use mpmwatch_core::info::{Lags, MiOptions, SurrogateOptions, Units, XKind, lagged_test, mutual_information};
use mpmwatch_core::io::Table;
use serde_json::json;

/// Arguments of the verb (documented on the verb in `main.rs`).
#[derive(clap::Args)]
pub struct Args {
    /// CSV file with a `time` column.
    file: PathBuf,
    /// Column of x (e.g. a dither).
    #[arg(long)]
    x: String,
    /// Column of y (e.g. a residual).
    #[arg(long)]
    y: String,
    /// Lag L in samples: pairs x(t) with y(t+L). Negative pairs x(t) with earlier y.
    #[arg(long, default_value_t = 0, allow_hyphen_values = true)]
    lag: i64,
    /// Number of nearest neighbours (2–10 is usual; larger lowers variance, raises bias).
    #[arg(long, default_value_t = 4)]
    k: usize,
    /// Units of the output: nats, or bits as in the paper.
    #[arg(long, default_value_t = Units::Nats, value_parser = super::choice::<Units>())]
    units: Units,
    /// How to treat x: auto picks discrete when x has at most 16 distinct values.
    #[arg(long, default_value_t = XKind::Auto, value_parser = super::choice::<XKind>())]
    x_kind: XKind,
    /// Test significance against this many surrogates (lag ≥ 0 only).
    #[arg(long)]
    surrogates: Option<usize>,
    /// Multiplier of the surrogate standard deviation in the critical value.
    #[arg(long, default_value_t = 6.0)]
    z: f64,
    /// Seed of the surrogates.
    #[arg(long, default_value_t = 0)]
    seed: u64,
    /// Print one JSON object.
    #[arg(long)]
    json: bool,
}

pub fn run(args: Args) -> anyhow::Result<()> {
    let table = Table::read_csv(&args.file)?;
    let x = table.column(&args.x).with_context(|| format!("--x in {}", args.file.display()))?;
    let y = table.column(&args.y).with_context(|| format!("--y in {}", args.file.display()))?;
    let n = x.len();
    let shift = args.lag.unsigned_abs() as usize;
    anyhow::ensure!(shift < n, "--lag {} is not shorter than the record ({n} samples)", args.lag);
    let (xs, ys) =
        if args.lag >= 0 { (&x[..n - shift], &y[shift..]) } else { (&x[shift..], &y[..n - shift]) };
    let opts = MiOptions { k: args.k, x_kind: args.x_kind, ..MiOptions::default() };
    let est = mutual_information(xs, ys, &opts)
        .with_context(|| format!("estimating I({}; {}) at lag {}", args.x, args.y, args.lag))?;
    let u = args.units;
    let mut out = json!({
        "mi": u.from_nats(est.nats),
        "n": est.n,
        "units": u,
        "estimator": est.estimator,
        "k": args.k,
        "lag": args.lag,
        "x": args.x,
        "y": args.y,
        "joe": joe(est.nats),
    });
    if let Some(m) = args.surrogates {
        anyhow::ensure!(args.lag >= 0, "--surrogates needs a lag ≥ 0");
        let lag = args.lag as usize;
        let sur = SurrogateOptions { count: m, z: args.z, seed: args.seed, ..SurrogateOptions::default() };
        let t = lagged_test(x, y, Lags::new(lag, lag)?, 1, &opts, &sur)?;
        out["surrogates"] = json!({
            "count": m,
            "method": t.method,
            "seed": t.seed,
            "z": args.z,
            "mi": u.from_nats(t.norm),
            "mean": u.from_nats(t.threshold.mean),
            "std": u.from_nats(t.threshold.std),
            "critical": u.from_nats(t.threshold.critical),
            "p_value": t.p_value,
            "significant": t.significant,
        });
    }
    if args.json {
        println!("{out}");
    } else {
        let unit = if u == Units::Bits { "bits" } else { "nats" };
        println!(
            "I({}(t); {}(t{:+})) = {:.6} {unit}  (n = {}, k = {}, {:?}, Joe's normalised MI {:.3})",
            args.x,
            args.y,
            args.lag,
            u.from_nats(est.nats),
            est.n,
            args.k,
            est.estimator,
            joe(est.nats)
        );
        if let Some(s) = out.get("surrogates") {
            println!(
                "surrogates ({} by {}, seed {}): critical value {:.6} {unit}, p = {:.4} -> {}",
                s["count"],
                s["method"].as_str().unwrap_or("?"),
                s["seed"],
                s["critical"].as_f64().unwrap_or(f64::NAN),
                s["p_value"].as_f64().unwrap_or(f64::NAN),
                if s["significant"].as_bool() == Some(true) { "significant" } else { "not significant" }
            );
        }
    }
    Ok(())
}
