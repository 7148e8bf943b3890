//! Real recordings. The Silverbox (an electronic Duffing oscillator, `m ÿ + d ẏ + k1 y + k3 y³ =
//! u`) against a linear ARX(2,3) simulation fitted on the low-amplitude start of its arrow-head
//! record: `diagnose` must name the cubic stiffness and raise the held-out FIT by at least 5
//! points, the target for real recordings. Every recording of the folder: only the
//! cascaded tanks show an instrument's range.
//!
//! The data are not in the repository. They are read from `$MPMWATCH_DATA/silverbox/SNLS80mV.csv`
//! or, without that variable, from `../shared/data` next to the crate. When the file is absent
//! the test fails with a message naming it (the data folder's own rule: never pass silently).

use mpmwatch_core::detect::Signal;
use mpmwatch_core::model::{Arx, ArxOrders};
use mpmwatch_diagnose::{DiagnoseInput, DiagnoseOptions, Physics, diagnose};

use super::shared_data::{data_dir, read_columns};

#[test]
fn silverbox_cubic_stiffness_is_named_and_the_held_out_fit_rises() {
    let path = data_dir().join("silverbox/SNLS80mV.csv");
    let cols = read_columns(&path, &["V1", "V2"]);
    let (u, y) = (&cols[0][..40_000], &cols[1][..40_000]);
    // ARX(2,3) with a constant, least squares on samples 2 000..10 000 (the low amplitudes).
    let orders = ArxOrders { na: 2, nb: 3, delays: vec![0] };
    let s = Arx::fit(y, &[u], &orders, 2_002..10_000).unwrap().simulate_from(&[u], y[0]).unwrap();
    // Diagnosed on the last 10 000 samples of the arrow (the largest amplitudes).
    let w = 30_000..40_000;
    let time: Vec<f64> = (0..w.len()).map(|k| k as f64 / 610.35).collect();
    let input = DiagnoseInput::open_loop(
        &time,
        Signal { name: "u", values: &u[w.clone()] },
        Signal { name: "y", values: &y[w.clone()] },
        &s[w],
    );
    let d = diagnose(&input, &DiagnoseOptions::default()).unwrap();
    let f = d.report.findings.first().expect("a finding on the Silverbox");
    assert_eq!(f.physics, Physics::Cubic, "{}", f.summary);
    let (before, after) = (d.report.holdout.fit_before_pct["y"], d.report.holdout.fit_after_pct["y"]);
    assert!(after - before >= 5.0, "held-out FIT {before:.1} → {after:.1}");
}

/// The cascaded tanks against the Torricelli two-tank model without overflow, calibrated on the
/// estimation record's overflow-free runs, the model itself handed to `diagnose` (state limits,
/// `diagnose::physical`): the upper tank's overflow must be named (a saturation of state 0) and
/// the held-out FIT (the validation record but its first 102 samples) must rise by ≥ 5 points.
#[test]
fn cascaded_tanks_upper_tank_overflow_is_named_and_the_held_out_fit_rises() {
    use mpmwatch::tanks::{benchmark_options, benchmark_record};
    use mpmwatch_diagnose::PhysicalModel;
    let path = data_dir().join("cascaded_tanks/dataBenchmark.csv");
    let cols = read_columns(&path, &["uEst", "uVal", "yEst", "yVal"]);
    let (ue, uv, ye, yv) = (&cols[0], &cols[1], &cols[2], &cols[3]);
    let record = benchmark_record(ue, ye, uv, yv);
    let s = record.simulate();
    let u: Vec<f64> = ue.iter().chain(uv).copied().collect();
    let y: Vec<f64> = ye.iter().chain(yv).copied().collect();
    let time: Vec<f64> = (0..u.len()).map(|k| k as f64 * 4.0).collect();
    let input = DiagnoseInput {
        physical: vec![Some(&record)],
        ..DiagnoseInput::open_loop(
            &time,
            Signal { name: "u", values: &u },
            Signal { name: "y", values: &y },
            &s,
        )
    };
    let d = diagnose(&input, &benchmark_options(&DiagnoseOptions::default())).unwrap();
    let f = d.report.findings.first().expect("a finding on the cascaded tanks");
    assert_eq!(f.physics, Physics::Saturation, "{}", f.summary);
    assert_eq!(f.parameters.get("state_index"), Some(&0.0), "{}", f.summary);
    let (before, after) = (d.report.holdout.fit_before_pct["y"], d.report.holdout.fit_after_pct["y"]);
    assert!(after - before >= 5.0, "held-out FIT {before:.1} → {after:.1}");
}

