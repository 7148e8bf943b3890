//! What a re-fitted linear model changes against the nominal, for a finding that is a linear
//! change: a gain, a time constant or a dead time, read off the two step responses (the
//! re-fit's and the nominal's own channel), or a missing coupling, the re-fit's response where
//! the nominal has no channel; the responses drawn, and the note a dead time at the search's
//! bound carries.

use std::collections::BTreeMap;

use super::{ElementCurve, Fitted, Layout, Names, Orders};
use crate::candidates::Physics;
use crate::describe::num;
use crate::nominal::NominalArx;
use mpmwatch_core::numerics::median;

/// The share of its final value a step response must pass to have moved. A re-fit from noisy
/// data puts a small coefficient on every tap it is given, and one ahead of the true dead time
/// would otherwise count as the response's start (a re-fitted extra sample of dead time read
/// as a time constant); a path that carries a hundredth of the gain in its first sample is
/// still a start.
const FIRST_MOVE: f64 = 0.01;

/// Response of input `i` through its channel of a fitted linear structure (the linear model on
/// input 0, [`Layout`]) to a unit step at sample 1 (as the nominal's channel is stepped).
fn step(f: &Fitted, orders: &Orders, i: usize, n: usize) -> Vec<f64> {
    let mut u = vec![1.0; n];
    u[0] = 0.0;
    response(f, orders, i, &u)
}

/// Input `i`'s contribution through its channel of a fitted linear structure (the linear model
/// on input 0, [`Layout`]) to `x`, from rest at `x(0)` (from 0 for a channel without a steady
/// state), as [`NominalArx::channel`] gives the nominal's.
fn response(f: &Fitted, orders: &Orders, i: usize, x: &[f64]) -> Vec<f64> {
    let l = Layout::new(orders, orders.nk.len(), 0, 0);
    let (alpha, beta) = (&f.theta[l.alpha(i)], &f.theta[l.beta(i)]);
    let x0 = x.first().copied().unwrap_or(0.0);
    let den = 1.0 - alpha.iter().sum::<f64>();
    let rest = if den.abs() > 1e-9 { beta.iter().sum::<f64>() * x0 / den } else { 0.0 };
    let mut y = vec![0.0; x.len()];
    for t in 0..x.len() {
        let mut v = 0.0;
        for (k, a) in alpha.iter().enumerate() {
            v += a * if t > k { y[t - k - 1] } else { rest };
        }
        for (k, b) in beta.iter().enumerate() {
            let lag = orders.nk[i] + k;
            v += b * if t >= lag { x[t - lag] } else { x0 };
        }
        y[t] = v;
    }
    y
}

/// The input whose channel a fitted linear structure (the linear model on input 0) changes
/// most against the nominal's: the largest RMS difference, over `rows`, between the two
/// channels' responses to the recorded input (about its median). With several inputs a re-fit
/// changes every channel a little; the finding names the one it changes most.
pub(super) fn changed_most(
    nominal: &NominalArx,
    f: &Fitted,
    orders: &Orders,
    u: &[&[f64]],
    rows: std::ops::Range<usize>,
) -> usize {
    let gap = |i: usize| {
        let m = median(u[i]);
        let x: Vec<f64> = u[i].iter().map(|v| v - m).collect();
        let (new, old) = (response(f, orders, i, &x), nominal.channel(i, &x));
        let rows = rows.start.min(x.len())..rows.end.min(x.len());
        let n = rows.len().max(1) as f64;
        (rows.map(|t| (new[t] - old[t]).powi(2)).sum::<f64>() / n).sqrt()
    };
    (0..u.len()).map(|i| (i, gap(i))).fold((0, f64::NEG_INFINITY), |b, c| if c.1 > b.1 { c } else { b }).0
}

/// The first move of a step response (the first sample beyond [`FIRST_MOVE`] of its final
/// value) and the samples from it to 63 % of the final value.
fn rise(step: &[f64]) -> (usize, f64) {
    let fin = step.last().copied().unwrap_or(0.0);
    if fin.abs() < 1e-300 {
        return (0, 1.0);
    }
    let start = step.iter().position(|v| (v / fin).abs() > FIRST_MOVE).unwrap_or(0);
    let t63 = step.iter().position(|v| v / fin >= 1.0 - (-1.0f64).exp()).unwrap_or(step.len() - 1);
    (start, (t63.saturating_sub(start) as f64).max(0.5))
}

