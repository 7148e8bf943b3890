//! Prometheus metrics (text format through `prometheus-client`). The names are the contract of
//! `deploy/grafana/dashboards/mpmwatch.json`; docs/deploy.md lists them.

use std::sync::atomic::AtomicU64;

use prometheus_client::encoding::EncodeLabelSet;
use prometheus_client::metrics::counter::Counter;
use prometheus_client::metrics::family::Family;
use prometheus_client::metrics::gauge::Gauge;
use prometheus_client::registry::Registry;

/// Labels of one controller.
#[derive(Debug, Clone, Hash, PartialEq, Eq, EncodeLabelSet)]
pub struct ControllerLabels {
    /// Controller id.
    pub controller: String,
}

/// Labels of one MV→CV channel.
#[derive(Debug, Clone, Hash, PartialEq, Eq, EncodeLabelSet)]
pub struct ChannelLabels {
    /// Controller id.
    pub controller: String,
    /// MV tag.
    pub mv: String,
    /// Dither tag.
    pub dither: String,
    /// CV tag.
    pub cv: String,
}

/// Labels of a verdict indicator.
#[derive(Debug, Clone, Hash, PartialEq, Eq, EncodeLabelSet)]
pub struct VerdictLabels {
    /// Controller id.
    pub controller: String,
    /// MV tag.
    pub mv: String,
    /// CV tag.
    pub cv: String,
    /// `mismatch`, `clean` or `implicated_by_feedback`.
    pub verdict: String,
}

/// Labels of a dropped-sample counter.
#[derive(Debug, Clone, Hash, PartialEq, Eq, EncodeLabelSet)]
pub struct DropLabels {
    /// Controller id.
    pub controller: String,
    /// Drop reason.
    pub reason: String,
}

/// Labels of a run counter.
#[derive(Debug, Clone, Hash, PartialEq, Eq, EncodeLabelSet)]
pub struct RunLabels {
    /// Controller id.
    pub controller: String,
    /// `ok`, `insufficient_data` or `error`.
    pub status: String,
}

/// Labels of a store error counter.
#[derive(Debug, Clone, Hash, PartialEq, Eq, EncodeLabelSet)]
pub struct StoreLabels {
    /// `flush` (window rows) or `alarm` (alarm history).
    pub op: String,
}

type GaugeF = Gauge<f64, AtomicU64>;

