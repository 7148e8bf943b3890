//! The paper's claims as `mpmwatch reproduce` reports them, one seeded test per claim: the
//! report's table is backed by these assertions, including where our result differs from the
//! paper (those tests pin what we measure, so a change in behaviour shows up here first).

use mpmwatch::report::reproduce::{
    Reading, ReproduceOptions, claim_continuous, claim_data_length, claim_disturbance, claim_excitation,
    claim_false_alarms, claim_hammerstein, claim_model1, sweep,
};
use mpmwatch_core::detect::Method;
use serde_json::json;

fn opts() -> ReproduceOptions {
    ReproduceOptions::default()
}

#[test]
fn claim1_model1_mi_finds_the_interaction_and_linear_terms() {
    let (c, _) = claim_model1(&opts()).unwrap();
    assert_eq!(c.details["mi"], json!(["u→e2", "u→e3"]), "{}", c.ours);
    assert_eq!(c.details["ccf"], json!(["u→e3"]), "{}", c.ours);
    // ε4's dither-driven part (about 0.006 against an innovation of 0.1) is below what 2047
    // samples resolve, so the claim as a whole does not hold.
    assert!(!c.holds);
}

#[test]
fn claim2_spread_falls_with_record_length() {
    let (c, study) = claim_data_length(&opts()).unwrap();
    assert_eq!(study.len(), 7);
    assert!(c.holds, "{}", c.ours);
}

#[test]
fn claim3_excitation_type_ranking() {
    let (c, study) = claim_excitation(&opts()).unwrap();
    assert_eq!(study.len(), 3);
    assert!(study.iter().all(|s| s.1.is_finite()));
    assert_eq!(c.details["largest"], "Gaussian", "{}", c.ours);
    assert!(!c.holds);
}

#[test]
fn claim4_continuous_plant_mismatch_on_u1_only() {
    let (c, _, _) = claim_continuous(&opts()).unwrap();
    assert_eq!(c.details["mi"], json!(["ud1→e1", "ud1→e2"]), "{}", c.ours);
    assert_eq!(c.details["mi_nominal"], json!([]), "{}", c.ours);
    // At our operating point u1 ≈ 1 the parabola is locally linear and the CCF sees it.
    assert!(c.details["ccf"].as_array().unwrap().contains(&json!("ud1→e1")), "{}", c.ours);
    assert!(!c.holds);
}

/// The family rule finds g21 and localises nothing that did not change. g31's lag-1 correlation
/// (about 3.6 standard errors) sits at the family's critical value: found on seed 1 when the
/// correlation was standardised by 30 sampled surrogates, missed since it is standardised by its
/// exact moments, so only g21 is asserted. The claim fails on its second half either way: our
/// whitened CCF sees g21 as well.
#[test]
fn claim5_hammerstein_changed_submodels() {
    let (c, _) = claim_hammerstein(&opts()).unwrap();
    let mi = c.details["mi"].as_array().unwrap();
    assert!(mi.contains(&json!("ud2→e1")), "{}", c.ours);
    assert!(mi.iter().all(|m| m == "ud2→e1" || m == "ud3→e1"), "{}", c.ours);
    assert!(c.details["ccf"].as_array().unwrap().contains(&json!("ud2→e1")), "{}", c.ours);
    assert!(!c.holds);
}

/// Under the paper's 6σ rule g31 stays below its critical value: a weak linear effect is
/// beyond MI at one-in-a-billion per lag.
#[test]
fn claim5_under_the_papers_rule_misses_g31() {
    let (c, _) =
        claim_hammerstein(&ReproduceOptions { reading: Reading::default_for(Method::Paper), ..opts() })
            .unwrap();
    assert_eq!(c.details["mi"], json!(["ud2→e1"]), "{}", c.ours);
}

/// No reading of the open settings makes claim 5 hold: under every one, the CCF sees g21.
#[test]
fn claim5_sweep_finds_no_reading_under_which_it_holds() {
    let points = sweep(5, &opts()).unwrap().expect("claim 5 has settings to sweep");
    assert_eq!(points.len(), Reading::sweep(Method::Family).len());
    for p in &points {
        assert!(!p.holds, "{}: {}", p.reading.label, p.ours);
        let ccf = p.ours.split("the CCF flags ").nth(1).and_then(|s| s.split('.').next()).unwrap_or("");
        assert!(ccf.contains("ud2→e1"), "{}: {}", p.reading.label, p.ours);
    }
}

#[test]
fn claim6_disturbance_change_alone_is_silent() {
    let (c, _) = claim_disturbance(&opts()).unwrap();
    assert!(c.holds, "{}", c.ours);
}

/// 300 matched runs (the default 150 seeds of each case; the claim needs 50), each matrix tested
/// at a matrix-wide 5 % (0.05/m per element). Whether the claim "holds" is the point estimate
/// ≤ 5 %, which a valid 5 % test misses on about 4 runs in 10; what this test checks is the
/// level: 25 or more alarmed runs has probability 0.009 under Binomial(300, 0.05) and 0.86 under
/// a doubled rate, Binomial(300, 0.10). With 100 runs and a bound of 11 a doubled rate would
/// pass 7 times in 10 (docs/detection.md, "Stop 26 reverted it").
#[test]
fn claim7_false_alarm_rate_over_three_hundred_runs() {
    let (c, study) = claim_false_alarms(&opts(), |_| {}).unwrap();
    assert_eq!(study.iter().map(|s| s.1).sum::<usize>(), 300);
    let alarmed: usize = study.iter().map(|s| s.2).sum();
    assert!(alarmed <= 24, "{}", c.ours);
}
