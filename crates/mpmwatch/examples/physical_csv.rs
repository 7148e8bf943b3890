//! Writes one generated open-loop physical case (`mpmwatch_sim::physical_cases`) as the two
//! CSV files `diagnose` reads: the record (`time,u,y`) and the user's nominal ARX simulation
//! (`time,y`). For trying the CLI and drawing figures on a case whose truth is known.
//!
//! `cargo run --release --example physical_csv -- heater_voltage 1 2000 out/`

use std::io::Write;

use anyhow::{Context, bail};
use mpmwatch_sim::physical_cases::{PhysicalCase, run};

fn main() -> anyhow::Result<()> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let [name, seed, n, dir] = args.as_slice() else {
        bail!("usage: physical_csv CASE SEED SAMPLES DIR (cases: {})", names().join(", "));
    };
    let case = PhysicalCase::ALL
        .into_iter()
        .find(|c| c.name() == name)
        .with_context(|| format!("no case {name:?}; cases: {}", names().join(", ")))?;
    let rec = run(case, n.parse().context("SAMPLES")?, seed.parse().context("SEED")?)?;
    std::fs::create_dir_all(dir).with_context(|| format!("creating {dir}"))?;
    let write = |file: &str, cols: &[&[f64]], header: &str| -> anyhow::Result<()> {
        let path = std::path::Path::new(dir).join(file);
        let mut f = std::io::BufWriter::new(
            std::fs::File::create(&path).with_context(|| path.display().to_string())?,
        );
        writeln!(f, "{header}")?;
        for t in 0..rec.u.len() {
            let row: Vec<String> = cols.iter().map(|c| c[t].to_string()).collect();
            writeln!(f, "{t},{}", row.join(","))?;
        }
        Ok(())
    };
    write("rec.csv", &[&rec.u, &rec.y], "time,u,y")?;
    write("sim.csv", &[&rec.s], "time,y")?;
    eprintln!("{}: {}", case.name(), rec.description);
    Ok(())
}

fn names() -> Vec<&'static str> {
    PhysicalCase::ALL.iter().map(|c| c.name()).collect()
}
