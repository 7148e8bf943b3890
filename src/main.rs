//! `mpmwatch`: the command line. Parses, calls the library, prints.

mod cmd;

use clap::Parser;

/// Detects, localises and explains model–plant mismatch in model-based control loops.
#[derive(Parser)]
#[command(name = "mpmwatch", version, about, long_about = None)]
struct Cli {
    #[command(subcommand)]
    verb: Verb,
}

#[derive(clap::Subcommand)]
enum Verb {
    /// Simulate one of the paper's plants and write its CSV (see `simulate --help`).
    Simulate(cmd::simulate::Args),
}

fn main() -> anyhow::Result<()> {
    let cli = Cli::parse();
    match cli.verb {
        Verb::Simulate(args) => cmd::simulate::run(args),
    }
}
