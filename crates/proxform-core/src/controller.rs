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

use crate::azimuth::{AreaClassifier, AzimuthAreas};
use crate::control::{solve, Hessian};
use crate::dependency::DependencySet;
use crate::envelope::Envelope;
use crate::error::{positive, unit_interval, ConfigError};
use crate::formation::{Formation, FormationSlot};
use crate::horizon::{solve_horizon, HorizonProblem};
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
    /// A neighbour missing from the observations is predicted from its track for at most this
    /// long (s, ≥ 0; 0 disables coasting). Default 0.5 s.
    pub coast_s: f64,
    /// A coasting neighbour's acceleration is extrapolated for at most this long after its last
    /// measurement; beyond, it goes on at the velocity reached (s, ≥ 0). Default 0.2 s.
    pub coast_accel_s: f64,
    /// A coasting neighbour weighs `exp(−age / coast_decay_s)` in the means (a measured one
    /// weighs 1), so that the centre does not jump when a neighbour drops out or comes back,
    /// and a UAV that has really gone fades out instead of being followed as a ghost (s, > 0).
    /// Default 0.1 s.
    pub coast_decay_s: f64,
    /// In a course-following formation frame, add the slots' velocity in the turn (ω × r),
    /// with ω the reference's coordinated-turn rate from its bank. Only meaningful for vehicles
    /// that turn by banking (the fixed wing); scenario files switch it on for them. Default off.
    pub bank_turn_feedforward: bool,
    /// Gain in (0, 1] of the UAV's filter of its own state: the estimate is the model's
    /// prediction from the last estimate and the input the UAV applied, corrected toward the
    /// measurement by this fraction. 1 uses the raw measurement (METHOD). Default 1.
    pub own_filter_gain: f64,
    /// Separation keeping (m, ≥ 0; beyond the paper, METHOD §8): a neighbour predicted closer
    /// than this, and closer than [`SEPARATION_SLOT_FRACTION`] of the distance between the two
    /// slots, pushes the envelope centre's position away from it by the shortfall, which the
    /// velocity part of W then closes over τ. The slot condition keeps a formation whose
    /// slots are closer than this from being pushed apart. 0 switches it off; `None` leaves
    /// the choice to the caller (the simulator uses twice the scenario's safety distance) and
    /// is off for a controller on its own. Default `None`.
    pub separation_m: Option<f64>,
    /// Horizon H of the predictive input (updates, 1 to 50). 1 is the paper's closed-form
    /// one-step input; H > 1 solves a quadratic program with Clarabel ([`crate::horizon`]).
    /// Default 1.
    pub horizon: u32,
}

impl ControllerParams {
    /// The paper's permissible errors Δ (METHOD §9) in SI units.
    pub fn paper_thresholds() -> State9 {
        use crate::angle::{deg, kmh};
        State9::from_column_slice(&[0.5, 0.6, 0.2, kmh(5.0), kmh(2.0), kmh(2.0), deg(0.4), deg(0.2), deg(0.5)])
    }

    /// Permissible errors Δ for a fixed wing (SI units): 2 m on each axis, 2 m/s (7.2 km/h) on
    /// each velocity component, 5° of pitch, 10° of yaw and of roll. A fixed wing corrects its
    /// position only by pitching, turning and banking away from its neighbours' attitude, so
    /// the paper's tenths of a degree, made for a vehicle that moves sideways without
    /// turning, would forbid every correction (measured: the V of `scenarios/fixed-wing-v.toml`
    /// with the paper's Δ errs by up to 75 m and has pairs within 12.7 m in 7 of 200 runs).
    pub fn fixed_wing_thresholds() -> State9 {
        use crate::angle::{deg, kmh};
        State9::from_column_slice(&[2.0, 2.0, 2.0, kmh(7.2), kmh(7.2), kmh(7.2), deg(5.0), deg(10.0), deg(10.0)])
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
        positive("track_timeout_s", self.track_timeout_s)?;
        if !(self.coast_s.is_finite() && self.coast_s >= 0.0) {
            return Err(ConfigError::OutOfRange {
                field: "coast_s",
                value: self.coast_s,
                expected: "a finite time ≥ 0 s",
            });
        }
        if !(self.own_filter_gain > 0.0 && self.own_filter_gain <= 1.0) {
            return Err(ConfigError::OutOfRange {
                field: "own_filter_gain",
                value: self.own_filter_gain,
                expected: "a gain in (0, 1]",
            });
        }
        if let Some(d) = self.separation_m {
            if !(d.is_finite() && d >= 0.0) {
                return Err(ConfigError::OutOfRange {
                    field: "separation_m",
                    value: d,
                    expected: "a finite distance ≥ 0 m",
                });
            }
        }
        if !(1..=MAX_HORIZON).contains(&self.horizon) {
            return Err(ConfigError::OutOfRange {
                field: "horizon",
                value: f64::from(self.horizon),
                expected: "an integer horizon from 1 to 50",
            });
        }
        Ok(())
    }
}

