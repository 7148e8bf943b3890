//! The MI matrix and localisation on synthetic loops with a known mismatch pattern.

use crate::common;

use mpmwatch_core::detect::{
    Evidence, LagChoice, MatrixOptions, Method, Signal, Verdict, analyze, analyze_segments,
};
use mpmwatch_core::info::{Lags, SurrogateOptions};

fn opts(seed: u64) -> MatrixOptions {
    MatrixOptions {
        lags: LagChoice::Fixed(Lags::new(1, 5).unwrap()),
        surrogates: SurrogateOptions { count: 60, seed, ..SurrogateOptions::default() },
        ..MatrixOptions::default()
    }
}

/// Two dithers, two residuals. e1 gets a parabola of ud1 two samples later (an even map the
/// CCF cannot see), e2 is pure coloured noise: only (e1, ud1) is a mismatch, and the CCF stays
/// silent on it.
#[test]
fn parabola_is_localised_and_ccf_misses_it() {
    let mut rng = common::rng(41);
    let n = 2047;
    let ud1: Vec<f64> = (0..n).map(|_| rand::Rng::random_range(&mut rng, -1.0..1.0)).collect();
    let ud2 = common::binary(&mut rng, n);
    let v1 = common::ar1(&mut rng, n, 0.8);
    let v2 = common::ar1(&mut rng, n, 0.5);
    let e1: Vec<f64> =
        (0..n).map(|t| 0.3 * v1[t] + if t >= 2 { ud1[t - 2] * ud1[t - 2] } else { 0.0 }).collect();
    let d = [Signal { name: "ud1", values: &ud1 }, Signal { name: "ud2", values: &ud2 }];
    let r = [Signal { name: "e1", values: &e1 }, Signal { name: "e2", values: &v2 }];
    let m = analyze(&d, &r, &opts(1)).unwrap();
    assert!(m.mismatch);
    for ch in &m.channels {
        let want = if ch.mv == "ud1" && ch.cv == "e1" { Verdict::Mismatch } else { Verdict::Clean };
        assert_eq!(ch.verdict, want, "{} -> {}: {}", ch.mv, ch.cv, ch.reason);
    }
    let hit = m.cell(0, 0).unwrap();
    assert!(hit.significant && hit.value > 0.0);
    assert_ne!(hit.decision.evidence, Evidence::Ccf, "an even map is found by MI, not by the correlation");
    assert!(!hit.ccf.significant, "CCF {:?} limit {}", hit.ccf.values, hit.ccf.limit);
    assert_eq!(m.cell(1, 1).unwrap().value, 0.0);
}

/// A feedback path: ud1 reaches e1 through a wrong g11; the controller moves u2 against e1;
/// a wrong g22 carries u2, and with it ud1, into e2. (e2, ud1) is significant but explained by
/// feedback; (e1, ud1) and (e2, ud2) are mismatches; (e1, ud2) is clean.
#[test]
fn feedback_implication_is_reported() {
    let mut rng = common::rng(42);
    let n = 2047;
    let ud1 = common::binary(&mut rng, n);
    let ud2 = common::binary(&mut rng, n);
    let v1 = common::ar1(&mut rng, n, 0.5);
    let v2 = common::ar1(&mut rng, n, 0.5);
    let mut e1 = vec![0.0; n];
    let mut e2 = vec![0.0; n];
    let mut u2 = vec![0.0; n];
    for t in 0..n {
        e1[t] = 0.5 * v1[t] + if t >= 1 { 0.8 * ud1[t - 1] } else { 0.0 };
        u2[t] = ud2[t] - if t >= 1 { 1.5 * e1[t - 1] } else { 0.0 };
        e2[t] = 0.5 * v2[t] + if t >= 1 { 0.6 * u2[t - 1] } else { 0.0 };
    }
    let d = [Signal { name: "ud1", values: &ud1 }, Signal { name: "ud2", values: &ud2 }];
    let r = [Signal { name: "e1", values: &e1 }, Signal { name: "e2", values: &e2 }];
    let m = analyze(&d, &r, &opts(2)).unwrap();
    let verdict = |mv: &str, cv: &str| m.channels.iter().find(|c| c.mv == mv && c.cv == cv).unwrap().verdict;
    assert_eq!(verdict("ud1", "e1"), Verdict::Mismatch);
    assert_eq!(verdict("ud2", "e2"), Verdict::Mismatch);
    assert_eq!(verdict("ud1", "e2"), Verdict::ImplicatedByFeedback);
    assert_eq!(verdict("ud2", "e1"), Verdict::Clean);
}

