//! The proximity formation controller of one UAV (METHOD §2-§7).
//!
//! One call of [`ProximityController::step`] is one update period of the paper's method: it
//! sorts what the UAV perceives into azimuth areas (§2), predicts each kept neighbour (§3),
//! turns each prediction into an estimate of its own state through the formation offsets
//! (§4, eq. 10), averages them (eq. 11), leans on its main references by their dependency
//! degrees (§6 step 3), places the envelope centre on the line between the two (step 4), and
//! keeps its course while the course stays inside the envelope (steps 5-6) or computes the
//! one-step predictive input (step 7, eq. 12). The controller sees only its own state
//! estimate and its observations: it cannot tell a simulator from a network.

use std::sync::Arc;

use crate::azimuth::AzimuthAreas;
use crate::control::saturated_least_squares;
use crate::dependency::DependencySet;
use crate::envelope::Envelope;
use crate::error::{positive, unit_interval, ConfigError};
use crate::formation::Formation;
use crate::observation::{Observation, ObservationSource, UavId};
use crate::predictor::{NeighbourTracks, PredictorKind};
use crate::state::{self, Input, State9, VX, X};
use crate::vehicle::VehicleModel;

/// Parameters of the proximity controller. Defaults reproduce METHOD §9.
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct ControllerParams {
    /// Update period Δt (s, > 0). Default 0.1 s.
    pub dt_s: f64,
    /// Azimuth areas m and sensing range r_sense. Default 8 areas, 250 m.
    pub areas: AzimuthAreas,
    /// Distance parameter λ ∈ [0, 1] placing the envelope centre between the area mean
    /// (λ = 0) and the dependency mean (λ = 1). Default 0.8.
    pub lambda: f64,
    /// Permissible errors Δ and margin ρ of the envelope. Default: the paper's Δ, ρ = 0.4.
    pub envelope: Envelope,
    /// Time τ (s) over which the velocity reference closes a position gap: the velocity part
    /// of W, "determined by the current speed and relative position of proximal UAVs"
    /// (paper §2.3). `None` gives METHOD §4's zero velocity offset. Default 1 s.
    pub closing_time_s: Option<f64>,
    /// Input penalty (dimensionless, ≥ 0), applied to each input normalised by its per-step
    /// rate limit. Default 0.01.
    pub input_weight: f64,
    /// Neighbour predictor. Default α-β with α = 0.8, β = α²/(2 − α).
    pub predictor: PredictorKind,
    /// A neighbour track not refreshed for this long restarts (s, > 0). Default 1 s.
    pub track_timeout_s: f64,
}

impl ControllerParams {
    /// The paper's permissible errors Δ (METHOD §9) in SI units.
    pub fn paper_thresholds() -> State9 {
        use crate::angle::{deg, kmh};
        State9::from_column_slice(&[0.5, 0.6, 0.2, kmh(5.0), kmh(2.0), kmh(2.0), deg(0.4), deg(0.2), deg(0.5)])
    }

    /// Checks every parameter, naming the first one out of its domain.
    pub fn validate(&self) -> Result<(), ConfigError> {
        positive("dt_s", self.dt_s)?;
        self.areas.validate()?;
        unit_interval("lambda", self.lambda)?;
        self.envelope.validate()?;
        if let Some(tau) = self.closing_time_s {
            positive("closing_time_s", tau)?;
        }
        if !(self.input_weight.is_finite() && self.input_weight >= 0.0) {
            return Err(ConfigError::OutOfRange {
                field: "input_weight",
                value: self.input_weight,
                expected: "a finite weight ≥ 0",
            });
        }
        self.predictor.validate()?;
        positive("track_timeout_s", self.track_timeout_s)
    }
}

impl Default for ControllerParams {
    fn default() -> Self {
        Self {
            dt_s: 0.1,
            areas: AzimuthAreas::default(),
            lambda: 0.8,
            envelope: Envelope { thresholds: Self::paper_thresholds(), rho: 0.4 },
            closing_time_s: Some(1.0),
            input_weight: 0.01,
            predictor: PredictorKind::default(),
            track_timeout_s: 1.0,
        }
    }
}

