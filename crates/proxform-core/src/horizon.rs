//! The receding-horizon input of METHOD §6 step 7 for a horizon H > 1, as a quadratic program
//! solved by the Clarabel interior-point solver.
//!
//! With `d_h = X(t+h) − O(t+h)` the deviation from the envelope centre, the centre predicted
//! to move on at its own velocity and the course-keeping deviation `r = F·X(t) − O(t+1)`:
//!
//! `d_1 = r + B·u_0`,  `d_{h+1} = F·d_h + B·u_h`  (F: position advances by velocity · Δt),
//!
//! the inputs `u_0 … u_{H−1}` minimise `Σ_h d_hᵀ Q d_h + Σ_h u_hᵀ W u_h` subject to the first
//! step's bounds (rate and state limits at the current state), the per-step rate limits after
//! it, and, where the vehicle's state limits are linear in the summed inputs (the kinematic
//! model), the state limits at every step of the horizon. Only `u_0` is applied. For a vehicle
//! whose B depends on the state (the fixed wing) B is held at its value at the current state
//! over the horizon. H = 1 is the closed-form step of [`crate::control`].

use clarabel::algebra::CscMatrix;
use clarabel::solver::{DefaultSettings, DefaultSolver, IPSolver, NonnegativeConeT, SolverStatus};

use crate::control::ControlMatrix;
use crate::state::{Input, State9, P, VX};

/// Why the horizon QP gave no input (the controller then falls back to H = 1).
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum HorizonError {
    /// The solver did not reach an optimal solution.
    #[error("the horizon QP was not solved (solver status {0})")]
    NotSolved(String),
    /// The problem data could not be handed to the solver.
    #[error("the horizon QP could not be set up: {0}")]
    Setup(String),
}

/// One horizon problem. `n` inputs of `B` are in use.
#[derive(Debug, Clone, Copy)]
pub struct HorizonProblem<'a> {
    /// Horizon H (updates, ≥ 1).
    pub horizon: usize,
    /// Inputs in use.
    pub n: usize,
    /// Update period Δt (s).
    pub dt: f64,
    /// Control matrix at the current state.
    pub b: &'a ControlMatrix,
    /// Course-keeping deviation `F·X(t) − O(t+1)`.
    pub r: &'a State9,
    /// State weights `1/Δ_k²`.
    pub q: &'a State9,
    /// Input weights.
    pub w: &'a Input,
    /// Bounds of the first input (rate and state limits at the current state).
    pub first: (&'a Input, &'a Input),
    /// Bounds of each later input.
    pub later: (&'a Input, &'a Input),
    /// Bounds of the running sum of the inputs (linear state limits), if any.
    pub cumulative: Option<(&'a Input, &'a Input)>,
}

