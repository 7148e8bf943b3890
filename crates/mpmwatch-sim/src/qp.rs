//! The constrained output-tracking QP shared by the linear MPC and the NMPC, solved by
//! `clarabel` (an interior-point solver in pure Rust).
//!
//! Decision variable `w` (length `nc·nu`, index `l·nu + i`): the deviation of input `i` at
//! future step `l` from a base plan `ū`. Predicted outputs are `ŷ = c + r + Θ w` where `c` is
//! the base prediction minus the set point. The cost is `‖Θw + c‖²_Q + ‖Δu‖²_R` with the moves
//! `Δu(l) = u(l) − u(l−1)`, `u(−1)` the last applied controller output. Constraints:
//! `u_min ≤ ū + w ≤ u_max`, `|Δu| ≤ du_max`, and optionally a trust region `|w| ≤ ρ`.

use clarabel::algebra::CscMatrix;
use clarabel::solver::{DefaultSettings, DefaultSolver, IPSolver, NonnegativeConeT, SolverStatus};

/// The data of one tracking QP.
pub(crate) struct TrackingQp<'a> {
    pub nu: usize,
    pub ny: usize,
    pub np: usize,
    pub nc: usize,
    /// Sensitivity, `np·ny` rows by `nc·nu` columns, row-major.
    pub theta: &'a [f64],
    /// Base prediction plus disturbance estimate minus set point, `np·ny`.
    pub c: &'a [f64],
    /// Output weights (per output).
    pub q: &'a [f64],
    /// Move weights (per input).
    pub r: &'a [f64],
    /// Base plan, `nc·nu`.
    pub ubar: &'a [f64],
    /// Last controller output.
    pub u_prev: &'a [f64],
    pub u_min: &'a [f64],
    pub u_max: &'a [f64],
    pub du_max: &'a [f64],
    pub trust: Option<f64>,
}

/// Solves the QP; `None` when the solver did not reach a (near-)optimal point.
pub(crate) fn solve(p: &TrackingQp) -> Option<Vec<f64>> {
    let (nu, ny, nc) = (p.nu, p.ny, p.nc);
    let nrow = p.np * ny;
    let n = nc * nu;
    let mut h = vec![vec![0.0; n]; n];
    let mut g = vec![0.0; n];
    for row in 0..nrow {
        let qw = p.q[row % ny];
        let th = &p.theta[row * n..(row + 1) * n];
        for a in 0..n {
            if th[a] == 0.0 {
                continue;
            }
            g[a] += qw * th[a] * p.c[row];
            for b in a..n {
                h[a][b] += qw * th[a] * th[b];
            }
        }
    }
    // moves: Δu(l) = δ̄(l) + w(l) − w(l−1)
    let delta_bar =
        |l: usize, i: usize| p.ubar[l * nu + i] - if l == 0 { p.u_prev[i] } else { p.ubar[(l - 1) * nu + i] };
    for l in 0..nc {
        for i in 0..nu {
            let rw = p.r[i];
            let a = l * nu + i;
            let db = delta_bar(l, i);
            h[a][a] += rw;
            g[a] += rw * db;
            if l > 0 {
                let b = a - nu;
                h[b][b] += rw;
                h[b][a] -= rw;
                g[b] -= rw * db;
            }
        }
    }
    for (a, row) in h.iter_mut().enumerate() {
        row[a] += 1e-9;
        for v in row.iter_mut() {
            *v *= 2.0;
        }
        for v in row.iter_mut().take(a) {
            *v = 0.0;
        }
    }
    let g: Vec<f64> = g.iter().map(|v| 2.0 * v).collect();

    let mut rows: Vec<Vec<f64>> = Vec::with_capacity(6 * n);
    let mut b = Vec::with_capacity(6 * n);
    for l in 0..nc {
        for i in 0..nu {
            let a = l * nu + i;
            let mut e = vec![0.0; n];
            e[a] = 1.0;
            rows.push(e.clone());
            b.push(p.u_max[i] - p.ubar[a]);
            rows.push(e.iter().map(|v| -v).collect());
            b.push(p.ubar[a] - p.u_min[i]);
            let mut d = e.clone();
            if l > 0 {
                d[a - nu] = -1.0;
            }
            let db = delta_bar(l, i);
            rows.push(d.clone());
            b.push(p.du_max[i] - db);
            rows.push(d.iter().map(|v| -v).collect());
            b.push(p.du_max[i] + db);
            if let Some(rho) = p.trust {
                rows.push(e.clone());
                b.push(rho);
                rows.push(e.iter().map(|v| -v).collect());
                b.push(rho);
            }
        }
    }
    let pm = CscMatrix::from(&h);
    let am = CscMatrix::from(&rows);
    let cones = [NonnegativeConeT(rows.len())];
    let settings = DefaultSettings { verbose: false, ..DefaultSettings::default() };
    let mut solver = DefaultSolver::new(&pm, &g, &am, &b, &cones, settings).ok()?;
    solver.solve();
    match solver.solution.status {
        SolverStatus::Solved | SolverStatus::AlmostSolved => Some(solver.solution.x.clone()),
        _ => None,
    }
}
