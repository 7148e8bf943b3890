//! Concealed closed-loop cases, the casebook's (`mpmwatch_sim::scenarios::casebook_specs`) or
//! `WIDE=count` drawn by `wide_specs`, with the grey-box structures explaining the outputs the
//! dithers flag (`GREYBOX=1`) or the residual corrections (default). Ignored; `SEED=100
//! cargo test -p mpmwatch-diagnose --test it closed_loop_study -- --ignored --nocapture` prints
//! one line per case (with the held-out FIT of the true plant driven by the recorded MVs, what
//! a right finding would show: under feedback it can lie below the nominal's) and the rates,
//! split by whether the true plant raises the held-out FIT by the closed-loop margin; a draw
//! whose loop runs away is left out (`VERBOSE=1` adds each case's draw, the locating statistics
//! of its changed channel (MI and cross-correlation; not the dither-projection test) and every
//! finding's candidates; `GATE=a,b` sets the honesty gate's two margins, in points:
//! `min_gain_pct` and `closed_loop_min_gain_pct`; `BOTH_WAYS=1` also draws gain drops, faster
//! responses and shorter delays, `wide::Directions::Both`, and ends such a line with the true
//! change; `CASE=a,b` keeps the cases whose name contains one of them).

use mpmwatch_diagnose::{DiagnoseOptions, Method, Physics, diagnose_numbered, fit_pct};
use mpmwatch_sim::SimError;
use mpmwatch_sim::scenarios::{Directions, casebook_specs, run, wide_specs};

/// `GATE=a,b`: the honesty gate's `min_gain_pct` (here the small, consistent gain's margin
/// with the class lead) and `closed_loop_min_gain_pct`, in points.
fn gate() -> Option<(f64, f64)> {
    let v = std::env::var("GATE").ok()?;
    let parse = |x: &str| x.trim().parse::<f64>().unwrap_or_else(|_| panic!("GATE=a,b in points, not {v}"));
    let (a, b) = v.split_once(',').unwrap_or_else(|| panic!("GATE=a,b in points, not {v}"));
    Some((parse(a), parse(b)))
}

