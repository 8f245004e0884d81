//! The one-step predictive control of METHOD §6 step 7 (the paper's eq. 12, H = 1).
//!
//! With the prediction `X(t+1) = X_hold + B·u`, the input minimises
//! `Σ_k q_k (r_k + (B·u)_k)² + Σ_j w_j u_j²` subject to `lo ≤ u ≤ hi`, where `r = X_hold − O`
//! is the deviation of the course-keeping state from the envelope centre, `q_k = 1/Δ_k²` and
//! `w` the input penalty. This is a box-constrained least-squares problem; it is solved in
//! closed form per coordinate and by exact coordinate descent when inputs are coupled (the
//! iteration is exact in one sweep when B's columns are orthogonal under Q, as for the
//! kinematic model).

use nalgebra::{SMatrix, SVector};

use crate::state::{Input, State9, MAX_INPUTS, P};

/// Control matrix B (9 × `MAX_INPUTS`); only the first `n` columns are used.
pub type ControlMatrix = SMatrix<f64, P, MAX_INPUTS>;

/// Most coordinate-descent sweeps for coupled inputs.
const MAX_SWEEPS: usize = 64;

/// Hessian `H = BᵀQB + diag(w)` of the step's cost, and whether inputs are coupled (H not
/// diagonal). For a vehicle whose B does not depend on the state it is computed once.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Hessian {
    h: SMatrix<f64, MAX_INPUTS, MAX_INPUTS>,
    n: usize,
    coupled: bool,
}

impl Hessian {
    /// `BᵀQB + diag(w)` over the first `n` inputs.
    pub fn new(b: &ControlMatrix, n: usize, q: &State9, w: &Input) -> Self {
        let mut h = SMatrix::<f64, MAX_INPUTS, MAX_INPUTS>::zeros();
        for a in 0..n {
            let qa = b.column(a).component_mul(q);
            for c in a..n {
                let v = qa.dot(&b.column(c));
                h[(a, c)] = v;
                h[(c, a)] = v;
            }
            h[(a, a)] += w[a];
        }
        let coupled = (0..n).any(|a| (0..n).any(|c| a != c && h[(a, c)] != 0.0));
        Self { h, n, coupled }
    }
}

/// Solves the saturated least-squares step. `q` are the state weights, `w` the input weights,
/// `n` the number of inputs in use. Inputs whose column and weight are both zero stay at zero.
pub fn saturated_least_squares(
    b: &ControlMatrix,
    n: usize,
    r: &State9,
    q: &State9,
    w: &Input,
    lo: &Input,
    hi: &Input,
) -> Input {
    solve(&Hessian::new(b, n, q, w), b, r, q, lo, hi)
}

/// The same step with a precomputed Hessian.
pub fn solve(hess: &Hessian, b: &ControlMatrix, r: &State9, q: &State9, lo: &Input, hi: &Input) -> Input {
    let (h, n) = (&hess.h, hess.n);
    // Gradient g = BᵀQr.
    let qr = r.component_mul(q);
    let mut g = SVector::<f64, MAX_INPUTS>::zeros();
    for a in 0..n {
        g[a] = b.column(a).dot(&qr);
    }
    let mut u = Input::zeros();
    let sweeps = if hess.coupled { MAX_SWEEPS } else { 1 };
    for _ in 0..sweeps {
        let mut change: f64 = 0.0;
        for a in 0..n {
            if h[(a, a)] <= 0.0 {
                continue;
            }
            let mut s = g[a];
            if hess.coupled {
                for c in 0..n {
                    if c != a {
                        s += h[(a, c)] * u[c];
                    }
                }
            }
            let new = (-s / h[(a, a)]).clamp(lo[a], hi[a]);
            change = change.max((new - u[a]).abs());
            u[a] = new;
        }
        if change <= 1e-12 {
            break;
        }
    }
    if hess.coupled {
        polish(h, &g, n, lo, hi, &mut u);
    }
    u
}

