//! Open-loop physical cases (`mpmwatch_sim::physical_cases`, 3000 samples) diagnosed with the
//! user's least-squares ARX nominal: the grey-box step names the physics and the held-out FIT
//! rises. Seeds 1–3 are the development seeds of docs/diagnose-history.md; the report seeds are
//! measured by the ignored study, not here.

use super::physical_study::{bent, diagnose_against, diagnose_record, pinned};
use mpmwatch_diagnose::{ActsOn, Physics};
use mpmwatch_sim::physical_cases::{PhysicalCase, PhysicalRecord, nominal_simulation, run};

fn named(case: PhysicalCase, seed: u64) {
    let r = run(case, 3000, seed).unwrap();
    let d = diagnose_record(&r);
    let f = d.report.findings.iter().find(|f| f.physics != Physics::Unexplained);
    let f = f.unwrap_or_else(|| panic!("{case:?} seed {seed}: no finding: {:?}", d.report.findings));
    assert!(case.accepted().contains(&f.physics.name()), "{case:?} seed {seed}: {}", f.summary);
    let h = &d.report.holdout;
    assert!(h.fit_after_pct["y1"] > h.fit_before_pct["y1"], "{case:?} seed {seed}: {h:?}");
}

#[test]
fn heater_through_the_voltage_is_quadratic() {
    named(PhysicalCase::HeaterVoltage, 1);
}

#[test]
fn actuator_dead_zone() {
    named(PhysicalCase::ActuatorDeadZone, 1);
}

#[test]
fn friction_loaded_mass() {
    named(PhysicalCase::FrictionMass, 1);
}

#[test]
fn clipping_sensor() {
    named(PhysicalCase::ClippingSensor, 1);
}

#[test]
fn duffing_spring() {
    named(PhysicalCase::Duffing, 2);
}

/// A linear plant read through a sensor whose characteristic bends by a square law (a
/// Wiener model), either way: named `quadratic` on the output, not on the input, and the
/// held-out FIT rises. The bend, 0.3 standard deviations at one standard deviation, is the
/// middle of the study's `SENSOR=0.5` range (docs/diagnose.md); seed 1 as the other cases here.
#[test]
fn a_bent_sensor_is_a_quadratic_on_the_output() {
    for c in [0.3, -0.3] {
        let mut r = bent(run(PhysicalCase::Linear, 3000, 1).unwrap(), c);
        r.s = nominal_simulation(&r.u, &r.y).unwrap();
        let d = diagnose_record(&r);
        let f = d.report.findings.iter().find(|f| f.physics != Physics::Unexplained);
        let f = f.unwrap_or_else(|| panic!("bend {c}: no finding: {:?}", d.report.findings));
        assert_eq!((f.physics, f.acts_on), (Physics::Quadratic, ActsOn::Output), "bend {c}: {}", f.summary);
        assert_eq!(f.parameters["curvature"].signum(), c.signum(), "bend {c}: {}", f.summary);
        let h = &d.report.holdout;
        assert!(h.fit_after_pct["y1"] > h.fit_before_pct["y1"], "bend {c}: {h:?}");
    }
}

