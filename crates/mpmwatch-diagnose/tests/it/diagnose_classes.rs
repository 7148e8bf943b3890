//! Each vocabulary class is recovered (right channel, right physics) on a seeded concealed
//! closed-loop case of the casebook (3000 samples, seeds 100 + k, the effect's residual variance
//! 0.1–0.8 of the disturbance's), with the default options (closed-loop hypotheses scored by
//! prediction error). Every class has a test (the cubic on an input from the wide generator, since
//! the casebook's is withheld by the honesty gate); the casebook reports the cases not named here.

use mpmwatch_diagnose::{DiagnoseOptions, Physics, diagnose_numbered};
use mpmwatch_sim::scenarios::{Directions, casebook_specs, run, wide_specs};

fn recovers(case: &str) {
    let spec =
        casebook_specs(3000, 100).into_iter().find(|s| s.name.starts_with(case)).expect("casebook case");
    let rec = run(&spec).unwrap();
    assert!((0.1..=0.8).contains(&rec.effect_ratio), "{case} not concealed: ratio {}", rec.effect_ratio);
    let d = diagnose_numbered(&rec.u, &rec.d, &rec.y, &rec.s, &DiagnoseOptions::default()).unwrap();
    let want = (format!("u{}", spec.channel.0 + 1), format!("y{}", spec.channel.1 + 1));
    let f = d.report.findings.iter().find(|f| (f.input.clone(), f.output.clone()) == want);
    let f = f.unwrap_or_else(|| panic!("{case}: no finding on {want:?}: {:?}", d.report.findings));
    assert_eq!(f.physics.name(), spec.effect.physics(), "{case}: {}", f.summary);
}

/// The 2×2 case: on the SISO one (c01) the gain correction raises the held-out FIT (44.1 →
/// 46.0) but lowers the FIT on one block of the training part by 3.3 points, so the gate
/// withholds it.
#[test]
fn gain() {
    recovers("c02_");
}

#[test]
fn time_constant() {
    recovers("c03_");
}

#[test]
fn dead_time() {
    recovers("c05_");
}

#[test]
fn missing_coupling() {
    recovers("c07_");
}

/// The 2×2 case: the SISO one (c09) is named backlash, play of the same total width.
#[test]
fn dead_zone() {
    recovers("c10_");
}

#[test]
fn saturation() {
    recovers("c11_");
}

#[test]
fn quadratic() {
    recovers("c13_");
}

/// A cubic on the input, from the wide generator's report set (w9047: a drawn 1×1 loop, its
/// effect 0.1–0.8 of the disturbance): named, on its channel, and the held-out FIT rises.
#[test]
fn cubic() {
    let spec = wide_specs(48, 3000, 9000, Directions::Up).pop().expect("48 cases");
    assert!(spec.name.starts_with("w9047_cubic"), "{}", spec.name);
    let rec = run(&spec).unwrap();
    let d = diagnose_numbered(&rec.u, &rec.d, &rec.y, &rec.s, &DiagnoseOptions::default()).unwrap();
    let f = d.report.findings.iter().find(|f| (f.input.as_str(), f.output.as_str()) == ("u1", "y1"));
    let f = f.unwrap_or_else(|| panic!("no finding on u1→y1: {:?}", d.report.findings));
    assert_eq!(f.physics, Physics::Cubic, "{}", f.summary);
    let h = &d.report.holdout;
    assert!(
        h.fit_after_pct["y1"] > h.fit_before_pct["y1"],
        "held-out FIT {:?} → {:?}",
        h.fit_before_pct,
        h.fit_after_pct
    );
}

/// The casebook's one cubic on an input (c15) is ranked first, but its correction lowers the
/// held-out FIT (41.5 → 38.7); on the training part's blocks it gains 0.06 points on average and
/// loses 4.0 on one, so the honesty gate withholds it: `unexplained`, naming cubic as the best
/// candidate, and no correction.
#[test]
fn cubic_is_withheld_when_it_does_not_improve_out_of_sample() {
    let spec =
        casebook_specs(3000, 100).into_iter().find(|s| s.name.starts_with("c15_")).expect("casebook case");
    let rec = run(&spec).unwrap();
    let d = diagnose_numbered(&rec.u, &rec.d, &rec.y, &rec.s, &DiagnoseOptions::default()).unwrap();
    let f = d.report.findings.iter().find(|f| f.output == "y1").expect("a finding on y1");
    assert_eq!(f.physics, Physics::Unexplained, "{}", f.summary);
    assert!(f.summary.contains("best-scored candidate, cubic"), "{}", f.summary);
    assert_eq!(d.corrected[0], rec.s[0], "a withheld finding leaves the simulation as it was");
}