/// Solves the free inputs exactly once coordinate descent has found the active bounds; keeps
/// the descent's answer if the exact one would leave the box.
fn polish(h: &SMatrix<f64, MAX_INPUTS, MAX_INPUTS>, g: &Input, n: usize, lo: &Input, hi: &Input, u: &mut Input) {
    let mut a = SMatrix::<f64, MAX_INPUTS, MAX_INPUTS>::identity();
    let mut rhs = *u;
    for j in 0..n {
        let at_bound = u[j] <= lo[j] || u[j] >= hi[j] || h[(j, j)] <= 0.0;
        if at_bound {
            continue;
        }
        rhs[j] = -g[j];
        for c in 0..n {
            let free_c = !(u[c] <= lo[c] || u[c] >= hi[c] || h[(c, c)] <= 0.0);
            if free_c {
                a[(j, c)] = h[(j, c)];
            } else {
                a[(j, c)] = 0.0;
                rhs[j] -= h[(j, c)] * u[c];
            }
        }
    }
    if let Some(exact) = a.lu().solve(&rhs) {
        if (0..n).all(|j| exact[j] >= lo[j] - 1e-12 && exact[j] <= hi[j] + 1e-12 && exact[j].is_finite()) {
            for j in 0..n {
                u[j] = exact[j].clamp(lo[j], hi[j]);
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use approx::assert_relative_eq;

    fn identity_b() -> ControlMatrix {
        let mut b = ControlMatrix::zeros();
        for j in 0..MAX_INPUTS {
            b[(j + 3, j)] = 1.0;
        }
        b
    }

    #[test]
    fn unconstrained_solution_cancels_the_deviation() {
        let b = identity_b();
        let mut r = State9::zeros();
        r[4] = 0.3;
        let u = saturated_least_squares(
            &b,
            6,
            &r,
            &State9::from_element(1.0),
            &Input::zeros(),
            &Input::from_element(-1.0),
            &Input::from_element(1.0),
        );
        assert_relative_eq!(u[1], -0.3);
        assert_relative_eq!(u[0], 0.0);
    }

    #[test]
    fn saturates_at_the_bounds() {
        let b = identity_b();
        let mut r = State9::zeros();
        r[4] = 5.0;
        r[6] = -5.0;
        let u = saturated_least_squares(
            &b,
            6,
            &r,
            &State9::from_element(1.0),
            &Input::zeros(),
            &Input::from_element(-0.5),
            &Input::from_element(0.25),
        );
        assert_relative_eq!(u[1], -0.5);
        assert_relative_eq!(u[3], 0.25);
    }

    #[test]
    fn coupled_inputs_reach_the_constrained_optimum() {
        // One state driven by two inputs: minimise (1 + u0 + u1)² + 0.1(u0² + u1²), u0 ≤ 0.
        let mut b = ControlMatrix::zeros();
        b[(0, 0)] = 1.0;
        b[(0, 1)] = 1.0;
        let mut r = State9::zeros();
        r[0] = 1.0;
        let mut q = State9::zeros();
        q[0] = 1.0;
        let w = Input::from_element(0.1);
        let lo = Input::from_element(-10.0);
        let mut hi = Input::from_element(10.0);
        let u = saturated_least_squares(&b, 2, &r, &q, &w, &lo, &hi);
        // Symmetric optimum: u0 = u1 = −1/2.1.
        assert_relative_eq!(u[0], -1.0 / 2.1, epsilon = 1e-9);
        assert_relative_eq!(u[1], -1.0 / 2.1, epsilon = 1e-9);
        hi[0] = -0.9;
        let u = saturated_least_squares(&b, 2, &r, &q, &w, &lo, &hi);
        // u0 pinned at its bound; u1 optimal given it: (1 − 0.9 + u1) + 0.1 u1 = 0.
        assert_relative_eq!(u[0], -0.9, epsilon = 1e-9);
        assert_relative_eq!(u[1], -0.1 / 1.1, epsilon = 1e-9);
    }
}