/// Only one MV excited (the other dither is all zeros): Proposition 4 applies, the constant
/// dither is reported as not excited and gets no cells.
#[test]
fn single_excited_mv_uses_proposition_4() {
    let mut rng = common::rng(43);
    let n = 1500;
    let ud1 = common::binary(&mut rng, n);
    let ud2 = vec![0.0; n];
    let v = common::ar1(&mut rng, n, 0.5);
    let e1: Vec<f64> = (0..n).map(|t| v[t] + if t >= 3 { 0.7 * ud1[t - 3] } else { 0.0 }).collect();
    let d = [Signal { name: "ud1", values: &ud1 }, Signal { name: "ud2", values: &ud2 }];
    let r = [Signal { name: "e1", values: &e1 }];
    let m = analyze(&d, &r, &opts(3)).unwrap();
    assert_eq!(m.excited, vec![true, false]);
    assert_eq!(m.cells.len(), 1);
    assert_eq!(m.channels[0].verdict, Verdict::Mismatch);
    assert!(m.channels[0].reason.contains("Proposition 4"), "{}", m.channels[0].reason);
}

/// `u(t−1)·u(t−2)`: the matrix flags it through the joint-lag statistic, not the pairwise one.
#[test]
fn interaction_is_flagged_by_the_joint_statistic() {
    let mut rng = common::rng(44);
    let n = 2047;
    let u = common::binary(&mut rng, n);
    let v = common::ar1(&mut rng, n, 0.5);
    let e: Vec<f64> = (0..n).map(|t| v[t] + if t >= 2 { 0.8 * u[t - 1] * u[t - 2] } else { 0.0 }).collect();
    let m =
        analyze(&[Signal { name: "ud", values: &u }], &[Signal { name: "e", values: &e }], &opts(4)).unwrap();
    let c = &m.cells[0];
    assert!(!c.pairwise.significant);
    assert!(c.joint.as_ref().unwrap().significant);
    assert!(c.significant && m.mismatch);
}

#[test]
fn bad_signals_are_errors() {
    let a = vec![1.0, -1.0, 1.0];
    let b = vec![0.1, 0.2];
    let e = analyze(&[Signal { name: "ud1", values: &a }], &[Signal { name: "e1", values: &b }], &opts(5))
        .unwrap_err();
    assert!(e.to_string().contains("e1"), "{e}");
    let z = vec![0.0; 3];
    let e = analyze(&[Signal { name: "ud1", values: &z }], &[Signal { name: "e1", values: &a }], &opts(5))
        .unwrap_err();
    assert!(e.to_string().contains("every dither"), "{e}");
}

/// 30 seeded 2×2 matrices of binary dithers against AR residuals, lags 1..=10, no mismatch.
fn independent_matrices_alarmed(o: impl Fn(u64) -> MatrixOptions) -> usize {
    let mut alarmed = 0;
    for seed in 0..30u64 {
        let mut rng = common::rng(60_000 + seed);
        let n = 1000;
        let (a, b) = (common::binary(&mut rng, n), common::binary(&mut rng, n));
        let (e1, e2) = (common::ar1(&mut rng, n, 0.8), common::ar1(&mut rng, n, 0.3));
        let d = [Signal { name: "ud1", values: &a }, Signal { name: "ud2", values: &b }];
        let r = [Signal { name: "e1", values: &e1 }, Signal { name: "e2", values: &e2 }];
        alarmed += usize::from(analyze(&d, &r, &o(seed)).unwrap().mismatch);
    }
    alarmed
}

/// The paper's rule (norm or any lag above its 6σ critical value, pairwise or joint): each
/// matrix makes 2 × 4 × 11 comparisons with a 6σ limit; at most one matrix in 30 may alarm.
#[test]
fn independent_matrices_rarely_alarm_under_the_papers_rule() {
    let alarmed = independent_matrices_alarmed(|seed| MatrixOptions {
        method: Method::Paper,
        lags: LagChoice::Fixed(Lags::new(1, 10).unwrap()),
        ..opts(seed)
    });
    assert!(alarmed <= 1, "{alarmed} of 30 independent matrices alarmed");
}

/// The family rule with a matrix-wide rate of 1 % (alpha = 0.01 / 4 per element): 0.3 false
/// matrices expected in 30; three or more has probability 0.0033 for a valid test.
#[test]
fn independent_matrices_rarely_alarm_under_the_family_rule() {
    let alarmed = independent_matrices_alarmed(|seed| MatrixOptions {
        alpha: 0.01 / 4.0,
        lags: LagChoice::Fixed(Lags::new(1, 10).unwrap()),
        ..opts(seed)
    });
    assert!(alarmed <= 2, "{alarmed} of 30 independent matrices alarmed");
}