/// Separation keeping engages only for a neighbour closer than this fraction of the distance
/// between its slot and the UAV's own (see [`ControllerParams::separation_m`]).
pub const SEPARATION_SLOT_FRACTION: f64 = 0.8;

/// Longest horizon accepted (updates).
pub const MAX_HORIZON: u32 = 50;

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
            coast_s: 0.5,
            coast_accel_s: 0.2,
            coast_decay_s: 0.1,
            bank_turn_feedforward: false,
            own_filter_gain: 1.0,
            separation_m: None,
            horizon: 1,
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

/// What every controller of a swarm shares: the parameters, the vehicle model, and what is
/// derived from them once (weights, area boundaries, the cost Hessian when B is constant).
#[derive(Debug, Clone)]
pub struct ControllerSetup {
    params: ControllerParams,
    vehicle: VehicleModel,
    q: State9,
    input_weights: Input,
    classifier: AreaClassifier,
    hessian: Option<Hessian>,
}

impl ControllerSetup {
    /// Checks `params` and `vehicle` and derives the shared quantities.
    pub fn new(params: ControllerParams, vehicle: VehicleModel) -> Result<Arc<Self>, ConfigError> {
        params.validate()?;
        vehicle.validate()?;
        let q = params.envelope.thresholds.map(|d| 1.0 / (d * d));
        let scale = vehicle.input_scale(params.dt_s);
        let n = vehicle.n_inputs();
        let input_weights =
            Input::from_fn(
                |j, _| if j < n && scale[j] > 0.0 { params.input_weight / (scale[j] * scale[j]) } else { 0.0 },
            );
        let hessian = vehicle
            .control_matrix_is_constant()
            .then(|| Hessian::new(&vehicle.control_matrix(&State9::zeros(), params.dt_s), n, &q, &input_weights));
        let classifier = AreaClassifier::new(params.areas.areas);
        Ok(Arc::new(Self { params, vehicle, q, input_weights, classifier, hessian }))
    }

    /// The parameters.
    pub fn params(&self) -> &ControllerParams {
        &self.params
    }

    /// The vehicle model.
    pub fn vehicle(&self) -> &VehicleModel {
        &self.vehicle
    }

    /// METHOD §6 step 7: the input that brings the UAV at `own` toward the target whose
    /// course-keeping deviation is `r = F·X − target`, within the vehicle's limits: the
    /// closed-form step for H = 1, the horizon QP for H > 1 (falling back to the one-step
    /// input if the solver fails). Every controller of proxform, the baselines included,
    /// turns its target into an input here, so they all fly under the same limits.
    pub fn input_toward(&self, own: &State9, r: &State9) -> Input {
        let (vehicle, dt) = (&self.vehicle, self.params.dt_s);
        let b = vehicle.control_matrix(own, dt);
        let (lo, hi) = vehicle.input_bounds(own, dt);
        if self.params.horizon > 1 {
            let cumulative = vehicle.cumulative_input_bounds(own);
            let rate = vehicle.input_scale(dt);
            let neg_rate = -rate;
            let pb = HorizonProblem {
                horizon: self.params.horizon as usize,
                n: vehicle.n_inputs(),
                dt,
                b: &b,
                r,
                q: &self.q,
                w: &self.input_weights,
                first: (&lo, &hi),
                // Where the state limits are in the cumulative bounds, later steps are bound
                // by the rate only; otherwise by the first step's bounds.
                later: if cumulative.is_some() { (&neg_rate, &rate) } else { (&lo, &hi) },
                cumulative: cumulative.as_ref().map(|(l, h)| (l, h)),
            };
            if let Ok(u) = solve_horizon(&pb) {
                return u;
            }
        }
        match &self.hessian {
            Some(h) => solve(h, &b, r, &self.q, &lo, &hi),
            None => {
                let h = Hessian::new(&b, vehicle.n_inputs(), &self.q, &self.input_weights);
                solve(&h, &b, r, &self.q, &lo, &hi)
            }
        }
    }
}

/// Marks an empty area in the per-area scratch.
const EMPTY: u32 = u32::MAX;
/// Marks an area candidate that is a coasting track (its slot in the low bits), not an
/// observation index.
const TRACK: u32 = 1 << 31;