/// The two step responses of a linear change, drawn from the step until both have had five of
/// their time constants after their dead time (at least 20 samples), in seconds.
fn step_curve(
    physics: Physics,
    s_new: &[f64],
    s_old: &[f64],
    settle: usize,
    ts: f64,
    names: &Names<'_>,
    i: usize,
) -> ElementCurve {
    let end = settle.clamp(20, s_new.len());
    let at = |s: &[f64]| -> Vec<(f64, f64)> { (0..end).map(|t| (t as f64 * ts, s[t])).collect() };
    let (inp, out) = (names.inputs[i], names.output);
    ElementCurve {
        physics,
        x_label: format!("time since a unit step of {inp} [s]"),
        y_label: format!("{out}'s response"),
        points: at(s_new),
        baseline: at(s_old),
        label: format!("re-fitted to the record ({})", physics.name()),
        baseline_label: "the model".into(),
    }
}

/// A dead time at the search's bound `longest` is a boundary estimate: the fit would have taken
/// a longer one had it been offered, so the figure is a lower bound, and the reader is told.
/// Empty otherwise.
pub(super) fn at_the_bound(physics: Physics, orders: &Orders, i: usize, longest: usize) -> String {
    if physics == Physics::DeadTime && orders.nk.get(i).is_some_and(|&k| k >= longest) {
        format!(
            "; this is the longest dead time the re-fit searches ({longest} samples), so the record's may be longer"
        )
    } else {
        String::new()
    }
}

/// What a linear re-fit changes against the nominal, for input `i`: a missing coupling when the
/// model has no path from it (`modelled` false), the dead time when the responses start at
/// different samples, else the gain or the time constant, whichever moved most (as a log
/// ratio); with both step responses drawn.
pub(super) fn linear_change(
    nominal: &NominalArx,
    f: &Fitted,
    orders: &Orders,
    i: usize,
    modelled: bool,
    ts: f64,
    names: &Names<'_>,
) -> (Physics, String, BTreeMap<String, f64>, ElementCurve) {
    // Long enough for the response to settle after the longest dead time searched.
    let n = 2000 + orders.nk.iter().copied().max().unwrap_or(0);
    let mut u = vec![1.0; n];
    u[0] = 0.0;
    let s_new = step(f, orders, i, n);
    let s_old = nominal.channel(i, &u);
    let (d_new, tau_new) = rise(&s_new);
    let (d_old, tau_old) = rise(&s_old);
    let settle = |d: usize, tau: f64| d as f64 + 5.0 * tau;
    let settle = settle(d_new, tau_new).max(settle(d_old, tau_old)).ceil() as usize + 1;
    let (physics, summary, parameters) = if modelled {
        change(&s_new, &s_old, (d_new, tau_new), (d_old, tau_old), ts, names, i)
    } else {
        let (g, inp, out) = (s_new[n - 1], names.inputs[i], names.output);
        (
            Physics::MissingCoupling,
            format!(
                "{inp} acts on {out} (steady-state gain {}, dead time {} s), a path the model leaves out",
                num(g),
                num(d_new as f64 * ts)
            ),
            BTreeMap::from([("gain".into(), g), ("dead_time_s".into(), d_new as f64 * ts)]),
        )
    };
    (physics, summary, parameters, step_curve(physics, &s_new, &s_old, settle, ts, names, i))
}

