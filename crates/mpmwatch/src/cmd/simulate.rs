//! `mpmwatch simulate CASE --out FILE`: runs one of the paper's plants and writes its CSV.

use std::io::BufWriter;
use std::path::PathBuf;

use anyhow::Context;
use mpmwatch_sim::Excitation;
use mpmwatch_sim::cases::{self, CaseName, CaseOptions, Disturbance};

const CASES_HELP: &str = "\
CASES (every CSV starts with `time`; T = 1 s; default 2047 samples, one ±1 PRBS period):

  model1          Paper eq 12: y(t) = −0.8y(t−1) + 0.08(y²(t−1) + 4.5u(t−1) + u(t−1)u(t−2)) + d(t),
                  open loop, u = the excitation (±1 PRBS by default), d = ARIMA(2,0,0) of eq 14.
                  Columns: time,u,y,e1,e2,e3,e4 with the four residual candidates of eq 13:
                  e1 = 0.7d(t−1)+d (no u information), e2 = 0.06u(t−1)u(t−2)+d,
                  e3 = 0.2y(t−1)+d, e4 = 0.03y²(t−1)+d.

  continuous2x3   Paper eqs 25–26: 3 MVs, 2 CVs, u1 enters as a·u1², sampled by ZOH at T = 1 s,
                  linear MPC (QP with input and move limits) on the model linearised at u = (1,0,0),
                  ±1 PRBS dithers on all MVs, coloured noise of eq 26. Nominal a = 0.2.
                  --mismatch none | a=VALUE   (default a=0.8: mismatch on u1's channels only)
                  Columns: time,u1..u3,ud1..ud3,y1,y2,yhat1,yhat2,e1,e2.

  hammerstein3x3  Paper eq 27: y = G(q)[u1, u2², sin(u3)] + coloured noise, NMPC (successive
                  linearisation, one QP per iteration), ±1 PRBS dithers.
                  --mismatch none | g21 | g31 | both   (default both: eqs 28 and 29)
                  --disturbance nominal | changed      (changed = eq 30; must not look like mismatch)
                  Columns: time,u1..u3,ud1..ud3,y1..y3,yhat1..yhat3,e1..e3.

Column roles: u = total MV (controller output + dither), ud = dither, y = measured CV,
yhat = nominal model G0 driven by the total MVs, e = y − yhat (the residual).

STUDIES of the paper's §3.1 as options: --samples 512..32768 (Figure 4), --noise-ratio
(Figure 5, model1), --excitation prbs|uniform|gaussian at --dither-std 1 (Figure 6).

The seed is printed on stderr; the same seed gives byte-identical files.";

/// Arguments of `mpmwatch simulate`.
#[derive(Debug, clap::Args)]
#[command(after_long_help = CASES_HELP, after_help = "Run `mpmwatch simulate --help` for the cases and their columns.")]
pub struct Args {
    /// Case to run: model1, continuous2x3 or hammerstein3x3.
    pub case: String,
    /// Output CSV file.
    #[arg(long)]
    pub out: PathBuf,
    /// Seed of every random draw (dither and noise).
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    /// Number of samples (default 2047).
    #[arg(long)]
    pub samples: Option<usize>,
    /// Which plant/model mismatch to simulate (case-specific, see below).
    #[arg(long)]
    pub mismatch: Option<String>,
    /// Dither / input excitation: prbs, multilevel, uniform or gaussian.
    #[arg(long, default_value = "prbs")]
    pub excitation: String,
    /// Standard deviation of each dither (1 = ±1 PRBS, unit-variance white noise).
    #[arg(long, default_value_t = 1.0)]
    pub dither_std: f64,
    /// Multiplies the standard deviation of every noise source.
    #[arg(long, default_value_t = 1.0)]
    pub noise_scale: f64,
    /// model1: scale the disturbance to this noise-to-signal ratio std(d)/std(0.06u(t−1)u(t−2)).
    #[arg(long)]
    pub noise_ratio: Option<f64>,
    /// hammerstein3x3: disturbance dynamics, nominal (eq 27) or changed (eq 30).
    #[arg(long, default_value = "nominal")]
    pub disturbance: String,
}

/// Runs the verb.
pub fn run(args: Args) -> anyhow::Result<()> {
    let case = CaseName::parse(&args.case)?;
    if args.noise_ratio.is_some() && case != CaseName::Model1 {
        anyhow::bail!("--noise-ratio applies to model1 only; use --noise-scale for {}", case.name());
    }
    if args.disturbance != "nominal" && case != CaseName::Hammerstein3x3 {
        anyhow::bail!("--disturbance applies to hammerstein3x3 only");
    }
    let opts = CaseOptions {
        seed: args.seed,
        samples: args.samples,
        mismatch: args.mismatch.clone(),
        excitation: Excitation::parse(&args.excitation)?,
        dither_std: args.dither_std,
        noise_scale: args.noise_scale,
        noise_ratio: args.noise_ratio,
        disturbance: Disturbance::parse(&args.disturbance)?,
    };
    eprintln!("simulate {}: seed {}", case.name(), args.seed);
    let out = cases::run(case, &opts).with_context(|| format!("simulating {}", case.name()))?;
    let file =
        std::fs::File::create(&args.out).with_context(|| format!("cannot create {}", args.out.display()))?;
    out.table.write_csv(BufWriter::new(file)).with_context(|| format!("writing {}", args.out.display()))?;
    eprintln!("{}", out.summary);
    if let Some(s) = &out.controller {
        eprintln!(
            "controller: {} QPs, {} unsolved (held last output), largest raw constraint violation {:.2e}",
            s.solves, s.failures, s.max_raw_violation
        );
    }
    eprintln!(
        "wrote {} rows × {} columns to {}",
        out.table.len(),
        out.table.names().len() + 1,
        args.out.display()
    );
    Ok(())
}
