//! Each vocabulary class is recovered on at least one seeded concealed closed-loop case from the
//! scenario generator (the effect's residual variance 0.1–0.8 of the disturbance's): the right
//! channel and the right physics.

use mpmwatch::diagnose::DiagnoseOptions;
use mpmwatch::sim::Excitation;
use mpmwatch::sim::scenarios::{Effect, ScenarioSpec, diagnose_record, run};

fn recovers(effect: Effect, size: usize, channel: (usize, usize), excitation: Excitation, seed: u64, ratio: f64) {
    let spec = ScenarioSpec { name: "t".into(), effect, size, channel, excitation, n: 3000, seed, target_ratio: ratio };
    let rec = run(&spec).unwrap();
    assert!((0.1..=0.8).contains(&rec.effect_ratio), "not concealed: ratio {}", rec.effect_ratio);
    let d = diagnose_record(&rec, &DiagnoseOptions::default()).unwrap();
    let want = (format!("u{}", channel.0 + 1), format!("y{}", channel.1 + 1));
    let f = d.report.findings.iter().find(|f| (f.input.clone(), f.output.clone()) == want);
    let f = f.unwrap_or_else(|| panic!("{effect:?}: no finding on {want:?}: {:?}", d.report.findings));
    assert_eq!(f.physics.name(), effect.physics(), "{effect:?}: {}", f.summary);
}
