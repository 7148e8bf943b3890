//! Benchmark-grade accuracy on the benchmarks' own splits (the data are read from the shared
//! folder; a missing file fails the test with its name).

use super::shared_data::{data_dir, read_columns};

/// The goal: ≤ 2 % NRMSE on the arrow head with the cubic spring; the linear model of the
/// same orders must stay far from it (above 10 %), or the benchmark would not test the physics.
#[test]
fn silverbox_with_the_cubic_spring_on_the_arrow_head() {
    let cols = read_columns(&data_dir().join("silverbox/SNLS80mV.csv"), &["V1", "V2"]);
    let rows = mpmwatch::accuracy::silverbox(&cols[0], &cols[1]).unwrap();
    for r in &rows {
        eprintln!(
            "{} {:.3} {} {:.2} % (estimation {:.3})",
            r.model, r.rmse, r.unit, r.nrmse_pct, r.estimation_rmse
        );
    }
    assert!(
        rows[1].nrmse_pct <= 2.0 && rows[0].nrmse_pct > 10.0,
        "{:.2} % and {:.2} %",
        rows[1].nrmse_pct,
        rows[0].nrmse_pct
    );
}

/// The named physics alone (the upper tank's overflow and the sensor's top) must cut the
/// nominal's test RMSE by a third (no better than the nominal on the test split would mean it
/// does not carry out of sample); with the refinements chosen on the estimation record
/// (`scripts/tanks_structure.py`: fitted outflow exponents, the lower tank overflowing at the
/// sensor's top) the goal, ≤ 0.25 V on the validation record, must hold.
#[test]
fn cascaded_tanks_with_the_overflow_on_the_validation_record() {
    let cols =
        read_columns(&data_dir().join("cascaded_tanks/dataBenchmark.csv"), &["uEst", "uVal", "yEst", "yVal"]);
    let rows = mpmwatch::accuracy::cascaded_tanks(&cols[0], &cols[2], &cols[1], &cols[3]).unwrap();
    for r in &rows {
        eprintln!(
            "{} {:.3} {} {:.2} % (estimation {:.3})",
            r.model, r.rmse, r.unit, r.nrmse_pct, r.estimation_rmse
        );
    }
    assert!(
        rows[1].rmse <= rows[0].rmse * 2.0 / 3.0,
        "{:.3} V against the nominal's {:.3} V",
        rows[1].rmse,
        rows[0].rmse
    );
    assert!(rows[2].rmse <= 0.25, "refined: {:.3} V", rows[2].rmse);
}

/// Coupled drives, fitted on the first uniform experiment: on the second one (the split
/// ControlSystemIdentification.jl's belt-drive example uses) the direction-blind sensor must
/// beat the linear model of the same orders. The PRBS records are scored too (eight rows in
/// all) but not held to anything; docs/diagnose.md says why.
#[test]
fn coupled_drives_with_the_abs_sensor_on_the_second_uniform_experiment() {
    use mpmwatch::accuracy::DrivesRecord;
    let dir = data_dir().join("ced");
    let unif = read_columns(&dir.join("DATAUNIF.csv"), &["u11", "z11", "u12", "z12"]);
    let prbs = read_columns(&dir.join("DATAPRBS.csv"), &["u1", "z1", "u2", "z2", "u3", "z3"]);
    let tests = [
        DrivesRecord { label: "u12→z12", u: &unif[2], z: &unif[3] },
        DrivesRecord { label: "u1→z1", u: &prbs[0], z: &prbs[1] },
        DrivesRecord { label: "u2→z2", u: &prbs[2], z: &prbs[3] },
        DrivesRecord { label: "u3→z3", u: &prbs[4], z: &prbs[5] },
    ];
    let rows = mpmwatch::accuracy::coupled_drives(&unif[0], &unif[1], &tests).unwrap();
    for r in &rows {
        eprintln!(
            "{} | {} | {:.4} | {:.2} % | est {:.4}",
            r.model, r.split, r.rmse, r.nrmse_pct, r.estimation_rmse
        );
    }
    assert_eq!(rows.len(), 8);
    assert!(
        rows[4].rmse < rows[0].rmse,
        "u12→z12: sensor {:.4} against linear {:.4}",
        rows[4].rmse,
        rows[0].rmse
    );
}
