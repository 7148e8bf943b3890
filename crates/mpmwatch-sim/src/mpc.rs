//! Linear model predictive control with input and move constraints, one QP per sample.
//!
//! The controller runs its linear model in parallel with the plant on the applied (total) input
//! and takes the current residual `d = y − ŷ` as a constant output disturbance over the
//! horizon: the IMC structure of the paper's Figure 1, offset-free for constant disturbances.

use super::closed_loop::Controller;
use super::error::SimError;
use super::qp::{self, TrackingQp};
use mpmwatch_core::model::{MimoModel, MimoState};

/// Horizons, weights and constraints of a predictive controller.
#[derive(Debug, Clone, PartialEq)]
pub struct MpcConfig {
    /// Prediction horizon (samples).
    pub np: usize,
    /// Control horizon (moves); inputs are held after it.
    pub nc: usize,
    /// Output tracking weights, one per output.
    pub q: Vec<f64>,
    /// Move-suppression weights, one per input.
    pub r: Vec<f64>,
    /// Lower input bounds.
    pub u_min: Vec<f64>,
    /// Upper input bounds.
    pub u_max: Vec<f64>,
    /// Largest move per sample (absolute value).
    pub du_max: Vec<f64>,
}

impl MpcConfig {
    /// Checks the sizes and signs against a model with `ny` outputs and `nu` inputs.
    pub fn validate(&self, ny: usize, nu: usize) -> Result<(), SimError> {
        if self.np == 0 || self.nc == 0 || self.nc > self.np {
            return Err(SimError::parameter(
                "MPC horizons",
                format!("np={}, nc={}", self.np, self.nc),
                "need 1 ≤ nc ≤ np",
            ));
        }
        for (name, v, len) in [
            ("q", &self.q, ny),
            ("r", &self.r, nu),
            ("u_min", &self.u_min, nu),
            ("u_max", &self.u_max, nu),
            ("du_max", &self.du_max, nu),
        ] {
            if v.len() != len {
                return Err(SimError::parameter(
                    &format!("MPC {name}"),
                    format!("{v:?}"),
                    &format!("needs {len} entries"),
                ));
            }
            if v.iter().any(|x| !x.is_finite()) {
                return Err(SimError::parameter(&format!("MPC {name}"), format!("{v:?}"), "must be finite"));
            }
        }
        if self.q.iter().chain(&self.r).any(|w| *w < 0.0) {
            return Err(SimError::parameter(
                "MPC weights",
                format!("q={:?}, r={:?}", self.q, self.r),
                "must be non-negative",
            ));
        }
        if self.u_min.iter().zip(&self.u_max).any(|(a, b)| a > b) || self.du_max.iter().any(|d| *d <= 0.0) {
            return Err(SimError::parameter(
                "MPC bounds",
                format!("u_min={:?}, u_max={:?}, du_max={:?}", self.u_min, self.u_max, self.du_max),
                "need u_min ≤ u_max and du_max > 0",
            ));
        }
        Ok(())
    }

    /// Projects a proposed move onto the input box and move limits. The solver's answer is
    /// already feasible to its tolerance (~1e-8); the projection makes the constraints exact.
    pub(crate) fn project(&self, u_prev: &[f64], u: &mut [f64]) {
        for i in 0..u.len() {
            let lo = self.u_min[i].max(u_prev[i] - self.du_max[i]);
            let hi = self.u_max[i].min(u_prev[i] + self.du_max[i]);
            u[i] = u[i].clamp(lo, hi);
        }
    }
}

/// Counters a caller can inspect after a run.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct MpcStats {
    /// QPs solved.
    pub solves: usize,
    /// QPs the solver did not finish (the controller then held its last output).
    pub failures: usize,
    /// Largest constraint violation of the raw solver answer, before projection.
    pub max_raw_violation: f64,
}

/// Sensitivity matrix `Θ` (`np·ny × nc·nu`): effect of input `i` at step `l` on output `j` at
/// step `p` (1-based), `h_ji(p − l)·slope(l, j, i)`, with the last control move held to the end.
pub(crate) fn sensitivity(
    impulses: &[Vec<f64>],
    ny: usize,
    nu: usize,
    np: usize,
    nc: usize,
    slope: impl Fn(usize, usize, usize) -> f64,
) -> Vec<f64> {
    let n = nc * nu;
    let mut theta = vec![0.0; np * ny * n];
    for p in 1..=np {
        for j in 0..ny {
            let h = |i: usize, m: usize| impulses[j * nu + i].get(m).copied().unwrap_or(0.0);
            for l in 0..nc.min(p + 1) {
                for i in 0..nu {
                    let effect = if l + 1 < nc { h(i, p - l) } else { (0..=p - l).map(|m| h(i, m)).sum() };
                    theta[((p - 1) * ny + j) * n + l * nu + i] = effect * slope(l, j, i);
                }
            }
        }
    }
    theta
}

/// Impulse responses of each channel's linear part, `np + 1` samples, row-major `j·nu + i`.
pub(crate) fn channel_impulses(model: &MimoModel, np: usize) -> Vec<Vec<f64>> {
    let (ny, nu) = (model.outputs(), model.inputs());
    (0..ny * nu)
        .map(|k| model.channel(k / nu, k % nu).map_or_else(Vec::new, |c| c.tf.impulse_response(np + 1)))
        .collect()
}

