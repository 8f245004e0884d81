//! A Kalman filter per axis on position, velocity and a Singer acceleration: the manoeuvre
//! acceleration is a first-order Gauss-Markov process of standard deviation σ_a and
//! correlation time τ (Singer 1970), observed through the position and the velocity.
//!
//! Per axis the state is `[p, v, a]`; over `T` seconds, with `α = 1/τ`,
//! `F = [[1, T, (αT − 1 + e^{−αT})/α²], [0, 1, (1 − e^{−αT})/α], [0, 0, e^{−αT}]]` and `Q` is
//! Singer's closed form for `q = 2ασ_a²`. An update takes the measured position and velocity
//! with their noise `R = diag(σ_p², σ_v²)`; two measurements at the same instant (an onboard
//! detection and a radio report of the same UAV) are simply two updates.

/// One axis: state `[p, v, a]` and its covariance (upper triangle: p11 p12 p13 p22 p23 p33).
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct Axis {
    /// Position (m), velocity (m/s), acceleration (m/s²).
    pub x: [f64; 3],
    /// Covariance, upper triangle.
    pub p: [f64; 6],
}

/// `F` and `Q` over one interval, computed once for every axis and track that use it.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Step {
    /// The interval (s).
    pub t: f64,
    f12: f64,
    f13: f64,
    f23: f64,
    f33: f64,
    q: [f64; 6],
}

/// The model's parameters.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Singer {
    /// Manoeuvre acceleration σ_a (m/s²).
    pub accel_sigma_mps2: f64,
    /// Correlation time τ (s).
    pub tau_s: f64,
    /// Measurement noise of a position (m) and a velocity (m/s), 1σ.
    pub position_sigma_m: f64,
    /// See `position_sigma_m`.
    pub velocity_sigma_mps: f64,
}

impl Singer {
    /// An axis started from a measured position and velocity.
    pub fn start(&self, p: f64, v: f64) -> Axis {
        let (rp, rv) = (self.position_sigma_m.powi(2), self.velocity_sigma_mps.powi(2));
        Axis { x: [p, v, 0.0], p: [rp, 0.0, 0.0, rv, 0.0, self.accel_sigma_mps2.powi(2)] }
    }

    /// `F` over `t` seconds, as (f12, f13, f23, f33).
    fn transition(&self, t: f64) -> (f64, f64, f64, f64) {
        let a = 1.0 / self.tau_s;
        let e = (-a * t).exp();
        (t, (a * t - 1.0 + e) / (a * a), (1.0 - e) / a, e)
    }

    /// The state `t` seconds ahead, without changing the axis.
    pub fn extrapolate(&self, axis: &Axis, t: f64) -> [f64; 3] {
        let (f12, f13, f23, f33) = self.transition(t);
        let x = axis.x;
        [x[0] + f12 * x[1] + f13 * x[2], x[1] + f23 * x[2], f33 * x[2]]
    }

    /// `F` and `Q` over `t` seconds.
    pub fn step(&self, t: f64) -> Step {
        let (f12, f13, f23, f33) = self.transition(t);
        Step { t, f12, f13, f23, f33, q: self.noise(t) }
    }

    /// Predicts the axis `t` seconds ahead (state and covariance).
    pub fn predict(&self, axis: &mut Axis, t: f64) {
        if t > 0.0 {
            Self::predict_with(axis, &self.step(t));
        }
    }

    /// Predicts the axis over the interval of `step`.
    pub fn predict_with(axis: &mut Axis, step: &Step) {
        let Step { f12, f13, f23, f33, q, .. } = *step;
        let x = axis.x;
        axis.x = [x[0] + f12 * x[1] + f13 * x[2], x[1] + f23 * x[2], f33 * x[2]];
        // P ← F P Fᵀ + Q, with F = [[1, f12, f13], [0, 1, f23], [0, 0, f33]].
        let [p11, p12, p13, p22, p23, p33] = axis.p;
        let (r1, r2, r3) = (
            [p11 + f12 * p12 + f13 * p13, p12 + f12 * p22 + f13 * p23, p13 + f12 * p23 + f13 * p33],
            [p12 + f23 * p13, p22 + f23 * p23, p23 + f23 * p33],
            [f33 * p13, f33 * p23, f33 * p33],
        );
        // (F P) Fᵀ: row i of F P times row j of F.
        let row = |r: [f64; 3], j: usize| match j {
            0 => r[0] + f12 * r[1] + f13 * r[2],
            1 => r[1] + f23 * r[2],
            _ => f33 * r[2],
        };
        axis.p = [
            row(r1, 0) + q[0],
            row(r1, 1) + q[1],
            row(r1, 2) + q[2],
            row(r2, 1) + q[3],
            row(r2, 2) + q[4],
            row(r3, 2) + q[5],
        ];
    }

