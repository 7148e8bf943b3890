//! The load generator behind `mpmwatch loadgen`: N synthetic controllers publishing over zenoh
//! with the keys and payloads of DESIGN.md §4.3, at a given rate, one sample or a batch per
//! message, for a given time; it counts what it sent so a run can be checked against the
//! monitor's `mpm_samples_ingested_total` and `mpm_samples_dropped_total`.
//!
//! Each controller is an `mvs × cvs` loop whose signals give the monitor real work: dithers are
//! maximal-length PRBS (±1, one feedback polynomial per MV), the predictions are smooth, and the
//! residual `e = cv − pred` is noise plus, when `mismatch` is not zero, `mismatch · ud1(t−1)` in
//! `y1` only: the monitor should flag `ud1→y1` and nothing else.
//!
//! Publishers use congestion control `Block` by default, so zenoh never drops silently on the
//! way: every sample sent reaches the monitor, which ingests it or counts why it dropped it.

use std::time::{Duration, Instant};

use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use serde::Serialize;
use zenoh::qos::CongestionControl;

use mpmwatch_sim::Lfsr;

/// PRBS register order: period 32 767 samples, far beyond any window, so a window never holds a
/// repeated dither (circular-shift surrogates would otherwise find exact copies).
const PRBS_ORDER: u32 = 15;

/// A load generator failure.
#[derive(Debug, thiserror::Error)]
pub enum LoadgenError {
    /// Options that cannot work.
    #[error("loadgen: {0}")]
    Options(String),
    /// Zenoh said no.
    #[error("zenoh: {0}")]
    Zenoh(String),
}

/// What to publish.
#[derive(Debug, Clone)]
pub struct LoadgenOptions {
    /// Key prefix (`<prefix>/<controller>/<role>/<tag>`).
    pub prefix: String,
    /// Number of controllers.
    pub controllers: usize,
    /// Controller ids are `<id_prefix><index>`, index zero-padded to three digits.
    pub id_prefix: String,
    /// Index of the first controller (to split one plant over several generators).
    pub first: usize,
    /// MVs (and dithers) per controller.
    pub mvs: usize,
    /// CVs (and predictions) per controller.
    pub cvs: usize,
    /// Publish `pred/<tag>` (residual = "pred"); without it only MVs, dithers and CVs.
    pub pred: bool,
    /// Rows per second per controller (one sample of every tag per row); 0 = as fast as
    /// possible.
    pub rate: f64,
    /// Samples per message: 1 sends `{"t": .., "v": ..}`, more sends `{"t": [..], "v": [..]}`.
    pub batch: usize,
    /// How long to publish.
    pub duration: Duration,
    /// Gain of `ud1(t−1)` in the residual of `y1`.
    pub mismatch: f64,
    /// Seed of the noise and of the PRBS initial states.
    pub seed: u64,
    /// Sample period of the source times, seconds (times are `t0 + k·period`).
    pub period: f64,
    /// Source time of the first row.
    pub t0: f64,
    /// Block (default: nothing is lost on the way) or drop when zenoh's queues are full.
    pub block: bool,
    /// Longest wait for every key to have a subscriber before publishing.
    pub wait_subscribers: Duration,
}

impl Default for LoadgenOptions {
    fn default() -> Self {
        Self {
            prefix: "mpm".into(),
            controllers: 1,
            id_prefix: "lg".into(),
            first: 0,
            mvs: 3,
            cvs: 3,
            pred: true,
            rate: 100.0,
            batch: 100,
            duration: Duration::from_secs(10),
            mismatch: 0.5,
            seed: 1,
            period: 1.0,
            t0: 0.0,
            block: true,
            wait_subscribers: Duration::from_secs(10),
        }
    }
}