/// Free prediction: fork the model state and feed the plan (held after its end) for `np` steps.
pub(crate) fn predict(
    state: &MimoState,
    plan: &[f64],
    nu: usize,
    np: usize,
    offset: &[f64],
) -> Result<Vec<f64>, SimError> {
    let nc = plan.len() / nu;
    let mut s = state.clone();
    let mut out = Vec::new();
    let mut u = vec![0.0; nu];
    for p in 0..np {
        let l = p.min(nc - 1);
        for i in 0..nu {
            u[i] = plan[l * nu + i] - offset[i];
        }
        s.step(&u)?;
        out.extend(s.peek());
    }
    Ok(out)
}

/// A linear MPC on a linear [`MimoModel`] written in deviations from an operating input `u_op`.
#[derive(Debug, Clone)]
pub struct LinearMpc {
    cfg: MpcConfig,
    u_op: Vec<f64>,
    state: MimoState,
    theta: Vec<f64>,
    u_prev: Vec<f64>,
    ny: usize,
    nu: usize,
    stats: MpcStats,
}

impl LinearMpc {
    /// `model` must be linear and strictly proper; `u_init` is the controller output before the
    /// first sample (inside the bounds).
    pub fn new(
        model: &MimoModel,
        u_op: Vec<f64>,
        u_init: Vec<f64>,
        cfg: MpcConfig,
    ) -> Result<Self, SimError> {
        let (ny, nu) = (model.outputs(), model.inputs());
        cfg.validate(ny, nu)?;
        if !model.is_linear() {
            return Err(SimError::parameter(
                "MPC model",
                "nonlinear",
                "the linear MPC needs a linear model; linearise it first or use the NMPC",
            ));
        }
        if !model.is_strictly_proper() {
            return Err(SimError::parameter(
                "MPC model",
                "not strictly proper",
                "y(t) must not depend on u(t)",
            ));
        }
        if u_op.len() != nu || u_init.len() != nu {
            return Err(SimError::parameter(
                "MPC operating point",
                format!("{u_op:?}, {u_init:?}"),
                &format!("needs {nu} entries"),
            ));
        }
        if (0..nu).any(|i| u_init[i] < cfg.u_min[i] || u_init[i] > cfg.u_max[i]) {
            return Err(SimError::parameter(
                "MPC initial input",
                format!("{u_init:?}"),
                "must lie inside [u_min, u_max]",
            ));
        }
        let impulses = channel_impulses(model, cfg.np);
        let theta = sensitivity(&impulses, ny, nu, cfg.np, cfg.nc, |_, _, _| 1.0);
        Ok(Self {
            cfg,
            u_op,
            state: model.state(),
            theta,
            u_prev: u_init,
            ny,
            nu,
            stats: MpcStats::default(),
        })
    }

    /// Pre-runs the internal model with a constant applied input (to start at steady state).
    pub fn warm_up(&mut self, u: &[f64], samples: usize) -> Result<(), SimError> {
        for _ in 0..samples {
            self.apply(u)?;
        }
        Ok(())
    }

    /// Counters of the run so far.
    pub fn stats(&self) -> &MpcStats {
        &self.stats
    }

    /// The configuration.
    pub fn config(&self) -> &MpcConfig {
        &self.cfg
    }
}

impl Controller for LinearMpc {
    fn control(&mut self, y: &[f64], r: &[f64]) -> Result<Vec<f64>, SimError> {
        let (nu, ny, np, nc) = (self.nu, self.ny, self.cfg.np, self.cfg.nc);
        let yhat = self.state.peek();
        let plan: Vec<f64> = (0..nc).flat_map(|_| self.u_prev.iter().copied()).collect();
        let free = predict(&self.state, &plan, nu, np, &self.u_op)?;
        let c: Vec<f64> = (0..np * ny).map(|k| free[k] + (y[k % ny] - yhat[k % ny]) - r[k % ny]).collect();
        let qp = TrackingQp {
            nu,
            ny,
            np,
            nc,
            theta: &self.theta,
            c: &c,
            q: &self.cfg.q,
            r: &self.cfg.r,
            ubar: &plan,
            u_prev: &self.u_prev,
            u_min: &self.cfg.u_min,
            u_max: &self.cfg.u_max,
            du_max: &self.cfg.du_max,
            trust: None,
        };
        self.stats.solves += 1;
        let mut u: Vec<f64> = match qp::solve(&qp) {
            Some(w) => (0..nu).map(|i| self.u_prev[i] + w[i]).collect(),
            None => {
                self.stats.failures += 1;
                self.u_prev.clone()
            }
        };
        self.stats.max_raw_violation =
            self.stats.max_raw_violation.max(violation(&self.cfg, &self.u_prev, &u));
        self.cfg.project(&self.u_prev, &mut u);
        self.u_prev.clone_from(&u);
        Ok(u)
    }

    fn apply(&mut self, u: &[f64]) -> Result<(), SimError> {
        let dev: Vec<f64> = u.iter().zip(&self.u_op).map(|(a, b)| a - b).collect();
        self.state.step(&dev)?;
        Ok(())
    }
}

/// How far `u` lies outside the box and move limits (0 when feasible).
pub(crate) fn violation(cfg: &MpcConfig, u_prev: &[f64], u: &[f64]) -> f64 {
    (0..u.len())
        .map(|i| {
            let box_v = (cfg.u_min[i] - u[i]).max(u[i] - cfg.u_max[i]).max(0.0);
            let move_v = ((u[i] - u_prev[i]).abs() - cfg.du_max[i]).max(0.0);
            box_v.max(move_v)
        })
        .fold(0.0, f64::max)
}