    /// Singer's process noise over `t` seconds (upper triangle).
    fn noise(&self, t: f64) -> [f64; 6] {
        let a = 1.0 / self.tau_s;
        let q = 2.0 * a * self.accel_sigma_mps2.powi(2);
        let (at, e1, e2) = (a * t, (-a * t).exp(), (-2.0 * a * t).exp());
        [
            q / (2.0 * a.powi(5)) * (1.0 - e2 + 2.0 * at + 2.0 * at.powi(3) / 3.0 - 2.0 * at * at - 4.0 * at * e1),
            q / (2.0 * a.powi(4)) * (e2 + 1.0 - 2.0 * e1 + 2.0 * at * e1 - 2.0 * at + at * at),
            q / (2.0 * a.powi(3)) * (1.0 - e2 - 2.0 * at * e1),
            q / (2.0 * a.powi(3)) * (4.0 * e1 - 3.0 - e2 + 2.0 * at),
            q / (2.0 * a * a) * (e2 + 1.0 - 2.0 * e1),
            q / (2.0 * a) * (1.0 - e2),
        ]
    }

    /// Updates the axis with a measured position `zp` and velocity `zv`.
    pub fn update(&self, axis: &mut Axis, zp: f64, zv: f64) {
        let [p11, p12, p13, p22, p23, p33] = axis.p;
        let (rp, rv) = (self.position_sigma_m.powi(2), self.velocity_sigma_mps.powi(2));
        // S = H P Hᵀ + R (H picks p and v), and its inverse.
        let (s11, s12, s22) = (p11 + rp, p12, p22 + rv);
        let det = s11 * s22 - s12 * s12;
        if !(det.is_finite() && det > 0.0) {
            return;
        }
        let (i11, i12, i22) = (s22 / det, -s12 / det, s11 / det);
        // K = P Hᵀ S⁻¹: rows of P's first two columns times S⁻¹.
        let ph = [[p11, p12], [p12, p22], [p13, p23]];
        let k: [[f64; 2]; 3] =
            std::array::from_fn(|i| [ph[i][0] * i11 + ph[i][1] * i12, ph[i][0] * i12 + ph[i][1] * i22]);
        let (y1, y2) = (zp - axis.x[0], zv - axis.x[1]);
        for i in 0..3 {
            axis.x[i] += k[i][0] * y1 + k[i][1] * y2;
        }
        // P ← (I − K H) P = P − K (H P), with H P the first two rows of P.
        let hp = [[p11, p12, p13], [p12, p22, p23]];
        let full = [[p11, p12, p13], [p12, p22, p23], [p13, p23, p33]];
        let new = |i: usize, j: usize| full[i][j] - k[i][0] * hp[0][j] - k[i][1] * hp[1][j];
        axis.p = [new(0, 0), new(0, 1), new(0, 2), new(1, 1), new(1, 2), new(2, 2)];
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn model() -> Singer {
        Singer { accel_sigma_mps2: 1.0, tau_s: 1.0, position_sigma_m: 0.02, velocity_sigma_mps: 0.05 }
    }

    #[test]
    fn it_learns_an_acceleration_and_predicts_it() {
        let m = model();
        // A neighbour accelerating at 2 m/s² along the axis, measured every 0.1 s.
        let truth = |t: f64| (10.0 * t + t * t, 10.0 + 2.0 * t);
        let mut axis = m.start(0.0, 10.0);
        for k in 1..=100 {
            let t = k as f64 * 0.1;
            m.predict(&mut axis, 0.1);
            let (p, v) = truth(t);
            m.update(&mut axis, p, v);
        }
        // The Singer acceleration reverts to zero between updates (τ = 1 s), so a constant
        // acceleration is estimated a little low.
        assert!(axis.x[2] > 1.6 && axis.x[2] < 2.1, "acceleration {}", axis.x[2]);
        // Its prediction one period ahead errs about a fifth of constant velocity's.
        let (p_next, _) = truth(10.1);
        let kf = m.extrapolate(&axis, 0.1)[0];
        let cv = axis.x[0] + 0.1 * axis.x[1];
        assert!((kf - p_next).abs() < 0.3 * (cv - p_next).abs(), "{kf} vs {cv} vs {p_next}");
        // The covariance stays symmetric positive: variances positive.
        assert!(axis.p[0] > 0.0 && axis.p[3] > 0.0 && axis.p[5] > 0.0);
    }

    #[test]
    fn two_measurements_at_once_shrink_the_uncertainty_more_than_one() {
        let m = model();
        let mut one = m.start(0.0, 10.0);
        m.predict(&mut one, 0.1);
        let mut two = one;
        m.update(&mut one, 1.0, 10.0);
        m.update(&mut two, 1.0, 10.0);
        m.update(&mut two, 1.0, 10.0);
        assert!(two.p[0] < one.p[0] && two.p[3] < one.p[3]);
    }

    #[test]
    fn the_process_noise_is_a_covariance() {
        let q = model().noise(0.1);
        // Variances positive, and the 3×3 matrix positive definite (leading minors).
        let m1 = q[0];
        let m2 = q[0] * q[3] - q[1] * q[1];
        let m3 = q[0] * (q[3] * q[5] - q[4] * q[4]) - q[1] * (q[1] * q[5] - q[4] * q[2])
            + q[2] * (q[1] * q[4] - q[3] * q[2]);
        assert!(m1 > 0.0 && m2 > 0.0 && m3 > 0.0, "{q:?}");
    }
}
