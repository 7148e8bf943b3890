//! Exploration over all casebook scenarios (ignored; run with --ignored --nocapture).

use mpmwatch_diagnose::{DiagnoseOptions, Scoring, diagnose_numbered};

/// `SCORING=shifted|projected` picks a closed-loop criterion other than the default.
fn scoring_from_env() -> Scoring {
    match std::env::var("SCORING").as_deref() {
        Ok("shifted") => Scoring::Shifted,
        Ok("projected") => Scoring::Projected,
        _ => Scoring::Prediction,
    }
}
use mpmwatch_sim::scenarios::{casebook_specs, describe, run};

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
        let opts = DiagnoseOptions { scoring: scoring_from_env(), ..Default::default() };
        let d = diagnose_numbered(&rec.u, &rec.d, &rec.y, &rec.s, &opts).unwrap();
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
                .map(|t| {
                    format!(
                        "{} {:.1}/{:.2}",
                        t.physics.name(),
                        t.score_vs_null.unwrap_or(f64::NAN),
                        t.validation_gain_pct
                    )
                })
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
        let opts = DiagnoseOptions { scoring: scoring_from_env(), ..Default::default() };
        let d = diagnose_numbered(&rec.u, &rec.d, &rec.y, &rec.s, &opts).unwrap();
        for f in &d.report.findings {
            eprintln!("{} {}→{} {} {:?}", spec.name, f.input, f.output, f.physics.name(), f.parameters);
            for t in &f.tried {
                eprintln!(
                    "    {:<18} {:>9.1} {:>7.2}",
                    t.physics.name(),
                    t.score_vs_null.unwrap_or(f64::NAN),
                    t.validation_gain_pct
                );
            }
        }
    }
}

/// The cascaded-tanks benchmark's four columns `uEst, uVal, yEst, yVal` (needs ../shared/data);
/// lines with fewer cells (a blank last line) are skipped so the columns stay aligned.
fn read_tanks() -> Vec<Vec<f64>> {
    let p = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../../../shared/data/cascaded_tanks/dataBenchmark.csv");
    let text = std::fs::read_to_string(&p).unwrap();
    let mut cols = vec![Vec::new(); 4];
    for l in text.lines().skip(1).filter(|l| l.split(',').count() >= 4) {
        for (c, v) in l.split(',').take(4).enumerate() {
            cols[c].push(v.trim().parse::<f64>().unwrap_or(f64::NAN));
        }
    }
    cols
}

/// The Torricelli calibration on the cascaded tanks (needs ../shared/data).
#[test]
#[ignore]
fn tanks_calibration() {
    let cols = read_tanks();
    let (ue, uv, ye, yv) = (&cols[0], &cols[1], &cols[2], &cols[3]);
    let run = mpmwatch::tanks::overflow_free_runs(ye, 50).into_iter().max_by_key(|r| r.len()).unwrap();
    eprintln!("runs {:?}", mpmwatch::tanks::overflow_free_runs(ye, 50));
    let m = mpmwatch::tanks::calibrate(ue, ye, 4.0);
    let se = m.simulate_from(ue, 4.0, ye[0]);
    let sv = m.simulate_from(uv, 4.0, yv[0]);
    let fr = mpmwatch_diagnose::fit_pct(
        &ye[run.clone()],
        &m.simulate_from(&ue[run.clone()], 4.0, ye[run.start])[..],
    );
    eprintln!("run {run:?} model {m:?}");
    eprintln!(
        "FIT on run {fr:.1}, est {:.1}, val {:.1}; min sim est {:.2} val {:.2}",
        mpmwatch_diagnose::fit_pct(ye, &se),
        mpmwatch_diagnose::fit_pct(yv, &sv),
        se.iter().fold(f64::MAX, |a, &b| a.min(b)),
        sv.iter().fold(f64::MAX, |a, &b| a.min(b))
    );
    for k in (0..1024).step_by(64) {
        eprintln!(
            "{k:>5} u {:.2} y {:.2} s {:.2} | val u {:.2} y {:.2} s {:.2}",
            ue[k], ye[k], se[k], uv[k], yv[k], sv[k]
        );
    }
}

