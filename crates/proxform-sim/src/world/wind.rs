//! Dryden turbulence filters, one set per simulated UAV.
//!
//! The scenario's [`proxform_scenario::wind`] gives the spectra (MIL-F-8785C low altitude:
//! scale lengths `L_w = h`, `L_u = L_v = h / (0.177 + 0.000823 h)^1.2` with h in ft; intensities
//! `σ_w = 0.1·W20`, `σ_u = σ_v = σ_w / (0.177 + 0.000823 h)^0.4`). The longitudinal component is
//! first order, `σ_u·sqrt(2L_u/πV)/(1 + (L_u/V)s)`; the lateral and vertical ones second order,
//! `σ·sqrt(L/πV)(1 + √3(L/V)s)/(1 + (L/V)s)²`. Each is discretised exactly (the covariance
//! of the sampled process is integrated in closed form), so it is stable and has the right
//! variance for any Δt. The components are along the UAV's course (u), to its left (v) and up
//! (w), turned into the world frame by its course. Each UAV has its own independent field.

use nalgebra::Vector3;
use proxform_core::state::State9;
use proxform_scenario::wind::Turbulence;

use crate::random::{StepRng, Ziggurat};

/// One UAV's turbulence state: the u filter (1 state), and the v and w filters (2 each).
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct TurbulenceState {
    u: f64,
    v: [f64; 2],
    w: [f64; 2],
}

/// Exact one-step discretisation of a first-order Gauss-Markov process of time constant `tau`
/// and standard deviation `sigma`: `x ← φ·x + σ·sqrt(1 − φ²)·n`.
fn first_order(x: f64, tau: f64, sigma: f64, dt: f64, n: f64) -> f64 {
    let phi = (-dt / tau).exp();
    phi * x + sigma * (1.0 - phi * phi).max(0.0).sqrt() * n
}

/// Exact step of the second-order Dryden filter `(1 + √3 T s)/(1 + T s)²` with states
/// `x1' = (n − x1)/T`, `x2' = (x1 − x2)/T`, output `√3·x1 + (1 − √3)·x2`, driven by white noise
/// of intensity `q = σ²·T` (which gives the output variance σ²). The process noise over `dt`
/// has the closed-form covariance below; it is sampled through its Cholesky factor.
fn second_order(x: &mut [f64; 2], t: f64, sigma: f64, dt: f64, n: (f64, f64)) -> f64 {
    let a = 1.0 / t;
    let e = (-a * dt).exp();
    // Mean: e^{A dt} x with A = [[−a, 0], [a, −a]].
    let m1 = e * x[0];
    let m2 = e * (a * dt * x[0] + x[1]);
    // Covariance q ∫₀^dt e^{As} G Gᵀ e^{Aᵀs} ds with G = [a, 0]ᵀ.
    let q = sigma * sigma * t;
    let e2 = e * e;
    let i0 = (1.0 - e2) / (2.0 * a);
    let i1 = (1.0 - e2 * (1.0 + 2.0 * a * dt)) / (4.0 * a * a);
    let i2 = (2.0 - e2 * (2.0 + 4.0 * a * dt + 4.0 * a * a * dt * dt)) / (8.0 * a * a * a);
    let c11 = q * a * a * i0;
    let c12 = q * a * a * a * i1;
    let c22 = q * a.powi(4) * i2;
    let l11 = c11.max(0.0).sqrt();
    let l21 = if l11 > 0.0 { c12 / l11 } else { 0.0 };
    let l22 = (c22 - l21 * l21).max(0.0).sqrt();
    x[0] = m1 + l11 * n.0;
    x[1] = m2 + l21 * n.0 + l22 * n.1;
    3f64.sqrt() * x[0] + (1.0 - 3f64.sqrt()) * x[1]
}

impl TurbulenceState {
    /// Advances one period for a UAV flying at `speed` (m/s) and returns the gust velocity in
    /// its course frame (along, left, up).
    pub fn step(&mut self, turb: &Turbulence, speed: f64, dt: f64, rng: &mut StepRng) -> Vector3<f64> {
        let v = speed.max(1.0);
        let (l, s) = turb.scales();
        let z = Ziggurat::get();
        let (n0, n1) = z.pair(rng);
        let (n2, n3) = z.pair(rng);
        let n4 = z.sample(rng);
        self.u = first_order(self.u, l[0] / v, s[0], dt, n0);
        let gv = second_order(&mut self.v, l[1] / v, s[1], dt, (n1, n2));
        let gw = second_order(&mut self.w, l[2] / v, s[2], dt, (n3, n4));
        Vector3::new(self.u, gv, gw)
    }
}

/// Turns a course-frame vector (along, left, up) into the world frame for a UAV whose state
/// is `x` (its course from its horizontal velocity).
pub fn course_to_world(x: &State9, g: &Vector3<f64>) -> Vector3<f64> {
    let h = x[3].hypot(x[4]);
    let (c, s) = if h > 1e-9 { (x[3] / h, x[4] / h) } else { (1.0, 0.0) };
    Vector3::new(c * g.x - s * g.y, s * g.x + c * g.y, g.z)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::random::{stream_key, Source};
    use proxform_scenario::wind::Severity;

    #[test]
    fn moderate_turbulence_has_its_specified_intensity_for_any_dt() {
        let turb = Turbulence { severity: Severity::Moderate, altitude_m: 300.0 };
        let (_, sigma) = turb.scales();
        // At 1000 ft: σ_w = 0.1 · 30 kt = 1.54 m/s, σ_u = σ_w / 1.0^0.4 ≈ 1.54 m/s.
        assert!((sigma[2] - 1.543).abs() < 0.01, "{sigma:?}");
        // The time constants are about 5 s: 400 000 steps of ≥ 0.05 s span ≥ 4000 of them.
        for dt in [0.05, 0.1, 1.0, 5.0] {
            let mut st = TurbulenceState::default();
            let key = stream_key(1, 0, 0, Source::Wind);
            let n = 400_000u64;
            let mut sum = [0.0f64; 3];
            for k in 0..n {
                let g = st.step(&turb, 60.0, dt, &mut StepRng::new(key, k));
                for a in 0..3 {
                    sum[a] += g[a] * g[a];
                }
            }
            for a in 0..3 {
                let sd = (sum[a] / n as f64).sqrt();
                assert!((sd / sigma[a] - 1.0).abs() < 0.06, "dt {dt}, axis {a}: σ {sd} vs {}", sigma[a]);
            }
        }
    }
}
