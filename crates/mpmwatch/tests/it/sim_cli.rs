//! The `simulate` verb end to end: file written, seed reported, bad input refused by name.

use std::process::Command;

fn mpmwatch() -> Command {
    Command::new(env!("CARGO_BIN_EXE_mpmwatch"))
}

#[test]
fn simulate_writes_the_csv_and_reports_the_seed() {
    let dir = std::env::temp_dir().join(format!("mpmwatch-sim-cli-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let out = dir.join("m1.csv");
    let o = mpmwatch().args(["simulate", "model1", "--seed", "42", "--out"]).arg(&out).output().unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    assert!(String::from_utf8_lossy(&o.stderr).contains("seed 42"));
    let text = std::fs::read_to_string(&out).unwrap();
    assert_eq!(text.lines().next(), Some("time,u,y,e1,e2,e3,e4"));
    assert_eq!(text.lines().count(), 2048);
    let again = dir.join("m1b.csv");
    assert!(
        mpmwatch()
            .args(["simulate", "model1", "--seed", "42", "--out"])
            .arg(&again)
            .output()
            .unwrap()
            .status
            .success()
    );
    assert_eq!(std::fs::read(&out).unwrap(), std::fs::read(&again).unwrap());
    std::fs::remove_dir_all(&dir).ok();
}

#[test]
fn unknown_case_and_options_fail_with_their_name() {
    let o = mpmwatch().args(["simulate", "model7", "--out", "/dev/null"]).output().unwrap();
    assert!(!o.status.success());
    assert!(String::from_utf8_lossy(&o.stderr).contains("model7"));
    let o = mpmwatch()
        .args(["simulate", "model1", "--excitation", "pink", "--out", "/dev/null"])
        .output()
        .unwrap();
    assert!(!o.status.success());
    assert!(String::from_utf8_lossy(&o.stderr).contains("pink"));
    let o = mpmwatch()
        .args(["simulate", "continuous2x3", "--noise-ratio", "0.5", "--out", "/dev/null"])
        .output()
        .unwrap();
    assert!(!o.status.success());
}

#[test]
fn help_lists_every_case_and_its_columns() {
    let o = mpmwatch().args(["simulate", "--help"]).output().unwrap();
    let text = String::from_utf8_lossy(&o.stdout);
    for needle in ["model1", "continuous2x3", "hammerstein3x3", "yhat", "time,u,y,e1,e2,e3,e4"] {
        assert!(text.contains(needle), "help lacks {needle}");
    }
}