/// An instrument whose range ends at a quantile of the recorded output, every reading beyond
/// it that end exactly (the study's `PIN` shift), on the top or the bottom. Against an exact
/// model of the linear plant (its noise-free output as the simulation), read through a range
/// that holds a fifth of the record, the range is all the model left out: named a clip on the
/// output at that end, no limit fitted. (On the top, holding a twentieth, nothing is named:
/// the exact model leaves the range only by about the noise, and the range must earn the
/// half-point margin as any finding.) An actuator dead zone against its least-squares
/// nominal, read through a range holding a twentieth, keeps its name, fitted read through the
/// range. Each raises the held-out FIT. Seed 1 as the other cases here.
#[test]
fn a_pinned_instrument_is_read_through_its_range() {
    let cases = [
        (PhysicalCase::Linear, 0.8, true, Physics::Saturation),
        (PhysicalCase::Linear, 0.8, false, Physics::Saturation),
        (PhysicalCase::ActuatorDeadZone, 0.95, true, Physics::DeadZone),
    ];
    for (case, q, top, want) in cases {
        let r = pinned(run(case, 3000, 1).unwrap(), q, top);
        let end = if top {
            r.y.iter().copied().fold(f64::MIN, f64::max)
        } else {
            r.y.iter().copied().fold(f64::MAX, f64::min)
        };
        let d = if want == Physics::Saturation {
            diagnose_against(&r, &r.plant)
        } else {
            diagnose_against(&r, &nominal_simulation(&r.u, &r.y).unwrap())
        };
        let f = d.report.findings.iter().find(|f| f.physics != Physics::Unexplained);
        let f = f.unwrap_or_else(|| panic!("{case:?} top {top}: no finding: {:?}", d.report.findings));
        assert_eq!(f.physics, want, "{case:?} top {top}: {}", f.summary);
        if want == Physics::Saturation {
            assert_eq!(f.acts_on, ActsOn::Output, "{case:?} top {top}: {}", f.summary);
            let side = if top { "upper" } else { "lower" };
            assert_eq!(f.parameters.get(side), Some(&end), "{case:?} top {top}: {:?}", f.parameters);
            assert_eq!(f.parameters.len(), 1, "{case:?} top {top}: {:?}", f.parameters);
        } else {
            assert!(f.summary.contains("read through the range the record shows"), "{}", f.summary);
        }
        let h = &d.report.holdout;
        assert!(h.fit_after_pct["y1"] > h.fit_before_pct["y1"], "{case:?} top {top}: {h:?}");
    }
    let r = pinned(run(PhysicalCase::Linear, 3000, 1).unwrap(), 0.95, true);
    let d = diagnose_against(&r, &r.plant);
    for f in &d.report.findings {
        assert_eq!(f.physics, Physics::Unexplained, "a twentieth: {}", f.summary);
    }
}

/// A linear plant: no nonlinear class is named (a linear change may be, when the re-fit earns
/// it out of sample), and whatever is reported does not lower the held-out FIT.
#[test]
fn a_linear_plant_gets_no_nonlinear_physics() {
    for seed in 1..=3 {
        let r = run(PhysicalCase::Linear, 3000, seed).unwrap();
        let d = diagnose_record(&r);
        for f in &d.report.findings {
            assert!(
                matches!(
                    f.physics,
                    Physics::Gain | Physics::TimeConstant | Physics::DeadTime | Physics::Unexplained
                ),
                "seed {seed}: {}",
                f.summary
            );
        }
        let h = &d.report.holdout;
        assert!(h.fit_after_pct["y1"] >= h.fit_before_pct["y1"], "seed {seed}: {h:?}");
    }
}

/// The development tank of seed 6028: its best correction is a store whose fitted limits lie
/// beyond the range its level visits, a linear extra pole under a nonlinear name (on the
/// report seed 5063 such a store, named `saturation`, lowered the held-out FIT 3.8 → −16.3 %;
/// since stop 49 that tank finds a longer dead time and a slow cubic ranks first). A named
/// element must act on 1 % of the training rows (`greybox::explain`), so it is withheld, and
/// the finding says why.
#[test]
fn a_store_whose_limits_never_bind_is_withheld() {
    let r = run(PhysicalCase::TankOverflow, 3000, 6028).unwrap();
    let d = diagnose_record(&r);
    let f = d.report.findings.first().expect("a withheld correction is reported as unexplained");
    assert_eq!(f.physics, Physics::Unexplained, "{}", f.summary);
    assert!(f.summary.contains("acts on 0.0 % of the training rows"), "{}", f.summary);
    let h = &d.report.holdout;
    assert_eq!(h.fit_after_pct["y1"], h.fit_before_pct["y1"], "{h:?}");
}

/// The development heater of seed 6118 at 1000 samples: its best structure is two tanks in
/// cascade whose rim the level never reaches (on none of the training rows), and which still
/// gains 6.6 points over the best linear re-fit through their square-root outflows, a
/// nonlinearity the vocabulary has no class for. Until stop 74 an idle winner ended the walk
/// and nothing was named (the held-out FIT stayed at 51.0 %, where the true plant reaches
/// 70.0); a tank's class is now set aside instead, and the square law on the voltage, within
/// a point of it, is named and raises the held-out FIT.
#[test]
fn a_tank_whose_rim_never_binds_gives_way_to_the_next_class() {
    let r = run(PhysicalCase::HeaterVoltage, 1000, 6118).unwrap();
    let d = diagnose_record(&r);
    let f = d.report.findings.first().expect("a finding on heater 6118");
    assert_eq!(f.physics, Physics::Quadratic, "{}", f.summary);
    assert!(f.summary.contains("is not reported"), "the idle tank is said: {}", f.summary);
    let h = &d.report.holdout;
    assert!(h.fit_after_pct["y1"] > h.fit_before_pct["y1"], "{h:?}");
}