/// The controller of one UAV.
#[derive(Debug, Clone)]
pub struct ProximityController {
    id: UavId,
    setup: Arc<ControllerSetup>,
    formation: Arc<Formation>,
    dependency: DependencySet,
    tracks: NeighbourTracks,
    /// Per area: index into the observation slice of the nearest UAV (or `EMPTY`) and its
    /// squared distance (f32 is ample to rank neighbours). Working memory, allocated once.
    nearest: Box<[(u32, f32)]>,
    /// The own state this UAV expects at the next step: the model applied to its estimate
    /// and the input it chose (None before the first step, and when the filter is off; boxed
    /// so that controllers without it stay small).
    own_prediction: Option<Box<State9>>,
}

impl ProximityController {
    /// A controller for UAV `id` of `formation`.
    pub fn new(
        id: UavId,
        setup: Arc<ControllerSetup>,
        formation: Arc<Formation>,
        dependency: DependencySet,
    ) -> Result<Self, ConfigError> {
        if formation.slot(id).is_none() {
            return Err(ConfigError::UnknownUav { id, size: formation.len() });
        }
        for &(r, _) in dependency.refs() {
            if formation.slot(r).is_none() {
                return Err(ConfigError::BadReference { owner: id, reference: r, reason: "not in the formation" });
            }
        }
        let p = &setup.params;
        let m = p.areas.areas;
        let tracks = NeighbourTracks::new(p.predictor, m + dependency.refs().len(), p.track_timeout_s, p.coast_accel_s);
        Ok(Self {
            id,
            setup,
            formation,
            dependency,
            tracks,
            nearest: vec![(EMPTY, 0.0); m].into_boxed_slice(),
            own_prediction: None,
        })
    }

    /// A controller with its own [`ControllerSetup`] (convenient for a single UAV).
    pub fn standalone(
        id: UavId,
        params: ControllerParams,
        formation: Arc<Formation>,
        dependency: DependencySet,
        vehicle: VehicleModel,
    ) -> Result<Self, ConfigError> {
        Self::new(id, ControllerSetup::new(params, vehicle)?, formation, dependency)
    }

    /// This controller's UAV.
    pub fn id(&self) -> UavId {
        self.id
    }

    /// Its parameters.
    pub fn params(&self) -> &ControllerParams {
        &self.setup.params
    }

    /// Its vehicle model.
    pub fn vehicle(&self) -> &VehicleModel {
        &self.setup.vehicle
    }

    /// Bytes this controller holds on the heap (shared setup and formation excluded).
    pub fn heap_bytes(&self) -> usize {
        self.tracks.heap_bytes() + std::mem::size_of_val(&*self.nearest)
    }

    /// One update period at time `now_s`: `own` is the UAV's estimate of its own state,
    /// `observations` what it perceives of the others (each id at most once).
    pub fn step(&mut self, now_s: f64, own_measured: &State9, observations: &[Observation]) -> Decision {
        // The own-state filter: the model's prediction corrected toward the measurement.
        let gain = self.setup.params.own_filter_gain;
        let own = match self.own_prediction {
            Some(ref pred) if gain < 1.0 => {
                // Position and velocity are filtered; attitude, measured far more finely than
                // its tolerances, is taken as measured (filtering it would only add lag).
                let mut own = **pred + gain * state::difference(own_measured, pred);
                for k in state::ALPHA..=state::GAMMA {
                    own[k] = own_measured[k];
                }
                own
            }
            _ => *own_measured,
        };
        let decision = self.decide(now_s, &own, observations);
        if gain < 1.0 {
            let (vehicle, dt) = (&self.setup.vehicle, self.setup.params.dt_s);
            let next = vehicle.propagate(&own, &decision.input, dt);
            match &mut self.own_prediction {
                Some(p) => **p = next,
                None => self.own_prediction = Some(Box::new(next)),
            }
        }
        decision
    }

    /// Forgets the own-state prediction (after inputs that were not applied).
    pub fn forget_own_prediction(&mut self) {
        self.own_prediction = None;
    }