#[test]
fn bilinear() {
    recovers("c17_");
}

#[test]
fn backlash() {
    recovers("c19_");
}

/// The 2×2 case: flagged by the dither-projection test only (the MI matrix flags nothing).
#[test]
fn coulomb_friction() {
    recovers("c22_");
}

/// A hardening spring fed back from the output: flagged by the dither-projection test only.
#[test]
fn cubic_output_spring() {
    recovers("c16_");
}

/// A 3×3 input limit: flagged by the dither-projection test only.
#[test]
fn saturation_mimo() {
    recovers("c12_");
}

/// Needs the prediction-error scoring: the sensor's effect in the residual depends on the
/// disturbance-driven part of the output, which the shifted scoring scrambled (it named backlash).
#[test]
fn abs_sensor() {
    recovers("c23_");
}

/// The SISO friction case, with a binary dither (the shifted scoring named it cubic).
#[test]
fn coulomb_friction_siso() {
    recovers("c21_");
}

/// The closed-loop path in other units: the 2×2 dead zone (c10) with its inputs and dithers a
/// million times smaller and its outputs a million times larger (gains of 1e12). The findings
/// keep their channels and classes; the held-out FITs (ratios) move by less than 0.01 points,
/// a chosen bound as in `physical_cases::the_diagnosis_does_not_depend_on_the_units`.
#[test]
fn the_closed_loop_diagnosis_does_not_depend_on_the_units() {
    let spec = casebook_specs(3000, 100).into_iter().find(|s| s.name.starts_with("c10_")).expect("c10");
    let rec = run(&spec).unwrap();
    let opts = DiagnoseOptions::default();
    let times = |x: &[Vec<f64>], k: f64| -> Vec<Vec<f64>> {
        x.iter().map(|c| c.iter().map(|v| v * k).collect()).collect()
    };
    let unit = diagnose_numbered(&rec.u, &rec.d, &rec.y, &rec.s, &opts).unwrap();
    let (su, sy) = (1e-6, 1e6);
    let scaled = diagnose_numbered(
        &times(&rec.u, su),
        &times(&rec.d, su),
        &times(&rec.y, sy),
        &times(&rec.s, sy),
        &opts,
    )
    .unwrap();
    let said = |d: &mpmwatch_diagnose::Diagnosis| -> Vec<(String, String, &'static str)> {
        d.report.findings.iter().map(|f| (f.input.clone(), f.output.clone(), f.physics.name())).collect()
    };
    assert_eq!(said(&scaled), said(&unit));
    for (k, before) in &unit.report.holdout.fit_before_pct {
        let after = unit.report.holdout.fit_after_pct[k];
        let (b, a) = (scaled.report.holdout.fit_before_pct[k], scaled.report.holdout.fit_after_pct[k]);
        eprintln!("{k}: {before} → {after}; at gains 1e12 {b} → {a}");
        assert!(
            (b - before).abs() < 0.01 && (a - after).abs() < 0.01,
            "{k}: {before} → {after} vs {b} → {a}"
        );
    }
}

/// The closed-loop hypotheses are fitted on every core, and what is decided does not depend on
/// how many there are: the SISO quadratic (c13) diagnosed on one thread and on four gives the
/// same report and corrected simulation, bit for bit (every term's score comes back in the
/// order the terms were listed, whichever thread fitted it).
#[test]
fn the_closed_loop_diagnosis_does_not_depend_on_the_threads() {
    let spec = casebook_specs(3000, 100).into_iter().find(|s| s.name.starts_with("c13_")).expect("c13");
    let rec = run(&spec).unwrap();
    let on = |threads: usize| {
        let pool = rayon::ThreadPoolBuilder::new().num_threads(threads).build().unwrap();
        let d = pool
            .install(|| diagnose_numbered(&rec.u, &rec.d, &rec.y, &rec.s, &DiagnoseOptions::default()))
            .unwrap();
        assert!(d.report.findings.iter().any(|f| f.physics == Physics::Quadratic), "{:?}", d.report.findings);
        (serde_json::to_string(&d.report).unwrap(), d.corrected)
    };
    assert_eq!(on(1), on(4));
}