/// What the controller decided in one update period.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Outcome {
    /// The course-keeping state was inside the envelope: no new input.
    Held,
    /// The course left the envelope and the UAV adjusted.
    Adjusted {
        /// `Σ((X − O)/Δ)²` of the course-keeping state before the adjustment.
        normalised_sq: f64,
    },
    /// Nothing was perceived: the UAV flies on its own prediction (METHOD §8).
    Alone,
}

impl Outcome {
    /// Short label used in reports.
    pub fn label(&self) -> &'static str {
        match self {
            Outcome::Held => "held",
            Outcome::Adjusted { .. } => "adjusted",
            Outcome::Alone => "alone",
        }
    }
}

/// The result of one step: the outcome and the input to apply (zero unless adjusted).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Decision {
    /// Held, adjusted or alone.
    pub outcome: Outcome,
    /// Input Δu for the coming period.
    pub input: Input,
    /// Number of areas that held a neighbour.
    pub occupied_areas: u16,
    /// Number of main references perceived.
    pub main_refs: u16,
}

/// Per-step working memory, allocated once.
#[derive(Debug, Clone)]
struct Scratch {
    /// For each area: index into the observation slice and squared horizontal distance.
    nearest: Vec<Option<(usize, f64)>>,
}

/// The controller of one UAV.
#[derive(Debug, Clone)]
pub struct ProximityController {
    id: UavId,
    params: ControllerParams,
    formation: Arc<Formation>,
    dependency: DependencySet,
    vehicle: VehicleModel,
    tracks: NeighbourTracks,
    q: State9,
    input_weights: Input,
    scratch: Scratch,
}

impl ProximityController {
    /// A controller for UAV `id` of `formation`.
    pub fn new(
        id: UavId,
        params: ControllerParams,
        formation: Arc<Formation>,
        dependency: DependencySet,
        vehicle: VehicleModel,
    ) -> Result<Self, ConfigError> {
        params.validate()?;
        vehicle.validate()?;
        if formation.slot(id).is_none() {
            return Err(ConfigError::UnknownUav { id, size: formation.len() });
        }
        for &(r, _) in dependency.refs() {
            if formation.slot(r).is_none() {
                return Err(ConfigError::BadReference { owner: id, reference: r, reason: "not in the formation" });
            }
        }
        let m = params.areas.areas;
        let tracks = NeighbourTracks::new(params.predictor, 2 * (m + dependency.refs().len()), params.track_timeout_s);
        let q = params.envelope.thresholds.map(|d| 1.0 / (d * d));
        let scale = vehicle.input_scale(params.dt_s);
        let n = vehicle.n_inputs();
        let input_weights =
            Input::from_fn(
                |j, _| {
                    if j < n && scale[j] > 0.0 {
                        params.input_weight / (scale[j] * scale[j])
                    } else {
                        0.0
                    }
                },
            );
        Ok(Self {
            id,
            params,
            formation,
            dependency,
            vehicle,
            tracks,
            q,
            input_weights,
            scratch: Scratch { nearest: vec![None; m] },
        })
    }

    /// This controller's UAV.
    pub fn id(&self) -> UavId {
        self.id
    }

    /// Its parameters.
    pub fn params(&self) -> &ControllerParams {
        &self.params
    }

    /// Its vehicle model.
    pub fn vehicle(&self) -> &VehicleModel {
        &self.vehicle
    }