/// Pooled surrogates keep the level: 12 null matrices of 10 alike binary dithers against 3
/// coloured residuals, so every element shares its surrogates with 9 others (360 elements at
/// alpha = 0.05, 18 false elements expected). Sharing makes the elements of a group err together:
/// the group's rate read from 100 null maxima has a standard error of about √(0.05·0.95/100) =
/// 0.022, which over 36 groups adds 0.0036 to the binomial 0.0115 of the overall rate, a count
/// spread of about 4.3; 32 is 3.2 of those above 18, and 5 as far below on the other side.
#[test]
fn elements_sharing_surrogates_keep_the_level() {
    let mut flagged = 0;
    let mut elements = 0;
    for seed in 0..12u64 {
        let mut rng = common::rng(70_000 + seed);
        let n = 1024;
        let dithers: Vec<Vec<f64>> = (0..10).map(|_| common::binary(&mut rng, n)).collect();
        let residuals: Vec<Vec<f64>> =
            [0.9, 0.5, -0.3].iter().map(|&a| common::ar1(&mut rng, n, a)).collect();
        let names: Vec<String> = (0..10).map(|i| format!("d{i}")).collect();
        let d: Vec<Signal> = dithers.iter().zip(&names).map(|(v, name)| Signal { name, values: v }).collect();
        let rn = ["e1", "e2", "e3"];
        let r: Vec<Signal> = residuals.iter().zip(rn).map(|(v, name)| Signal { name, values: v }).collect();
        let m = analyze(
            &d,
            &r,
            &MatrixOptions {
                alpha: 0.05,
                surrogates: SurrogateOptions { seed, ..SurrogateOptions::default() },
                ..opts(seed)
            },
        )
        .unwrap();
        assert!(m.cells.iter().all(|c| c.family.as_ref().unwrap().pooled == 10), "alike dithers are pooled");
        flagged += m.cells.iter().filter(|c| c.significant).count();
        elements += m.cells.len();
    }
    assert_eq!(elements, 360);
    assert!((5..=32).contains(&flagged), "{flagged} of 360 null elements flagged at alpha = 0.05");
}

/// A gap of 40 rows in the middle: the analysis in segments uses both sides (about 1 950
/// pairs, not the 1 000 after the gap) and reaches the decisions of the same data without the
/// gap: only (e1, ud1), a linear effect at lag 3, is a mismatch. At alpha = 0.001, so that a
/// null element near the level (at 0.01 one of the three is flagged about 3 % of the time) does
/// not flip between two analyses of slightly different rows.
#[test]
fn a_gap_keeps_the_data_before_it_and_the_decisions_of_the_whole_record() {
    let mut rng = common::rng(43);
    let n = 2047;
    let ud1 = common::binary(&mut rng, n);
    let ud2 = common::binary(&mut rng, n);
    let v1 = common::ar1(&mut rng, n, 0.8);
    let v2 = common::ar1(&mut rng, n, 0.5);
    let e1: Vec<f64> = (0..n).map(|t| v1[t] + if t >= 3 { 0.15 * ud1[t - 3] } else { 0.0 }).collect();
    let whole = {
        let d = [Signal { name: "ud1", values: &ud1 }, Signal { name: "ud2", values: &ud2 }];
        let r = [Signal { name: "e1", values: &e1 }, Signal { name: "e2", values: &v2 }];
        analyze(&d, &r, &MatrixOptions { alpha: 0.001, ..opts(7) }).unwrap()
    };
    let cut = |x: &[f64]| -> Vec<f64> { x[..1000].iter().chain(&x[1040..]).copied().collect() };
    let (g1, g2, ge1, ge2) = (cut(&ud1), cut(&ud2), cut(&e1), cut(&v2));
    let d = [Signal { name: "ud1", values: &g1 }, Signal { name: "ud2", values: &g2 }];
    let r = [Signal { name: "e1", values: &ge1 }, Signal { name: "e2", values: &ge2 }];
    let gapped = analyze_segments(&d, &r, &[1000, 1007], &MatrixOptions { alpha: 0.001, ..opts(7) }).unwrap();
    for (a, b) in whole.channels.iter().zip(&gapped.channels) {
        assert_eq!(a.verdict, b.verdict, "{} -> {}: {} / {}", a.mv, a.cv, a.reason, b.reason);
    }
    assert_eq!(gapped.channels.iter().filter(|c| c.verdict == Verdict::Mismatch).count(), 1);
    assert!(gapped.cell(0, 0).unwrap().significant);
    // Pairs: 2 007 rows less, per segment, 5 partialling rows, the whitening order (≤ 10) and
    // 5 lags: between 2 007 − 2·20 and 2 007 − 2·10.
    let pairs = gapped.cell(0, 0).unwrap().ccf.n;
    assert!((2007 - 40..=2007 - 20).contains(&pairs), "{pairs}");
    assert!(
        analyze_segments(&d, &r, &[1000, 1000], &MatrixOptions { alpha: 0.001, ..opts(7) }).is_err(),
        "segments must cover the record"
    );
}
