//! The paper's own closed loops under model predictive control, diagnosed as a user of
//! `simulate` and `diagnose` would: the record's `yhat` columns are the simulation. These loops
//! come from another generator than the one the diagnosis was developed on (PI loops,
//! `scenarios::wide_specs`), with slow disturbances the MPC rejects well.

use mpmwatch_core::detect::Signal;
use mpmwatch_diagnose::{DiagnoseInput, DiagnoseOptions, Physics, diagnose};
use mpmwatch_sim::cases::{CaseName, CaseOptions, run};

/// Diagnoses one paper case: inputs `u1..`, dithers `ud1..`, outputs `y1..` against `yhat1..`.
fn diagnose_case(case: CaseName, seed: u64, mismatch: &str) -> mpmwatch_diagnose::Diagnosis {
    let opts = CaseOptions { seed, mismatch: Some(mismatch.into()), ..CaseOptions::default() };
    let table = run(case, &opts).unwrap().table;
    let col = |name: String| table.column(&name).unwrap().to_vec();
    let outputs = if case == CaseName::Hammerstein3x3 { 3 } else { 2 };
    let u: Vec<Vec<f64>> = (1..=3).map(|i| col(format!("u{i}"))).collect();
    let ud: Vec<Vec<f64>> = (1..=3).map(|i| col(format!("ud{i}"))).collect();
    let y: Vec<Vec<f64>> = (1..=outputs).map(|j| col(format!("y{j}"))).collect();
    let s: Vec<Vec<f64>> = (1..=outputs).map(|j| col(format!("yhat{j}"))).collect();
    let time = table.time().to_vec();
    let names = ["u1", "u2", "u3"];
    let (dn, yn) = (["ud1", "ud2", "ud3"], ["y1", "y2", "y3"]);
    let input = DiagnoseInput {
        time: &time,
        inputs: u.iter().zip(names).map(|(v, name)| Signal { name, values: v }).collect(),
        excitations: Some(ud.iter().zip(dn).map(|(v, name)| Signal { name, values: v }).collect()),
        outputs: y.iter().zip(yn).map(|(v, name)| Signal { name, values: v }).collect(),
        simulated: s.iter().zip(yn).map(|(v, name)| Signal { name, values: v }).collect(),
        physical: Vec::new(),
    };
    diagnose(&input, &DiagnoseOptions::default()).unwrap()
}

/// No reported finding lowers its output's held-out FIT.
fn assert_no_fall(d: &mpmwatch_diagnose::Diagnosis, what: &str) {
    let h = &d.report.holdout;
    for f in d.report.findings.iter().filter(|f| f.physics != Physics::Unexplained) {
        let (before, after) = (h.fit_before_pct[&f.output], h.fit_after_pct[&f.output]);
        assert!(
            after >= before,
            "{what}: {}→{} {:?} held-out {before:.1} → {after:.1}",
            f.input,
            f.output,
            f.physics
        );
    }
}

/// continuous2x3 at a = 0.8 (eqs 25–26): the u1² term's coefficient is four times the model's
/// on both outputs. On y2 that is named a `gain` of u1's channel, four times the model's: the
/// nominal's own response to u1 is a square law, which the polynomial channels of the nominal
/// carry (against a linear approximation of it the finding was a `quadratic`). On y1 the MPC's
/// rejection of the slow disturbance (time constant 40 s) makes the nominal's error cancel part
/// of it, so the right correction lowers the plain FIT; before the gate measured a correction
/// against the intercept alone too, seeds 1 and 3 reported one there whose held-out FIT fell
/// (−8.7 → −14.6 % and 2.6 → −21.1 %). Seeds 1 and 3 are those two. The ratio is bounded by
/// 3.8–4.2: 4.00 and 3.95 were measured on them.
#[test]
fn the_papers_linear_mpc_case_is_named_without_a_falling_finding() {
    for seed in [1, 3] {
        let d = diagnose_case(CaseName::Continuous2x3, seed, "a=0.8");
        let y2 = d.report.findings.iter().find(|f| f.output == "y2").expect("a finding on y2");
        assert_eq!((y2.input.as_str(), y2.physics), ("u1", Physics::Gain), "seed {seed}: {}", y2.summary);
        let ratio = y2.parameters["gain_ratio"];
        assert!((3.8..4.2).contains(&ratio), "seed {seed}: gain ratio {ratio}");
        assert_no_fall(&d, &format!("continuous2x3 seed {seed}"));
    }
}

/// hammerstein3x3 (eq 27, NMPC). g21 changed (eq 28: MV2 → CV1 from a slow second-order
/// response to `2q⁻¹/(1−0.2q⁻¹)`): named a faster `time_constant` on u2→y1, and the held-out
/// FIT rises (by 30 to 31 points on seeds 1–3 through the `diagnose` verb before the test was
/// written; 10 are asked, where a withheld finding would gain nothing). g31 changed (eq 29:
/// MV3 → CV1 from `q⁻¹/(1−0.7q⁻¹)` to `0.59q⁻¹/(1−0.607q⁻¹)`, a DC gain 0.45 times the model's
/// and a slightly faster pole): named a `gain` on u3→y1 through sin(u3), which the nominal's
/// polynomial channels carry (against the linear approximation it was named `cubic`).
#[test]
fn the_papers_nmpc_case_names_the_changed_channels() {
    let d = diagnose_case(CaseName::Hammerstein3x3, 2, "g21");
    let f = d.report.findings.iter().find(|f| f.output == "y1").expect("a finding on y1");
    assert_eq!((f.input.as_str(), f.physics), ("u2", Physics::TimeConstant), "{}", f.summary);
    let h = &d.report.holdout;
    assert!(h.fit_after_pct["y1"] > h.fit_before_pct["y1"] + 10.0, "{:?}", h);
    assert_no_fall(&d, "hammerstein3x3 g21 seed 2");
    let d = diagnose_case(CaseName::Hammerstein3x3, 2, "g31");
    let f = d.report.findings.iter().find(|f| f.output == "y1").expect("a finding on y1");
    assert_eq!((f.input.as_str(), f.physics), ("u3", Physics::Gain), "{}", f.summary);
    assert_no_fall(&d, "hammerstein3x3 g31 seed 2");
}
