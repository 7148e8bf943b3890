//! `mpmwatch loadgen`: publishes synthetic controllers over zenoh to load a monitor. Thin: the
//! logic is `mpmwatch::loadgen`.

use std::time::Duration;

use anyhow::Context;
use mpmwatch::loadgen::{self, LoadgenOptions};

const LOADGEN_HELP: &str = "\
WHAT IT SENDS
  For each controller <id> = <id-prefix>000, 001, ... (from --first), one sample of every tag
  per row on the keys of the monitor's contract:
    <prefix>/<id>/mv/u1..uM       total MV = smooth uc + dither
    <prefix>/<id>/dither/ud1..udM  maximal-length PRBS, ±1 (order 15, one polynomial per MV)
    <prefix>/<id>/cv/y1..yC       prediction + residual
    <prefix>/<id>/pred/p1..pC     the prediction (omit with --no-pred)
  The residual is uniform noise plus --mismatch × ud1(t−1) in y1 only, so a monitor running
  these controllers should flag ud1→y1 and nothing else. Payloads are {\"t\": t, \"v\": v} with
  --batch 1, else {\"t\": [..], \"v\": [..]}; times are t0 + k·period seconds.

RATE
  --rate is rows per second per controller, so the offered load is
    controllers × tags × rate  samples/s   (tags = 2·M + 2·C with predictions)
  --rate 0 publishes as fast as this process can. Puts block when zenoh's queues are full
  (congestion control Block), so nothing is lost on the way: every sample reported as sent
  reaches the monitor, which ingests it or counts it in mpm_samples_dropped_total{reason}.
  (`queue_full` counts messages, not samples: multiply by --batch.) --drop lets zenoh drop
  instead, as a publisher that must never stall would.

MATCHING MONITOR CONFIG
  --print-config prints the [[controller]] tables a monitor needs for these controllers (add
  [zenoh] and [http] sections) and exits.

OUTPUT
  One summary line (samples/s achieved), or one JSON object with --json.

Examples:
  mpmwatch loadgen --connect tcp/127.0.0.1:7447 --controllers 20 --rate 1000 --batch 100 --duration 60
  mpmwatch loadgen --controllers 60 --print-config --extra 'window = 2048' > controllers.toml";

/// Arguments of `mpmwatch loadgen`.
#[derive(Debug, clap::Args)]
#[command(after_long_help = LOADGEN_HELP)]
pub struct Args {
    /// Number of synthetic controllers.
    #[arg(long, default_value_t = 1)]
    controllers: usize,
    /// MVs (and dithers) per controller.
    #[arg(long, default_value_t = 3)]
    mvs: usize,
    /// CVs (and predictions) per controller.
    #[arg(long, default_value_t = 3)]
    cvs: usize,
    /// Do not publish predictions (pred/<tag>).
    #[arg(long)]
    no_pred: bool,
    /// Rows per second per controller (one sample of every tag); 0 = as fast as possible.
    #[arg(long, default_value_t = 100.0)]
    rate: f64,
    /// Samples per message (1 = single-sample payloads).
    #[arg(long, default_value_t = 100)]
    batch: usize,
    /// Seconds to publish.
    #[arg(long, default_value_t = 10.0)]
    duration: f64,
    /// Gain of ud1(t−1) in y1's residual (0 = a clean model).
    #[arg(long, default_value_t = 0.5)]
    mismatch: f64,
    /// Key prefix.
    #[arg(long, default_value = "mpm")]
    prefix: String,
    /// Controller ids are <id-prefix><index, 3 digits>.
    #[arg(long, default_value = "lg")]
    id_prefix: String,
    /// Index of the first controller.
    #[arg(long, default_value_t = 0)]
    first: usize,
    /// Sample period of the source times, seconds.
    #[arg(long, default_value_t = 1.0)]
    period: f64,
    /// Source time of the first row, seconds.
    #[arg(long, default_value_t = 0.0)]
    t0: f64,
    /// Seed of the noise and of the PRBS states.
    #[arg(long, default_value_t = 1)]
    seed: u64,
    /// Zenoh endpoints to connect to (the monitor's listen endpoint, or a router).
    #[arg(long, value_delimiter = ',', default_value = "tcp/127.0.0.1:7447")]
    connect: Vec<String>,
    /// Zenoh endpoints to listen on (none by default).
    #[arg(long, value_delimiter = ',')]
    listen: Vec<String>,
    /// Zenoh mode: peer or client.
    #[arg(long, default_value = "peer")]
    mode: String,
    /// Let zenoh drop messages when its queues are full instead of blocking the publisher.
    #[arg(long)]
    drop: bool,
    /// Seconds to wait for every key to have a subscriber before publishing.
    #[arg(long, default_value_t = 10.0)]
    wait: f64,
    /// Seconds to keep the session open after the last put: closing it at once would discard
    /// messages still in zenoh's transmit queue (sent, never delivered).
    #[arg(long, default_value_t = 2.0)]
    linger: f64,
    /// Print the matching [[controller]] tables and exit.
    #[arg(long)]
    print_config: bool,
    /// Extra lines for each printed [[controller]] table (e.g. "window = 2048").
    #[arg(long, default_value = "")]
    extra: String,
    /// Print one JSON object.
    #[arg(long)]
    json: bool,
}

/// Runs the verb.
pub fn run(args: Args) -> anyhow::Result<()> {
    anyhow::ensure!(args.duration.is_finite() && args.duration > 0.0, "--duration must be positive");
    anyhow::ensure!(args.wait.is_finite() && args.wait >= 0.0, "--wait must be ≥ 0");
    anyhow::ensure!(args.linger.is_finite() && args.linger >= 0.0, "--linger must be ≥ 0");
    anyhow::ensure!(["peer", "client"].contains(&args.mode.as_str()), "--mode must be peer or client");
    let opts = LoadgenOptions {
        prefix: args.prefix,
        controllers: args.controllers,
        id_prefix: args.id_prefix,
        first: args.first,
        mvs: args.mvs,
        cvs: args.cvs,
        pred: !args.no_pred,
        rate: args.rate,
        batch: args.batch,
        duration: Duration::from_secs_f64(args.duration),
        mismatch: args.mismatch,
        seed: args.seed,
        period: args.period,
        t0: args.t0,
        block: !args.drop,
        wait_subscribers: Duration::from_secs_f64(args.wait),
    };
    opts.check()?;
    if args.print_config {
        print!("{}", opts.controller_toml(&args.extra.replace("\\n", "\n")));
        return Ok(());
    }
    let mut zc = zenoh::Config::default();
    let json = |v: &[String]| serde_json::to_string(v).unwrap_or_else(|_| "[]".into());
    let set = |zc: &mut zenoh::Config, k: &str, v: &str| {
        zc.insert_json5(k, v).map_err(|e| anyhow::anyhow!("zenoh config {k}: {e}"))
    };
    set(&mut zc, "mode", &format!("{:?}", args.mode))?;
    set(&mut zc, "scouting/multicast/enabled", "false")?;
    set(&mut zc, "listen/endpoints", &json(&args.listen))?;
    set(&mut zc, "connect/endpoints", &json(&args.connect))?;
    let rt = tokio::runtime::Builder::new_multi_thread().enable_all().build().context("tokio runtime")?;
    let report = rt.block_on(async {
        let session = zenoh::open(zc).await.map_err(|e| anyhow::anyhow!("zenoh: {e}"))?;
        let r = loadgen::run(&session, &opts).await;
        tokio::time::sleep(Duration::from_secs_f64(args.linger)).await;
        let _ = session.close().await;
        r.map_err(anyhow::Error::from)
    })?;
    if args.json {
        println!("{}", serde_json::to_string(&report)?);
    } else {
        println!(
            "sent {} samples in {} messages over {:.1} s: {:.0} samples/s ({:.0} msg/s), target {:.0} samples/s; \
             {} controllers × {} tags, batch {}, {} put errors, {} keys without subscriber",
            report.samples,
            report.messages,
            report.elapsed_s,
            report.samples_per_s,
            report.messages_per_s,
            report.samples_per_s_target,
            report.controllers,
            report.tags_per_controller,
            report.batch,
            report.put_errors,
            report.unmatched_keys
        );
    }
    if report.unmatched_keys > 0 {
        eprintln!(
            "warning: {} keys had no subscriber after --wait {} s: their samples went nowhere",
            report.unmatched_keys, args.wait
        );
    }
    Ok(())
}
