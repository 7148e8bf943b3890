//! `mpmwatch demo`: the monitor, an embedded zenoh peer on loopback and a simulated plant
//! publishing into it, in one command.

use std::path::PathBuf;
use std::sync::Arc;
use std::time::{Duration, Instant};

use anyhow::Context;
use mpmwatch::demo::DemoPlant;
use mpmwatch_service::RunStatus;
use mpmwatch_service::Service;
use mpmwatch_service::config::Config;
use mpmwatch_service::payload;

const DEMO_HELP: &str = "\
WHAT YOU SEE
  The paper's continuous 2×3 plant (eqs 25–26: u1 enters through a·u1², a = 0.2 in the model)
  under its linear MPC, with ±1 PRBS dithers ud1..ud3 on the three MVs, runs sample by sample
  and publishes on zenoh, in accelerated time (--rate samples per second), to
  mpm/c2x3/{mv,dither,cv,pred}/<tag>. The monitor in the same process subscribes, aligns,
  and every 3 s computes, on the newest 2048 samples, the MI matrix of the dithers against the residuals e = y − yhat of
  y1 and y2. At sample --switch-at the plant's a jumps to 0.8 (the paper's mismatch): only
  u1's submodels are now wrong, so the alarm must rise on ud1→y1 and ud1→y2 and nowhere else.
  With --fix-at the plant returns to a = 0.2 and the alarms clear.

WHERE TO LOOK
  http://127.0.0.1:9464/            the heat map (red frame = alarm), refreshing itself
  http://127.0.0.1:9464/metrics     Prometheus text
  http://127.0.0.1:9464/api/v1/controllers/c2x3/matrix
  zenoh: mpm/c2x3/alarm and mpm/c2x3/matrix on tcp/127.0.0.1:7447

Progress is printed every 5 s; alarms as they arrive on zenoh.";

/// Arguments of `mpmwatch demo`.
#[derive(Debug, clap::Args)]
#[command(after_long_help = DEMO_HELP)]
pub struct Args {
    /// HTTP address of the monitor.
    #[arg(long, default_value = "127.0.0.1:9464")]
    pub http: String,
    /// Loopback TCP port of the embedded zenoh peer.
    #[arg(long, default_value_t = 7447)]
    pub zenoh_port: u16,
    /// Plant samples published per wall-clock second (the plant's period is 1 s).
    #[arg(long, default_value_t = 100.0)]
    pub rate: f64,
    /// Sample at which the plant changes (a: 0.2 → 0.8).
    #[arg(long, default_value_t = 2500)]
    pub switch_at: usize,
    /// Sample at which the plant returns to the model (a = 0.2); never by default.
    #[arg(long)]
    pub fix_at: Option<usize>,
    /// Seed of the dithers and the noise.
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    /// Stop after this many seconds (0: run until Ctrl-C).
    #[arg(long, default_value_t = 0.0)]
    pub duration: f64,
    /// Keep the windows and alarms in this SQLite file (none by default).
    #[arg(long)]
    pub store: Option<PathBuf>,
}

const RECORD: usize = 200_000;

fn config(args: &Args) -> anyhow::Result<Config> {
    let store = match &args.store {
        Some(p) => format!("[store]\npath = {:?}\n", p.display().to_string()),
        None => String::new(),
    };
    let text = format!(
        r#"
[zenoh]
mode = "peer"
listen = ["tcp/127.0.0.1:{port}"]
[http]
bind = "{http}"
{store}
[[controller]]
id = "c2x3"
period = 1.0
mv = ["u1", "u2", "u3"]
dither = ["ud1", "ud2", "ud3"]
cv = ["y1", "y2"]
pred = ["yhat1", "yhat2"]
residual = "pred"
window = 2048
min_samples = 1024
lag_min = 1
lag_max = 5
surrogates = 40
sigma = 6.0
every = 3.0
raise_after = 2
clear_after = 3
"#,
        port = args.zenoh_port,
        http = args.http,
    );
    Ok(Config::parse(&text, "demo")?)
}

/// Runs the verb.
pub fn run(args: Args) -> anyhow::Result<()> {
    anyhow::ensure!(args.rate.is_finite() && args.rate > 0.0, "--rate must be positive");
    let cfg = config(&args)?;
    super::serve::init_logging();
    let rt = tokio::runtime::Builder::new_multi_thread().enable_all().build().context("tokio runtime")?;
    rt.block_on(demo(args, cfg))
}

