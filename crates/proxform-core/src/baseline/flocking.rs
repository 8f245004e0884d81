//! Flocking with a virtual leader, after Olfati-Saber ("Flocking for multi-agent dynamic
//! systems: algorithms and theory", IEEE Trans. Automatic Control 51(3), 2006, Algorithm 2).
//!
//! `a_i = Σ_j φ_α(‖q_j − q_i‖_σ)·n̂_ij + k_a·Σ_j a_ij(q)(p_j − p_i) + f_γ`, with the σ-norm
//! `‖z‖_σ = (√(1 + ε‖z‖²) − 1)/ε`, the bump `ρ_h` and action `φ_α(z) = ρ_h(z/r_α)·φ(z − d_α)`,
//! `φ(z) = ½[(a + b)σ₁(z + c) + (a − b)]`, `σ₁(z) = z/√(1 + z²)`, `c = |a − b|/√(4ab)`,
//! adjacency `a_ij = ρ_h(‖q_j − q_i‖_σ / r_α)` and the navigation feedback
//! `f_γ = a_d − c₁(q_i − q_d) − c₂(p_i − p_d)` toward the UAV's slot `X_d = X_L + W_iL` (q
//! positions, p velocities in Olfati-Saber's notation). Two choices make it a formation law
//! rather than an α-lattice: the desired distance to neighbour j is the distance between the
//! two slots, and the γ-agent is the navigator plus the slot offset. The neighbours are those
//! the UAV senses onboard (range r = the sensing range); the virtual leader is the navigator's
//! state however it arrives (its broadcast, or sensing when in range). n̂_ij is the unit vector,
//! so a and b are accelerations (m/s²).

use std::sync::Arc;

use super::{act, mean_attitude, pd_acceleration, Hearing};
use crate::controller::{ControllerSetup, Decision};
use crate::error::{positive, ConfigError};
use crate::formation::Formation;
use crate::observation::{Observation, UavId};
use crate::state::{State9, ALPHA, VX, X};

/// Gains of the flocking law. Defaults: ε 0.1, h 0.2, a = b = 0.3 m/s², k_a 0.5/s,
/// c₁ 1/s², c₂ 2/s.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct FlockingGains {
    /// σ-norm parameter ε (> 0).
    pub epsilon: f64,
    /// Bump function parameter h ∈ (0, 1).
    pub h: f64,
    /// Attraction a of the action function (m/s², > 0).
    pub a_mps2: f64,
    /// Repulsion b of the action function (m/s², > 0).
    pub b_mps2: f64,
    /// Velocity-alignment gain k_a (1/s, ≥ 0).
    pub alignment_per_s: f64,
    /// Position gain c₁ toward the slot (1/s², > 0).
    pub c1: f64,
    /// Velocity gain c₂ toward the slot (1/s, > 0).
    pub c2: f64,
}

impl Default for FlockingGains {
    fn default() -> Self {
        Self { epsilon: 0.1, h: 0.2, a_mps2: 0.3, b_mps2: 0.3, alignment_per_s: 0.5, c1: 1.0, c2: 2.0 }
    }
}

impl FlockingGains {
    /// Checks the gains.
    pub fn validate(&self) -> Result<(), ConfigError> {
        positive("flocking.epsilon", self.epsilon)?;
        if !(self.h > 0.0 && self.h < 1.0) {
            return Err(ConfigError::OutOfRange { field: "flocking.h", value: self.h, expected: "a value in (0, 1)" });
        }
        positive("flocking.a_mps2", self.a_mps2)?;
        positive("flocking.b_mps2", self.b_mps2)?;
        if !(self.alignment_per_s.is_finite() && self.alignment_per_s >= 0.0) {
            return Err(ConfigError::OutOfRange {
                field: "flocking.alignment_per_s",
                value: self.alignment_per_s,
                expected: "a finite gain ≥ 0",
            });
        }
        positive("flocking.c1", self.c1)?;
        positive("flocking.c2", self.c2)
    }