/// The cascaded tanks' overflow measured outside `diagnose`: the calibrated Torricelli model
/// with its upper tank overflowing at `level`, a fraction `spill` of the overflow reaching the
/// lower tank ([`TwoTanks::simulate_overflowing`]), held-out FIT on the casebook's split (last
/// 45 % of the two records joined) over a grid; and how well the linear nominal that `diagnose`
/// identifies from the simulation reproduces it. Needs ../shared/data.
#[test]
#[ignore]
fn tanks_overflow_physics() {
    use mpmwatch::tanks::Overflow;
    let cols = read_tanks();
    let (ue, uv, ye, yv) = (&cols[0], &cols[1], &cols[2], &cols[3]);
    let m = mpmwatch::tanks::calibrate(ue, ye, 4.0);
    let y: Vec<f64> = ye.iter().chain(yv).copied().collect();
    let u: Vec<f64> = ue.iter().chain(uv).copied().collect();
    let split = y.len() - (0.45 * y.len() as f64).round() as usize;
    let joined = |o: Option<Overflow>| -> (Vec<f64>, Vec<[f64; 2]>) {
        let (mut s, mut h) = m.simulate_overflowing(ue, 4.0, ye[0], o);
        let (s2, h2) = m.simulate_overflowing(uv, 4.0, yv[0], o);
        s.extend(s2);
        h.extend(h2);
        (s, h)
    };
    let (nominal, h) = joined(None);
    let h1: Vec<f64> = h.iter().map(|x| x[0]).collect();
    let q = |p: f64| mpmwatch_core::numerics::quantile(&h1[..split], p);
    let fit = |s: &[f64]| mpmwatch_diagnose::fit_pct(&y[split..], &s[split..]);
    eprintln!(
        "model {m:?} (A1/A2 = k2/k1 = {:.3}); held-out from sample {split}; FIT without overflow {:.1}",
        m.k2 / m.k1,
        fit(&nominal)
    );
    eprintln!(
        "upper level on the training part: median {:.2}, q0.9 {:.2}, q0.99 {:.2}, max {:.2}",
        q(0.5),
        q(0.9),
        q(0.99),
        q(1.0)
    );
    // The upper level's scale is not identifiable (it depends on the calibration), so the rims
    // are fractions of its highest level on the training part.
    for level in [0.5, 0.55, 0.6, 0.65, 0.7, 0.8].map(|f| f * q(1.0)) {
        let row: Vec<String> = [0.0, 0.2, 0.4, 0.6, 0.8, 1.0]
            .iter()
            .map(|&spill| {
                format!("spill {spill}: {:.1}", fit(&joined(Some(Overflow { tank: 0, level, spill })).0))
            })
            .collect();
        eprintln!("upper level {level:>8.2}: {}", row.join("  "));
    }
    let train = 0..split;
    let arx = mpmwatch_diagnose::identify_nominal(&[u.as_slice()], &nominal, train);
    eprintln!("linear nominal identified from the simulation: FIT {:.1} % against it", arx.fit_pct);
}

/// The cascaded tanks diagnosed with the Torricelli model over surrogate seeds 1..=SEEDS
/// (default 20): the state-limit test, the finding and the held-out FIT per seed. The state-limit
/// test uses every shift and no seed (a first version drew 40 random shifts: significant on 17
/// of 20 seeds); the seed still moves the MI matrix. Needs ../shared/data.
#[test]
#[ignore]
fn tanks_state_test_seeds() {
    use mpmwatch_core::detect::Signal;
    use mpmwatch_diagnose::{DiagnoseInput, PhysicalModel};
    let seeds: u64 = std::env::var("SEEDS").ok().and_then(|v| v.parse().ok()).unwrap_or(20);
    let cols = read_tanks();
    let (ue, uv, ye, yv) = (&cols[0], &cols[1], &cols[2], &cols[3]);
    let record = mpmwatch::tanks::benchmark_record(ue, ye, uv, yv);
    let s = record.simulate();
    let y: Vec<f64> = ye.iter().chain(yv).copied().collect();
    let u: Vec<f64> = ue.iter().chain(uv).copied().collect();
    let time: Vec<f64> = (0..u.len()).map(|k| k as f64 * 4.0).collect();
    let mut hits = 0;
    for seed in 1..=seeds {
        let input = DiagnoseInput {
            physical: vec![Some(&record)],
            ..DiagnoseInput::open_loop(
                &time,
                Signal { name: "u", values: &u },
                Signal { name: "y", values: &y },
                &s,
            )
        };
        let opts = mpmwatch::tanks::benchmark_options(&DiagnoseOptions { seed, ..Default::default() });
        let d = mpmwatch_diagnose::diagnose(&input, &opts).unwrap();
        let st = &d.report.states[0];
        hits += usize::from(st.significant);
        eprintln!(
            "seed {seed}: r2 {:.4} critical {:.4} {} | {:?} | held-out {:.1} → {:.1}",
            st.r2,
            st.critical,
            st.significant,
            d.report.findings.first().map(|f| (f.physics.name(), f.parameters.clone())),
            d.report.holdout.fit_before_pct["y"],
            d.report.holdout.fit_after_pct["y"]
        );
    }
    eprintln!("significant on {hits} of {seeds} seeds");
}