/// What was sent.
#[derive(Debug, Clone, Serialize)]
pub struct LoadgenReport {
    /// Controllers.
    pub controllers: usize,
    /// Tags per controller.
    pub tags_per_controller: usize,
    /// Samples per message.
    pub batch: usize,
    /// Target rows per second per controller (0 = unpaced).
    pub rate_target: f64,
    /// Target samples per second over all controllers (0 = unpaced).
    pub samples_per_s_target: f64,
    /// Messages put.
    pub messages: u64,
    /// Samples in them.
    pub samples: u64,
    /// Rows per controller (every tag got this many samples).
    pub rows_per_controller: u64,
    /// Puts zenoh refused (not counted in `messages` or `samples`).
    pub put_errors: u64,
    /// Keys that still had no subscriber when publishing started.
    pub unmatched_keys: usize,
    /// Seconds spent publishing.
    pub elapsed_s: f64,
    /// Samples per second achieved.
    pub samples_per_s: f64,
    /// Messages per second achieved.
    pub messages_per_s: f64,
}

impl LoadgenOptions {
    /// The id of controller `i` (counting from `first`).
    pub fn id(&self, i: usize) -> String {
        format!("{}{:03}", self.id_prefix, self.first + i)
    }

    /// Tag leaves `<role>/<tag>` of one controller, in publishing order.
    pub fn leaves(&self) -> Vec<String> {
        let mut v = Vec::new();
        for i in 1..=self.mvs {
            v.push(format!("mv/u{i}"));
        }
        for i in 1..=self.mvs {
            v.push(format!("dither/ud{i}"));
        }
        for j in 1..=self.cvs {
            v.push(format!("cv/y{j}"));
        }
        if self.pred {
            for j in 1..=self.cvs {
                v.push(format!("pred/p{j}"));
            }
        }
        v
    }

    /// `[[controller]]` tables that match what this generator publishes; `extra` is appended to
    /// each (window, lags, every, ...). Tags arrive one batch after another; the monitor's
    /// default alignment (per-tag watermarks) waits for the last tag, so nothing is tuned to the
    /// batch. Without `pred` the residual needs a model, which the synthetic loop has not: such
    /// a config is refused by the monitor.
    pub fn controller_toml(&self, extra: &str) -> String {
        let list = |p: &str, n: usize| (1..=n).map(|i| format!("\"{p}{i}\"")).collect::<Vec<_>>().join(", ");
        let mut s = String::new();
        for i in 0..self.controllers {
            s.push_str(&format!(
                "[[controller]]\nid = \"{}\"\nperiod = {}\nmv = [{}]\ndither = [{}]\ncv = [{}]\npred = [{}]\n{extra}\n\n",
                self.id(i),
                self.period,
                list("u", self.mvs),
                list("ud", self.mvs),
                list("y", self.cvs),
                if self.pred { list("p", self.cvs) } else { String::new() },
            ));
        }
        s
    }

    /// Refuses options that cannot work, before any session is opened.
    pub fn check(&self) -> Result<(), LoadgenError> {
        let bad = |m: &str| Err(LoadgenError::Options(m.into()));
        if self.controllers == 0 || self.mvs == 0 || self.cvs == 0 {
            return bad("controllers, MVs and CVs must be at least 1");
        }
        if self.batch == 0 || self.batch > 100_000 {
            return bad("batch must lie in 1..=100000");
        }
        if !(self.rate.is_finite() && self.rate >= 0.0) {
            return bad("rate must be a finite number ≥ 0 (0 = as fast as possible)");
        }
        if !(self.period.is_finite() && self.period > 0.0 && self.t0.is_finite()) {
            return bad("period must be positive and t0 finite");
        }
        Ok(())
    }
}

/// One synthetic controller: its signals, one row at a time.
struct Synth {
    dither: Vec<Lfsr>,
    prev_ud1: f64,
    rng: ChaCha8Rng,
    k: u64,
    mvs: usize,
    cvs: usize,
    pred: bool,
    mismatch: f64,
}

