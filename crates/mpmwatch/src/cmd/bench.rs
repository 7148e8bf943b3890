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
    /// Instead of the timings, run the power study (docs/detection.md) and write
    /// `power.md`, `power.json` and one figure per mismatch shape into this folder. Case c
    /// draws its data from seed `seed·1000000 + c`. Takes about half an hour on 2 cores.
    #[arg(long)]
    power: Option<std::path::PathBuf>,
    /// Instead of the timings, time one default analysis of a 20×40 controller (binary
    /// dithers, three planted mismatches, lags 1–20). Takes minutes.
    #[arg(long)]
    large: bool,
    /// Instead of the timings, time one open-loop diagnosis (`diagnose`'s grey-box path) of a
    /// generated Duffing oscillator of N samples against its least-squares ARX nominal, first
    /// on one thread, then on every thread, and check that both name the same. Took 27 to
    /// 37 s in all at N = 3000 on a 2-core machine (docs/performance.md).
    #[arg(long)]
    diagnose: bool,
    /// Scale the study's case counts (0.25 for a quick look; the documented run uses 1).
    #[arg(long, default_value_t = 1.0)]
    power_scale: f64,
}

pub fn run(args: Args) -> anyhow::Result<()> {
    if let Some(dir) = &args.power {
        return power(dir, args.seed, args.power_scale);
    }
    if args.large {
        eprintln!("analysing a 20x40 controller, N = {}, seed {} (the default rule)...", args.n, args.seed);
        let r = benchmark::run_large(args.n, args.seed)?;
        if args.json {
            println!("{}", serde_json::to_string(&r)?);
        } else {
            println!(
                "20x40 default analysis, N = {}: {:.1} s on {} threads; planted found {}/3, other elements flagged {}",
                r.n,
                r.seconds,
                rayon::current_num_threads(),
                r.planted_found,
                r.false_elements
            );
        }
        return Ok(());
    }
    if args.diagnose {
        eprintln!(
            "diagnosing a Duffing oscillator, N = {}, seed {}, on one thread, then on {}...",
            args.n,
            args.seed,
            rayon::current_num_threads()
        );
        let r = benchmark::run_diagnosis(args.n, args.seed)?;
        anyhow::ensure!(r.same, "the two runs named differently: the decisions depend on the threads");
        if args.json {
            println!("{}", serde_json::to_string(&r)?);
        } else {
            println!(
                "diagnose ({}, N = {}, seed {}, named {}): {:.1} s on one thread, {:.1} s on {} ({:.2}x); the same findings",
                r.case,
                r.n,
                r.seed,
                r.named,
                r.one_thread_s,
                r.all_threads_s,
                r.threads,
                r.one_thread_s / r.all_threads_s
            );
        }
        return Ok(());
    }
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
        println!(
            "  binary-dither, per lag   {:>9.3} ms (median; residual sorted once for 20 lags)",
            report.ksg_binary_per_lag_ms
        );
        println!("  continuous estimate      {:>9.3} ms (median)", report.ksg_continuous_ms);
        println!("  iAAFT surrogate          {:>9.3} ms (median)", report.iaaft_ms);
        println!("  3x3 matrix, 20 lags, 100 surrogates  {:>9.1} ms", report.matrix_3x3_ms);
        println!("  3x3 default analysis (joint, whitened, partialled)  {:>9.1} ms", report.analyze_3x3_ms);
    }
    Ok(())
}

fn power(dir: &std::path::Path, seed: u64, scale: f64) -> anyhow::Result<()> {
    use mpmwatch::power::{self, PowerOptions};
    use mpmwatch::report::figures::{XySeries, write_xy_chart};
    anyhow::ensure!(scale > 0.0 && scale <= 10.0, "--power-scale must be in (0, 10] (got {scale})");
    let d = PowerOptions::default();
    let sc = |k: usize| ((k as f64 * scale).round() as usize).max(1);
    let opts = PowerOptions {
        seed,
        binary_cases: sc(d.binary_cases),
        uniform_cases: sc(d.uniform_cases),
        binary_nulls: sc(d.binary_nulls),
        uniform_nulls: sc(d.uniform_nulls),
        ..d
    };
    std::fs::create_dir_all(dir).map_err(|e| anyhow::anyhow!("cannot create {}: {e}", dir.display()))?;
    let start = std::time::Instant::now();
    let out = power::run(&opts, |done, total| {
        if done % 20 == 0 || done == total {
            eprintln!("{done}/{total} cases, {:.0} s", start.elapsed().as_secs_f64());
        }
    })?;
    let summary = power::summarise(&opts, &out);
    let md = summary.markdown();
    std::fs::write(dir.join("power.md"), &md)?;
    std::fs::write(
        dir.join("power.json"),
        serde_json::to_string_pretty(&serde_json::json!({ "summary": summary, "outcomes": out }))?,
    )?;
    let mut families: Vec<(power::Shape, power::DitherKind)> = Vec::new();
    for r in &summary.power {
        if !families.contains(&(r.shape, r.dither)) {
            families.push((r.shape, r.dither));
        }
    }
    for (shape, dither) in families {
        let rows: Vec<&power::PowerRow> =
            summary.power.iter().filter(|r| r.shape == shape && r.dither == dither).collect();
        let series = |label: &str, f: &dyn Fn(&power::PowerRow) -> power::Rate| {
            XySeries::points(
                label,
                rows.iter().map(|r| (r.size, 100.0 * f(r).value())).collect(),
                Some(rows.iter().map(|r| 50.0 * (f(r).high - f(r).low)).collect()),
            )
        };
        let name = format!(
            "{}_{}",
            serde_json::to_value(shape)?.as_str().unwrap_or("shape"),
            serde_json::to_value(dither)?.as_str().unwrap_or("dither")
        );
        write_xy_chart(
            dir,
            &name,
            &format!("{shape:?} mismatch, {dither:?} dither: detections (%), N = {}", opts.n),
            "effect size (std of the effect / std of the noise innovation)",
            "detected (%)",
            &[
                series(&format!("family-wise, alpha {}", opts.alpha), &|r| r.family),
                series("paper, 6 sigma", &|r| r.paper),
                series(&format!("whitened CCF, alpha {}", opts.alpha), &|r| r.ccf),
            ],
        )?;
    }
    println!("{md}");
    eprintln!("wrote {} in {:.0} s", dir.display(), start.elapsed().as_secs_f64());
    Ok(())
}
