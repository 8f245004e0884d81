//! The proximity controller's parameters, with their units and defaults (METHOD §9).

use crate::azimuth::AzimuthAreas;
use crate::envelope::Envelope;
use crate::error::{positive, unit_interval, ConfigError};
use crate::predictor::PredictorKind;
use crate::state::State9;

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
    /// Limit the velocity that closes a position gap to what braking can stop within the gap,
    /// `min(|e|/τ, √(2·a·|e|))` on each axis, `a` the collision avoidance's share of the
    /// vehicle's braking (beyond the paper, METHOD §8): a UAV far from its slot (scattered
    /// starts, a change of formation, a UAV joining) arrives without overshooting it. It binds
    /// only on gaps wider than 2·a·τ² (5 m for the paper's vehicle), never in formation.
    /// Default true.
    pub stop_closing: bool,
    /// Input penalty (dimensionless, ≥ 0), applied to each input normalised by its per-step
    /// rate limit. Default 0.01.
    pub input_weight: f64,
    /// Neighbour predictor. Default α-β with α = 0.8, β = α²/(2 − α).
    pub predictor: PredictorKind,
    /// A neighbour track not refreshed for this long restarts (s, > 0). Default 1 s.
    pub track_timeout_s: f64,
    /// What a UAV forwards of the navigator (`radio.relay_navigator`) may be this old (s, > 0):
    /// the time since the measurement it goes back to, hop by hop. Each hop adds a radio delay
    /// and a period, so a chain of relays is older than one track's timeout; brought forward by
    /// the plan ([`crate::plan`]) the report keeps its place. Without the plan it is
    /// `track_timeout_s`. Default 10 s.
    pub relay_max_age_s: f64,
    /// A neighbour missing from the observations is predicted from its track for at most this
    /// long (s, ≥ 0; 0 disables coasting). Default 0.5 s.
    pub coast_s: f64,
    /// A coasting neighbour's acceleration is extrapolated for at most this long after its last
    /// measurement; beyond, it goes on at the velocity reached (s, ≥ 0). Default 0.2 s.
    pub coast_accel_s: f64,
    /// A coasting neighbour weighs `exp(−missing / coast_decay_s)` in the means, `missing` the
    /// time since a report of it last arrived (a measured one
    /// weighs 1), so that the centre does not jump when a neighbour drops out or comes back,
    /// and a UAV that has really gone fades out instead of being followed as a ghost (s, > 0).
    /// Default 0.1 s.
    pub coast_decay_s: f64,
    /// In a formation frame that turns (course or heading), the formation turns as one rigid
    /// body: W carries the slots' velocity in the turn (ω × r), ω the reference's turn rate
    /// ([`crate::VehicleModel::turn_rate`]: from its bank for the fixed wing, from its heading
    /// otherwise). Scenario files switch it on for the fixed wing and the multirotor. Default off.
    pub turn_feedforward: bool,
    /// A report older than one period (delayed, relayed, or a coasting track) is brought
    /// forward beyond it as the mission plan moves, when the setup knows the plan
    /// ([`crate::plan`], METHOD §3); off, its track's rates carry it all the way (the paper's
    /// prediction). Default on.
    pub plan_forward: bool,
    /// Onboard observations are measured relative to this UAV and placed in the world with its
    /// own measured state (relative sensing): its neighbour tracks then move with that
    /// measurement's error, so that a track coasting from an earlier period and the UAV's own
    /// state share its position-fix error (METHOD §8). Default off.
    pub relative_sensing: bool,
    /// With relative sensing, radio reports count only for a UAV that has heard nobody by its
    /// own sensors within `coast_s` (a joiner homing, a UAV whose sensors see no one): the
    /// senders' position fixes differ from this UAV's by more than the formation allows (each
    /// UAV's fix has a bias of its own), and a report in its sender's frame mixed with onboard
    /// observations in this UAV's would move the estimate by that difference. Off, only the
    /// reports of neighbours heard onboard are left out. Default off.
    pub radio_fallback: bool,
    /// Smoothing time (s, > 0) of the formation's turn acceleration ω̇ that a vehicle lagging
    /// its setpoints leads its slot's tangential acceleration by (METHOD §5, the multirotor).
    /// Default 0.3 s.
    pub turn_trend_s: f64,
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
    /// Collision avoidance (beyond the paper, METHOD §8), in m (≥ 0): no perceived neighbour
    /// may come closer than this (nor than [`SEPARATION_SLOT_FRACTION`] of the distance between
    /// the two slots). The UAV limits the speed at which it closes on each neighbour to what
    /// its own braking ([`crate::VehicleModel::braking_mps2`]) can stop before that distance,
    /// `√(2·a·(d − d_min))`; while a limit binds it flies the limited velocity instead of
    /// its envelope centre's position. It binds only on UAVs closing fast or already too
    /// close, as in forming from scattered starts and in formation changes. 0 switches it off;
    /// `None` leaves the choice to the caller (the simulator uses the scenario's safety
    /// distance) and is off for a controller on its own. Default `None`.
    pub avoid_m: Option<f64>,
    /// Horizon H of the predictive input (updates, 1 to 50). 1 is the paper's closed-form
    /// one-step input; H > 1 solves a quadratic program with Clarabel ([`crate::horizon`]).
    /// Default 1.
    pub horizon: u32,
    /// Robust fusion (beyond the paper, METHOD §8), in permissible errors (> 0): with at least
    /// three neighbours' estimates X̂_ij, each is compared with their per-axis median position;
    /// one farther than `g`·Δ on some axis weighs less, linearly down to nothing at 2`g`·Δ, in
    /// X̄_i and X̂ᴰ_i alike. `None` is the paper's plain means. Default `None`.
    pub isolation_gate: Option<f64>,
    /// Own-sensor check (beyond the paper, METHOD §8), in m (> 0): a measurement of the UAV's
    /// own position farther than this from what its own model predicted (from its last
    /// estimate and the input it applied) is suspect, and the UAV flies on that prediction
    /// instead. `None` trusts every measurement. Default `None`.
    pub own_gate_m: Option<f64>,
    /// How fast the own-sensor check's gate widens while measurements are refused once one of
    /// them was frozen (m/s, ≥ 0): the drift of a prediction dead-reckoned without velocity
    /// readings, which the wind moves the UAV off. While every refused reading moves, it widens
    /// at the dead reckoning's own drift ([`crate::own_estimate::OWN_DRIFT_MPS`], or this where
    /// lower). A measurement that stays away longer than the prediction can be trusted is
    /// accepted again. Default 1 m/s.
    pub own_gate_growth_mps: f64,
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

    /// Permissible errors Δ for a multirotor (SI units): 0.4 m on each axis, 0.5 m/s (1.8 km/h)
    /// on each velocity component, 1.5° of yaw, and 30° of pitch and roll. Its pitch and roll are
    /// its inner loop's (they follow its accelerations and lean it into the wind; the controller
    /// does not steer them), so they should not ask for corrections.
    pub fn multirotor_thresholds() -> State9 {
        use crate::angle::{deg, kmh};
        State9::from_column_slice(&[0.4, 0.4, 0.4, kmh(1.8), kmh(1.8), kmh(1.8), deg(30.0), deg(1.5), deg(30.0)])
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
        positive("relay_max_age_s", self.relay_max_age_s)?;
        positive("turn_trend_s", self.turn_trend_s)?;
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
        if let Some(d) = self.avoid_m {
            if !(d.is_finite() && d >= 0.0) {
                return Err(ConfigError::OutOfRange {
                    field: "avoid_m",
                    value: d,
                    expected: "a finite distance ≥ 0 m",
                });
            }
        }
        if let Some(g) = self.isolation_gate {
            positive("isolation_gate", g)?;
        }
        if let Some(g) = self.own_gate_m {
            positive("own_gate_m", g)?;
        }
        if !(self.own_gate_growth_mps.is_finite() && self.own_gate_growth_mps >= 0.0) {
            return Err(ConfigError::OutOfRange {
                field: "own_gate_growth_mps",
                value: self.own_gate_growth_mps,
                expected: "a finite speed ≥ 0 m/s",
            });
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

impl ControllerParams {
    /// Weight of a neighbour known only from its track, `age` seconds after its last
    /// measurement: `exp(−age / coast_decay_s)` (measured neighbours weigh 1).
    #[inline]
    pub fn coasting_weight(&self, age: f64) -> f64 {
        (-age / self.coast_decay_s).exp()
    }
}

/// Separation keeping engages only for a neighbour closer than this fraction of the distance
/// between its slot and the UAV's own (see [`ControllerParams::separation_m`]).
pub const SEPARATION_SLOT_FRACTION: f64 = 0.8;

/// Collision avoidance counts on this share of the vehicle's braking
/// ([`crate::VehicleModel::braking_mps2`]): the limit it follows is then twice the distance
/// the UAV needs to stop, room for the lag of its rate-limited inputs and for a neighbour that
/// does not give way (the navigator).
pub const AVOID_BRAKING_SHARE: f64 = 0.5;

/// A sensor serving the collision avoidance reports every UAV within this many avoidance
/// distances (`avoid_m`), not only the nearest of each azimuth area: one hidden behind another
/// may be the one closing fastest.
pub const AVOID_WATCH: f64 = 2.0;

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
            stop_closing: true,
            input_weight: 0.01,
            predictor: PredictorKind::default(),
            track_timeout_s: 1.0,
            relay_max_age_s: 10.0,
            coast_s: 0.5,
            coast_accel_s: 0.2,
            coast_decay_s: 0.1,
            turn_feedforward: false,
            plan_forward: true,
            relative_sensing: false,
            radio_fallback: false,
            turn_trend_s: 0.3,
            own_filter_gain: 1.0,
            separation_m: None,
            avoid_m: None,
            horizon: 1,
            isolation_gate: None,
            own_gate_m: None,
            own_gate_growth_mps: 1.0,
        }
    }
}