async fn demo(args: Args, cfg: Config) -> anyhow::Result<()> {
    let service = Service::start(cfg).await.context("starting the monitor")?;
    let url = format!("http://{}/", service.http_addr);
    println!("mpmwatch demo");
    println!("  status page: {url}   (metrics: {url}metrics)");
    println!(
        "  plant: continuous2x3 under MPC, {} samples/s; at sample {} (after ~{:.0} s) a: 0.2 → 0.8",
        args.rate,
        args.switch_at,
        args.switch_at as f64 / args.rate
    );
    println!("  watch: the alarm must rise on ud1→y1 and ud1→y2 (u1's channels) and on no other channel");

    let mut zc = zenoh::Config::default();
    let set =
        |c: &mut zenoh::Config, k: &str, v: &str| c.insert_json5(k, v).map_err(|e| anyhow::anyhow!("{e}"));
    set(&mut zc, "mode", "\"peer\"")?;
    set(&mut zc, "scouting/multicast/enabled", "false")?;
    set(&mut zc, "listen/endpoints", "[]")?;
    set(&mut zc, "connect/endpoints", &format!("[\"tcp/127.0.0.1:{}\"]", args.zenoh_port))?;
    let plant_session = zenoh::open(zc).await.map_err(|e| anyhow::anyhow!("plant zenoh session: {e}"))?;
    let alarms = plant_session
        .declare_subscriber("mpm/c2x3/alarm")
        .await
        .map_err(|e| anyhow::anyhow!("alarm subscription: {e}"))?;

    let started = Instant::now();
    let switch_wall = Arc::new(std::sync::Mutex::new(None::<Instant>));
    let sw = switch_wall.clone();
    tokio::spawn(async move {
        while let Ok(s) = alarms.recv_async().await {
            let text = s.payload().try_to_string().map(|t| t.to_string()).unwrap_or_default();
            let v: serde_json::Value = serde_json::from_str(&text).unwrap_or_default();
            let since = sw
                .lock()
                .ok()
                .and_then(|g| *g)
                .map(|t| format!(", {:.0} s after the switch", t.elapsed().as_secs_f64()));
            let event = v["event"].as_str().unwrap_or("?");
            let statistic = v["statistic"].as_str().unwrap_or("?");
            // The correlation's value is |r|; every other statistic is MI in bits.
            let unit = if statistic == "ccf" { "" } else { " bits" };
            println!(
                "[{:>5.1} s] ALARM {} on {}: {} {:.4}{unit} {} critical {:.4}{unit}, p = {:.1e}, verdict {}{}",
                started.elapsed().as_secs_f64(),
                event.to_uppercase(),
                v["channel"].as_str().unwrap_or("?"),
                statistic,
                v["value_bits"].as_f64().unwrap_or(f64::NAN),
                if event == "raise" { ">" } else { "vs" },
                v["critical_bits"].as_f64().unwrap_or(f64::NAN),
                v["p_value"].as_f64().unwrap_or(f64::NAN),
                v["verdict"].as_str().unwrap_or("?"),
                since.unwrap_or_default()
            );
        }
    });

    let mut plant = DemoPlant::new(RECORD, args.seed)?;
    let mut tick = tokio::time::interval(Duration::from_secs_f64(1.0 / args.rate));
    let mut last_print = Instant::now();
    let names_u = ["u1", "u2", "u3"];
    let names_d = ["ud1", "ud2", "ud3"];
    let stop = super::serve::shutdown_signal();
    tokio::pin!(stop);
    loop {
        tokio::select! {
            _ = tick.tick() => {}
            _ = &mut stop => break,
        }
        if args.duration > 0.0 && started.elapsed().as_secs_f64() > args.duration {
            break;
        }
        let Some(s) = plant.step()? else {
            println!("the simulated record is used up; still serving (Ctrl-C to stop)");
            (&mut stop).await;
            break;
        };
        if s.k == args.switch_at {
            plant.mismatched = true;
            *switch_wall.lock().unwrap_or_else(|e| e.into_inner()) = Some(Instant::now());
            println!(
                "[{:>5.1} s] sample {}: the plant changes, a: 0.2 → 0.8",
                started.elapsed().as_secs_f64(),
                s.k
            );
        }
        if args.fix_at == Some(s.k) {
            plant.mismatched = false;
            println!(
                "[{:>5.1} s] sample {}: the plant is back to a = 0.2",
                started.elapsed().as_secs_f64(),
                s.k
            );
        }
        let t = s.k as f64;
        let mut puts = Vec::with_capacity(10);
        for i in 0..3 {
            puts.push((format!("mpm/c2x3/mv/{}", names_u[i]), s.u[i]));
            puts.push((format!("mpm/c2x3/dither/{}", names_d[i]), s.ud[i]));
        }
        for j in 0..2 {
            puts.push((format!("mpm/c2x3/cv/y{}", j + 1), s.y[j]));
            puts.push((format!("mpm/c2x3/pred/yhat{}", j + 1), s.yhat[j]));
        }
        for (key, v) in puts {
            if let Err(e) = plant_session.put(&key, payload::encode(t, v)).await {
                eprintln!("publish {key}: {e}");
            }
        }
        if last_print.elapsed() >= Duration::from_secs(5) {
            last_print = Instant::now();
            print_progress(&service, started, s.k, plant.mismatched);
        }
    }
    service.stop().await;
    let _ = plant_session.close().await;
    Ok(())
}

fn print_progress(service: &Service, started: Instant, k: usize, mismatched: bool) {
    let Some(c) = service.shared.lock("c2x3") else { return };
    let run = match &c.latest {
        None => "no run yet".to_string(),
        Some(r) if r.status == RunStatus::Ok => {
            let sig: Vec<String> = r
                .channels
                .iter()
                .filter(|ch| ch.significant)
                .map(|ch| format!("{}→{}", ch.dither, ch.cv))
                .collect();
            format!(
                "last run {:.2} s on {} samples, significant: {}",
                r.duration_s,
                r.n,
                if sig.is_empty() { "none".into() } else { sig.join(", ") }
            )
        }
        Some(r) => format!("last run: {} ({})", r.status.as_str(), r.message.clone().unwrap_or_default()),
    };
    let alarms: Vec<String> = c.active_alarms().into_iter().map(|(d, cv)| format!("{d}→{cv}")).collect();
    println!(
        "[{:>5.1} s] sample {k:>5}, plant a = {}, window {}/{}; {run}; alarms: {}",
        started.elapsed().as_secs_f64(),
        if mismatched { "0.8" } else { "0.2" },
        c.window.len(),
        c.window.capacity(),
        if alarms.is_empty() { "none".into() } else { alarms.join(", ") }
    );
}
