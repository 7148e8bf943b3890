//! `mpmwatch`: the command line. Parses, calls the library, prints.

mod cmd;

use clap::Parser;

/// Detects, localises and explains model–plant mismatch in model-based control loops.
///
/// mpmwatch estimates the mutual information between the dithers added to the manipulated
/// variables and the model residuals (Chen et al., Ind. Eng. Chem. Res. 2013). A residual that
/// carries information about a dither means the model of that channel is wrong.
#[derive(Parser)]
#[command(name = "mpmwatch", version, about, long_about)]
struct Cli {
    #[command(subcommand)]
    verb: Verb,
}

#[derive(clap::Subcommand)]
enum Verb {
    /// One MI estimate between two CSV columns, optionally with its surrogate threshold.
    Mi(cmd::mi::Args),
    /// Timings of the estimation core (run with --release).
    Bench(cmd::bench::Args),
}

fn main() -> anyhow::Result<()> {
    let cli = Cli::parse();
    match cli.verb {
        Verb::Mi(args) => cmd::mi::run(args),
        Verb::Bench(args) => cmd::bench::run(args),
    }
}
