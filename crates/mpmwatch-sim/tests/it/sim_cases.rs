//! The `simulate` cases: reproducible, bounded, with the contracted columns, and with residuals
//! that carry dither information only through a mismatch.

use mpmwatch_core::io::Table;
use mpmwatch_sim::Excitation;
use mpmwatch_sim::cases::{self, CaseName, CaseOptions, Disturbance};

fn run(case: CaseName, opts: &CaseOptions) -> Table {
    cases::run(case, opts).unwrap_or_else(|e| panic!("{case:?} {opts:?}: {e}")).table
}

fn csv_bytes(t: &Table) -> Vec<u8> {
    let mut buf = Vec::new();
    t.write_csv(&mut buf).unwrap();
    buf
}

fn opts(seed: u64) -> CaseOptions {
    CaseOptions { seed, ..CaseOptions::default() }
}

#[test]
fn one_seed_gives_identical_bytes_and_another_seed_differs() {
    for case in CaseName::ALL {
        let a = csv_bytes(&run(case, &opts(11)));
        let b = csv_bytes(&run(case, &opts(11)));
        let c = csv_bytes(&run(case, &opts(12)));
        assert_eq!(a, b, "{case:?}: same seed, same bytes");
        assert_ne!(a, c, "{case:?}: another seed, other bytes");
    }
}

#[test]
fn columns_follow_the_contract() {
    let expect: [(CaseName, &[&str]); 3] = [
        (CaseName::Model1, &["u", "y", "e1", "e2", "e3", "e4"]),
        (
            CaseName::Continuous2x3,
            &["u1", "u2", "u3", "ud1", "ud2", "ud3", "y1", "y2", "yhat1", "yhat2", "e1", "e2"],
        ),
        (
            CaseName::Hammerstein3x3,
            &[
                "u1", "u2", "u3", "ud1", "ud2", "ud3", "y1", "y2", "y3", "yhat1", "yhat2", "yhat3", "e1",
                "e2", "e3",
            ],
        ),
    ];
    for (case, names) in expect {
        let t = run(case, &opts(1));
        assert_eq!(t.names(), names, "{case:?}");
        assert_eq!(t.len(), 2047, "{case:?}");
        assert!(t.time().windows(2).all(|w| w[1] - w[0] == 1.0) && t.time()[0] == 0.0);
        if case != CaseName::Model1 {
            for j in 1..=names.iter().filter(|n| n.starts_with('e')).count() {
                let (y, yhat, e) = (
                    t.column(&format!("y{j}")).unwrap(),
                    t.column(&format!("yhat{j}")).unwrap(),
                    t.column(&format!("e{j}")).unwrap(),
                );
                assert!((0..t.len()).all(|k| e[k] == y[k] - yhat[k]), "{case:?}: e{j} = y{j} − yhat{j}");
            }
            for i in 1..=3 {
                let (u, ud) = (t.column(&format!("u{i}")).unwrap(), t.column(&format!("ud{i}")).unwrap());
                assert!(ud.iter().all(|v| v.abs() == 1.0), "±1 PRBS dither");
                assert!(u.iter().zip(ud).any(|(a, b)| a != b), "the controller acts on u{i}");
            }
        }
    }
}

fn assert_bounded(t: &Table, what: &str) {
    for name in t.names() {
        let x = t.column(name).unwrap();
        assert!(x.iter().all(|v| v.is_finite()), "{what}: {name} not finite");
        assert!(x.iter().all(|v| v.abs() < 100.0), "{what}: {name} leaves ±100");
        let h = x.len() / 2;
        let sd = |s: &[f64]| {
            let m = s.iter().sum::<f64>() / s.len() as f64;
            (s.iter().map(|v| (v - m).powi(2)).sum::<f64>() / s.len() as f64).sqrt()
        };
        assert!(sd(&x[h..]) <= 2.0 * sd(&x[..h]) + 1e-9, "{what}: {name} grows over the run");
    }
}

