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
    ///
    /// Estimates I(x(t); y(t+L)). The file's first column is `time`; --x and --y name two
    /// other columns. A positive lag pairs x with later y (a dither against the future
    /// residual, as in the paper). The estimator is KSG algorithm 1 for a continuous x and its
    /// discrete-x form (Ross 2014) when x has few levels, as a PRBS dither does. With
    /// --surrogates M, the estimate is tested against M surrogates (circular shifts of a
    /// discrete x, iAAFT of a continuous one) and the critical value mean + z·sd is printed.
    ///
    /// Example: mpmwatch mi run.csv --x ud1 --y e1 --lag 2 --units bits --surrogates 100
    Mi(cmd::mi::Args),
    /// The MI matrix of a recording: which MV→CV submodels are wrong.
    ///
    /// For every dither × residual pair: MI against lag (tmin..tmax), its norm (eq 19) and a
    /// critical value from surrogates (mean + z·sd, eq 11), also for the embedding of two
    /// consecutive dither lags (which catches interactions such as u(t-1)·u(t-2)); the
    /// cross-correlation baseline beside it; and a verdict per channel from the paper's
    /// Propositions 1-4: mismatch, clean, or implicated by feedback. Residuals are given as
    /// columns (--residual) or computed as outputs minus a simulation CSV (--output,
    /// --simulated). --figures writes MI and CCF against lag and the matrix heat map.
    ///
    /// Example: mpmwatch analyze run.csv --dither ud1,ud2 --residual e1,e2 --figures out/
    Analyze(cmd::analyze::Args),
    /// Every scenario of the paper, re-run; each claim against our result.
    ///
    /// Simulates model 1, the continuous 2×3 plant under MPC and the Hammerstein 3×3 plant
    /// under NMPC (with and without their mismatches and the changed disturbance), analyses
    /// each with the default MI matrix, runs the data-length and excitation studies and the
    /// false-alarm rate over 50 seeds per matched case, and writes DIR/report.md (a table:
    /// the paper's claim | our result | holds?), DIR/report.json and the figures. Takes a few
    /// minutes in a release build.
    ///
    /// Example: cargo run --release -- reproduce --out out/reproduce
    Reproduce(cmd::reproduce::Args),
    /// Timings of the estimation core (run with --release).
    ///
    /// Reports the median time of one binary-dither estimate and one continuous KSG estimate
    /// at length N (k = 4), of a binary-dither estimate per lag of a 20-lag profile (the
    /// residual sorted once and reused, as an analysis spends its estimates), of one iAAFT
    /// surrogate, and the wall time of a full 3×3 norm-of-MI matrix (binary dithers, lags
    /// 1..=20, 100 surrogates per element, all threads), on seeded synthetic data. A debug
    /// build is about ten times slower. `scripts/bench_sklearn.py` sets these beside
    /// scikit-learn's in one run. `--diagnose` times one open-loop diagnosis on one thread and
    /// on every thread instead (docs/performance.md).
    ///
    /// Example: cargo run --release -- bench --n 2048 --json
    ///
    /// Example: cargo run --release -- bench --diagnose --n 3000
    Bench(cmd::bench::Args),
    /// Simulate one of the paper's plants and write its CSV (see `simulate --help`).
    Simulate(cmd::simulate::Args),
    /// The online monitor: zenoh in; alarms, the MI matrix, metrics and an HTTP API out.
    ///
    /// Subscribes to <prefix>/<controller>/{mv,dither,cv,pred}/<tag>, aligns the samples on each
    /// controller's grid, analyses a bounded window on a schedule and raises debounced alarms
    /// per MV→CV channel. See `serve --help` and config/default.toml.
    ///
    /// Example: mpmwatch serve --config config/examples/continuous2x3.toml
    Serve(cmd::serve::Args),
    /// Load generator: synthetic controllers publishing over zenoh into a monitor.
    ///
    /// N controllers × (MVs, PRBS dithers, CVs, predictions) at a rate, one sample or a batch
    /// per message, for a duration, on the monitor's keys and payloads; prints the samples/s it
    /// achieved (--json for one object). The residuals carry a planted mismatch on ud1→y1, so
    /// the monitor's analyses have real work. `loadgen --help` explains rate and accounting.
    ///
    /// Example: mpmwatch loadgen --connect tcp/127.0.0.1:7447 --controllers 20 --rate 1000 --batch 100
    Loadgen(cmd::loadgen::Args),
    /// One-command demo: a simulated MPC loop publishing into the monitor, and the status page.
    ///
    /// Starts an embedded zenoh peer on loopback, the monitor with its HTTP page, and the
    /// paper's continuous 2×3 plant in accelerated time; after a while the plant changes
    /// (a: 0.2 → 0.8) and the alarm rises on u1's channels. Prints the URL and what to watch.
    ///
    /// Example: cargo run --release -- demo
    Demo(cmd::demo::Args),
    /// Say what physics a simulation left out, fit it, and show the fit improve on held-out data.
    ///
    /// Residuals are recorded minus simulated outputs. (1) Locate: the MI matrix of the
    /// excitations (--excitations, or the inputs themselves for open-loop records) against the
    /// residuals, on the training part, says which input→output channels are wrong. (2) Name.
    /// Open loop (no --excitations): each output is explained by grey-box structures, the
    /// nominal's linear dynamics re-estimated together with one physics element (dead zone,
    /// saturation, polynomial, backlash on an input; |x| sensor, clip or square-law bend on the
    /// output; Coulomb friction or a cubic spring fed back), fitted by simulation error; a
    /// linear re-fit always competes. An output whose training part sits at its extreme value
    /// on 1 % of its rows or more (at least 5), ten times as often as it holds a value on
    /// average (for example a transmitter at the end of its span), is read through that range
    /// by every structure and by the nominal it is compared with; the range alone is named
    /// (`saturation` on the output) when no element is and the range adds more than the
    /// linear change beside it. Closed loop: on each flagged channel every candidate
    /// physics (gain, time_constant, dead_time, missing_coupling, dead_zone, saturation,
    /// quadratic, cubic, bilinear, backlash, coulomb_friction, abs_sensor) is fitted as a
    /// correction, instrumented by the dither-driven part of the inputs, and scored by one-step
    /// prediction error under a noise model. Both choose by blocked cross-validation inside the
    /// training part with a parsimony penalty. (3) Gate: a finding is reported only when its
    /// correction raises the FIT on held-back training data by --min-gain points; otherwise
    /// `unexplained`, naming the best candidate and its gain. (4) Prove: FIT% before → after on the last
    /// --holdout-fraction of the record, which no step above has seen; where that tail leaves
    /// the range the training part visited, the report says so (`holdout.beyond_training`), and
    /// a correction is extrapolated there.
    ///
    /// Record length: the training part must hold the plant's slow modes several times over,
    /// since a correction slower than a validation block is withheld (unless it is an
    /// integrator, the finding then says how long a record would give blocks that long). On
    /// generated open-loop cases, 3000 samples name the physics in about 91 % of cases (eleven
    /// sets of 45, stops 67–73), 1500 and 1000 samples in about 84 % (one set each) and 6000 in
    /// 45 of 45; a slow plant (a tank) is named less often in a short record
    /// (docs/diagnose-history.md, stop 73). Time grows about in proportion to the record: one
    /// open-loop output took 16 to 32 s at 3000 samples and 1.4 to 5.5 min at 24 000 on a
    /// 2-core machine (docs/diagnose.md, "Time against record length"); cut a much longer
    /// record to a window that holds the slow modes several times over. In open loop every
    /// element is tried on every input and each input has a channel of its own to fit: in the
    /// generated cases two inputs took about four times as long as one (docs/diagnose-history.md,
    /// stop 63). Those times are on one thread; the hypotheses are fitted on every core, with
    /// the same decisions, 1.3 to 1.8 times faster on two (`mpmwatch bench --diagnose`).
    ///
    /// Progress: each stage as it starts goes to stderr with the seconds since the start
    /// (locating, each output explained, done); stdout keeps the findings and FITs alone.
    ///
    /// Example: mpmwatch diagnose --recorded rec.csv --simulated sim.csv --inputs u1,u2
    ///          --excitations d1,d2 --outputs y1,y2 --report diag.json --corrected corr.csv
    Diagnose(cmd::diagnose::Args),
    /// The diagnosis proof: concealed simulated cases and the real recordings.
    ///
    /// Runs 28 seeded closed-loop cases (one hidden effect each, every vocabulary class twice,
    /// disturbance-only and no-change cases; 1×1, 2×2, 3×3; binary and uniform dithers) and the
    /// real recordings under --data (Silverbox, coupled electric drives, TCLab, cascaded tanks),
    /// and writes DIR/casebook.md (table, rates, figures) and DIR/casebook.json. Progress on
    /// stderr. Takes several minutes in a release build. --wide COUNT replaces the 28 fixed
    /// cases by COUNT cases whose plant, PI tuning, disturbance, dither level and effect are all
    /// drawn at random: the check on cases nobody picked.
    ///
    /// Example: cargo run --release -- casebook --out out/casebook --data ../shared/data
    ///          cargo run --release -- casebook --out out/wide --wide 60 --seed 7000 --simulated-only
    Casebook(cmd::casebook::Args),
}

