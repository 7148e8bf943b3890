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
    let k0 = ctx.dc_gain(i);
    let mut p = BTreeMap::new();
    let s = match &f.term {
        Term::Gain => {
            p.insert("gain_ratio".into(), 1.0 + th);
            p.insert("gain".into(), k0 * (1.0 + th));
            p.insert("nominal_gain".into(), k0);
            format!(
                "the gain of {input}→{output} is {:.2}× the model's ({} instead of {})",
                1.0 + th,
                num(k0 * (1.0 + th)),
                num(k0)
            )
        }
        Term::DeadTime(d) => {
            let d0 = ctx.delay(i) as f64 * ts;
            let extra = *d as f64 * ts;
            p.insert("extra_dead_time_s".into(), extra);
            p.insert("dead_time_s".into(), d0 + extra);
            format!(
                "{output} answers {input} {} s {} than the model says (dead time {} s, not {} s)",
                num(extra.abs()),
                if *d >= 0 { "later" } else { "earlier" },
                num(d0 + extra),
                num(d0)
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
                num(t1),
                num(t0)
            )
        }
        Term::MissingCoupling { pole, delay } => {
            let tau = if *pole > 0.0 { -ts / pole.ln() } else { 0.0 };
            p.insert("gain".into(), th);
            p.insert("time_constant_s".into(), tau);
            p.insert("dead_time_s".into(), *delay as f64 * ts);
            format!(
                "{output} responds to {input} although the model says it does not: gain {}, time constant {} s, dead time {} s",
                num(th),
                num(tau),
                num(*delay as f64 * ts)
            )
        }
        Term::DeadZone { centre, w } => {
            p.insert("width".into(), *w);
            p.insert("centre".into(), u0 + centre);
            format!(
                "MV {input} has no effect on {output} inside {} ± {} (a dead zone)",
                num(u0 + centre),
                num(*w)
            )
        }
        Term::SaturationIn { lo, hi } => {
            let mut parts = Vec::new();
            if hi.is_finite() {
                p.insert("upper_limit".into(), u0 + hi);
                parts.push(format!("above {}", num(u0 + hi)));
            }
            if lo.is_finite() {
                p.insert("lower_limit".into(), u0 + lo);
                parts.push(format!("below {}", num(u0 + lo)));
            }
            format!("MV {input} stops acting on {output} {} (an actuator limit)", parts.join(" and "))
        }
        Term::SaturationOut { lo, hi } => {
            let mut parts = Vec::new();
            if hi.is_finite() {
                p.insert("upper_limit".into(), *hi);
                parts.push(format!("above {}", num(*hi)));
            }
            if lo.is_finite() {
                p.insert("lower_limit".into(), *lo);
                parts.push(format!("below {}", num(*lo)));
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
                "{output} responds to the {what} of {input}'s move: an extra {}·({input} − {}){power} through the channel's dynamics, fitted for {input} in [{}, {}] and continued along its tangent beyond it",
                num(th),
                num(c),
                num(lo),
                num(hi)
            )
        }
        Term::CubicOut => {
            p.insert("cubic_stiffness".into(), -th);
            p.insert("centre".into(), ctx.y0);
            format!(
                "a cubic restoring term is missing: {output} as the model simulates it (before the fitted offset of {}) feeds back −{}·({output} − {})³ into {input}'s channel (a hardening spring)",
                num(f.intercept),
                num(-th),
                num(ctx.y0)
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
                "{output} responds to a product of lagged input moves ({}; inputs numbered in --inputs order), coefficient {}",
                names.join(", "),
                num(th)
            )
        }
        Term::Backlash(w) => {
            p.insert("width".into(), *w);
            format!(
                "MV {input} acts on {output} through play of {} (backlash): reversals are lost until the input has moved that far",
                num(*w)
            )
        }
        Term::Coulomb { on_change } => {
            p.insert("friction".into(), -th);
            format!(
                "a constant force of {} (in {input}'s units) opposes the {} of {output} as the model simulates it, before the fitted offset of {} (Coulomb friction)",
                num(-th),
                if *on_change { "motion" } else { "sign" },
                num(f.intercept)
            )
        }
        Term::AbsSensor(o) => {
            p.insert("zero_offset".into(), *o);
            format!(
                "the {output} sensor reads the absolute value of the signal (|x − {}|): it cannot see the sign",
                num(*o)
            )
        }
        Term::StateLimit { state, level, spill, spills, .. } => {
            let name = ctx.state_names.get(*state).cloned().unwrap_or_else(|| format!("state {state}"));
            p.insert("state_index".into(), *state as f64);
            p.insert("level".into(), *level);
            let mut s = format!(
                "the model's {name} cannot rise above {} (an overflow the model leaves out)",
                num(*level)
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

/// A value in the user's units with at least four significant digits: fixed notation from
/// 0.001 to below a million (whole numbers from 1000 up), scientific outside, so a gain of 3e-10 (a flow in m³/s on a pressure in bar)
/// does not print as 0.0000.
pub(crate) fn num(v: f64) -> String {
    let a = v.abs();
    if a == 0.0 {
        "0".into()
    } else if !a.is_finite() {
        format!("{v}")
    } else {
        // The exponent after rounding to four digits: 0.99999 is 1.000e0, not 9.9999e-1.
        let sci = format!("{v:.3e}");
        let exp: i32 = sci.rsplit('e').next().and_then(|e| e.parse().ok()).unwrap_or(0);
        if (-3..6).contains(&exp) {
            let decimals = (3 - exp).max(0) as usize;
            format!("{v:.decimals$}")
        } else {
            sci
        }
    }
}

#[cfg(test)]
mod tests {
    use super::num;

    /// At least four significant digits, fixed notation from 0.001 to below a million,
    /// scientific outside; the digits are counted after rounding; a negative zero prints as 0.
    #[test]
    fn numbers_keep_four_significant_digits_in_any_units() {
        let cases = [
            (0.7339119, "0.7339"),
            (0.99999999, "1.000"),
            (509.43, "509.4"),
            (-12345.6, "-12346"),
            (0.0012, "0.001200"),
            (7.3389e-11, "7.339e-11"),
            (7.3389e11, "7.339e11"),
            (0.0, "0"),
            (-0.0, "0"),
        ];
        for (v, want) in cases {
            assert_eq!(num(v), want, "{v}");
        }
    }
}