/// Every metric the service exports.
pub struct Metrics {
    registry: Registry,
    /// `mpm_norm_mi_bits`: norm of MI of the last run.
    pub norm_mi: Family<ChannelLabels, GaugeF>,
    /// `mpm_critical_bits`: its surrogate critical value.
    pub critical: Family<ChannelLabels, GaugeF>,
    /// `mpm_significant`: 1 when the channel was significant in the last run.
    pub significant: Family<ChannelLabels, Gauge>,
    /// `mpm_alarm_active`: 1 while the channel's alarm is raised.
    pub alarm: Family<ChannelLabels, Gauge>,
    /// `mpm_verdict`: 1 for the channel's current verdict, 0 for the others.
    pub verdict: Family<VerdictLabels, Gauge>,
    /// `mpm_samples_ingested_total`.
    pub ingested: Family<ControllerLabels, Counter>,
    /// `mpm_samples_dropped_total` by reason.
    pub dropped: Family<DropLabels, Counter>,
    /// `mpm_window_fill_ratio`.
    pub window_fill: Family<ControllerLabels, GaugeF>,
    /// `mpm_window_contiguous_samples`: rows the next run can use.
    pub window_contiguous: Family<ControllerLabels, Gauge>,
    /// `mpm_last_run_duration_seconds`.
    pub run_duration: Family<ControllerLabels, GaugeF>,
    /// `mpm_last_run_timestamp_seconds` (Unix time).
    pub run_time: Family<ControllerLabels, GaugeF>,
    /// `mpm_runs_total` by status.
    pub runs: Family<RunLabels, Counter>,
    /// `mpm_active_alarms`.
    pub active_alarms: Family<ControllerLabels, Gauge>,
    /// `mpm_gap_rows_total`: sample slots missing between window rows.
    pub gap_rows: Family<ControllerLabels, Counter>,
    /// `mpm_time_jumps_total`: confirmed jumps of the source clock.
    pub time_jumps: Family<ControllerLabels, Counter>,
    /// `mpm_backfilled_rows_total`: gaps inside the window filled by back-fill.
    pub backfilled_rows: Family<ControllerLabels, Counter>,
    /// `mpm_overflow_rows_total`: rows closed early because a window of rows was pending.
    pub overflow_rows: Family<ControllerLabels, Counter>,
    /// `mpm_store_errors_total` by operation: failed writes to the store.
    pub store_errors: Family<StoreLabels, Counter>,
    /// `mpm_store_ok`: 1 while the store's last write succeeded (or there is no store), 0 while
    /// it fails.
    pub store_ok: Gauge,
    /// `mpm_ingest_queue_messages`: messages waiting in the controller's ingest queue.
    pub queue_messages: Family<ControllerLabels, Gauge>,
    /// `mpm_ingest_queue_bytes`: their payload bytes.
    pub queue_bytes: Family<ControllerLabels, Gauge>,
    /// `mpm_run_lateness_seconds`: how long after its scheduled instant the last run started.
    pub run_lateness: Family<ControllerLabels, GaugeF>,
    /// `mpm_runs_late_total`: runs that finished after the next scheduled instant (overran
    /// their period). A controller is on schedule while this stays still.
    pub runs_late: Family<ControllerLabels, Counter>,
    /// `mpm_runs_missed_total`: scheduled runs skipped because the previous one was still going.
    pub runs_missed: Family<ControllerLabels, Counter>,
}

impl Default for Metrics {
    fn default() -> Self {
        Self::new()
    }
}

