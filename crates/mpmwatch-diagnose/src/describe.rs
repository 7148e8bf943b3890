//! Findings in words and engineering units: the summary sentence and the parameter map.

use std::collections::BTreeMap;

use super::candidates::{OutputCtx, Term};
use super::simulate::FittedTerm;

/// The summary sentence and parameters of a fitted term on `input → output`; `ts` is the sample
/// time in seconds.
pub fn describe(
    ctx: &OutputCtx,
    f: &FittedTerm,
    input: &str,
    output: &str,
    ts: f64,
) -> (String, BTreeMap<String, f64>) {
    let i = f.input;
    let th = f.coefs.first().copied().unwrap_or(0.0);
    let u0 = ctx.u0[i];
    let k0 = ctx.model.dc_gain(i);
    let mut p = BTreeMap::new();
    let s = match &f.term {
        Term::Gain => {
            p.insert("gain_ratio".into(), 1.0 + th);
            p.insert("gain".into(), k0 * (1.0 + th));
            p.insert("nominal_gain".into(), k0);
            format!(
                "the gain of {input}→{output} is {:.2}× the model's ({:.3} instead of {:.3})",
                1.0 + th,
                k0 * (1.0 + th),
                k0
            )
        }
        Term::DeadTime(d) => {
            let d0 = ctx.model.delay(i) as f64 * ts;
            p.insert("extra_dead_time_s".into(), *d as f64 * ts);
            p.insert("dead_time_s".into(), d0 + *d as f64 * ts);
            format!(
                "{output} answers {input} {} s later than the model says (dead time {} s, not {} s)",
                fmt(*d as f64 * ts),
                fmt(d0 + *d as f64 * ts),
                fmt(d0)
            )
        }
        Term::TimeConstant { p0, p1 } => {
            let (t0, t1) = (-ts / p0.ln(), -ts / p1.ln());
            p.insert("time_constant_s".into(), t1);
            p.insert("nominal_time_constant_s".into(), t0);
            p.insert("ratio".into(), t1 / t0);
            format!(
                "the {input}→{output} response is {} than modelled: time constant about {} s instead of {} s",
                if t1 > t0 { "slower" } else { "faster" },
                fmt(t1),
                fmt(t0)
            )
        }
        Term::MissingCoupling { pole, delay } => {
            let tau = if *pole > 0.0 { -ts / pole.ln() } else { 0.0 };
            p.insert("gain".into(), th);
            p.insert("time_constant_s".into(), tau);
            p.insert("dead_time_s".into(), *delay as f64 * ts);
            format!(
                "{output} responds to {input} although the model says it does not: gain {:.3}, time constant {} s, dead time {} s",
                th,
                fmt(tau),
                fmt(*delay as f64 * ts)
            )
        }
        Term::DeadZone { centre, w } => {
            p.insert("width".into(), *w);
            p.insert("centre".into(), u0 + centre);
            format!(
                "MV {input} has no effect on {output} inside {} ± {} (a dead zone)",
                fmt(u0 + centre),
                fmt(*w)
            )
        }
        Term::SaturationIn { lo, hi } => {
            let mut parts = Vec::new();
            if hi.is_finite() {
                p.insert("upper_limit".into(), u0 + hi);
                parts.push(format!("above {}", fmt(u0 + hi)));
            }
            if lo.is_finite() {
                p.insert("lower_limit".into(), u0 + lo);
                parts.push(format!("below {}", fmt(u0 + lo)));
            }
            format!("MV {input} stops acting on {output} {} (an actuator limit)", parts.join(" and "))
        }
        Term::SaturationOut { lo, hi } => {
            let mut parts = Vec::new();
            if hi.is_finite() {
                p.insert("upper_limit".into(), *hi);
                parts.push(format!("above {}", fmt(*hi)));
            }
            if lo.is_finite() {
                p.insert("lower_limit".into(), *lo);
                parts.push(format!("below {}", fmt(*lo)));
            }
            format!("{output} cannot go {} while the model's can (an overflow or clip)", parts.join(" or "))
        }
        Term::Quadratic | Term::Cubic => {
            let (lo, hi) = ctx.u_range.get(i).map_or((f64::NAN, f64::NAN), |&(a, b)| (u0 + a, u0 + b));
            p.insert("coefficient".into(), th);
            p.insert("fitted_range_low".into(), lo);
            p.insert("fitted_range_high".into(), hi);
            let (what, power, c) = if matches!(f.term, Term::Quadratic) {
                ("square", "²", u0 - f.coefs.get(1).copied().unwrap_or(0.0) / (2.0 * th))
            } else {
                ("cube", "³", u0)
            };
            p.insert("centre".into(), c);
            format!(
                "{output} responds to the {what} of {input}'s move: an extra {th:.3}·({input} − {}){power} through the channel's dynamics, fitted for {input} in [{}, {}] and held at that range's edges beyond it",
                fmt(c),
                fmt(lo),
                fmt(hi)
            )
        }
        Term::CubicOut => {
            p.insert("cubic_stiffness".into(), -th);
            p.insert("centre".into(), ctx.y0);
            format!(
                "a cubic restoring term is missing: {output} as the model simulates it (before the fitted offset of {}) feeds back −{:.4}·({output} − {})³ into {input}'s channel (a hardening spring)",
                fmt(f.intercept),
                -th,
                fmt(ctx.y0)
            )
        }
        Term::Bilinear(pairs) => {
            let names: Vec<String> = pairs
                .iter()
                .map(|&(a, la, b, lb)| format!("u{}(t−{la})·u{}(t−{lb})", a + 1, b + 1))
                .collect();
            for (k, (&(a, la, b, lb), c)) in pairs.iter().zip(&f.coefs).enumerate() {
                p.insert(format!("coefficient_{}", k + 1), *c);
                p.insert(format!("lag_a_s_{}", k + 1), la as f64 * ts);
                p.insert(format!("lag_b_s_{}", k + 1), lb as f64 * ts);
                p.insert(format!("input_a_{}", k + 1), a as f64);
                p.insert(format!("input_b_{}", k + 1), b as f64);
            }
            format!(
                "{output} responds to a product of lagged input moves ({}; inputs numbered in --inputs order), coefficient {:.3}",
                names.join(", "),
                th
            )
        }
        Term::Backlash(w) => {
            p.insert("width".into(), *w);
            format!(
                "MV {input} acts on {output} through play of {} (backlash): reversals are lost until the input has moved that far",
                fmt(*w)
            )
        }
        Term::Coulomb { on_change } => {
            p.insert("friction".into(), -th);
            format!(
                "a constant force of {:.3} (in {input}'s units) opposes the {} of {output} as the model simulates it, before the fitted offset of {} (Coulomb friction)",
                -th,
                if *on_change { "motion" } else { "sign" },
                fmt(f.intercept)
            )
        }
        Term::AbsSensor(o) => {
            p.insert("zero_offset".into(), *o);
            format!(
                "the {output} sensor reads the absolute value of the signal (|x − {}|): it cannot see the sign",
                fmt(*o)
            )
        }
        Term::StateLimit { state, level, spill, spills, .. } => {
            let name = ctx.state_names.get(*state).cloned().unwrap_or_else(|| format!("state {state}"));
            p.insert("state_index".into(), *state as f64);
            p.insert("level".into(), *level);
            let mut s = format!(
                "the model's {name} cannot rise above {} (an overflow the model leaves out)",
                fmt(*level)
            );
            if *spills {
                p.insert("spill_fraction".into(), *spill);
                s.push_str(&format!(
                    "; {:.0} % of what overflows reaches the next stage on the way to {output}",
                    100.0 * spill
                ));
            }
            s
        }
        Term::ModelGain { ratio, .. } => {
            p.insert("gain_ratio".into(), *ratio);
            format!(
                "{input} acts on the model {ratio:.2}× as strongly as modelled (an actuator gain, stated through the physical model)"
            )
        }
    };
    p.insert("intercept".into(), f.intercept);
    (s, p)
}

fn fmt(v: f64) -> String {
    let a = v.abs();
    if a == 0.0 {
        "0".into()
    } else if a >= 100.0 {
        format!("{v:.0}")
    } else if a >= 1.0 {
        format!("{v:.2}")
    } else {
        format!("{v:.3}")
    }
}
