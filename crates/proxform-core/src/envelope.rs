//! The state envelope (METHOD §6 step 5, the paper's eq. 13).
//!
//! The 9-dimensional ellipsoid `Σ_k ((X_k − O_k)/Δ_k)² ≤ ρ²` around the centre O. In
//! coordinates normalised by the permissible errors Δ it is the paper's sphere; ρ ≤ 1 leaves a
//! margin, so inside it every parameter is within ρ·Δ_k of the centre.

use crate::error::{positive, ConfigError};
use crate::state::{State9, NAMES};

/// Permissible errors and margin of the envelope.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Envelope {
    /// Permissible error Δ_k of each parameter (m, m/s, rad), all > 0.
    pub thresholds: State9,
    /// Envelope radius ρ in normalised units, in (0, 1]. Default 0.4.
    pub rho: f64,
}

impl Envelope {
    /// Checks Δ > 0 and ρ ∈ (0, 1].
    pub fn validate(&self) -> Result<(), ConfigError> {
        for (k, d) in self.thresholds.iter().enumerate() {
            positive(threshold_name(k), *d)?;
        }
        if !(self.rho.is_finite() && self.rho > 0.0 && self.rho <= 1.0) {
            return Err(ConfigError::OutOfRange { field: "rho", value: self.rho, expected: "ρ in (0, 1]" });
        }
        Ok(())
    }

    /// `Σ_k (d_k/Δ_k)²` of a deviation `d = X − O`.
    #[inline]
    pub fn normalised_sq(&self, deviation: &State9) -> f64 {
        deviation.component_div(&self.thresholds).norm_squared()
    }

    /// True when a deviation lies inside the envelope (on the boundary counts as inside).
    #[inline]
    pub fn contains(&self, deviation: &State9) -> bool {
        self.normalised_sq(deviation) <= self.rho * self.rho
    }
}

fn threshold_name(k: usize) -> &'static str {
    const FIELDS: [&str; 9] = [
        "threshold x",
        "threshold y",
        "threshold z",
        "threshold vx",
        "threshold vy",
        "threshold vz",
        "threshold alpha",
        "threshold beta",
        "threshold gamma",
    ];
    debug_assert_eq!(FIELDS.len(), NAMES.len());
    FIELDS[k]
}

#[cfg(test)]
mod tests {
    use super::*;

    fn env() -> Envelope {
        Envelope { thresholds: State9::from_element(1.0).map(|_| 0.5), rho: 1.0 }
    }

    #[test]
    fn membership_is_the_normalised_sphere() {
        let e = env();
        let mut d = State9::zeros();
        assert!(e.contains(&d));
        d[2] = 0.5; // exactly Δ_z: on the boundary
        assert!(e.contains(&d));
        d[2] = 0.5001;
        assert!(!e.contains(&d));
        // Two parameters each at 0.8·Δ: inside the box, outside the sphere.
        let mut d = State9::zeros();
        d[0] = 0.4;
        d[1] = 0.4;
        assert!(!e.contains(&d));
        let half = Envelope { rho: 0.5, ..e };
        let mut d = State9::zeros();
        d[7] = 0.26;
        assert!(!half.contains(&d));
        d[7] = 0.24;
        assert!(half.contains(&d));
    }

    #[test]
    fn rejects_bad_parameters() {
        assert!(Envelope { rho: 0.0, ..env() }.validate().is_err());
        assert!(Envelope { rho: 1.5, ..env() }.validate().is_err());
        let mut t = env();
        t.thresholds[4] = 0.0;
        assert!(t.validate().is_err());
        assert!(env().validate().is_ok());
    }
}