impl Metrics {
    /// Registers every family.
    pub fn new() -> Self {
        let mut registry = Registry::default();
        let m = Self {
            norm_mi: Family::default(),
            critical: Family::default(),
            significant: Family::default(),
            alarm: Family::default(),
            verdict: Family::default(),
            ingested: Family::default(),
            dropped: Family::default(),
            window_fill: Family::default(),
            window_contiguous: Family::default(),
            run_duration: Family::default(),
            run_time: Family::default(),
            runs: Family::default(),
            active_alarms: Family::default(),
            gap_rows: Family::default(),
            time_jumps: Family::default(),
            backfilled_rows: Family::default(),
            overflow_rows: Family::default(),
            store_errors: Family::default(),
            store_ok: Gauge::default(),
            queue_messages: Family::default(),
            queue_bytes: Family::default(),
            run_lateness: Family::default(),
            runs_late: Family::default(),
            runs_missed: Family::default(),
            registry: Registry::default(),
        };
        registry.register(
            "mpm_norm_mi_bits",
            "Norm of MI (eq 19) of dither and residual, bits",
            m.norm_mi.clone(),
        );
        registry.register(
            "mpm_critical_bits",
            "Surrogate critical value mu + z sigma of the norm of MI, bits",
            m.critical.clone(),
        );
        registry.register(
            "mpm_significant",
            "1 when the channel was significant in the last run",
            m.significant.clone(),
        );
        registry.register(
            "mpm_alarm_active",
            "1 while the channel's mismatch alarm is raised",
            m.alarm.clone(),
        );
        registry.register("mpm_verdict", "1 for the channel's current verdict", m.verdict.clone());
        registry.register("mpm_samples_ingested", "Samples accepted onto the grid", m.ingested.clone());
        registry.register("mpm_samples_dropped", "Samples dropped, by reason", m.dropped.clone());
        registry.register(
            "mpm_window_fill_ratio",
            "Rows in the window over its length",
            m.window_fill.clone(),
        );
        registry.register(
            "mpm_window_contiguous_samples",
            "Contiguous rows at the end of the window (what the next run uses)",
            m.window_contiguous.clone(),
        );
        registry.register(
            "mpm_last_run_duration_seconds",
            "Wall time of the last analysis",
            m.run_duration.clone(),
        );
        registry.register(
            "mpm_last_run_timestamp_seconds",
            "Unix time of the last analysis",
            m.run_time.clone(),
        );
        registry.register("mpm_runs", "Analyses by status", m.runs.clone());
        registry.register("mpm_active_alarms", "Channels whose alarm is raised", m.active_alarms.clone());
        registry.register("mpm_gap_rows", "Sample slots missing between window rows", m.gap_rows.clone());
        registry.register("mpm_time_jumps", "Confirmed jumps of the source clock", m.time_jumps.clone());
        registry.register(
            "mpm_backfilled_rows",
            "Gaps inside the window filled by back-filled samples",
            m.backfilled_rows.clone(),
        );
        registry.register(
            "mpm_overflow_rows",
            "Rows closed early because a window of rows was waiting for tags",
            m.overflow_rows.clone(),
        );
        registry.register(
            "mpm_store_errors",
            "Failed writes to the store, by operation",
            m.store_errors.clone(),
        );
        registry.register(
            "mpm_store_ok",
            "1 while the store's last write succeeded (or no store is configured), 0 while it fails",
            m.store_ok.clone(),
        );
        m.store_ok.set(1);
        for op in ["flush", "alarm"] {
            let _ = m.store_errors.get_or_create(&StoreLabels { op: op.into() });
        }
        registry.register(
            "mpm_ingest_queue_messages",
            "Messages waiting in the controller's bounded ingest queue",
            m.queue_messages.clone(),
        );
        registry.register(
            "mpm_ingest_queue_bytes",
            "Payload bytes waiting in the controller's bounded ingest queue",
            m.queue_bytes.clone(),
        );
        registry.register(
            "mpm_run_lateness_seconds",
            "How long after its scheduled instant the last analysis started",
            m.run_lateness.clone(),
        );
        registry.register(
            "mpm_runs_late",
            "Analyses that finished after the next scheduled instant (overran their period)",
            m.runs_late.clone(),
        );
        registry.register(
            "mpm_runs_missed",
            "Scheduled analyses skipped because the previous one was still running",
            m.runs_missed.clone(),
        );
        Self { registry, ..m }
    }

    /// Creates a controller's counters at zero, so every drop reason shows from the start.
    pub fn init(&self, controller: &str) {
        let c = ControllerLabels { controller: controller.to_string() };
        let _ = self.ingested.get_or_create(&c);
        for r in crate::align::DropReason::ALL {
            let _ = self
                .dropped
                .get_or_create(&DropLabels { controller: controller.to_string(), reason: r.as_str().into() });
        }
        let _ = self.active_alarms.get_or_create(&c);
        let _ = self.gap_rows.get_or_create(&c);
        let _ = self.time_jumps.get_or_create(&c);
        let _ = self.backfilled_rows.get_or_create(&c);
        let _ = self.overflow_rows.get_or_create(&c);
        let _ = self.window_fill.get_or_create(&c);
        let _ = self.queue_messages.get_or_create(&c);
        let _ = self.queue_bytes.get_or_create(&c);
        let _ = self.runs_late.get_or_create(&c);
        let _ = self.runs_missed.get_or_create(&c);
    }

    /// The text exposition.
    pub fn encode(&self) -> String {
        let mut s = String::new();
        // Writing to a String cannot fail.
        let _ = prometheus_client::encoding::text::encode(&mut s, &self.registry);
        s
    }
}

#[cfg(test)]
mod tests {
    use std::collections::BTreeSet;

    use super::Metrics;

