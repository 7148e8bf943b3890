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
