//! What a diagnosis is given, and the checks that every signal, setting and physical model is
//! usable before anything is fitted: a bad input is answered with an error naming it.

use mpmwatch_core::detect::{Method, Signal};
use mpmwatch_core::info::Lags;

use crate::PhysicalModel;
use crate::error::DiagnoseError;
use crate::select::Scoring;

/// The signals of one diagnosis, all on the time axis `time`.
#[derive(Debug, Clone)]
pub struct DiagnoseInput<'a> {
    /// Time axis, seconds.
    pub time: &'a [f64],
    /// Recorded inputs (MVs).
    pub inputs: Vec<Signal<'a>>,
    /// The dithers added to each input, by position; `None`: the inputs are their own
    /// excitation (open-loop records).
    pub excitations: Option<Vec<Signal<'a>>>,
    /// Recorded outputs.
    pub outputs: Vec<Signal<'a>>,
    /// The simulation of each output (same order), driven by the recorded inputs.
    pub simulated: Vec<Signal<'a>>,
    /// Per output (same order), the physical model behind its simulation when the caller has
    /// one: limits on the model's states and the inputs' actuator gains are then stated by
    /// re-running it ([`crate::physical`]). Empty: none. Open-loop records only: `diagnose` refuses it
    /// with excitations, but a record without excitations taken in a closed loop is the
    /// caller's to keep out (the test's null assumes inputs independent of the residual).
    pub physical: Vec<Option<&'a dyn PhysicalModel>>,
}

impl<'a> DiagnoseInput<'a> {
    /// An open-loop record of one input and one output, with the nominal's simulation of that
    /// output (under the output's name) and no physical model: the commonest diagnosis, a
    /// least-squares or first-principles model run over a step or PRBS test.
    pub fn open_loop(time: &'a [f64], input: Signal<'a>, output: Signal<'a>, simulated: &'a [f64]) -> Self {
        DiagnoseInput {
            time,
            inputs: vec![input],
            excitations: None,
            outputs: vec![output],
            simulated: vec![Signal { name: output.name, values: simulated }],
            physical: Vec::new(),
        }
    }
}

/// Options of a diagnosis.
#[derive(Debug, Clone, PartialEq)]
pub struct DiagnoseOptions {
    /// Fraction of the record held out at its end (default 0.3).
    pub holdout_fraction: f64,
    /// Surrogates per MI element (default 40).
    pub surrogates: usize,
    /// Seed of the surrogates (default 1).
    pub seed: u64,
    /// Lags of the MI profile (default 1..=15).
    pub lags: Lags,
    /// Multiplier of the BIC penalty per coefficient (default 1).
    pub penalty: f64,
    /// The honesty gate's margin (default 0.5): a finding is reported only when its correction
    /// raises the plain FIT, refitted on two blocks of the training part and scored on the
    /// third, by this many points on average. Open-loop records, and the grey-box path in a
    /// closed loop; the residual corrections of a closed loop use the next margin.
    pub min_gain_pct: f64,
    /// The honesty gate's margin on a dithered closed-loop record's residual corrections
    /// (default 2.0 points on average, no condition on single blocks). There the plain FIT is a
    /// weaker witness (feedback lets a correction cancel part of the disturbance), so its
    /// cross-validated gain is noisier: of five development findings with 0.5 to 2 points, three
    /// fell on the held-out tail (docs/diagnose-history.md, "The closed loop's margin"). A smaller gain
    /// still passes at `min_gain_pct` on average when no block is lower and its class's score
    /// leads every other class's by 10 units (the data single out what was left out).
    pub closed_loop_min_gain_pct: f64,
    /// Open loop: points of cross-validated FIT a drift term (a straight line in time) must add
    /// to the re-fitted linear model, on average over the blocks, for every grey-box structure
    /// and the nominal's reference to carry one, the drift also going the same way over both
    /// halves of the training part: an output drifting in a way no input carries bends every
    /// re-fit otherwise (`greybox::drift_gain`, `greybox::drift_is_one_line`). Default 1.0;
    /// `f64::INFINITY` never fits a drift.
    pub drift_min_gain_pct: f64,
    /// Samples skipped at the start of every fit (initial transients; default 20).
    pub warmup: usize,
    /// Closed loop: how hypotheses are scored (default: prediction error, [`Scoring`]).
    pub scoring: Scoring,
    /// Closed loop: explain the outputs the dithers' MI flags with the grey-box structures
    /// instead of residual corrections, each fitted by its one-step prediction error under an
    /// AR noise model and ranked by it out of sample (the honesty gate stays the plain FIT's).
    /// Off by default: on the wide generator it names fewer cases right than the residual
    /// corrections (docs/diagnose-history.md, "Closed loop, the grey-box path").
    pub greybox_closed_loop: bool,
    /// The MI matrix's decision rule in the locating step: [`Method::Family`] (default), one
    /// family-wise test per element over the lags and the statistics (pairwise MI, joint-lag
    /// MI, the cross-correlation) at a false-alarm rate of [`Self::alpha`] per record; or
    /// [`Method::Paper`], the paper's 6σ per lag and per norm (the diagnosis's rule until stop
    /// 32, about a one-in-a-billion test per lag, which left linear mismatches unflagged).
    pub locate: Method,
    /// Under [`Method::Family`]: the probability that a record whose every submodel is right
    /// has some element flagged by the MI matrix (default 0.01), split evenly over its elements
    /// (Bonferroni). The dither-projection test flags on its own besides (see
    /// [`crate::projection`]).
    pub alpha: f64,
}

