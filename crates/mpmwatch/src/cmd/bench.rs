//! `mpmwatch bench`: timings of the estimation core.

use mpmwatch::benchmark::{self, BenchOptions};

/// Arguments of the verb (documented on the verb in `main.rs`).
#[derive(clap::Args)]
pub struct Args {
    /// Record length N.
    #[arg(long, default_value_t = 2048)]
    n: usize,
    /// Repetitions per single-estimate timing (the median is reported).
    #[arg(long, default_value_t = 50)]
    reps: usize,
    /// Seed of the synthetic data.
    #[arg(long, default_value_t = 1)]
    seed: u64,
    /// Print one JSON object instead of a table.
    #[arg(long)]
    json: bool,
}

pub fn run(args: Args) -> anyhow::Result<()> {
    anyhow::ensure!(args.n >= 512, "--n must be at least 512 for a 20-lag matrix (got {})", args.n);
    let opts = BenchOptions { n: args.n, reps: args.reps, seed: args.seed };
    let quiet = args.json;
    let report = benchmark::run(&opts, |what| {
        if !quiet {
            eprintln!("timing {what}...");
        }
    })?;
    if args.json {
        println!("{}", serde_json::to_string(&report)?);
    } else {
        println!("N = {}, k = {}, seed = {}, {} threads", report.n, report.k, report.seed, report.threads);
        println!("  binary-dither estimate   {:>9.3} ms (median)", report.ksg_binary_ms);
        println!("  continuous estimate      {:>9.3} ms (median)", report.ksg_continuous_ms);
        println!("  iAAFT surrogate          {:>9.3} ms (median)", report.iaaft_ms);
        println!("  3x3 matrix, 20 lags, 100 surrogates  {:>9.1} ms", report.matrix_3x3_ms);
        println!("  3x3 default analysis (joint, whitened, partialled)  {:>9.1} ms", report.analyze_3x3_ms);
    }
    Ok(())
}