    /// Every name the exposition can carry: each family's name from its `# TYPE` line (present
    /// even before a run has created its per-channel series) and a counter's `_total` sample.
    fn exported() -> BTreeSet<String> {
        let m = Metrics::new();
        m.init("c1");
        let mut names = BTreeSet::new();
        for line in m.encode().lines() {
            if let Some(rest) = line.strip_prefix("# TYPE ") {
                let mut parts = rest.split_whitespace();
                let (Some(name), Some(kind)) = (parts.next(), parts.next()) else { continue };
                names.insert(name.to_string());
                if kind == "counter" {
                    names.insert(format!("{name}_total"));
                }
            }
        }
        names
    }

    /// The `mpm_…` identifiers in a query or rule text.
    fn referenced(text: &str) -> BTreeSet<String> {
        let mut out = BTreeSet::new();
        let mut rest = text;
        while let Some(k) = rest.find("mpm_") {
            let tail = &rest[k..];
            let end = tail.find(|c: char| !(c.is_ascii_alphanumeric() || c == '_')).unwrap_or(tail.len());
            out.insert(tail[..end].to_string());
            rest = &tail[end..];
        }
        out
    }

    fn collect_exprs(v: &serde_json::Value, out: &mut Vec<String>) {
        match v {
            serde_json::Value::Object(map) => {
                for (k, x) in map {
                    match (k.as_str(), x) {
                        ("expr" | "query", serde_json::Value::String(s)) => out.push(s.clone()),
                        _ => collect_exprs(x, out),
                    }
                }
            }
            serde_json::Value::Array(a) => a.iter().for_each(|x| collect_exprs(x, out)),
            _ => {}
        }
    }

    #[test]
    fn the_dashboard_and_the_alert_rules_query_only_exported_metrics() {
        let dashboard: serde_json::Value =
            serde_json::from_str(include_str!("../../../deploy/grafana/dashboards/mpmwatch.json")).unwrap();
        let mut exprs = Vec::new();
        collect_exprs(&dashboard, &mut exprs);
        exprs.push(include_str!("../../../deploy/prometheus.yml").to_string());
        let used: BTreeSet<String> = exprs.iter().flat_map(|e| referenced(e)).collect();
        let exported = exported();
        // A dashboard whose queries named no metric would pass the check below vacuously.
        assert!(used.len() >= 8, "only {used:?} found in the dashboard's queries");
        let unknown: Vec<&String> = used.iter().filter(|n| !exported.contains(*n)).collect();
        assert!(unknown.is_empty(), "queried but not exported: {unknown:?}; exported: {exported:?}");
    }

    #[test]
    fn the_dashboard_is_provisionable() {
        let d: serde_json::Value =
            serde_json::from_str(include_str!("../../../deploy/grafana/dashboards/mpmwatch.json")).unwrap();
        assert_eq!(d["uid"], "mpmwatch");
        let vars = d["templating"]["list"].as_array().unwrap();
        let ds = vars.iter().find(|v| v["name"] == "datasource").expect("a datasource variable");
        assert_eq!(ds["type"], "datasource");
        assert_eq!(ds["query"], "prometheus");
        // The variable defaults to the provisioned source's pinned uid.
        let source = include_str!("../../../deploy/grafana/provisioning/datasources/prometheus.yml");
        let uid = ds["current"]["value"].as_str().unwrap();
        assert!(source.contains(&format!("uid: {uid}")), "{uid} is not the provisioned data source");
        let provider = include_str!("../../../deploy/grafana/provisioning/dashboards/mpmwatch.yml");
        assert!(provider.contains("type: file") && provider.contains("path: "));
        // Every panel and query takes its source from the variable, none from a fixed uid.
        let panels = d["panels"].as_array().unwrap();
        assert!(!panels.is_empty());
        for p in panels {
            let title = &p["title"];
            if p.get("targets").is_some() {
                assert_eq!(p["datasource"]["uid"], "${datasource}", "panel {title}");
                for t in p["targets"].as_array().unwrap() {
                    if let Some(ds) = t.get("datasource") {
                        assert_eq!(ds["uid"], "${datasource}", "a target of panel {title}");
                    }
                }
            }
        }
    }
}