#[test]
fn every_closed_loop_stays_finite_and_bounded() {
    for m in ["none", "a=0.8", "a=0.5"] {
        let o = CaseOptions { mismatch: Some(m.into()), ..opts(5) };
        assert_bounded(&run(CaseName::Continuous2x3, &o), &format!("continuous2x3 {m}"));
    }
    for m in ["none", "g21", "g31", "both"] {
        for d in [Disturbance::Nominal, Disturbance::Changed] {
            let o = CaseOptions { mismatch: Some(m.into()), disturbance: d, ..opts(5) };
            assert_bounded(&run(CaseName::Hammerstein3x3, &o), &format!("hammerstein3x3 {m} {d:?}"));
        }
    }
    for ex in [Excitation::Uniform, Excitation::Gaussian, Excitation::Multilevel] {
        for case in CaseName::ALL {
            let o = CaseOptions { excitation: ex, ..opts(6) };
            assert_bounded(&run(case, &o), &format!("{case:?} {ex:?}"));
        }
    }
    for n in [512, 32768] {
        let t = run(CaseName::Model1, &CaseOptions { samples: Some(n), ..opts(7) });
        assert_eq!(t.len(), n);
        assert_bounded(&t, "model1 long");
    }
}

/// Proposition 1 of the paper: with no mismatch the residual is the disturbance alone, so a
/// different dither (same noise seed) leaves it unchanged; with a mismatch it does not.
#[test]
fn without_mismatch_the_residual_ignores_the_dither() {
    let residual_change = |case: CaseName, mismatch: &str, dist: Disturbance| {
        let base = CaseOptions { mismatch: Some(mismatch.into()), disturbance: dist, ..opts(21) };
        let a = run(case, &base);
        let b = run(case, &CaseOptions { excitation: Excitation::Gaussian, ..base });
        let ny = a.names().iter().filter(|n| n.starts_with('e')).count();
        (1..=ny)
            .map(|j| {
                let (x, y) = (a.column(&format!("e{j}")).unwrap(), b.column(&format!("e{j}")).unwrap());
                x.iter().zip(y).map(|(p, q)| (p - q).abs()).fold(0.0, f64::max)
            })
            .collect::<Vec<_>>()
    };
    for d in residual_change(CaseName::Continuous2x3, "none", Disturbance::Nominal) {
        assert!(d < 1e-9, "no mismatch: {d}");
    }
    let mism = residual_change(CaseName::Continuous2x3, "a=0.8", Disturbance::Nominal);
    assert!(mism.iter().all(|d| *d > 0.1), "a = 0.8 acts on both outputs: {mism:?}");

    for d in [Disturbance::Nominal, Disturbance::Changed] {
        for e in residual_change(CaseName::Hammerstein3x3, "none", d) {
            assert!(e < 1e-9, "no mismatch, {d:?}: {e}");
        }
    }
    let mism = residual_change(CaseName::Hammerstein3x3, "g21", Disturbance::Nominal);
    assert!(mism[0] > 0.1, "g21 changes e1: {mism:?}");
    assert!(mism[1] < 1e-9 && mism[2] < 1e-9, "g21 leaves e2, e3 alone: {mism:?}");
}