/// The coupled drives' other experiments, each against the linear ARX(3,3) calibrated on the
/// uniform-input record `u12 → z12` (the casebook's nominal), diagnosed whole with the last 30 %
/// held out: the speed sensor that sees no direction must be named on every one, and the
/// held-out FIT must rise by at least 5 points. These are the casebook's rows first run at stop
/// 74, on records the diagnosis had never been run on (docs/diagnose-history.md): the PRBS ±1.5
/// (`u2 → z2`) and ±0.5 (`u3 → z3`) experiments and the first uniform-input record.
#[test]
fn the_drives_other_experiments_name_the_direction_blind_sensor() {
    let dir = data_dir();
    let unif = read_columns(&dir.join("ced/DATAUNIF.csv"), &["u11", "z11", "u12", "z12"]);
    let prbs = read_columns(&dir.join("ced/DATAPRBS.csv"), &["u2", "z2", "u3", "z3"]);
    let orders = ArxOrders { na: 3, nb: 3, delays: vec![1] };
    let nominal = Arx::fit(&unif[3], &[&unif[2]], &orders, 4..unif[2].len()).unwrap();
    for (label, u, y) in
        [("u2→z2", &prbs[0], &prbs[1]), ("u3→z3", &prbs[2], &prbs[3]), ("u11→z11", &unif[0], &unif[1])]
    {
        let s = nominal.simulate_from(&[u], y[0]).unwrap();
        let time: Vec<f64> = (0..u.len()).map(|k| k as f64 * 0.02).collect();
        let input = DiagnoseInput::open_loop(
            &time,
            Signal { name: "u", values: u },
            Signal { name: "y", values: y },
            &s,
        );
        let d = diagnose(&input, &DiagnoseOptions::default()).unwrap();
        let f = d.report.findings.first().unwrap_or_else(|| panic!("{label}: no finding"));
        assert_eq!(f.physics, Physics::AbsSensor, "{label}: {}", f.summary);
        let (before, after) = (d.report.holdout.fit_before_pct["y"], d.report.holdout.fit_after_pct["y"]);
        assert!(after - before >= 5.0, "{label}: held-out FIT {before:.1} → {after:.1}");
    }
}

/// The instrument's range read off the real recordings: the cascaded tanks' level sensor stops
/// at 10 V, on both records (the data folder's README counts the samples there), and nothing
/// else the folder holds shows a range: not TCLab's quantised temperatures (0.32 °C steps,
/// each held many times), not the drives' pulse-counted speeds, not the Silverbox's voltage.
#[test]
fn only_the_tanks_level_sensor_shows_its_range() {
    let dir = data_dir();
    let tanks = read_columns(&dir.join("cascaded_tanks/dataBenchmark.csv"), &["yEst", "yVal"]);
    // Whole records, and the validation record's first 70 %, the training part the casebook's
    // row diagnoses (13 rows at 10 V, where ten times its average hold is 10.6 rows).
    for y in [&tanks[0][..], &tanks[1][..], &tanks[1][..716]] {
        let r = mpmwatch_diagnose::pinned(y).expect("the tanks' level sensor stops at 10 V");
        assert_eq!((r.lower, r.upper), (f64::NEG_INFINITY, 10.0), "{r:?}");
        assert_eq!(r.at_upper, y.iter().filter(|&&v| v == 10.0).count());
        assert!(r.at_upper >= 13, "{r:?}");
    }
    let mut others: Vec<(String, Vec<f64>)> = Vec::new();
    for file in ["tclab/tclab_step_test.csv", "tclab/tclab_sine_test_5min_period.csv"] {
        let cols = read_columns(&dir.join(file), &["T1", "T2"]);
        others.extend(cols.into_iter().zip(["T1", "T2"]).map(|(c, n)| (format!("{file} {n}"), c)));
    }
    let names = ["z1", "z2", "z3"];
    let ced = read_columns(&dir.join("ced/DATAPRBS.csv"), &names);
    others.extend(ced.into_iter().zip(names).map(|(c, n)| (format!("ced {n}"), c)));
    let silverbox = read_columns(&dir.join("silverbox/SNLS80mV.csv"), &["V2"]);
    others.push(("silverbox V2".into(), silverbox[0][..40_000].to_vec()));
    for (name, y) in others {
        assert_eq!(mpmwatch_diagnose::pinned(&y), None, "{name}");
    }
}