    fn sigma_norm(&self, d: f64) -> f64 {
        ((1.0 + self.epsilon * d * d).sqrt() - 1.0) / self.epsilon
    }

    /// The bump function ρ_h.
    fn bump(&self, z: f64) -> f64 {
        if z < self.h {
            1.0
        } else if z <= 1.0 {
            0.5 * (1.0 + (std::f64::consts::PI * (z - self.h) / (1.0 - self.h)).cos())
        } else {
            0.0
        }
    }

    /// The uneven sigmoid φ.
    fn phi(&self, z: f64) -> f64 {
        let (a, b) = (self.a_mps2, self.b_mps2);
        let c = (a - b).abs() / (4.0 * a * b).sqrt();
        let s = z + c;
        0.5 * ((a + b) * s / (1.0 + s * s).sqrt() + (a - b))
    }
}

/// The flocking controller of one UAV.
#[derive(Debug, Clone)]
pub struct Flocking {
    gains: FlockingGains,
    core: Hearing,
}

impl Flocking {
    /// The flocking controller of UAV `id`, with `leader` as the virtual leader.
    pub fn new(
        id: UavId,
        leader: UavId,
        gains: FlockingGains,
        setup: Arc<ControllerSetup>,
        formation: Arc<Formation>,
    ) -> Result<Self, ConfigError> {
        gains.validate()?;
        let cap = setup.params().areas.areas + 1;
        Ok(Self { gains, core: Hearing::new(id, leader, setup, formation, cap)? })
    }

    /// The setup shared with the other controllers.
    pub fn setup(&self) -> &ControllerSetup {
        &self.core.setup
    }

    /// Bytes held on the heap.
    pub fn heap_bytes(&self) -> usize {
        self.core.heap_bytes()
    }

    /// One period: α-lattice terms from the sensed neighbours, γ feedback from the leader.
    pub fn step(&mut self, now_s: f64, own: &State9, observations: &[Observation]) -> Decision {
        let g = self.gains;
        let core = &mut self.core;
        let range = core.setup.params().areas.sensing_range_m;
        core.hear(now_s, observations, |_| true);
        if core.heard.is_empty() {
            return Decision::alone();
        }
        let Some(slot_i) = core.formation.slot(core.id) else { return Decision::alone() };
        let r_alpha = g.sigma_norm(range);
        let mut a = [0.0; 3];
        for h in &core.heard {
            let Some(slot_j) = core.formation.slot(h.id) else { continue };
            let q: [f64; 3] = std::array::from_fn(|k| h.now[X + k] - own[X + k]);
            let dist = (q[0] * q[0] + q[1] * q[1] + q[2] * q[2]).sqrt();
            if dist <= 1e-9 || dist > range {
                continue;
            }
            let z = g.sigma_norm(dist);
            let d_alpha = g.sigma_norm((slot_i.offset_m - slot_j.offset_m).norm());
            let adjacency = g.bump(z / r_alpha);
            let push = adjacency * g.phi(z - d_alpha) * h.weight / dist;
            for k in 0..3 {
                a[k] += push * q[k] + g.alignment_per_s * adjacency * h.weight * (h.now[VX + k] - own[VX + k]);
            }
        }
        let leader = core.heard.iter().find(|h| h.id == core.leader);
        let slot = leader.and_then(|h| core.slot_from(h));
        let attitude = match slot {
            Some((d_now, d_next)) => {
                let pd = super::PdGains { kp: g.c1, kv: g.c2 };
                let f = pd_acceleration(own, &d_now, &d_next, core.setup.params().dt_s, &pd);
                for k in 0..3 {
                    a[k] += f[k];
                }
                std::array::from_fn(|k| d_next[ALPHA + k])
            }
            None => {
                let desired = core.heard.iter().filter_map(|h| core.slot_from(h).map(|d| (d.1, h.weight)));
                mean_attitude(own, desired).unwrap_or_else(|| std::array::from_fn(|k| own[ALPHA + k]))
            }
        };
        act(&core.setup, own, a, attitude)
    }
}