/// The change a linear re-fit names, from the two step responses and their (dead time, time
/// constant) in samples.
fn change(
    s_new: &[f64],
    s_old: &[f64],
    (d_new, tau_new): (usize, f64),
    (d_old, tau_old): (usize, f64),
    ts: f64,
    names: &Names<'_>,
    i: usize,
) -> (Physics, String, BTreeMap<String, f64>) {
    let n = s_new.len();
    let (g_new, g_old) = (s_new[n - 1], s_old[n - 1]);
    let (inp, out) = (names.inputs[i], names.output);
    if d_new != d_old {
        let extra = (d_new as f64 - d_old as f64) * ts;
        return (
            Physics::DeadTime,
            format!(
                "{inp} reaches {out} after {} s, the model says {} s (dead time {}{} s)",
                num(d_new as f64 * ts),
                num(d_old as f64 * ts),
                if extra >= 0.0 { "+" } else { "" },
                num(extra)
            ),
            BTreeMap::from([("extra_dead_time_s".into(), extra)]),
        );
    }
    let gain_ratio = g_new / g_old;
    let tau_ratio = tau_new / tau_old;
    let log = |r: f64| if r > 0.0 { r.ln().abs() } else { f64::INFINITY };
    if log(gain_ratio) >= log(tau_ratio) {
        (
            Physics::Gain,
            format!(
                "the gain of {inp}→{out} is {}, the model's {} (×{gain_ratio:.2})",
                num(g_new),
                num(g_old)
            ),
            BTreeMap::from([("gain".into(), g_new), ("model_gain".into(), g_old)]),
        )
    } else {
        (
            Physics::TimeConstant,
            format!(
                "the time constant of {inp}→{out} is {} s, the model's {} s",
                num(tau_new * ts),
                num(tau_old * ts)
            ),
            BTreeMap::from([
                ("time_constant_s".into(), tau_new * ts),
                ("model_time_constant_s".into(), tau_old * ts),
            ]),
        )
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use mpmwatch_core::model::Arx;

    /// A linear change is drawn as the two step responses: the model's (its own channel, as
    /// the finding compares) and the re-fit's, long enough for both to settle.
    /// A re-fit puts a small coefficient on a tap ahead of the true dead time: a step that
    /// carries 0.5 % of its final value there has not moved yet, one that carries 2 % has.
    /// The rise counts from the first move to the first sample at 63 % of the final value.
    #[test]
    fn a_step_moves_at_one_percent_of_its_final_value() {
        let late = [0.0, 0.005, 0.3, 0.6, 0.8, 0.9, 1.0];
        assert_eq!(rise(&late), (2, 2.0));
        let early = [0.0, 0.02, 0.3, 0.6, 0.8, 0.9, 1.0];
        assert_eq!(rise(&early), (1, 3.0));
        // A flat response has no move; its rise is half a sample, not zero.
        assert_eq!(rise(&[0.0; 5]), (0, 1.0));
        assert_eq!(rise(&[0.0, 0.0, 1.0]), (2, 0.5));
    }

    /// With two inputs the finding names the channel the re-fit changes most. The model:
    /// `y(t) = 0.8 y(t−1) + 0.2 u1(t−1) + 0.1 u2(t−1)`. A re-fit that keeps u1's channel and
    /// triples u2's gain names u2, and its u1 channel answers the record exactly as the model's
    /// does (to rounding, 1e-12, both from rest); one that changes u1's gain instead names u1.
    #[test]
    fn the_channel_a_refit_changes_most_is_named() {
        let arx = Arx::new(vec![1.0, -0.8], vec![vec![0.0, 0.2], vec![0.0, 0.1]], vec![0, 0]).unwrap();
        let model = NominalArx { arx, fit_pct: 100.0, score: f64::INFINITY };
        let n = 600;
        let u1: Vec<f64> = (0..n).map(|t| if (t / 31) % 2 == 0 { 1.0 } else { -1.0 }).collect();
        let u2: Vec<f64> = (0..n).map(|t| ((t / 19) % 3) as f64 - 1.0).collect();
        let orders = Orders { na: 1, nb: 1, nk: vec![1, 1], trend: false, reading: None };
        // [α of u1's channel, α of u2's, β of u1, β of u2, c].
        let u2_tripled = Fitted { p: vec![], theta: vec![0.8, 0.8, 0.2, 0.3, 0.0], noise: vec![] };
        assert_eq!(changed_most(&model, &u2_tripled, &orders, &[&u1, &u2], 0..n), 1);
        let same = response(&u2_tripled, &orders, 0, &u1);
        let own = model.channel(0, &u1);
        assert!(same.iter().zip(&own).all(|(a, b)| (a - b).abs() < 1e-12));
        let u1_doubled = Fitted { p: vec![], theta: vec![0.8, 0.8, 0.4, 0.1, 0.0], noise: vec![] };
        assert_eq!(changed_most(&model, &u1_doubled, &orders, &[&u1, &u2], 0..n), 0);
    }

    #[test]
    fn a_linear_change_draws_both_step_responses() {
        // The model: y(t) = 0.8 y(t−1) + 0.2 u(t−1), unit gain, time constant about 4.5 samples.
        let arx = Arx::new(vec![1.0, -0.8], vec![vec![0.0, 0.2]], vec![0]).unwrap();
        let model = NominalArx { arx, fit_pct: 100.0, score: f64::INFINITY };
        let names = Names { inputs: vec!["u"], output: "y" };
        let ts = 0.5;
        // Settled: within 2 % of the steady state (unit gain here). Five time constants leave
        // e^−5 ≈ 0.7 %; the time constant is read off the response in whole samples, which at
        // 4.5 samples can shorten the window to 20 samples after the move, 0.8^20 ≈ 1.2 %.
        let settled = |c: &[(f64, f64)]| (c.last().unwrap().1 - 1.0).abs() < 0.02;
        let first_move = |c: &[(f64, f64)]| c.iter().position(|p| p.1.abs() > 1e-9).unwrap();

        // The record's plant answers three samples later.
        let late = Fitted { p: vec![], theta: vec![0.8, 0.2, 0.0], noise: vec![] };
        let orders = Orders { na: 1, nb: 1, nk: vec![4], trend: false, reading: None };
        let (physics, summary, parameters, c) = linear_change(&model, &late, &orders, 0, true, ts, &names);
        assert_eq!(physics, Physics::DeadTime);
        assert!(!summary.contains("longest dead time"), "{summary}");
        assert!((parameters["extra_dead_time_s"] - 3.0 * ts).abs() < 1e-12, "{parameters:?}");
        assert_eq!(first_move(&c.points), first_move(&c.baseline) + 3);
        assert!(settled(&c.points) && settled(&c.baseline), "the window ends before both settle");
        let mut u = vec![1.0; c.baseline.len()];
        u[0] = 0.0;
        let own = model.channel(0, &u);
        for (k, &(t, v)) in c.baseline.iter().enumerate() {
            assert_eq!((t, v), (k as f64 * ts, own[k]), "the baseline is the model's own step response");
        }

        // A dead time at the search's bound is said to be one.
        let orders = Orders { na: 1, nb: 1, nk: vec![40], trend: false, reading: None };
        let (physics, ..) = linear_change(&model, &late, &orders, 0, true, ts, &names);
        assert_eq!(physics, Physics::DeadTime);
        let note = at_the_bound(physics, &orders, 0, 40);
        assert!(note.contains("longest dead time the re-fit searches (40 samples)"), "{note}");
        assert_eq!(at_the_bound(physics, &orders, 0, 41), "");
        assert_eq!(at_the_bound(Physics::Gain, &orders, 0, 40), "");

        // Twice the gain, the same timing.
        let strong = Fitted { p: vec![], theta: vec![0.8, 0.4, 0.0], noise: vec![] };
        let orders = Orders { na: 1, nb: 1, nk: vec![1], trend: false, reading: None };
        let (physics, _, _, c) = linear_change(&model, &strong, &orders, 0, true, ts, &names);
        assert_eq!(physics, Physics::Gain);
        let (end_new, end_old) = (c.points.last().unwrap().1, c.baseline.last().unwrap().1);
        assert!((end_new - 2.0).abs() < 0.04 && (end_old - 1.0).abs() < 0.02, "{end_new} {end_old}");

        // A path the model does not have is a missing coupling, whatever the step looks like;
        // its gain is the re-fit's steady state (0.4 / 0.2, settled to 0.8^2000 in 2000 samples).
        let (physics, summary, parameters, _) = linear_change(&model, &strong, &orders, 0, false, ts, &names);
        assert_eq!(physics, Physics::MissingCoupling, "{summary}");
        assert!((parameters["gain"] - 2.0).abs() < 1e-9, "{parameters:?}");
        assert!(summary.contains("a path the model leaves out"), "{summary}");
    }
}
