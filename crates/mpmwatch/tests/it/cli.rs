//! The command line as a user runs it: `mpmwatch mi` and `mpmwatch bench`.

use crate::common;

use std::path::PathBuf;
use std::process::Command;

fn bin() -> Command {
    Command::new(env!("CARGO_BIN_EXE_mpmwatch"))
}

/// A scratch directory, removed when the returned guard drops.
fn scratch_dir(name: &str) -> tempfile::TempDir {
    tempfile::Builder::new().prefix(&format!("mpmwatch-cli-{name}-")).tempdir().unwrap()
}

/// A record with a binary dither acting on the residual one sample later.
fn write_record(dir: &std::path::Path) -> PathBuf {
    let mut rng = common::rng(21);
    let n = 1500;
    let ud = common::binary(&mut rng, n);
    let v = common::ar1(&mut rng, n, 0.6);
    let mut text = String::from("time,ud1,e1,e2\n");
    for t in 0..n {
        let e1 = v[t] + if t > 0 { 0.8 * ud[t - 1] } else { 0.0 };
        text.push_str(&format!("{},{},{},{}\n", t as f64 * 0.5, ud[t], e1, v[t]));
    }
    let path = dir.join("record.csv");
    std::fs::write(&path, text).unwrap();
    path
}

fn json_of(out: &std::process::Output) -> serde_json::Value {
    assert!(out.status.success(), "stderr: {}", String::from_utf8_lossy(&out.stderr));
    serde_json::from_slice(&out.stdout).expect("one JSON object on stdout")
}

#[test]
fn mi_prints_json_in_nats_and_bits() {
    let scratch = scratch_dir("mi");
    let dir = scratch.path().to_path_buf();
    let file = write_record(&dir);
    let nats = json_of(
        &bin()
            .args(["mi"])
            .arg(&file)
            .args(["--x", "ud1", "--y", "e1", "--lag", "1", "--json"])
            .output()
            .unwrap(),
    );
    assert_eq!(nats["n"], 1499);
    assert_eq!(nats["estimator"], "ross");
    let mi = nats["mi"].as_f64().unwrap();
    assert!(mi > 0.1, "dependent pair: {mi}");
    let bits = json_of(
        &bin()
            .args(["mi"])
            .arg(&file)
            .args(["--x", "ud1", "--y", "e1", "--lag", "1", "--units", "bits", "--json"])
            .output()
            .unwrap(),
    );
    assert!((bits["mi"].as_f64().unwrap() - mi / std::f64::consts::LN_2).abs() < 1e-12);
    let other = json_of(
        &bin()
            .args(["mi"])
            .arg(&file)
            .args(["--x", "ud1", "--y", "e2", "--lag", "1", "--json"])
            .output()
            .unwrap(),
    );
    assert!(other["mi"].as_f64().unwrap() < 0.02, "independent pair: {}", other["mi"]);
}

#[test]
fn mi_with_surrogates_reports_threshold_and_seed() {
    let scratch = scratch_dir("sur");
    let dir = scratch.path().to_path_buf();
    let file = write_record(&dir);
    let args = ["--x", "ud1", "--y", "e1", "--lag", "1", "--surrogates", "30", "--seed", "5", "--json"];
    let out = json_of(&bin().args(["mi"]).arg(&file).args(args).output().unwrap());
    let s = &out["surrogates"];
    assert_eq!(s["seed"], 5);
    assert_eq!(s["method"], "circular_shift");
    assert_eq!(s["significant"], true);
    assert!(s["critical"].as_f64().unwrap() < out["mi"].as_f64().unwrap());
}

#[test]
fn bad_input_exits_nonzero_with_a_message_naming_it() {
    let scratch = scratch_dir("bad");
    let dir = scratch.path().to_path_buf();
    let file = write_record(&dir);
    let out = bin().args(["mi"]).arg(&file).args(["--x", "ud9", "--y", "e1"]).output().unwrap();
    assert!(!out.status.success());
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(err.contains("ud9") && err.contains("ud1"), "{err}");

    let nan = dir.join("nan.csv");
    std::fs::write(&nan, "time,a,b\n0,1,2\n1,NaN,3\n2,3,1\n3,1,1\n4,2,5\n5,0,2\n").unwrap();
    let out = bin().args(["mi"]).arg(&nan).args(["--x", "a", "--y", "b", "--k", "2"]).output().unwrap();
    assert!(!out.status.success());
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(err.contains("non-finite") && err.contains("index 1"), "{err}");

    let text = dir.join("text.csv");
    std::fs::write(&text, "time,a,b\n0,1,2\n1,oops,3\n").unwrap();
    let out = bin().args(["mi"]).arg(&text).args(["--x", "a", "--y", "b"]).output().unwrap();
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(!out.status.success() && err.contains("line 3") && err.contains("oops"), "{err}");

    let out = bin().args(["mi", "/nonexistent/x.csv", "--x", "a", "--y", "b"]).output().unwrap();
    assert!(!out.status.success() && String::from_utf8_lossy(&out.stderr).contains("/nonexistent/x.csv"));
}