#[test]
#[ignore]
fn closed_loop_study() {
    let seed: u64 = std::env::var("SEED").ok().and_then(|v| v.parse().ok()).unwrap_or(100);
    let n: usize = std::env::var("N").ok().and_then(|v| v.parse().ok()).unwrap_or(3000);
    let greybox = std::env::var_os("GREYBOX").is_some();
    let only: Option<Vec<String>> =
        std::env::var("CASE").ok().map(|v| v.split(',').map(str::to_string).collect());
    // PAPER=1: localise with the paper's 6σ rule (the default until stop 32); ALPHA=a: the
    // family rule's false-alarm rate per record.
    let defaults = DiagnoseOptions::default();
    let opts = DiagnoseOptions {
        greybox_closed_loop: greybox,
        locate: if std::env::var_os("PAPER").is_some() { Method::Paper } else { defaults.locate },
        alpha: std::env::var("ALPHA").ok().and_then(|v| v.parse().ok()).unwrap_or(defaults.alpha),
        // GATE=a,b: the honesty gate's two margins, in points.
        min_gain_pct: gate().map_or(defaults.min_gain_pct, |g| g.0),
        closed_loop_min_gain_pct: gate().map_or(defaults.closed_loop_min_gain_pct, |g| g.1),
        ..defaults
    };
    let (mut named, mut chan, mut total, mut alarms, mut nulls, mut fell) = (0, 0, 0, 0, 0, 0);
    // Mismatch cases named right / counted, split by whether the true plant raises the
    // held-out FIT by the closed-loop gate's margin (under feedback it may not).
    let (mut winnable, mut unwinnable) = ((0, 0), (0, 0));
    // The same, for the cases whose effect stayed under a tenth of the disturbance's variance
    // (a bounded strength, a time constant at most 3.94 times the model's or a dead time at
    // most 6 samples longer, may not reach the drawn ratio of 0.1–0.8).
    let mut weak = (0, 0);
    let wide: Option<usize> = std::env::var("WIDE").ok().and_then(|v| v.parse().ok());
    let verbose = std::env::var_os("VERBOSE").is_some();
    let directions = if std::env::var_os("BOTH_WAYS").is_some() { Directions::Both } else { Directions::Up };
    let specs = match wide {
        Some(count) => wide_specs(count, n, seed, directions),
        None => casebook_specs(n, seed),
    };
    for spec in specs {
        if only.as_ref().is_some_and(|o| !o.iter().any(|o| spec.name.contains(o.as_str()))) {
            continue;
        }
        // A draw whose loop runs away at every strength is no case (`scenarios::run`).
        let rec = match run(&spec) {
            Ok(rec) => rec,
            Err(e @ SimError::Runaway { .. }) => {
                eprintln!("{:<28} skipped: {e}", spec.name);
                continue;
            }
            Err(e) => panic!("{}: {e}", spec.name),
        };
        if verbose {
            eprintln!(
                "  {:?} ratio {:.2} strength {:.3} draw {:?}",
                spec.channel, rec.effect_ratio, rec.strength, spec.plant
            );
        }
        let d = diagnose_numbered(&rec.u, &rec.d, &rec.y, &rec.s, &opts).unwrap();
        let (ci, cj) = spec.channel;
        let (tin, tout) = (format!("u{}", ci + 1), format!("y{}", cj + 1));
        let f = d
            .report
            .findings
            .iter()
            .find(|f| f.physics != Physics::Unexplained)
            .or(d.report.findings.first());
        let right_channel = f.is_some_and(|f| f.input == tin && f.output == tout);
        let right = f.is_some_and(|f| f.physics.name() == spec.effect.physics()) && right_channel;
        let (fb, fa) = (d.report.holdout.fit_before_pct[&tout], d.report.holdout.fit_after_pct[&tout]);
        if spec.effect.is_mismatch() {
            total += 1;
            named += usize::from(right);
            chan += usize::from(right_channel);
        } else {
            nulls += 1;
            alarms += usize::from(!d.report.findings.is_empty());
        }
        if verbose {
            for c in d.report.channels.iter().filter(|c| c.input == tin && c.output == tout) {
                eprintln!(
                    "    locate {}→{}: MI {:.4} bits, limit {:.4}, {}, cross-correlation {}, projection R² {:.4}, limit {:.4}",
                    c.input,
                    c.output,
                    c.norm_mi_bits,
                    c.threshold_bits,
                    c.verdict,
                    c.ccf_significant,
                    c.projection_r2,
                    c.projection_critical
                );
            }
            // `cv` counts the tested residuals, which the matrix names.
            for (m, c) in d
                .matrix
                .iter()
                .flat_map(|m| m.cells.iter().map(move |c| (m, c)))
                .filter(|(_, c)| c.significant)
            {
                eprintln!(
                    "    decided u{}→{}: {:?} at lag {:?}, p {:.2e} at alpha {:?}, value {:.4} against {:.4}",
                    c.mv + 1,
                    m.residuals[c.cv],
                    c.decision.evidence,
                    c.decision.lag,
                    c.decision.p_value,
                    c.decision.alpha,
                    c.decision.value,
                    c.decision.critical
                );
            }
            for g in &d.report.findings {
                eprintln!("    {}", g.summary);
                for t in &g.tried {
                    eprintln!(
                        "    {}→{} tried {:<16} score−null {:>9.1} validation gain {:6.2}",
                        g.input,
                        g.output,
                        t.physics.name(),
                        t.score_vs_null.unwrap_or(f64::NAN),
                        t.validation_gain_pct
                    );
                }
            }
        }
        // What the true plant does to the held-out FIT: what a right finding would show.
        let tail = d.report.holdout.start_index..rec.y[cj].len();
        let truth = fit_pct(&rec.y[cj][tail.clone()], &rec.plant_output[cj][tail]);
        if spec.effect.is_mismatch() {
            let by =
                if truth - fb >= opts.closed_loop_min_gain_pct { &mut winnable } else { &mut unwinnable };
            by.0 += usize::from(right);
            by.1 += 1;
            if rec.effect_ratio < 0.1 {
                weak.0 += usize::from(right);
                weak.1 += 1;
            }
        }
        let reported = f.is_some_and(|f| f.physics != Physics::Unexplained);
        fell += usize::from(reported && fa < fb);
        eprintln!(
            "{:<28} {:<16} named {:<16} on {:<8} {} held-out {:6.1} → {:6.1} (the true plant {:6.1}; effect ratio {:.3}){}",
            spec.name,
            spec.effect.physics(),
            f.map_or("none", |f| f.physics.name()),
            f.map_or("none".into(), |f| format!("{}→{}", f.input, f.output)),
            if !spec.effect.is_mismatch() {
                if d.report.findings.is_empty() { "ok" } else { "NO" }
            } else if right {
                "ok"
            } else {
                "NO"
            },
            fb,
            fa,
            truth,
            rec.effect_ratio,
            if spec.decrease { format!("; {}", spec.describe(rec.strength)) } else { String::new() }
        );
    }
    eprintln!(
        "greybox {greybox} seed {seed}: physics {named}/{total}, channel {chan}/{total}, null cases with findings {alarms}/{nulls}, reported findings whose held-out FIT fell {fell}"
    );
    eprintln!(
        "  where the true plant raises the held-out FIT by at least {} points: physics {}/{}; elsewhere {}/{}",
        opts.closed_loop_min_gain_pct, winnable.0, winnable.1, unwinnable.0, unwinnable.1
    );
    eprintln!(
        "  whose effect stayed under a tenth of the disturbance's variance: physics {}/{}",
        weak.0, weak.1
    );
}
