//! Exploration over all casebook scenarios (ignored; run with --ignored --nocapture).

use mpmwatch::diagnose::DiagnoseOptions;
use mpmwatch::sim::scenarios::{casebook_specs, describe, diagnose_record, run};

#[test]
#[ignore]
fn explore() {
    let only = std::env::var("CASE").ok();
    let n: usize = std::env::var("N").ok().and_then(|v| v.parse().ok()).unwrap_or(2000);
    let seed: u64 = std::env::var("SEED").ok().and_then(|v| v.parse().ok()).unwrap_or(100);
    for spec in casebook_specs(n, seed) {
        if only.as_ref().is_some_and(|o| !spec.name.contains(o.as_str())) {
            continue;
        }
        let rec = run(&spec).unwrap();
        let t = std::time::Instant::now();
        let d = diagnose_record(&rec, &DiagnoseOptions::default()).unwrap();
        let f: Vec<String> = d
            .report
            .findings
            .iter()
            .map(|f| {
                format!(
                    "{}→{} {} ({:?}) {:.1}→{:.1}",
                    f.input,
                    f.output,
                    f.physics.name(),
                    f.parameters,
                    f.fit_before_pct,
                    f.fit_after_pct
                )
            })
            .collect();
        let sig: Vec<String> = d
            .report
            .channels
            .iter()
            .map(|c| {
                format!(
                    "{}→{}{}{} p{:.3}/{:.3}{}",
                    c.input,
                    c.output,
                    if c.significant { " MI" } else { "" },
                    if c.ccf_significant { " ccf" } else { "" },
                    c.projection_r2,
                    c.projection_critical,
                    if c.projection_significant { "*" } else { "" }
                )
            })
            .collect();
        eprintln!(
            "{} [{}] ratio {:.2} | sig {:?} | {:?} | holdout {:?}→{:?} | {:.1}s",
            spec.name,
            describe(spec.effect, rec.strength),
            rec.effect_ratio,
            sig,
            f,
            d.report.holdout.fit_before_pct,
            d.report.holdout.fit_after_pct,
            t.elapsed().as_secs_f64()
        );
        if let Some(f) = d.report.findings.first() {
            let tr: Vec<String> = f
                .tried
                .iter()
                .take(5)
                .map(|t| format!("{} {:.1}/{:.2}", t.physics.name(), t.score_vs_null, t.validation_gain_pct))
                .collect();
            eprintln!("    tried {:?}", tr);
        }
    }
}

/// One case's hypotheses in detail: every class's best score against the null (CASE=name).
#[test]
#[ignore]
fn detail() {
    let only = std::env::var("CASE").unwrap_or_else(|_| "c23".into());
    let seed: u64 = std::env::var("SEED").ok().and_then(|v| v.parse().ok()).unwrap_or(100);
    for spec in casebook_specs(3000, seed) {
        if !spec.name.contains(only.as_str()) {
            continue;
        }
        let rec = run(&spec).unwrap();
        let d = diagnose_record(&rec, &DiagnoseOptions::default()).unwrap();
        for f in &d.report.findings {
            eprintln!("{} {}→{} {} {:?}", spec.name, f.input, f.output, f.physics.name(), f.parameters);
            for t in &f.tried {
                eprintln!("    {:<18} {:>9.1} {:>7.2}", t.physics.name(), t.score_vs_null, t.validation_gain_pct);
            }
        }
    }
}

/// The Torricelli calibration on the cascaded tanks (needs ../shared/data).
#[test]
#[ignore]
fn tanks_calibration() {
    let p = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../shared/data/cascaded_tanks/dataBenchmark.csv");
    let text = std::fs::read_to_string(&p).unwrap();
    let mut cols = vec![Vec::new(); 4];
    for l in text.lines().skip(1) {
        for (c, v) in l.split(',').take(4).enumerate() {
            cols[c].push(v.trim().parse::<f64>().unwrap_or(f64::NAN));
        }
    }
    let (ue, uv, ye, yv) = (&cols[0], &cols[1], &cols[2], &cols[3]);
    let run = mpmwatch::diagnose::tanks::overflow_free(ye);
    let m = mpmwatch::diagnose::tanks::calibrate(ue, ye, 4.0);
    let se = m.simulate(ue, 4.0);
    let sv = m.simulate(uv, 4.0);
    let fr = mpmwatch::diagnose::fit_pct(&ye[run.clone()], &m.simulate_from(&ue[run.clone()], 4.0, ye[run.start])[..]);
    eprintln!("run {run:?} model {m:?}");
    eprintln!(
        "FIT on run {fr:.1}, est {:.1}, val {:.1}; min sim est {:.2} val {:.2}",
        mpmwatch::diagnose::fit_pct(ye, &se),
        mpmwatch::diagnose::fit_pct(yv, &sv),
        se.iter().fold(f64::MAX, |a, &b| a.min(b)),
        sv.iter().fold(f64::MAX, |a, &b| a.min(b))
    );
    for k in (0..1024).step_by(64) {
        eprintln!("{k:>5} u {:.2} y {:.2} s {:.2} | val u {:.2} y {:.2} s {:.2}", ue[k], ye[k], se[k], uv[k], yv[k], sv[k]);
    }
}