impl Synth {
    fn new(o: &LoadgenOptions, index: usize) -> Result<Self, LoadgenError> {
        let mut rng = ChaCha8Rng::seed_from_u64(o.seed.wrapping_add(index as u64 * 7919));
        let dither = (0..o.mvs)
            .map(|i| Lfsr::with_polynomial(PRBS_ORDER, i % 4, rng.random::<u32>()))
            .collect::<Result<Vec<_>, _>>()
            .map_err(|e| LoadgenError::Options(e.to_string()))?;
        Ok(Self {
            dither,
            prev_ud1: 0.0,
            rng,
            k: 0,
            mvs: o.mvs,
            cvs: o.cvs,
            pred: o.pred,
            mismatch: o.mismatch,
        })
    }

    /// The next row's values, in the order of [`LoadgenOptions::leaves`].
    fn row(&mut self, out: &mut Vec<f64>) {
        out.clear();
        let k = self.k as f64;
        let ud: Vec<f64> = self.dither.iter_mut().map(|l| if l.next_bit() { 1.0 } else { -1.0 }).collect();
        for (i, d) in ud.iter().enumerate() {
            out.push((k * 0.01 + i as f64).sin() + d); // uc + ud
        }
        out.extend(&ud);
        let preds: Vec<f64> = (0..self.cvs).map(|j| (k * 0.003 + j as f64).cos() * 2.0).collect();
        for (j, p) in preds.iter().enumerate() {
            let mut e = 0.3 * (self.rng.random::<f64>() - 0.5);
            if j == 0 {
                e += self.mismatch * self.prev_ud1;
            }
            out.push(p + e);
        }
        if self.pred {
            out.extend(&preds);
        }
        debug_assert_eq!(out.len(), 2 * self.mvs + if self.pred { 2 } else { 1 } * self.cvs);
        self.prev_ud1 = ud[0];
        self.k += 1;
    }
}

#[derive(Serialize)]
struct Batch<'a> {
    t: &'a [f64],
    v: &'a [f64],
}

#[derive(Serialize)]
struct Single {
    t: f64,
    v: f64,
}

/// The payload of `t`/`v` (a single sample when one, else a batch), DESIGN.md §4.3.
pub fn payload(t: &[f64], v: &[f64]) -> String {
    if t.len() == 1 {
        serde_json::to_string(&Single { t: t[0], v: v[0] }).unwrap_or_default()
    } else {
        serde_json::to_string(&Batch { t, v }).unwrap_or_default()
    }
}