    /// One update period at time `now_s`: `own` is the UAV's estimate of its own state,
    /// `observations` what it perceives of the others (each id at most once).
    pub fn step(&mut self, now_s: f64, own: &State9, observations: &[Observation]) -> Decision {
        let dt = self.params.dt_s;
        let x_hold = self.vehicle.hold(own, dt); // F·X_i(t): keep the present course
        let slot_i = match self.formation.slot(self.id) {
            Some(s) => *s,
            None => return alone(),
        };

        // §2: the nearest perceived UAV in each azimuth area.
        let areas = self.params.areas;
        let r2 = areas.sensing_range_m * areas.sensing_range_m;
        self.scratch.nearest.iter_mut().for_each(|a| *a = None);
        let yaw = own[state::BETA];
        for (k, o) in observations.iter().enumerate() {
            if o.id == self.id {
                continue;
            }
            let (dx, dy, dz) = (o.state[X] - own[X], o.state[X + 1] - own[X + 1], o.state[X + 2] - own[X + 2]);
            let d2 = dx * dx + dy * dy + dz * dz;
            if o.source == ObservationSource::Onboard && d2 > r2 {
                continue;
            }
            let s = areas.area_of(yaw, dx, dy);
            match self.scratch.nearest[s] {
                Some((_, best)) if best <= d2 => {}
                _ => self.scratch.nearest[s] = Some((k, d2)),
            }
        }

        // §3, §6 steps 1-3: per-neighbour estimates X̂_ij = F·X_j + W_ij, kept as deviations
        // from the course-keeping state (attitudes wrapped), then the area mean and the
        // dependency-weighted mean.
        let mut sum_bar = State9::zeros();
        let mut n_bar = 0u16;
        let mut sum_dep = State9::zeros();
        let mut c_sum = 0.0;
        let mut main_refs = 0u16;
        for (k, o) in observations.iter().enumerate() {
            if o.id == self.id {
                continue;
            }
            let in_area = self.scratch.nearest.iter().any(|a| matches!(a, Some((idx, _)) if *idx == k));
            let degree = self.dependency.degree(o.id);
            if !in_area && degree.is_none() {
                continue;
            }
            if !in_area && o.source == ObservationSource::Onboard {
                let d = state::position(&o.state) - state::position(own);
                if d.norm_squared() > r2 {
                    continue;
                }
            }
            let Some(slot_j) = self.formation.slot(o.id) else {
                continue;
            };
            let x_j = self.tracks.predict(o, now_s, dt); // F·X_j(t) with the neighbour's track
            let x_hat_ij = x_j + self.formation.w(&slot_i, slot_j, &x_j); // eq. 10
            let delta = state::difference(&x_hat_ij, &x_hold);
            if in_area {
                sum_bar += delta;
                n_bar += 1;
            }
            if let Some(c) = degree {
                sum_dep += c * delta;
                c_sum += c;
                main_refs += 1;
            }
        }
        if n_bar == 0 && main_refs == 0 {
            return alone();
        }

        // §6 step 4: O_i = (1 − λ)·X̄_i + λ·X̂ᴰ_i, as a deviation from the course.
        let lambda = self.params.lambda;
        let x_bar = if n_bar > 0 { sum_bar / f64::from(n_bar) } else { sum_dep / c_sum };
        let mut centre = if main_refs > 0 { (1.0 - lambda) * x_bar + lambda * (sum_dep / c_sum) } else { x_bar };
        // Velocity part of W (paper §2.3): close the remaining position gap over τ.
        if let Some(tau) = self.params.closing_time_s {
            for k in X..VX {
                centre[k + 3] += centre[k] / tau;
            }
        }

        // §6 steps 5-6: keep the course while X_hold lies inside the envelope around O.
        let r = -centre; // X_hold − O
        let envelope = &self.params.envelope;
        let normalised_sq = envelope.normalised_sq(&r);
        let occupied_areas = n_bar;
        if normalised_sq <= envelope.rho * envelope.rho {
            return Decision { outcome: Outcome::Held, input: Input::zeros(), occupied_areas, main_refs };
        }

        // §6 step 7: one-step predictive control, saturated by the vehicle's limits.
        let b = self.vehicle.control_matrix(own, dt);
        let (lo, hi) = self.vehicle.input_bounds(own, dt);
        let input = saturated_least_squares(&b, self.vehicle.n_inputs(), &r, &self.q, &self.input_weights, &lo, &hi);
        Decision { outcome: Outcome::Adjusted { normalised_sq }, input, occupied_areas, main_refs }
    }
}

fn alone() -> Decision {
    Decision { outcome: Outcome::Alone, input: Input::zeros(), occupied_areas: 0, main_refs: 0 }
}
