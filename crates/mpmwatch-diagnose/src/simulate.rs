//! The corrected simulation in simulation mode: the nominal simulation plus the fitted
//! correction, computed from the recorded inputs and the corrected simulation's own past state
//! (its output without the fitted intercept) only. The recorded outputs never enter (they only
//! fit the coefficients).

use super::candidates::{OutputCtx, Term};

/// A term with its fitted coefficients on one input channel.
#[derive(Debug, Clone, PartialEq)]
pub struct FittedTerm {
    /// Input index.
    pub input: usize,
    /// The hypothesis.
    pub term: Term,
    /// Intercept.
    pub intercept: f64,
    /// One coefficient per column of the term.
    pub coefs: Vec<f64>,
}

/// The correction series over the whole record (`None` if the recursion diverges).
pub fn correction(ctx: &OutputCtx, f: &FittedTerm) -> Option<Vec<f64>> {
    if f.term.is_recursive() {
        return recursive(ctx, f);
    }
    let cols = ctx.columns(f.input, &f.term);
    let mut c = vec![f.intercept; ctx.s.len()];
    for (col, th) in cols.iter().zip(&f.coefs) {
        c.iter_mut().zip(col).for_each(|(a, b)| *a += th * b);
    }
    Some(c)
}

/// A term fed back from the simulated state through the channel's dynamics:
/// `x̂ = s + θ1·G0(g(x̂))`, `ŷ = x̂ + θ0`, stepped sample by sample. The intercept `θ0` is an offset
/// of the output (in a closed loop mostly the disturbance's level), so the force `g` (a spring's
/// cube, a friction's sign) sees the state without it, as the plant's force sees its state and
/// not the measured output. The model's direct feed-through (if any) sees the previous sample of
/// `g`, so the loop stays causal.
fn recursive(ctx: &OutputCtx, f: &FittedTerm) -> Option<Vec<f64>> {
    let b = ctx.model.arx.numerator(f.input);
    let a = ctx.model.arx.denominator();
    let n = ctx.s.len();
    let th = f.coefs.first().copied().unwrap_or(0.0);
    let mut lin = vec![0.0; n];
    let mut w = vec![0.0; n];
    let mut yhat = vec![0.0; n];
    let mut state = vec![0.0; n];
    let mut c = vec![0.0; n];
    let bound = 1e6 * (1.0 + ctx.s.iter().fold(0.0f64, |m, v| m.max(v.abs())));
    for t in 0..n {
        let mut v = 0.0;
        for (k, bk) in b.iter().enumerate() {
            let kk = k.max(1);
            if t >= kk {
                v += bk * w[t - kk];
            }
        }
        for (l, al) in a.iter().enumerate().skip(1) {
            if t >= l {
                v -= al * lin[t - l];
            }
        }
        lin[t] = v;
        c[t] = f.intercept + th * v;
        yhat[t] = ctx.s[t] + c[t];
        if !yhat[t].is_finite() || yhat[t].abs() > bound {
            return None;
        }
        state[t] = yhat[t] - f.intercept;
        w[t] = match f.term {
            Term::CubicOut => (state[t] - ctx.y0).powi(3),
            Term::Coulomb { on_change } => {
                let m = if on_change { if t > 0 { state[t] - state[t - 1] } else { 0.0 } } else { state[t] };
                m.signum() * f64::from(u8::from(m != 0.0))
            }
            _ => 0.0,
        };
    }
    Some(c)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The intercept is an offset of the output (in a closed loop, the disturbance's level), not
    /// of the state a fed-back force acts on: on a simulation that crosses zero, a friction or
    /// spring correction with intercept 0.7 is the one with intercept 0 shifted by 0.7, sample
    /// for sample. Were the force read off the offset output, every sample whose simulated state
    /// lies in (−0.7, 0) would flip the friction's sign and move the spring's cube. The friction
    /// on the state's change is a guard only: an offset cancels in a difference.
    #[test]
    fn the_intercept_does_not_move_the_state_a_force_acts_on() {
        let n = 400;
        let u: Vec<f64> = (0..n).map(|t| (0.05 * t as f64).sin()).collect();
        let ctx = crate::plan::delay_ctx(&u, 0.5);
        for term in [Term::Coulomb { on_change: false }, Term::Coulomb { on_change: true }, Term::CubicOut] {
            let f = |intercept| FittedTerm { input: 0, term: term.clone(), intercept, coefs: vec![-0.2] };
            let c0 = correction(&ctx, &f(0.0)).unwrap();
            let c1 = correction(&ctx, &f(0.7)).unwrap();
            assert!(c0.iter().any(|v| v.abs() > 0.01), "{term:?}: no force at all");
            let worst = c0.iter().zip(&c1).map(|(a, b)| (b - a - 0.7).abs()).fold(0.0, f64::max);
            assert!(worst < 1e-12, "{term:?}: the intercept moved the force by {worst}");
        }
    }
}
