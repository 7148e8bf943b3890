//! Nonlinear MPC for Hammerstein models by successive linearisation around the predicted
//! trajectory.
//!
//! Scheme, at every sample:
//! 1. Shift the previous optimal input plan by one step (repeat its last move) to get `ū`.
//! 2. Simulate the nominal nonlinear model along `ū`: the exact nonlinear prediction `ȳ`.
//! 3. Linearise around `ū`: for a Hammerstein channel `yⱼ = gⱼᵢ(q) fⱼᵢ(uᵢ)` the sensitivity of
//!    `yⱼ(k+p)` to `uᵢ(k+l)` is the impulse response `hⱼᵢ(p−l)` times the slope `f'ⱼᵢ(ūᵢ(k+l))`,
//!    exact in the linear dynamics and first-order in the static map.
//! 4. Solve the constrained tracking QP (input bounds, move limits and a trust region `|w| ≤ ρ`
//!    that keeps the step where the linearisation holds) with clarabel; `ū ← ū + w`.
//! 5. Repeat 2–4 `iterations` times (a Gauss–Newton / sequential-QP iteration), apply the first
//!    input.
//!
//! Why this scheme: the Hammerstein structure makes the linearisation cheap and exact in the
//! dynamics, every subproblem is a convex QP the same solver as the linear MPC handles, and a
//! fixed number of QPs per sample keeps the run time bounded and the result reproducible, where
//! a general NLP solver would add a dependency and iteration counts that vary with the data.
//! The paper used the YANE NMPC package (a full NLP per sample); a plant this mildly nonlinear
//! does not need more, and the residual analysis only needs a reasonable closed loop.

use super::closed_loop::Controller;
use super::error::SimError;
use super::mpc::{MpcConfig, MpcStats, channel_impulses, predict, sensitivity, violation};
use super::qp::{self, TrackingQp};
use mpmwatch_core::model::{MimoModel, MimoState};

/// The NMPC controller on a (Hammerstein) [`MimoModel`] in absolute units.
#[derive(Debug, Clone)]
pub struct Nmpc {
    cfg: MpcConfig,
    model: MimoModel,
    state: MimoState,
    impulses: Vec<Vec<f64>>,
    plan: Vec<f64>,
    u_prev: Vec<f64>,
    iterations: usize,
    trust: f64,
    stats: MpcStats,
}

impl Nmpc {
    /// `u_init` is the controller output before the first sample; `iterations` ≥ 1 linearisations
    /// per sample, each step limited to `trust` (> 0) per input.
    pub fn new(
        model: MimoModel,
        u_init: Vec<f64>,
        cfg: MpcConfig,
        iterations: usize,
        trust: f64,
    ) -> Result<Self, SimError> {
        let (ny, nu) = (model.outputs(), model.inputs());
        cfg.validate(ny, nu)?;
        if !model.is_strictly_proper() {
            return Err(SimError::parameter(
                "NMPC model",
                "not strictly proper",
                "y(t) must not depend on u(t)",
            ));
        }
        if iterations == 0 {
            return Err(SimError::parameter("NMPC iterations", iterations, "must be at least 1"));
        }
        if !(trust.is_finite() && trust > 0.0) {
            return Err(SimError::parameter("NMPC trust region", trust, "must be positive and finite"));
        }
        if u_init.len() != nu || (0..nu).any(|i| u_init[i] < cfg.u_min[i] || u_init[i] > cfg.u_max[i]) {
            return Err(SimError::parameter(
                "NMPC initial input",
                format!("{u_init:?}"),
                "needs one entry per input inside [u_min, u_max]",
            ));
        }
        let impulses = channel_impulses(&model, cfg.np);
        let plan = (0..cfg.nc).flat_map(|_| u_init.iter().copied()).collect();
        Ok(Self {
            state: model.state(),
            impulses,
            plan,
            u_prev: u_init,
            model,
            cfg,
            iterations,
            trust,
            stats: MpcStats::default(),
        })
    }

    /// Pre-runs the internal model with a constant applied input.
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

impl Controller for Nmpc {
    fn control(&mut self, y: &[f64], r: &[f64]) -> Result<Vec<f64>, SimError> {
        let (nu, ny, np, nc) = (self.model.inputs(), self.model.outputs(), self.cfg.np, self.cfg.nc);
        let zero = vec![0.0; nu];
        let yhat = self.state.peek();
        // shift the previous plan; clamp so that rounding never makes the base plan infeasible
        let mut ubar: Vec<f64> = self.plan[nu..].to_vec();
        ubar.extend_from_slice(&self.plan[(nc - 1) * nu..]);
        for (k, u) in ubar.iter_mut().enumerate() {
            *u = u.clamp(self.cfg.u_min[k % nu], self.cfg.u_max[k % nu]);
        }
        if !plan_is_feasible(&self.cfg, &self.u_prev, &ubar) {
            ubar = (0..nc).flat_map(|_| self.u_prev.iter().copied()).collect();
        }
        for _ in 0..self.iterations {
            let free = predict(&self.state, &ubar, nu, np, &zero)?;
            let c: Vec<f64> =
                (0..np * ny).map(|k| free[k] + (y[k % ny] - yhat[k % ny]) - r[k % ny]).collect();
            let model = &self.model;
            let theta = sensitivity(&self.impulses, ny, nu, np, nc, |l, j, i| {
                model.channel(j, i).map_or(0.0, |ch| ch.map.slope(ubar[l * nu + i]))
            });
            let qp = TrackingQp {
                nu,
                ny,
                np,
                nc,
                theta: &theta,
                c: &c,
                q: &self.cfg.q,
                r: &self.cfg.r,
                ubar: &ubar,
                u_prev: &self.u_prev,
                u_min: &self.cfg.u_min,
                u_max: &self.cfg.u_max,
                du_max: &self.cfg.du_max,
                trust: Some(self.trust),
            };
            self.stats.solves += 1;
            match qp::solve(&qp) {
                Some(w) => {
                    for (u, dw) in ubar.iter_mut().zip(&w) {
                        *u += dw;
                    }
                }
                None => {
                    self.stats.failures += 1;
                    break;
                }
            }
        }
        let mut u = ubar[..nu].to_vec();
        self.stats.max_raw_violation =
            self.stats.max_raw_violation.max(violation(&self.cfg, &self.u_prev, &u));
        self.cfg.project(&self.u_prev, &mut u);
        ubar[..nu].copy_from_slice(&u);
        self.plan = ubar;
        self.u_prev.clone_from(&u);
        Ok(u)
    }

    fn apply(&mut self, u: &[f64]) -> Result<(), SimError> {
        self.state.step(u)?;
        Ok(())
    }
}

fn plan_is_feasible(cfg: &MpcConfig, u_prev: &[f64], plan: &[f64]) -> bool {
    let nu = u_prev.len();
    plan.chunks(nu).enumerate().all(|(l, ul)| {
        let prev = if l == 0 { u_prev } else { &plan[(l - 1) * nu..l * nu] };
        violation(cfg, prev, ul) <= 1e-12
    })
}