    /// The method proper, from the UAV's own state estimate.
    fn decide(&mut self, now_s: f64, own: &State9, observations: &[Observation]) -> Decision {
        let Self { id: me, setup, formation, dependency, tracks, nearest, .. } = self;
        let (me, setup, formation) = (*me, &**setup, &**formation);
        let (params, vehicle) = (&setup.params, &setup.vehicle);
        let dt = params.dt_s;
        let x_hold = vehicle.hold(own, dt); // F·X_i(t): keep the present course
        let slot_i = match formation.slot(me) {
            Some(s) => *s,
            None => return alone(),
        };

        // §2: the nearest perceived UAV in each azimuth area.
        let r2 = params.areas.sensing_range_m.powi(2);
        nearest.iter_mut().for_each(|a| a.0 = EMPTY);
        let (sin_yaw, cos_yaw) = own[state::BETA].sin_cos();
        for (k, o) in observations.iter().enumerate() {
            if o.id == me {
                continue;
            }
            let (dx, dy, dz) = (o.state[X] - own[X], o.state[X + 1] - own[X + 1], o.state[X + 2] - own[X + 2]);
            let d2 = dx * dx + dy * dy + dz * dz;
            if o.source == ObservationSource::Onboard && d2 > r2 {
                continue;
            }
            let s = setup.classifier.area(sin_yaw, cos_yaw, dx, dy);
            let a = &mut nearest[s];
            let d2 = d2 as f32;
            if a.0 == EMPTY || d2 < a.1 {
                *a = (k as u32, d2);
            }
        }
        // §3: neighbours perceived recently but missing now coast on their tracks.
        let coast = params.coast_s;
        for s in 0..tracks.slots() {
            let Some(id) = tracks.coasting(s, now_s, coast) else { continue };
            if id == me || observations.iter().any(|o| o.id == id) {
                continue;
            }
            let x = tracks.state_at(s, now_s);
            let (dx, dy, dz) = (x[X] - own[X], x[X + 1] - own[X + 1], x[X + 2] - own[X + 2]);
            let d2 = dx * dx + dy * dy + dz * dz;
            if d2 > r2 {
                continue;
            }
            // A coasting neighbour only fills an area that has no fresh observation.
            let a = &mut nearest[setup.classifier.area(sin_yaw, cos_yaw, dx, dy)];
            let d2 = d2 as f32;
            if a.0 == EMPTY || (a.0 & TRACK != 0 && d2 < a.1) {
                *a = (TRACK | s as u32, d2);
            }
        }

        // §3, §6 steps 1-3: per-neighbour estimates X̂_ij = F·X_j + W_ij, kept as deviations
        // from the course-keeping state (attitudes wrapped), then the area mean and the
        // dependency-weighted mean. Area neighbours first, then main references perceived
        // outside the areas' nearest.
        let mut sum_bar = State9::zeros();
        let mut n_bar = 0u16;
        let mut w_bar = 0.0;
        let mut sum_dep = State9::zeros();
        let mut c_sum = 0.0;
        let mut main_refs = 0u16;
        let separation = params.separation_m.unwrap_or(0.0);
        let mut push = [0.0f64; 3];
        for a in 0..nearest.len() {
            let k = nearest[a].0;
            if k == EMPTY {
                continue;
            }
            let (id, x_j, f) = if k & TRACK != 0 {
                let s = (k & !TRACK) as usize;
                match tracks.coasting(s, now_s, params.coast_s) {
                    Some(id) => (id, tracks.state_at(s, now_s + dt), freshness(params, tracks.age(s, now_s))),
                    None => continue,
                }
            } else {
                let o = &observations[k as usize];
                (o.id, tracks.predict(o, now_s, dt), 1.0) // F·X_j(t) with the neighbour's track
            };
            if separation > 0.0 {
                keep_apart(formation, id, &x_j, &slot_i, &x_hold, separation, &mut push);
            }
            let Some(delta) = deviation(formation, id, &x_j, &slot_i, &x_hold, params.bank_turn_feedforward) else {
                continue;
            };
            sum_bar += f * delta;
            w_bar += f;
            n_bar += 1;
            if let Some(c) = dependency.degree(id) {
                sum_dep += (c * f) * delta;
                c_sum += c * f;
                main_refs += 1;
            }
        }
        for r in 0..dependency.refs().len() {
            let (id, c) = dependency.refs()[r];
            let x_j = match observations.iter().position(|o| o.id == id) {
                Some(k) => {
                    if nearest.iter().any(|a| a.0 == k as u32) {
                        continue; // already counted with its area
                    }
                    let o = &observations[k];
                    if o.source == ObservationSource::Onboard
                        && (state::position(&o.state) - state::position(own)).norm_squared() > r2
                    {
                        continue;
                    }
                    (tracks.predict(o, now_s, dt), 1.0)
                }
                None => {
                    // Not observed now: coast on its track, unless its area already did.
                    let Some(s) = (0..tracks.slots()).find(|&s| tracks.coasting(s, now_s, params.coast_s) == Some(id))
                    else {
                        continue;
                    };
                    if nearest.iter().any(|a| a.0 == TRACK | s as u32) {
                        continue;
                    }
                    (tracks.state_at(s, now_s + dt), freshness(params, tracks.age(s, now_s)))
                }
            };
            let (x_j, f) = x_j;
            let Some(delta) = deviation(formation, id, &x_j, &slot_i, &x_hold, params.bank_turn_feedforward) else {
                continue;
            };
            sum_dep += (c * f) * delta;
            c_sum += c * f;
            main_refs += 1;
        }
        if n_bar == 0 && main_refs == 0 {
            return alone();
        }

        // §6 step 4: O_i = (1 − λ)·X̄_i + λ·X̂ᴰ_i, as a deviation from the course.
        let lambda = params.lambda;
        let x_bar = if n_bar > 0 { sum_bar / w_bar } else { sum_dep / c_sum };
        let mut centre = if main_refs > 0 { (1.0 - lambda) * x_bar + lambda * (sum_dep / c_sum) } else { x_bar };
        // Separation keeping (beyond the paper): away from neighbours that come too close.
        for k in X..VX {
            centre[k] += push[k];
        }
        // Velocity part of W (paper §2.3): close the remaining position gap over τ.
        if let Some(tau) = params.closing_time_s {
            for k in X..VX {
                centre[k + 3] += centre[k] / tau;
            }
        }

        // §6 steps 5-6: keep the course while X_hold lies inside the envelope around O.
        let r = -centre; // X_hold − O
        let envelope = &params.envelope;
        let normalised_sq = envelope.normalised_sq(&r);
        let occupied_areas = n_bar;
        if normalised_sq <= envelope.rho * envelope.rho {
            return Decision { outcome: Outcome::Held, input: Input::zeros(), occupied_areas, main_refs };
        }

        // §6 step 7: predictive control within the vehicle's limits.
        let input = setup.input_toward(own, &r);
        Decision { outcome: Outcome::Adjusted { normalised_sq }, input, occupied_areas, main_refs }
    }
}

