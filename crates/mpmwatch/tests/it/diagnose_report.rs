//! The `diagnose` contract: the report JSON has the shape of DESIGN.md §4.5, bad input gives an
//! error naming the offending column or file, and a disturbance-only change yields no finding.

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

use mpmwatch_core::detect::Signal;
use mpmwatch_diagnose::{
    BeyondTraining, DiagnoseError, DiagnoseInput, DiagnoseOptions, diagnose, diagnose_numbered,
};
use mpmwatch_sim::Excitation;
use mpmwatch_sim::scenarios::{Effect, ScenarioSpec, run};

fn spec(effect: Effect, excitation: Excitation, seed: u64) -> ScenarioSpec {
    ScenarioSpec {
        name: "t".into(),
        effect,
        size: 1,
        channel: (0, 0),
        excitation,
        n: 2000,
        seed,
        target_ratio: 0.6,
        plant: None,
        decrease: false,
    }
}

/// A scratch directory, removed when the returned guard drops.
fn tmp(name: &str) -> tempfile::TempDir {
    tempfile::Builder::new().prefix(&format!("mpmwatch_diag_{name}_")).tempdir().unwrap()
}

fn write_csv(path: &PathBuf, names: &[&str], cols: &[&[f64]]) {
    let mut s = String::from("time");
    for n in names {
        s.push(',');
        s.push_str(n);
    }
    s.push('\n');
    for k in 0..cols[0].len() {
        s.push_str(&k.to_string());
        for c in cols {
            s.push_str(&format!(",{}", c[k]));
        }
        s.push('\n');
    }
    std::fs::write(path, s).unwrap();
}

/// `mpmwatch diagnose` on one input `u1` with its dither `d1`, output `y1` and its simulation
/// `s`, written as CSV into `dir`; the report goes to `dir/r.json`, the corrected simulation to
/// `dir/c.csv`.
fn diagnose_cli(dir: &Path, u: &[f64], d: &[f64], y: &[f64], s: &[f64]) -> Output {
    let (recp, simp) = (dir.join("rec.csv"), dir.join("sim.csv"));
    write_csv(&recp, &["u1", "d1", "y1"], &[u, d, y]);
    write_csv(&simp, &["y1"], &[s]);
    Command::new(env!("CARGO_BIN_EXE_mpmwatch"))
        .args(["diagnose", "--recorded"])
        .arg(&recp)
        .arg("--simulated")
        .arg(&simp)
        .args(["--inputs", "u1", "--excitations", "d1", "--outputs", "y1", "--report"])
        .arg(dir.join("r.json"))
        .arg("--corrected")
        .arg(dir.join("c.csv"))
        .output()
        .unwrap()
}

#[test]
fn disturbance_only_change_yields_no_finding() {
    for seed in [3, 4] {
        let rec = run(&spec(Effect::DisturbanceOnly, Excitation::Prbs, seed)).unwrap();
        let d = diagnose_numbered(&rec.u, &rec.d, &rec.y, &rec.s, &DiagnoseOptions::default()).unwrap();
        assert!(d.report.findings.is_empty(), "seed {seed}: {:?}", d.report.findings);
        assert!(!d.report.mismatch, "seed {seed}");
        assert_eq!(d.corrected[0], rec.s[0], "no finding must leave the simulation as it is");
    }
}

