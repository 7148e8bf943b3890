//! The corrected simulation in simulation mode: the nominal simulation plus the fitted
//! correction, computed from the recorded inputs and the corrected simulation's own past
//! outputs only. The recorded outputs never enter (they only fit the coefficients).

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

/// A term fed back from the corrected output through the channel's dynamics:
/// `ŷ = s + θ0 + θ1·G0(g(ŷ))`, stepped sample by sample. The model's direct feed-through (if any)
/// sees the previous sample of `g`, so the loop stays causal.
fn recursive(ctx: &OutputCtx, f: &FittedTerm) -> Option<Vec<f64>> {
    let b = ctx.model.arx.numerator(f.input);
    let a = ctx.model.arx.denominator();
    let n = ctx.s.len();
    let th = f.coefs.first().copied().unwrap_or(0.0);
    let mut lin = vec![0.0; n];
    let mut w = vec![0.0; n];
    let mut yhat = vec![0.0; n];
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
        w[t] = match f.term {
            Term::CubicOut => (yhat[t] - ctx.y0).powi(3),
            Term::Coulomb { on_change } => {
                let m = if on_change { if t > 0 { yhat[t] - yhat[t - 1] } else { 0.0 } } else { yhat[t] };
                m.signum() * f64::from(u8::from(m != 0.0))
            }
            _ => 0.0,
        };
    }
    Some(c)
}