/// Weight of a neighbour known only from its track, `age` seconds after its last
/// measurement: `exp(−age / coast_decay_s)` (measured neighbours weigh 1).
#[inline]
fn freshness(params: &ControllerParams, age: f64) -> f64 {
    (-age / params.coast_decay_s).exp()
}

/// `X̂_ij − X_hold` for neighbour `id` predicted at `x_j` (eq. 10, attitudes wrapped); None
/// when the neighbour is not in the formation.
#[inline]
fn deviation(
    formation: &Formation,
    id: UavId,
    x_j: &State9,
    slot_i: &FormationSlot,
    x_hold: &State9,
    turn_feedforward: bool,
) -> Option<State9> {
    let slot_j = formation.slot(id)?;
    // X̂_ij − X_hold = (F·X_j + W_ij) − X_hold, built in place.
    let mut delta = x_j - x_hold;
    if turn_feedforward {
        formation.add_w_turning(slot_i, slot_j, x_j, &mut delta);
    } else {
        formation.add_w(slot_i, slot_j, x_j, &mut delta);
    }
    for k in state::ALPHA..=state::GAMMA {
        delta[k] = crate::angle::wrap_pi(delta[k]);
    }
    Some(delta)
}

/// Adds to `push` how far the UAV, at `x_hold` next step, must move away from neighbour `id`
/// predicted at `x_j` to be `separation` m from it, when it is closer than that and closer than
/// [`SEPARATION_SLOT_FRACTION`] of their slots' distance.
#[inline]
fn keep_apart(
    formation: &Formation,
    id: UavId,
    x_j: &State9,
    slot_i: &FormationSlot,
    x_hold: &State9,
    separation: f64,
    push: &mut [f64; 3],
) {
    let p = [x_hold[X] - x_j[X], x_hold[X + 1] - x_j[X + 1], x_hold[X + 2] - x_j[X + 2]];
    let d2 = p[0] * p[0] + p[1] * p[1] + p[2] * p[2];
    if d2 >= separation * separation {
        return;
    }
    let Some(slot_j) = formation.slot(id) else { return };
    let limit = separation.min(SEPARATION_SLOT_FRACTION * (slot_j.offset_m - slot_i.offset_m).norm());
    let d = d2.sqrt();
    if d < limit && d > 1e-9 {
        for k in 0..3 {
            push[k] += (limit - d) * p[k] / d;
        }
    }
}

fn alone() -> Decision {
    Decision { outcome: Outcome::Alone, input: Input::zeros(), occupied_areas: 0, main_refs: 0 }
}