#[test]
fn report_json_matches_design_4_5() {
    let rec = run(&spec(Effect::DeadTime, Excitation::Prbs, 7)).unwrap();
    let scratch = tmp("json");
    let dir = scratch.path().to_path_buf();
    let out = diagnose_cli(&dir, &rec.u[0], &rec.d[0], &rec.y[0], &rec.s[0]);
    let (rep, cor) = (dir.join("r.json"), dir.join("c.csv"));
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success(), "{stderr}");
    // The stages on stderr, in order; stdout keeps the findings alone.
    let stage = |s: &str| stderr.find(s).unwrap_or_else(|| panic!("no `{s}` on stderr: {stderr}"));
    assert!(
        stage("] locating: ") < stage("] explaining y1 (1 of 1)")
            && stage("] explaining y1") < stage("] done")
    );
    assert!(!String::from_utf8_lossy(&out.stdout).contains("locating"));
    let v: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(&rep).unwrap()).unwrap();
    assert_eq!(v["mismatch"], true);
    let ch = &v["channels"][0];
    for k in ["input", "output", "norm_mi_bits", "threshold_bits", "significant", "verdict"] {
        assert!(!ch[k].is_null(), "channels[0].{k} missing: {ch}");
    }
    assert!(["mismatch", "clean", "implicated_by_feedback"].contains(&ch["verdict"].as_str().unwrap()));
    let f = &v["findings"][0];
    for k in
        ["input", "output", "physics", "acts_on", "summary", "parameters", "fit_before_pct", "fit_after_pct"]
    {
        assert!(!f[k].is_null(), "findings[0].{k} missing: {f}");
    }
    let vocab = [
        "gain",
        "time_constant",
        "dead_time",
        "missing_coupling",
        "dead_zone",
        "saturation",
        "quadratic",
        "cubic",
        "bilinear",
        "backlash",
        "coulomb_friction",
        "abs_sensor",
        "unexplained",
    ];
    assert!(vocab.contains(&f["physics"].as_str().unwrap()), "{f}");
    assert!(["input", "output"].contains(&f["acts_on"].as_str().unwrap()));
    assert!(f["parameters"].as_object().unwrap().values().all(|p| p.is_f64()));
    // `settings` records the options used, the locating rule and both gate margins among them.
    let s = &v["settings"];
    assert_eq!(
        (s["locate"].as_str(), s["alpha"].as_f64(), s["seed"].as_u64()),
        (Some("family"), Some(0.01), Some(1))
    );
    assert_eq!((s["min_gain_pct"].as_f64(), s["closed_loop_min_gain_pct"].as_f64()), (Some(0.5), Some(2.0)));
    assert_eq!(s["drift_min_gain_pct"].as_f64(), Some(1.0));
    let h = &v["holdout"];
    assert_eq!(h["start_index"], 1400);
    assert!(h["fit_before_pct"]["y1"].is_f64() && h["fit_after_pct"]["y1"].is_f64());
    let corrected = std::fs::read_to_string(&cor).unwrap();
    assert!(corrected.starts_with("time,y1\n"), "{}", &corrected[..20]);
    assert_eq!(corrected.lines().count(), 2001);
}

/// Where the held-out tail leaves the training range: the report's `beyond_training` and the
/// printed lines are what the library measures on the same columns (the input's tail doubled
/// here, so that `u1` leaves its range; the dither's too, which is not a modelled signal and
/// is not listed).
#[test]
fn a_tail_beyond_the_training_range_is_reported() {
    let rec = run(&spec(Effect::DeadTime, Excitation::Prbs, 7)).unwrap();
    let (mut u, mut d) = (rec.u[0].clone(), rec.d[0].clone());
    u[1400..].iter_mut().for_each(|v| *v *= 2.0);
    d[1400..].iter_mut().for_each(|v| *v *= 2.0);
    let scratch = tmp("beyond");
    let dir = scratch.path().to_path_buf();
    let out = diagnose_cli(&dir, &u, &d, &rec.y[0], &rec.s[0]);
    let rep = dir.join("r.json");
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let v: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(&rep).unwrap()).unwrap();
    assert_eq!(v["holdout"]["start_index"], 1400);
    let expected: Vec<BeyondTraining> =
        [("u1", &u), ("y1", &rec.y[0])].iter().filter_map(|(n, x)| BeyondTraining::of(n, x, 1400)).collect();
    assert_eq!(expected.first().map(|b| b.signal.as_str()), Some("u1"));
    let got: Vec<BeyondTraining> = serde_json::from_value(v["holdout"]["beyond_training"].clone()).unwrap();
    assert_eq!(got, expected);
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert!(v["findings"].as_array().is_some_and(|f| f.iter().any(|f| f["physics"] != "unexplained")));
    assert!(expected.iter().all(|b| stdout.contains(&b.sentence())), "{stdout}");
}

