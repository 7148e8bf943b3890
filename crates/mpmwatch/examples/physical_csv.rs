//! Writes one generated open-loop physical case (`mpmwatch_sim::physical_cases`) as the two
//! CSV files `diagnose` reads: the record (`time,u,y`) and the user's nominal ARX simulation
//! (`time,y`). For trying the CLI and drawing figures on a case whose truth is known.
//!
//! `cargo run --release --example physical_csv -- heater_voltage 1 2000 out/`

use anyhow::{Context, bail};
use mpmwatch_core::io::Table;
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
    let time: Vec<f64> = (0..rec.u.len()).map(|t| t as f64).collect();
    let write = |file: &str, cols: &[(&str, &[f64])]| -> anyhow::Result<()> {
        let mut table = Table::new(time.clone());
        for &(name, values) in cols {
            table.push_column(name, values.to_vec())?;
        }
        let path = std::path::Path::new(dir).join(file);
        let f = std::fs::File::create(&path).with_context(|| format!("creating {}", path.display()))?;
        table.write_csv(std::io::BufWriter::new(f)).with_context(|| format!("writing {}", path.display()))
    };
    write("rec.csv", &[("u", &rec.u), ("y", &rec.y)])?;
    write("sim.csv", &[("y", &rec.s)])?;
    eprintln!("{}: {}", case.name(), rec.description);
    Ok(())
}

fn names() -> Vec<&'static str> {
    PhysicalCase::ALL.iter().map(|c| c.name()).collect()
}
