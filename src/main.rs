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
enum Verb {}

fn main() -> anyhow::Result<()> {
    let cli = Cli::parse();
    match cli.verb {}
}