#[test]
fn bad_input_names_the_culprit() {
    let scratch = tmp("bad");
    let dir = scratch.path().to_path_buf();
    let x: Vec<f64> = (0..400).map(|k| (k as f64 * 0.3).sin()).collect();
    let (recp, simp) = (dir.join("rec.csv"), dir.join("sim.csv"));
    write_csv(&recp, &["u1", "y1"], &[&x, &x]);
    write_csv(&simp, &["y1"], &[&x[..399]]);
    let cli = |inputs: &str, outputs: &str, sim: &PathBuf| {
        let out = Command::new(env!("CARGO_BIN_EXE_mpmwatch"))
            .args(["diagnose", "--recorded"])
            .arg(&recp)
            .arg("--simulated")
            .arg(sim)
            .args(["--inputs", inputs, "--outputs", outputs, "--report"])
            .arg(dir.join("r.json"))
            .arg("--corrected")
            .arg(dir.join("c.csv"))
            .env("RUST_BACKTRACE", "1")
            .output()
            .unwrap();
        assert!(!out.status.success());
        let stderr = String::from_utf8_lossy(&out.stderr).to_string();
        // The user gets the culprit's name, not the call stack, whatever RUST_BACKTRACE says.
        assert!(!stderr.contains("backtrace"), "{stderr}");
        stderr
    };
    let e = cli("u1", "y1", &simp);
    assert!(e.contains("time axes do not match") && e.contains("sim.csv"), "{e}");
    let good = dir.join("sim2.csv");
    write_csv(&good, &["y1"], &[&x]);
    let e = cli("u7", "y1", &good);
    assert!(e.contains("u7") && e.contains("u1"), "{e}");
    let mut nan = x.clone();
    nan[17] = f64::NAN;
    let nanp = dir.join("sim3.csv");
    write_csv(&nanp, &["y1"], &[&nan]);
    let e = cli("u1", "y1", &nanp);
    assert!(e.contains("y1") && e.contains("NaN") && e.contains("sim3.csv"), "{e}");
    // The library names the series too.
    let t: Vec<f64> = (0..400).map(|k| k as f64).collect();
    let input = DiagnoseInput::open_loop(
        &t,
        Signal { name: "u1", values: &x },
        Signal { name: "y1", values: &x },
        &nan,
    );
    match diagnose(&input, &DiagnoseOptions::default()) {
        Err(DiagnoseError::NotFinite { name, index, .. }) => assert_eq!((name.as_str(), index), ("y1", 17)),
        other => panic!("{other:?}"),
    }
}

/// An open-loop record from the CSV verb (no `--excitations`): an actuator dead zone
/// (`mpmwatch_sim::physical_cases`, development seed 1) against the user's ARX nominal. The
/// dead zone is named, and `--figures` draws the fitted element beside the output figure.
#[test]
fn open_loop_dead_zone_is_named_and_its_element_drawn() {
    use mpmwatch_sim::physical_cases::{PhysicalCase, run as run_case};
    let r = run_case(PhysicalCase::ActuatorDeadZone, 3000, 1).unwrap();
    let scratch = tmp("element");
    let dir = scratch.path().to_path_buf();
    let (recp, simp) = (dir.join("rec.csv"), dir.join("sim.csv"));
    write_csv(&recp, &["u1", "y1"], &[&r.u, &r.y]);
    write_csv(&simp, &["y1"], &[&r.s]);
    let figs = dir.join("figures");
    let out = Command::new(env!("CARGO_BIN_EXE_mpmwatch"))
        .args(["diagnose", "--recorded"])
        .arg(&recp)
        .arg("--simulated")
        .arg(&simp)
        .args(["--inputs", "u1", "--outputs", "y1", "--report"])
        .arg(dir.join("r.json"))
        .arg("--corrected")
        .arg(dir.join("c.csv"))
        .arg("--figures")
        .arg(&figs)
        .output()
        .unwrap();
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let v: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(dir.join("r.json")).unwrap()).unwrap();
    assert_eq!(v["findings"][0]["physics"], "dead_zone", "{stdout}");
    assert_eq!(v["mismatch"], true);
    for f in ["diagnose_y1.png", "diagnose_y1_element.png"] {
        let len = std::fs::metadata(figs.join(f)).map_or(0, |m| m.len());
        assert!(len > 1000, "{f}: {len} bytes");
    }
}