#[test]
fn model1_residuals_follow_eq13() {
    let t = run(CaseName::Model1, &opts(3));
    let (u, y) = (t.column("u").unwrap(), t.column("y").unwrap());
    let (e1, e2, e3, e4) =
        (t.column("e1").unwrap(), t.column("e2").unwrap(), t.column("e3").unwrap(), t.column("e4").unwrap());
    for k in 2..t.len() {
        // each residual minus its structured part is the same disturbance d(t)
        let d2 = e2[k] - 0.06 * u[k - 1] * u[k - 2];
        let d3 = e3[k] - 0.2 * y[k - 1];
        let d4 = e4[k] - 0.03 * y[k - 1] * y[k - 1];
        assert!((d2 - d3).abs() < 1e-12 && (d3 - d4).abs() < 1e-12, "k={k}");
        // and eq 12 holds with that disturbance
        let y_eq12 = -0.8 * y[k - 1] + 0.08 * (y[k - 1].powi(2) + 4.5 * u[k - 1] + u[k - 1] * u[k - 2]) + d2;
        assert!((y[k] - y_eq12).abs() < 1e-12, "k={k}");
        let d_prev = e2[k - 1] - if k >= 3 { 0.06 * u[k - 2] * u[k - 3] } else { 0.0 };
        assert!((e1[k] - (0.7 * d_prev + d2)).abs() < 1e-12, "k={k}");
    }
    // the disturbance has the variance of eq 14: 0.01·1.8/(0.2·(1.8² − 1.6²)) ≈ 0.132
    let d: Vec<f64> = (2..t.len()).map(|k| e2[k] - 0.06 * u[k - 1] * u[k - 2]).collect();
    let var = d.iter().map(|v| v * v).sum::<f64>() / d.len() as f64;
    assert!(var > 0.05 && var < 0.3, "var(d) = {var}");
}

#[test]
fn noise_ratio_sets_the_signal_to_noise_of_e2() {
    for ratio in [0.5, 2.0] {
        let t = run(CaseName::Model1, &CaseOptions { noise_ratio: Some(ratio), ..opts(4) });
        let (u, e2) = (t.column("u").unwrap(), t.column("e2").unwrap());
        let s: Vec<f64> = (2..t.len()).map(|k| 0.06 * u[k - 1] * u[k - 2]).collect();
        let d: Vec<f64> = (2..t.len()).map(|k| e2[k] - s[k - 2]).collect();
        let sd = |x: &[f64]| {
            let m = x.iter().sum::<f64>() / x.len() as f64;
            (x.iter().map(|v| (v - m).powi(2)).sum::<f64>() / x.len() as f64).sqrt()
        };
        let measured = sd(&d) / sd(&s);
        assert!((measured - ratio).abs() < 0.02 * ratio, "asked {ratio}, got {measured}");
    }
}

#[test]
fn bad_case_options_are_named_errors() {
    assert!(CaseName::parse("model2").unwrap_err().to_string().contains("model2"));
    let e = cases::run(CaseName::Continuous2x3, &CaseOptions { mismatch: Some("b=3".into()), ..opts(1) })
        .unwrap_err();
    assert!(e.to_string().contains("b=3"), "{e}");
    let e = cases::run(CaseName::Hammerstein3x3, &CaseOptions { mismatch: Some("g11".into()), ..opts(1) })
        .unwrap_err();
    assert!(e.to_string().contains("g11"), "{e}");
    assert!(cases::run(CaseName::Model1, &CaseOptions { mismatch: Some("a=1".into()), ..opts(1) }).is_err());
    assert!(cases::run(CaseName::Model1, &CaseOptions { samples: Some(1), ..opts(1) }).is_err());
    assert!(cases::run(CaseName::Model1, &CaseOptions { dither_std: -1.0, ..opts(1) }).is_err());
}

#[test]
fn noise_free_and_mismatch_free_residuals_are_exactly_zero() {
    for case in [CaseName::Continuous2x3, CaseName::Hammerstein3x3] {
        let o = CaseOptions { mismatch: Some("none".into()), noise_scale: 0.0, ..opts(8) };
        let t = run(case, &o);
        for name in t.names().iter().filter(|n| n.starts_with('e')) {
            assert!(t.column(name).unwrap().iter().all(|v| *v == 0.0), "{case:?}: {name}");
        }
        // and the same loop with its mismatch has non-zero residuals
        let t = run(case, &CaseOptions { mismatch: None, ..o });
        assert!(t.column("e1").unwrap().iter().any(|v| v.abs() > 0.1), "{case:?}");
    }
}