/// Runs the verb; an error is printed with its causes, as anyhow prints it, but without a
/// backtrace even where `RUST_BACKTRACE` is set: a user needs the bad input's name, not the
/// call stack.
fn main() -> std::process::ExitCode {
    let cli = Cli::parse();
    let result = match cli.verb {
        Verb::Mi(args) => cmd::mi::run(args),
        Verb::Bench(args) => cmd::bench::run(args),
        Verb::Analyze(args) => cmd::analyze::run(args),
        Verb::Reproduce(args) => cmd::reproduce::run(args),
        Verb::Simulate(args) => cmd::simulate::run(args),
        Verb::Serve(args) => cmd::serve::run(args),
        Verb::Demo(args) => cmd::demo::run(args),
        Verb::Loadgen(args) => cmd::loadgen::run(args),
        Verb::Diagnose(args) => cmd::diagnose::run(args),
        Verb::Casebook(args) => cmd::casebook::run(args),
    };
    match result {
        Ok(()) => std::process::ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("Error: {e}");
            let causes: Vec<String> = e.chain().skip(1).map(|c| c.to_string()).collect();
            if !causes.is_empty() {
                eprintln!("\nCaused by:");
                causes.iter().for_each(|c| eprintln!("    {c}"));
            }
            std::process::ExitCode::FAILURE
        }
    }
}