/// Solves the horizon QP and returns the first input.
#[allow(non_snake_case)] // the QP's matrices keep their usual names
pub fn solve_horizon(pb: &HorizonProblem<'_>) -> Result<Input, HorizonError> {
    let (H, n, dt) = (pb.horizon.max(1), pb.n, pb.dt);
    let nv = n * H;
    // G_j = F^j·B: F^j adds j·Δt times the velocity rows to the position rows.
    let g = |j: usize, row: usize, a: usize| -> f64 {
        let mut v = pb.b[(row, a)];
        if row < VX {
            v += j as f64 * dt * pb.b[(row + 3, a)];
        }
        v
    };
    // c_h = F^(h−1)·r and S (rows: 9 per step, columns: inputs), stacked for h = 1..H.
    let mut S = vec![0.0; P * H * nv];
    let mut c = vec![0.0; P * H];
    for h in 0..H {
        for row in 0..P {
            let mut v = pb.r[row];
            if row < VX {
                v += h as f64 * dt * pb.r[row + 3];
            }
            c[h * P + row] = v;
            for k in 0..=h {
                for a in 0..n {
                    S[(h * P + row) * nv + k * n + a] = g(h - k, row, a);
                }
            }
        }
    }
    // Cost ½uᵀPu + qᵀu with P = SᵀQS + W̄ and q = SᵀQc (upper triangle of P for the solver).
    let (mut pi, mut pj, mut pv) = (Vec::new(), Vec::new(), Vec::new());
    let mut q = vec![0.0; nv];
    for col in 0..nv {
        for row in 0..=col {
            let mut v = 0.0;
            for s in 0..P * H {
                let qs = pb.q[s % P];
                v += S[s * nv + row] * qs * S[s * nv + col];
            }
            if row == col {
                v += pb.w[col % n];
            }
            if v != 0.0 {
                pi.push(row);
                pj.push(col);
                pv.push(v);
            }
        }
        q[col] = (0..P * H).map(|s| S[s * nv + col] * pb.q[s % P] * c[s]).sum();
    }
    // Constraints A·u + s = b, s ≥ 0: upper and lower bounds of each input, then of the
    // running sums.
    let (mut ai, mut aj, mut av, mut bv) = (Vec::new(), Vec::new(), Vec::new(), Vec::new());
    let mut row = 0;
    let mut bound = |cols: &[usize], lo: f64, hi: f64, row: &mut usize| {
        for (sign, limit) in [(1.0, hi), (-1.0, -lo)] {
            for &col in cols {
                ai.push(*row);
                aj.push(col);
                av.push(sign);
            }
            bv.push(limit);
            *row += 1;
        }
    };
    for k in 0..H {
        let (lo, hi) = if k == 0 { pb.first } else { pb.later };
        for a in 0..n {
            bound(&[k * n + a], lo[a], hi[a], &mut row);
        }
    }
    if let Some((lo, hi)) = pb.cumulative {
        let mut cols = Vec::with_capacity(H);
        for a in 0..n {
            // A running-sum bound that the per-step bounds cannot reach is left out: it could
            // never bind, and every row costs the solver time.
            let reach_hi = pb.first.1[a].max(0.0) + (H - 1) as f64 * pb.later.1[a].max(0.0);
            let reach_lo = pb.first.0[a].min(0.0) + (H - 1) as f64 * pb.later.0[a].min(0.0);
            if hi[a] >= reach_hi && lo[a] <= reach_lo {
                continue;
            }
            cols.clear();
            for k in 0..H {
                cols.push(k * n + a);
                if k > 0 {
                    bound(&cols, lo[a], hi[a], &mut row);
                }
            }
        }
    }
    let Pm = CscMatrix::new_from_triplets(nv, nv, pi, pj, pv);
    let Am = CscMatrix::new_from_triplets(row, nv, ai, aj, av);
    let cones = [NonnegativeConeT(row)];
    // The inputs matter to about 1e-6 of their limits: looser tolerances than the solver's defaults
    // save iterations.
    let settings = DefaultSettings {
        verbose: false,
        tol_gap_abs: 1e-7,
        tol_gap_rel: 1e-7,
        tol_feas: 1e-7,
        tol_ktratio: 1e-5,
        ..DefaultSettings::default()
    };
    let mut solver =
        DefaultSolver::new(&Pm, &q, &Am, &bv, &cones, settings).map_err(|e| HorizonError::Setup(format!("{e:?}")))?;
    solver.solve();
    match solver.solution.status {
        SolverStatus::Solved | SolverStatus::AlmostSolved => {
            let mut u = Input::zeros();
            for a in 0..n {
                // Interior-point solutions sit a hair inside the bounds; clip the residue.
                u[a] = solver.solution.x[a].clamp(pb.first.0[a], pb.first.1[a]);
            }
            Ok(u)
        }
        s => Err(HorizonError::NotSolved(format!("{s:?}"))),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::control::saturated_least_squares;
    use crate::vehicle::KinematicModel;
    use approx::assert_relative_eq;

    fn problem_data() -> (ControlMatrix, State9, State9, Input, Input, Input) {
        let dt = 0.1;
        let b = KinematicModel::control_matrix(&State9::zeros(), dt);
        let r = State9::from_column_slice(&[0.8, -0.3, 0.1, 0.2, 0.0, -0.1, 0.001, 0.0, -0.002]);
        let q = State9::from_column_slice(&[4.0, 2.8, 25.0, 1.0, 6.0, 6.0, 2e4, 3e4, 1e4]);
        let w = Input::from_element(1e-3);
        let rate = Input::from_column_slice(&[0.5, 0.5, 0.5, 0.005, 0.0035, 0.0035]);
        (b, r, q, w, -rate, rate)
    }

    #[test]
    fn horizon_one_matches_the_closed_form_step() {
        let (b, r, q, w, lo, hi) = problem_data();
        let pb = HorizonProblem {
            horizon: 1,
            n: 6,
            dt: 0.1,
            b: &b,
            r: &r,
            q: &q,
            w: &w,
            first: (&lo, &hi),
            later: (&lo, &hi),
            cumulative: None,
        };
        let qp = solve_horizon(&pb).expect("solved");
        let ls = saturated_least_squares(&b, 6, &r, &q, &w, &lo, &hi);
        assert_relative_eq!(qp, ls, epsilon = 1e-5);
    }

    #[test]
    fn longer_horizons_respect_the_bounds_and_plan_less_aggressively() {
        let (b, r, q, w, lo, hi) = problem_data();
        let cum_lo = Input::from_element(-0.6);
        let cum_hi = Input::from_element(0.6);
        let pb = HorizonProblem {
            horizon: 8,
            n: 6,
            dt: 0.1,
            b: &b,
            r: &r,
            q: &q,
            w: &w,
            first: (&lo, &hi),
            later: (&lo, &hi),
            cumulative: Some((&cum_lo, &cum_hi)),
        };
        let u = solve_horizon(&pb).expect("solved");
        for a in 0..6 {
            assert!(u[a] >= lo[a] - 1e-9 && u[a] <= hi[a] + 1e-9, "input {a} = {}", u[a]);
        }
        // A position gap ahead of the UAV (r_x > 0 means it is ahead of the centre): both
        // horizons slow it down.
        let one = saturated_least_squares(&b, 6, &r, &q, &w, &lo, &hi);
        assert!(u[0] < 0.0 && one[0] < 0.0);
        // Over one step the closing is weighted by Δt/2 only; the longer horizon sees the
        // gap shrinking later and does not overshoot the velocity as much.
        assert!(u != one);
    }

    #[test]
    fn the_solver_succeeds_on_deviations_of_every_size() {
        // The controller falls back to H = 1 when the QP fails; it should not have to.
        let (b, _, q, w, lo, hi) = problem_data();
        let mut x: u64 = 0x1234_5678;
        let mut uniform = || {
            x = x.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
            ((x >> 11) as f64) / ((1u64 << 53) as f64) * 2.0 - 1.0
        };
        let (cum_lo, cum_hi) = (Input::from_element(-0.3), Input::from_element(2.0));
        for k in 0..300 {
            let scale = 10f64.powi(k % 6 - 3);
            let r = State9::from_fn(|_, _| scale * uniform());
            let pb = HorizonProblem {
                horizon: 2 + k as usize % 9,
                n: 6,
                dt: 0.1,
                b: &b,
                r: &r,
                q: &q,
                w: &w,
                first: (&lo, &hi),
                later: (&lo, &hi),
                cumulative: Some((&cum_lo, &cum_hi)),
            };
            let u = solve_horizon(&pb).unwrap_or_else(|e| panic!("case {k}: {e}"));
            assert!((0..6).all(|a| u[a] >= lo[a] && u[a] <= hi[a]));
        }
    }
}