/// No-change cases: every class's plant diagnosed against an exact model of itself (the
/// noise-free plant output as the simulation; the recorded output adds the case's coloured
/// noise). Nothing may be named and nothing corrected: the grey-box step runs on every output
/// of an open-loop record, so this is what keeps it from explaining noise. One seed per class
/// (seed 1, 2000 samples); the false-finding rate this bounds is the margins' (a finding must
/// gain the caller's margin of cross-validated FIT over the nominal, an exact model here).
#[test]
fn an_exact_model_gets_no_finding() {
    for case in PhysicalCase::ALL {
        let r = run(case, 2000, 1).unwrap();
        let d = diagnose_against(&r, &r.plant);
        for f in &d.report.findings {
            assert_eq!(f.physics, Physics::Unexplained, "{case:?}: {}", f.summary);
        }
        let h = &d.report.holdout;
        assert_eq!(h.fit_after_pct["y1"], h.fit_before_pct["y1"], "{case:?}: {h:?}");
    }
}

/// The diagnosis does not depend on the units. The actuator dead zone of seed 1 is diagnosed
/// as recorded, and again with its input a million times smaller and its output a million
/// times larger (a gain of 1e12, as a flow in m³/s on a pressure in Pa has), and the other way
/// round (1e-10). The solvers divide columns by their norms and the optimiser's steps follow
/// each parameter's start, so the named physics must agree. The held-out FITs, which are
/// ratios, may move through rounding and through the absolute difference step that a
/// parameter starting at zero keeps: 0.01 points is a chosen bound (the differences printed
/// on a run are in docs/diagnose.md), far inside the 0.5-point margin any decision uses.
/// Before the columns were scaled, a CSV record with a binary input named `gain` came back
/// `quadratic` at a gain of 1e12 and `time_constant` at 1e-10 (docs/diagnose.md); this test
/// was not run against that code.
#[test]
fn the_diagnosis_does_not_depend_on_the_units() {
    let r = run(PhysicalCase::ActuatorDeadZone, 3000, 1).unwrap();
    let said = |d: &mpmwatch_diagnose::Diagnosis| {
        let name = d.report.findings.first().map_or("none", |f| f.physics.name());
        let h = &d.report.holdout;
        (name, h.fit_before_pct["y1"], h.fit_after_pct["y1"])
    };
    let (name, before, after) = said(&diagnose_record(&r));
    for (su, sy) in [(1e-6, 1e6), (1e5, 1e-5)] {
        let times = |x: &[f64], k: f64| x.iter().map(|v| v * k).collect::<Vec<f64>>();
        let scaled = PhysicalRecord {
            u: times(&r.u, su),
            y: times(&r.y, sy),
            plant: times(&r.plant, sy),
            s: times(&r.s, sy),
            ..r.clone()
        };
        let (n, b, a) = said(&diagnose_record(&scaled));
        eprintln!("input ×{su:e}, output ×{sy:e}: {n}, {b} → {a}; as recorded {name}, {before} → {after}");
        assert_eq!(n, name, "input ×{su:e}, output ×{sy:e}");
        assert!((b - before).abs() < 0.01 && (a - after).abs() < 0.01, "{before} → {after} vs {b} → {a}");
    }
}

/// The report says where the held-out tail leaves the training range: a linear record whose
/// input and output are doubled over the tail lists both, each with the training part's own
/// extremes and the share of tail rows beyond them (the measure itself has closed-form tests
/// in the library).
#[test]
fn a_tail_beyond_the_training_range_is_reported() {
    let mut r = run(PhysicalCase::Linear, 1500, 1).unwrap();
    let start = diagnose_record(&r).report.holdout.start_index;
    r.u[start..].iter_mut().for_each(|v| *v *= 2.0);
    r.y[start..].iter_mut().for_each(|v| *v *= 2.0);
    let h = diagnose_record(&r).report.holdout;
    for (name, x) in [("u1", &r.u), ("y1", &r.y)] {
        let b = h.beyond_training.iter().find(|b| b.signal == name).expect("the tail leaves its range");
        let train = &x[..start];
        let lo = train.iter().copied().fold(f64::INFINITY, f64::min);
        let hi = train.iter().copied().fold(f64::NEG_INFINITY, f64::max);
        assert_eq!(b.training, [lo, hi], "{name}");
        let outside = x[start..].iter().filter(|&&v| v < lo || v > hi).count();
        assert!(outside > 0, "{name}");
        assert_eq!(b.share_pct, 100.0 * outside as f64 / (x.len() - start) as f64, "{name}");
    }
}
