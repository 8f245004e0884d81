//! The wind of a scenario: steady wind, Dryden turbulence (MIL-F-8785C) and a 1 − cos gust.
//!
//! This module holds the parameters and the wind every UAV shares; the turbulence filters
//! that each simulated UAV steps live in the simulator.
//!
//! Turbulence follows the Dryden spectra of MIL-F-8785C for low altitude (up to 1000 ft):
//! scale lengths `L_w = h`, `L_u = L_v = h / (0.177 + 0.000823 h)^1.2` (h in ft), intensities
//! `σ_w = 0.1·W20`, `σ_u = σ_v = σ_w / (0.177 + 0.000823 h)^0.4`, with the wind at 20 ft W20 =
//! 15, 30 and 45 kt for light, moderate and severe turbulence. The longitudinal component is
//! first order, `σ_u·sqrt(2L_u/πV)/(1 + (L_u/V)s)`; the lateral and vertical ones second order,
//! `σ·sqrt(L/πV)(1 + √3(L/V)s)/(1 + (L/V)s)²`. Each is discretised exactly (the covariance
//! of the sampled process is integrated in closed form), so it is stable and has the right
//! variance for any Δt. The components are along the UAV's course (u), to its left (v) and up
//! (w), turned into the world frame by its course. Each UAV has its own independent field.

use nalgebra::Vector3;

/// Turbulence severity.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Severity {
    /// W20 = 15 kt.
    Light,
    /// W20 = 30 kt.
    Moderate,
    /// W20 = 45 kt.
    Severe,
}

impl Severity {
    /// Wind speed at 20 ft (m/s).
    pub fn w20_mps(self) -> f64 {
        let kt = match self {
            Severity::Light => 15.0,
            Severity::Moderate => 30.0,
            Severity::Severe => 45.0,
        };
        kt * 0.514_444
    }
}

/// Dryden turbulence parameters.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Turbulence {
    /// Severity.
    pub severity: Severity,
    /// Altitude above ground for the low-altitude model (m), clamped to [3 m, 305 m].
    pub altitude_m: f64,
}

impl Turbulence {
    /// Scale lengths (L_u, L_v, L_w) and intensities (σ_u, σ_v, σ_w), SI.
    pub fn scales(&self) -> ([f64; 3], [f64; 3]) {
        let h_ft = (self.altitude_m / 0.3048).clamp(10.0, 1000.0);
        let f = 0.177 + 0.000823 * h_ft;
        let l_uv = h_ft / f.powf(1.2) * 0.3048;
        let l_w = h_ft * 0.3048;
        let sigma_w = 0.1 * self.severity.w20_mps();
        let sigma_uv = sigma_w / f.powf(0.4);
        ([l_uv, l_uv, l_w], [sigma_uv, sigma_uv, sigma_w])
    }
}

/// A 1 − cos gust.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Gust {
    /// Start (s).
    pub at_s: f64,
    /// Duration (s): the gust rises for half of it and falls for the other half.
    pub duration_s: f64,
    /// Peak wind (m/s, world frame).
    pub peak_mps: Vector3<f64>,
}

/// The wind of a scenario.
#[derive(Debug, Clone, Copy, PartialEq, Default, serde::Serialize, serde::Deserialize)]
pub struct Wind {
    /// Steady wind (m/s, world frame).
    pub steady_mps: Vector3<f64>,
    /// Turbulence, if any.
    pub turbulence: Option<Turbulence>,
    /// Gust, if any.
    pub gust: Option<Gust>,
}

impl Wind {
    /// True when there is no wind at all.
    pub fn is_calm(&self) -> bool {
        self.steady_mps == Vector3::zeros() && self.turbulence.is_none() && self.gust.is_none()
    }

    /// The wind at `t` that every UAV shares: steady plus gust.
    pub fn common(&self, t: f64) -> Vector3<f64> {
        let mut w = self.steady_mps;
        if let Some(g) = self.gust {
            let x = (t - g.at_s) / g.duration_s;
            if (0.0..=1.0).contains(&x) {
                w += g.peak_mps * 0.5 * (1.0 - (std::f64::consts::TAU * x).cos());
            }
        }
        w
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_gust_rises_and_falls() {
        let w = Wind {
            gust: Some(Gust { at_s: 10.0, duration_s: 4.0, peak_mps: Vector3::new(0.0, 8.0, 0.0) }),
            ..Wind::default()
        };
        assert_eq!(w.common(9.9), Vector3::zeros());
        assert!((w.common(12.0).y - 8.0).abs() < 1e-12);
        assert!(w.common(14.1).norm() < 1e-12);
    }
}