impl Default for DiagnoseOptions {
    fn default() -> Self {
        Self {
            holdout_fraction: 0.3,
            surrogates: 40,
            seed: 1,
            lags: Lags { min: 1, max: 15 },
            penalty: 1.0,
            min_gain_pct: 0.5,
            closed_loop_min_gain_pct: 2.0,
            drift_min_gain_pct: 1.0,
            warmup: 20,
            scoring: Scoring::default(),
            greybox_closed_loop: false,
            locate: Method::Family,
            alpha: 0.01,
        }
    }
}

/// What the checks established.
pub(crate) struct Checked<'a> {
    /// The excitation of each input: the dithers, or the inputs themselves on an open-loop record.
    pub exc: Vec<Signal<'a>>,
    /// Samples in the training part (the rest is the held-out tail).
    pub n_train: usize,
    /// The sample time, seconds.
    pub ts: f64,
}

/// Checks `input` and `opts` (lengths, finiteness, the time axis, the settings' ranges, each
/// physical model against its simulation).
pub(crate) fn validate<'a>(
    input: &DiagnoseInput<'a>,
    opts: &DiagnoseOptions,
) -> Result<Checked<'a>, DiagnoseError> {
    let n = input.time.len();
    let time_sig = Signal { name: "time", values: input.time };
    check(input.time, &time_sig)?;
    if input.inputs.is_empty() || input.outputs.is_empty() {
        return Err(DiagnoseError::invalid("signals", "at least one input and one output are needed"));
    }
    if input.simulated.len() != input.outputs.len() {
        return Err(DiagnoseError::invalid(
            "simulation",
            format!(
                "{} simulated outputs for {} recorded outputs",
                input.simulated.len(),
                input.outputs.len()
            ),
        ));
    }
    let exc = input.excitations.clone().unwrap_or_else(|| input.inputs.clone());
    if exc.len() != input.inputs.len() {
        return Err(DiagnoseError::invalid(
            "--excitations",
            format!("{} excitations for {} inputs (they pair by position)", exc.len(), input.inputs.len()),
        ));
    }
    for s in input.inputs.iter().chain(&exc).chain(&input.outputs).chain(&input.simulated) {
        check(input.time, s)?;
    }
    if !input.physical.is_empty() {
        if input.physical.len() != input.outputs.len() {
            return Err(DiagnoseError::invalid(
                "physical models",
                format!("{} entries for {} outputs", input.physical.len(), input.outputs.len()),
            ));
        }
        if input.excitations.is_some() && input.physical.iter().any(Option::is_some) {
            return Err(DiagnoseError::invalid(
                "physical models",
                "state limits are tested on open-loop records only (no excitations)",
            ));
        }
        for (j, m) in input.physical.iter().enumerate() {
            let Some(m) = m else { continue };
            if m.inputs() != input.inputs.len() {
                return Err(DiagnoseError::invalid(
                    "physical models",
                    format!(
                        "the model of output {} takes {} inputs, the record has {}",
                        input.outputs[j].name,
                        m.inputs(),
                        input.inputs.len()
                    ),
                ));
            }
            let sim = m.simulate();
            let s = input.simulated[j].values;
            let scale = 1.0 + s.iter().fold(0.0f64, |a, v| a.max(v.abs()));
            let gap = sim.iter().zip(s).map(|(a, b)| (a - b).abs()).fold(0.0, f64::max);
            if sim.len() != s.len() || gap > 1e-9 * scale {
                return Err(DiagnoseError::invalid(
                    "physical models",
                    format!(
                        "the model of output {} does not reproduce its simulation ({} samples, largest difference {gap:.3e})",
                        input.outputs[j].name,
                        sim.len()
                    ),
                ));
            }
        }
    }
    if !(0.05..=0.8).contains(&opts.holdout_fraction) {
        return Err(DiagnoseError::invalid(
            "holdout fraction",
            format!("{} is not in [0.05, 0.8]", opts.holdout_fraction),
        ));
    }
    for (name, margin) in
        [("minimum gain", opts.min_gain_pct), ("closed-loop minimum gain", opts.closed_loop_min_gain_pct)]
    {
        if !(margin.is_finite() && (0.0..=100.0).contains(&margin)) {
            return Err(DiagnoseError::invalid(name, format!("{margin} points is not in [0, 100]")));
        }
    }
    let drift = opts.drift_min_gain_pct;
    if !(drift == f64::INFINITY || (0.0..=100.0).contains(&drift)) {
        return Err(DiagnoseError::invalid(
            "drift minimum gain",
            format!("{drift} points is not in [0, 100] nor infinite (never a drift)"),
        ));
    }
    if !(opts.alpha > 0.0 && opts.alpha < 1.0) {
        return Err(DiagnoseError::invalid("alpha", format!("{} is not in (0, 1)", opts.alpha)));
    }
    let n_train = ((1.0 - opts.holdout_fraction) * n as f64).round() as usize;
    if n_train < 200 + opts.warmup {
        return Err(DiagnoseError::invalid(
            "record",
            format!("{n} samples leave {n_train} for training; at least {} are needed", 200 + opts.warmup),
        ));
    }
    let ts = sample_time(input.time)?;
    // An open-loop record's inputs are their own excitation. In a closed loop a dither may be
    // held at zero (an MV not excited, Proposition 4); the MI matrix skips it.
    let own_excitation = if input.excitations.is_none() { exc.as_slice() } else { &[] };
    for s in own_excitation {
        if let Some(v) = constant(&s.values[..n_train]) {
            return Err(DiagnoseError::invalid(
                format!("input `{}`", s.name),
                format!(
                    "it is constant on the training part (every value {v}), so its effect cannot be measured"
                ),
            ));
        }
    }
    for s in &input.outputs {
        for (part, rows) in [("training part", 0..n_train), ("held-out tail", n_train..n)] {
            if let Some(v) = constant(&s.values[rows]) {
                return Err(DiagnoseError::invalid(
                    format!("output `{}`", s.name),
                    format!(
                        "it is constant on the {part} (every value {v}); a FIT divides by the output's spread, so it is undefined there"
                    ),
                ));
            }
        }
    }

    Ok(Checked { exc, n_train, ts })
}