/// Publishes on `session` as `opts` says, and reports what it sent.
pub async fn run(session: &zenoh::Session, opts: &LoadgenOptions) -> Result<LoadgenReport, LoadgenError> {
    opts.check()?;
    let leaves = opts.leaves();
    let cc = if opts.block { CongestionControl::Block } else { CongestionControl::Drop };
    let mut pubs = Vec::with_capacity(opts.controllers);
    for i in 0..opts.controllers {
        let mut row = Vec::with_capacity(leaves.len());
        for leaf in &leaves {
            let key = format!("{}/{}/{leaf}", opts.prefix, opts.id(i));
            let p = session
                .declare_publisher(key.clone())
                .congestion_control(cc)
                .await
                .map_err(|e| LoadgenError::Zenoh(format!("publisher {key}: {e}")))?;
            row.push(p);
        }
        pubs.push(row);
    }
    let mut synths =
        (0..opts.controllers).map(|i| Synth::new(opts, opts.first + i)).collect::<Result<Vec<_>, _>>()?;

    // Wait until every key has a subscriber: earlier puts would go nowhere, uncounted.
    let deadline = Instant::now() + opts.wait_subscribers;
    let mut unmatched = usize::MAX;
    while unmatched > 0 {
        unmatched = 0;
        for p in pubs.iter().flatten() {
            if !p.matching_status().await.is_ok_and(|m| m.matching()) {
                unmatched += 1;
            }
        }
        if unmatched == 0 || Instant::now() >= deadline {
            break;
        }
        tokio::time::sleep(Duration::from_millis(100)).await;
    }

    let (mut messages, mut samples, mut errors, mut rows) = (0u64, 0u64, 0u64, 0u64);
    let width = leaves.len();
    let mut cols: Vec<Vec<f64>> = vec![Vec::with_capacity(opts.batch); width];
    let mut times = Vec::with_capacity(opts.batch);
    let mut row = Vec::with_capacity(width);
    let start = Instant::now();
    while start.elapsed() < opts.duration {
        if opts.rate > 0.0 {
            // The round that ends at `rows + batch` rows is due at that many rows / rate.
            let due = start + Duration::from_secs_f64((rows + opts.batch as u64) as f64 / opts.rate);
            if due > start + opts.duration {
                break;
            }
            tokio::time::sleep_until(due.into()).await;
        }
        times.clear();
        times.extend((0..opts.batch).map(|b| opts.t0 + (rows + b as u64) as f64 * opts.period));
        for (synth, ctl_pubs) in synths.iter_mut().zip(&pubs) {
            cols.iter_mut().for_each(Vec::clear);
            for _ in 0..opts.batch {
                synth.row(&mut row);
                for (c, v) in cols.iter_mut().zip(&row) {
                    c.push(*v);
                }
            }
            // Tags interleaved per batch: a row waits at most one batch for its last tag.
            for (p, c) in ctl_pubs.iter().zip(&cols) {
                match p.put(payload(&times, c)).await {
                    Ok(()) => {
                        messages += 1;
                        samples += opts.batch as u64;
                    }
                    Err(_) => errors += 1,
                }
            }
        }
        rows += opts.batch as u64;
    }
    let elapsed = start.elapsed().as_secs_f64();
    let total_tags = (opts.controllers * width) as f64;
    Ok(LoadgenReport {
        controllers: opts.controllers,
        tags_per_controller: width,
        batch: opts.batch,
        rate_target: opts.rate,
        samples_per_s_target: opts.rate * total_tags,
        messages,
        samples,
        rows_per_controller: rows,
        put_errors: errors,
        unmatched_keys: unmatched,
        elapsed_s: elapsed,
        samples_per_s: samples as f64 / elapsed.max(1e-9),
        messages_per_s: messages as f64 / elapsed.max(1e-9),
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use mpmwatch_service::config::Config;
    use mpmwatch_service::payload::decode;

    #[test]
    fn payloads_decode_as_the_monitor_reads_them() {
        assert_eq!(decode(payload(&[1.0], &[-0.5]).as_bytes()).unwrap().len(), 1);
        let b = decode(payload(&[1.0, 2.0, 3.0], &[0.5, 0.25, 1e-300]).as_bytes()).unwrap();
        assert_eq!(b.len(), 3);
        assert_eq!(b[2].v, 1e-300);
    }

    #[test]
    fn the_printed_config_matches_the_published_tags() {
        let o = LoadgenOptions { controllers: 2, ..LoadgenOptions::default() };
        let c = Config::parse(&o.controller_toml("window = 64\nmin_samples = 40"), "t").unwrap();
        assert_eq!(c.controllers.len(), 2);
        assert_eq!(c.controllers[1].id, "lg001");
        assert_eq!(o.leaves().len(), 12);
        assert!(o.leaves().contains(&"pred/p3".to_string()));
    }

    #[test]
    fn the_synthetic_loop_has_binary_dithers_and_the_planted_mismatch() {
        let o = LoadgenOptions { mismatch: 1.0, ..LoadgenOptions::default() };
        let mut s = Synth::new(&o, 0).unwrap();
        let mut row = Vec::new();
        let (mut prev, mut corr, mut ones) = (0.0, 0.0, 0);
        for _ in 0..1000 {
            s.row(&mut row);
            assert!(row[3].abs() == 1.0);
            ones += usize::from(row[3] > 0.0);
            let e1 = row[6] - row[9];
            corr += e1 * prev;
            prev = row[3];
        }
        assert!((400..600).contains(&ones), "{ones}");
        assert!(corr / 1000.0 > 0.8, "{corr}");
    }
}
