//! `mpmwatch serve [--config FILE]`: the online monitor.

use std::path::PathBuf;

use anyhow::Context;
use mpmwatch_service::Service;
use mpmwatch_service::config::{Config, ConfigError};

const SERVE_HELP: &str = "\
WHAT IT DOES
  Subscribes on zenoh to <prefix>/<controller>/{mv,dither,cv,pred}/<tag> (payload JSON
  {\"t\": time, \"v\": value} or {\"t\": [..], \"v\": [..]}, t in seconds or RFC 3339), snaps the
  samples to each controller's sample grid, forms residuals (cv − pred, or cv − G0(mv) with a
  nominal model from the config), keeps a bounded window per controller, and every `every`
  seconds computes the MI matrix of dithers against residuals with surrogate critical values.
  A channel whose statistic stays above its critical value for `raise_after` runs in a row
  raises an alarm; `clear_after` clean runs clear it.

OUT
  zenoh   <prefix>/<controller>/alarm    JSON on raise and on clear
          <prefix>/<controller>/matrix   the latest result after each run; also a queryable
  HTTP    GET /  /healthz  /metrics  /api/v1/controllers  /api/v1/controllers/{id}/matrix
          /api/v1/controllers/{id}/alarms  /api/v1/controllers/{id}/profile?mv=..&cv=..
          POST /api/v1/controllers/{id}/run (analyse now) needs Authorization: Bearer <token>,
          the token from [http] token_env / token or MPMWATCH_TOKEN; without one, 403
  store   SQLite (WAL): window samples and alarm history, restored on start

CONFIG
  TOML; config/default.toml explains every key, config/examples/ has complete setups. A bad
  file is refused with one line per problem, each naming its key. Logging: RUST_LOG=debug
  shows every dropped sample and why.

Example: mpmwatch serve --config config/examples/continuous2x3.toml";

/// Arguments of `mpmwatch serve`.
#[derive(Debug, clap::Args)]
#[command(after_long_help = SERVE_HELP)]
pub struct Args {
    /// The TOML configuration.
    #[arg(long, short, default_value = "config/default.toml")]
    pub config: PathBuf,
    /// Only validate the configuration and exit.
    #[arg(long)]
    pub check: bool,
}

/// Starts the tracing subscriber (RUST_LOG, default info).
pub fn init_logging() {
    let filter = tracing_subscriber::EnvFilter::try_from_default_env()
        .unwrap_or_else(|_| tracing_subscriber::EnvFilter::new("info,zenoh=warn"));
    let _ = tracing_subscriber::fmt().with_env_filter(filter).with_writer(std::io::stderr).try_init();
}

/// Runs the verb.
pub fn run(args: Args) -> anyhow::Result<()> {
    let config = match Config::load(&args.config) {
        Ok(c) => c,
        Err(ConfigError::Invalid { path, problems }) => {
            for p in &problems {
                eprintln!("error: {path}: {p}");
            }
            anyhow::bail!("{} problem(s) in {path}", problems.len());
        }
        Err(e) => return Err(e.into()),
    };
    if args.check {
        println!("{}: ok ({} controller(s))", args.config.display(), config.controllers.len());
        return Ok(());
    }
    init_logging();
    let rt = tokio::runtime::Builder::new_multi_thread().enable_all().build().context("tokio runtime")?;
    rt.block_on(async move {
        let service = Service::start(config).await?;
        eprintln!("mpmwatch: serving on http://{}/ (Ctrl-C to stop)", service.http_addr);
        shutdown_signal().await;
        eprintln!("mpmwatch: stopping (flushing the store)");
        service.stop().await;
        Ok(())
    })
}

/// Ctrl-C, or SIGTERM (what systemd sends).
pub async fn shutdown_signal() {
    #[cfg(unix)]
    {
        use tokio::signal::unix::{SignalKind, signal};
        match signal(SignalKind::terminate()) {
            Ok(mut term) => {
                tokio::select! {
                    _ = tokio::signal::ctrl_c() => {}
                    _ = term.recv() => {}
                }
            }
            Err(_) => {
                let _ = tokio::signal::ctrl_c().await;
            }
        }
    }
    #[cfg(not(unix))]
    {
        let _ = tokio::signal::ctrl_c().await;
    }
}