fn check(time: &[f64], s: &Signal<'_>) -> Result<(), DiagnoseError> {
    if s.values.len() != time.len() {
        return Err(DiagnoseError::LengthMismatch {
            name: s.name.to_string(),
            found: s.values.len(),
            reference: "time".into(),
            expected: time.len(),
        });
    }
    if let Some((index, &value)) = s.values.iter().enumerate().find(|(_, v)| !v.is_finite()) {
        return Err(DiagnoseError::NotFinite { name: s.name.to_string(), index, value });
    }
    if let Some((index, &value)) = s.values.iter().enumerate().find(|(_, v)| v.abs() > MAX_ABS) {
        return Err(DiagnoseError::invalid(
            format!("signal `{}`", s.name),
            format!(
                "{value:e} at row {index} is beyond ±{MAX_ABS:e}, where sums of squares overflow; rescale it"
            ),
        ));
    }
    Ok(())
}

/// The largest magnitude a signal may reach: a sum of a few thousand squares of it stays finite.
const MAX_ABS: f64 = 1e150;

/// The value of a series whose every value is the same, `None` when it varies (or is empty).
fn constant(x: &[f64]) -> Option<f64> {
    let first = *x.first()?;
    x.iter().all(|&v| v == first).then_some(first)
}

/// The median spacing of the time axis; it must increase strictly.
fn sample_time(time: &[f64]) -> Result<f64, DiagnoseError> {
    if let Some(k) = time.windows(2).position(|w| w[1] <= w[0]) {
        return Err(DiagnoseError::invalid(
            "time axis",
            format!("time does not increase at row {} ({} then {})", k + 1, time[k], time[k + 1]),
        ));
    }
    let mut d: Vec<f64> = time.windows(2).map(|w| w[1] - w[0]).collect();
    d.sort_by(f64::total_cmp);
    Ok(d.get(d.len() / 2).copied().unwrap_or(1.0))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The one-input, one-output record is an open-loop one: its excitation is the input
    /// itself, its simulation carries the output's name, and it holds no physical model; a
    /// simulation of another length is refused as any record's would be.
    #[test]
    fn an_open_loop_record_excites_with_its_input() {
        let time: Vec<f64> = (0..400).map(|t| 0.5 * f64::from(t)).collect();
        let (u, y): (Vec<f64>, Vec<f64>) = (0..400).map(|t| (f64::from(t % 7), f64::from(t % 5))).unzip();
        let (u_sig, y_sig) = (Signal { name: "u", values: &u }, Signal { name: "y", values: &y });
        let s: Vec<f64> = (0..400).map(|t| f64::from(t % 3)).collect();
        let input = DiagnoseInput::open_loop(&time, u_sig, y_sig, &s);
        assert_eq!(input.simulated[0].name, "y");
        assert!(input.excitations.is_none() && input.physical.is_empty());
        let checked = validate(&input, &DiagnoseOptions::default()).expect("a valid record");
        assert_eq!(checked.exc.len(), 1);
        assert_eq!(checked.exc[0].values, &u[..]);
        assert_eq!(checked.ts, 0.5);
        assert_eq!(checked.n_train, 280, "the default 30 % held out of 400 samples");
        let short = vec![0.0; 399];
        let input = DiagnoseInput::open_loop(&time, u_sig, y_sig, &short);
        assert!(validate(&input, &DiagnoseOptions::default()).is_err());
    }

    /// Each setting out of its range is refused with an error naming it, before anything is
    /// fitted.
    #[test]
    fn settings_out_of_range_are_named() {
        let time: Vec<f64> = (0..400).map(f64::from).collect();
        let x: Vec<f64> = (0..400).map(|t| f64::from(t % 7)).collect();
        let sig = |name| Signal { name, values: &x };
        let input = DiagnoseInput {
            time: &time,
            inputs: vec![sig("u1")],
            excitations: None,
            outputs: vec![sig("y1")],
            simulated: vec![sig("y1")],
            physical: Vec::new(),
        };
        assert!(validate(&input, &DiagnoseOptions::default()).is_ok());
        for (opts, name) in [
            (DiagnoseOptions { alpha: 0.0, ..Default::default() }, "alpha"),
            (DiagnoseOptions { alpha: 1.0, ..Default::default() }, "alpha"),
            (DiagnoseOptions { holdout_fraction: 0.9, ..Default::default() }, "holdout fraction"),
            (DiagnoseOptions { min_gain_pct: f64::NAN, ..Default::default() }, "minimum gain"),
            (DiagnoseOptions { drift_min_gain_pct: -1.0, ..Default::default() }, "drift minimum gain"),
            (DiagnoseOptions { drift_min_gain_pct: f64::NAN, ..Default::default() }, "drift minimum gain"),
            (
                DiagnoseOptions { closed_loop_min_gain_pct: -1.0, ..Default::default() },
                "closed-loop minimum gain",
            ),
        ] {
            let message = validate(&input, &opts).err().map(|e| e.to_string()).unwrap_or_default();
            assert!(message.contains(name), "{name}: {message}");
        }
    }
}