#[test]
fn bench_json_has_the_contract_keys() {
    let out = json_of(&bin().args(["bench", "--n", "512", "--reps", "3", "--json"]).output().unwrap());
    for key in ["ksg_binary_ms", "ksg_binary_per_lag_ms", "ksg_continuous_ms", "iaaft_ms", "matrix_3x3_ms"] {
        let v = out[key].as_f64().unwrap_or_else(|| panic!("{key} missing: {out}"));
        assert!(v > 0.0 && v.is_finite(), "{key} = {v}");
    }
    assert_eq!(out["n"], 512);
}

/// What `bench --diagnose` times and checks, run as a user runs it: one open-loop diagnosis of
/// the Duffing oscillator on one thread, then on every thread of the pool, with the same report
/// both times (the verb exits non-zero when they differ, so a success with `same` false would be
/// a broken check). A short record: the check is the plumbing and the agreement, not the time.
#[test]
fn bench_diagnose_runs_one_thread_then_all_and_finds_the_same() {
    let out = json_of(
        &bin().args(["bench", "--diagnose", "--n", "600", "--seed", "2", "--json"]).output().unwrap(),
    );
    assert_eq!(
        (out["case"].as_str(), out["n"].as_u64(), out["seed"].as_u64()),
        (Some("duffing"), Some(600), Some(2))
    );
    assert_eq!(out["same"], true, "{out}");
    assert!(out["threads"].as_u64().is_some_and(|t| t >= 1), "{out}");
    for key in ["one_thread_s", "all_threads_s"] {
        assert!(out[key].as_f64().is_some_and(|s| s > 0.0 && s.is_finite()), "{key}: {out}");
    }
    let names: Vec<&str> = mpmwatch_diagnose::Physics::ALL.iter().map(|p| p.name()).collect();
    let named = out["named"].as_str().unwrap_or_default();
    assert!(named == "none" || named == "unexplained" || names.contains(&named), "{named}");
}

#[test]
fn analyze_prints_json_verdicts_and_writes_figures() {
    let scratch = scratch_dir("analyze");
    let dir = scratch.path().to_path_buf();
    let file = write_record(&dir);
    let figs = dir.join("figs");
    let out = json_of(
        &bin()
            .args(["analyze"])
            .arg(&file)
            .args(["--dither", "ud1", "--residual", "e1,e2", "--tmax", "5", "--surrogates", "30", "--json"])
            .arg("--figures")
            .arg(&figs)
            .output()
            .unwrap(),
    );
    assert_eq!(out["mismatch"], true);
    let ch = out["channels"].as_array().unwrap();
    assert_eq!(ch.len(), 2);
    assert_eq!(ch[0]["input"], "ud1");
    assert_eq!(ch[0]["output"], "e1");
    assert_eq!(ch[0]["verdict"], "mismatch");
    assert_eq!(ch[1]["verdict"], "clean");
    assert!(
        ch[0]["norm_mi_bits"].as_f64().unwrap() > ch[0]["threshold_bits"].as_f64().unwrap()
            || ch[0]["peak_lag"] == 1
    );
    for name in ["mi_lags", "ccf_lags", "mi_matrix", "pair_ud1_e1_mi", "pair_ud1_e2_ccf"] {
        for ext in ["svg", "png"] {
            let f = figs.join(format!("{name}.{ext}"));
            let len = std::fs::metadata(&f).unwrap_or_else(|_| panic!("{} missing", f.display())).len();
            assert!(len > 1000, "{} is only {len} bytes", f.display());
        }
    }
    // Residuals as outputs minus a simulation: a zero simulation gives the same matrix.
    let sim = dir.join("sim.csv");
    let text = std::fs::read_to_string(&file).unwrap();
    let mut sim_text = String::from("time,e1,e2\n");
    for line in text.lines().skip(1) {
        let t = line.split(',').next().unwrap();
        sim_text.push_str(&format!("{t},0,0\n"));
    }
    std::fs::write(&sim, sim_text).unwrap();
    let via_sim = json_of(
        &bin()
            .args(["analyze"])
            .arg(&file)
            .args([
                "--dither",
                "ud1",
                "--output",
                "e1,e2",
                "--tmax",
                "5",
                "--surrogates",
                "30",
                "--json",
                "--simulated",
            ])
            .arg(&sim)
            .output()
            .unwrap(),
    );
    assert_eq!(via_sim["channels"][0]["norm_mi_bits"], out["channels"][0]["norm_mi_bits"]);
    assert_eq!(via_sim["channels"][0]["output"], "e_e1");
}
