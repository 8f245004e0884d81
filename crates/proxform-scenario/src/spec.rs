//! The scenario file format: raw TOML tables as written by users, before any check.
//!
//! Units are always in the key: `_m`, `_s`, `_kmh` (speeds), `_kmh_s` (speed change per
//! second), `_deg`, `_deg_s`. Every key is optional unless marked; omitted keys take the
//! paper experiment's values. Unknown keys are errors. The conversion in [`crate::convert`]
//! turns a spec into a checked [`crate::Scenario`]; [`crate::load`] reads one from TOML text and
//! locates errors in it; `docs/scenarios.md` documents every key.
//!
//! A spec is also what every override edits: the command line, a comparison's conditions and
//! the Python package change the spec and convert it again, so every check applies to them.

use std::collections::BTreeMap;

use serde::{Deserialize, Serialize};

/// A whole scenario file.
#[derive(Debug, Clone, Default, PartialEq, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct ScenarioSpec {
    /// Name used in reports. Default: the file name.
    pub name: Option<String>,
    /// Update period Δt (s). Default 0.1.
    pub dt_s: Option<f64>,
    /// Flight duration (s). Default 100.
    pub duration_s: Option<f64>,
    /// Number (from 1) of the navigator. Default 1.
    pub navigator: Option<u32>,
    /// Pairs closer than this are unsafe (m). Default 50.
    pub safety_distance_m: Option<f64>,
    /// How long the formation has flown before t = 0 (s, ≥ 0). Default 1.
    pub warmup_s: Option<f64>,
    /// Which engine steps the flight: "reference" (one agent object per UAV, bit-identical
    /// across versions), "fast" (every phase over arrays, for large swarms) or "auto" (the fast
    /// one from 10 000 UAVs when it runs the scenario). Default "auto".
    pub engine: Option<String>,
    /// The formation (required: slots or a shape).
    #[serde(default)]
    pub formation: FormationSpec,
    /// The navigator's path. Default: the paper's.
    #[serde(default)]
    pub path: PathSpec,
    /// Initial state of every UAV. Default: the navigator's initial state, each in its slot.
    #[serde(default)]
    pub initial: InitialSpec,
    /// Controller parameters.
    #[serde(default)]
    pub controller: ControllerSpec,
    /// Vehicle model.
    #[serde(default)]
    pub vehicle: VehicleSpec,
    /// Measurement noise and actuation error.
    #[serde(default)]
    pub noise: NoiseSpec,
    /// Onboard sensing.
    #[serde(default)]
    pub sensing: SensingSpec,
    /// Radio.
    #[serde(default)]
    pub radio: RadioSpec,
    /// The transport of a distributed run (world ↔ agents).
    #[serde(default)]
    pub network: NetworkSpec,
    /// Wind, turbulence and gusts.
    #[serde(default)]
    pub wind: WindSpec,
    /// Pass criterion.
    #[serde(default)]
    pub allowable: AllowableSpec,
    /// Scheduled faults.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub fault: Vec<FaultSpec>,
}

/// `[formation]`.
#[derive(Debug, Clone, Default, PartialEq, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct FormationSpec {
    /// "world" (default) or "course".
    pub frame: Option<String>,
    /// When a UAV is lost, the others take new slots: a slot at the formation's edge is left
    /// empty and the survivors re-assigned (by `[initial] assign_by`). Default false.
    pub reassign_on_loss: Option<bool>,
    /// Explicit slots (`[[formation.slot]]`), or …
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub slot: Vec<SlotSpec>,
    /// … a generated shape (`[formation.shape]`).
    pub shape: Option<ShapeSpec>,
    /// How dependency tables are derived for slots without `depends_on`.
    pub dependencies: Option<AutoDepsSpec>,
    /// Changes of formation in flight (`[[formation.change]]`), in time order.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub change: Vec<FormationChangeSpec>,
}

/// One `[[formation.change]]`: from `at_s` on, other slots (explicit or a shape), with their
/// own dependency tables; the frame stays the formation's.
#[derive(Debug, Clone, Default, PartialEq, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct FormationChangeSpec {
    /// When the new formation takes over (s, > 0, before the end) (required).
    pub at_s: Option<f64>,
    /// Explicit slots, as many as the formation's, or …
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub slot: Vec<SlotSpec>,
    /// … a generated shape.
    pub shape: Option<ShapeSpec>,
    /// How dependency tables are derived for slots without `depends_on`.
    pub dependencies: Option<AutoDepsSpec>,
}

/// One explicit slot.
#[derive(Debug, Clone, Default, PartialEq, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct SlotSpec {
    /// UAV number, from 1, unique (required).
    pub id: Option<u32>,
    /// Offset in the formation frame: forward, left, up (m) (required).
    pub offset_m: Option<[f64; 3]>,
    /// Attitude offset: pitch, yaw, roll (deg). Default 0.
    pub attitude_offset_deg: Option<[f64; 3]>,
    /// Main references: UAV number (as a string key) → dependency degree.
    pub depends_on: Option<BTreeMap<String, f64>>,
}

/// `[formation.shape]`: a generated formation.
#[derive(Debug, Clone, Default, PartialEq, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct ShapeSpec {
    /// "triangle", "v", "echelon", "line_abreast", "column", "diamond", "grid", "lattice",
    /// "circle".
    pub kind: Option<String>,
    /// Number of UAVs (all shapes but triangle, which uses `rows`).
    pub uavs: Option<u32>,
    /// Rows of the triangle (row r holds r + 1 UAVs) or of the grid.
    pub rows: Option<u32>,
    /// Distance between neighbouring UAVs (m).
    pub spacing_m: Option<f64>,
    /// Half-angle of a V or angle of an echelon from the course (deg). Default 30.
    pub angle_deg: Option<f64>,
    /// Height step between successive rows or ranks (m, may be negative). Default 0.
    pub level_step_m: Option<f64>,
    /// Echelon side: "left" or "right". Default "right".
    pub side: Option<String>,
    /// Lattice levels (≥ 1). Default: 1 below 50 UAVs, 2 below 400, then 4.
    pub levels: Option<u32>,
}

/// `[formation.dependencies]`.
#[derive(Debug, Clone, Default, PartialEq, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct AutoDepsSpec {
    /// Main references per UAV. Default 2.
    pub k: Option<u32>,
    /// Farthest reference (m). Default: the sensing range.
    pub max_distance_m: Option<f64>,
    /// Degree of every follower on the navigator (heard over the radio), in [0, 1). Default 0.
    pub navigator_degree: Option<f64>,
}

/// `[path]`.
#[derive(Debug, Clone, Default, PartialEq, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct PathSpec {
    /// "paper" (default), "segments" or "waypoints".
    pub kind: Option<String>,
    /// Waypoints path: the points to fly through, `[x, y, z]` (m, world frame, relative to
    /// the navigator's start), in order.
    pub points_m: Option<Vec<[f64; 3]>>,
    /// Waypoints path: radius of the turns at each waypoint (m).
    pub turn_radius_m: Option<f64>,
    /// Waypoints path: the speed of each leg (km/h), one per leg; default `speed_kmh` for all.
    pub leg_speeds_kmh: Option<Vec<f64>>,
    /// Segments path: initial speed (km/h).
    pub speed_kmh: Option<f64>,
    /// Segments path: initial course (deg, counter-clockwise from x). Default 0.
    pub course_deg: Option<f64>,
    /// Segments path: blend time of turn and climb rates at each segment start (s). Default 8.
    pub transition_s: Option<f64>,
    /// Paper path: amplitude of the height oscillation (m). Default 20.
    pub height_amplitude_m: Option<f64>,
    /// Paper path: pitch swing Δα (deg). Default 40.
    pub pitch_swing_deg: Option<f64>,
    /// Paper path: yaw amplitude (deg). Default 15.
    pub yaw_amplitude_deg: Option<f64>,
    /// Paper path: roll amplitude (deg). Default 30.
    pub roll_amplitude_deg: Option<f64>,
    /// Paper path: time flown before the profile starts (s). Default 0.
    pub lead_in_s: Option<f64>,
    /// Segments path: the pieces, flown in order; after the last, straight on.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub segment: Vec<SegmentSpec>,
}

/// One `[[path.segment]]`.
#[derive(Debug, Clone, Default, PartialEq, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct SegmentSpec {
    /// Duration (s, > 0) (required).
    pub duration_s: Option<f64>,
    /// Turn rate (deg/s, counter-clockwise positive). Default 0.
    pub turn_rate_deg_s: Option<f64>,
    /// Climb rate (km/h, up positive). Default 0.
    pub climb_kmh: Option<f64>,
    /// Speed at the end of the segment (km/h), reached smoothly. Default: unchanged.
    pub speed_kmh: Option<f64>,
}

/// `[initial]`.
#[derive(Debug, Clone, Default, PartialEq, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct InitialSpec {
    /// Forward speed of every UAV (km/h). Default: the navigator's.
    pub speed_kmh: Option<f64>,
    /// Where the followers start: "slots" (default), "box", "disc" or "explicit".
    pub placement: Option<String>,
    /// "box": its size along x (the initial course), y (left) and z (up), m.
    pub box_m: Option<[f64; 3]>,
    /// "disc": its radius (m).
    pub radius_m: Option<f64>,
    /// "disc": the height of its band (m). Default 0.
    pub height_m: Option<f64>,
    /// "box", "disc", "row": assign the starts to the slots so that the distance from start
    /// to slot is least (else in draw order). Default false.
    pub assign_slots: Option<bool>,
    /// What the assignment minimises (with `assign_slots` and `formation.reassign_on_loss`):
    /// "total" (default) or "largest" (the largest distance, then the total).
    pub assign_by: Option<String>,
    /// "row": distance between neighbours in the take-off row (m).
    pub row_spacing_m: Option<f64>,
    /// "row": height of the ground below the navigator's start (m).
    pub ground_below_m: Option<f64>,
    /// Not in the slots: a run passes when its formation has formed (every follower within its
    /// allowable errors from then to the end) by this time (s). Default 120.
    pub form_within_s: Option<f64>,
    /// "explicit": `[[initial.uav]]` entries, `id` and `position_m` (relative to the
    /// navigator's start, world axes).
    #[serde(default, rename = "uav", skip_serializing_if = "Vec::is_empty")]
    pub uavs: Vec<InitialUavSpec>,
}

/// `[[initial.uav]]`: one follower's explicit start.
#[derive(Debug, Clone, Default, PartialEq, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct InitialUavSpec {
    /// UAV number (from 1, not the navigator).
    pub id: Option<u32>,
    /// Position relative to the navigator's start: x (the initial course), y (left), z (up), m.
    pub position_m: Option<[f64; 3]>,
}

/// `[controller]`.
#[derive(Debug, Clone, Default, PartialEq, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct ControllerSpec {
    /// Azimuth areas m (≥ 1). Default 8.
    pub areas: Option<i64>,
    /// Sensing range (m). Default 250.
    pub sensing_range_m: Option<f64>,
    /// λ in [0, 1]. Default 0.8.
    pub lambda: Option<f64>,
    /// ρ in (0, 1]. Default 0.4.
    pub rho: Option<f64>,
    /// Position-closing time τ (s); 0 switches it off. Default 1.
    pub closing_time_s: Option<f64>,
    /// Input penalty (≥ 0). Default 0.01.
    pub input_weight: Option<f64>,
    /// "alpha_beta" (default), "constant_velocity" or "singer" (a Kalman filter with a Singer
    /// manoeuvre model; the attitude on α-β).
    pub predictor: Option<String>,
    /// α of the α-β predictor, in (0, 1]. Default 0.8.
    pub predictor_alpha: Option<f64>,
    /// β of the α-β predictor, in [0, 1]. Default α²/(2 − α).
    pub predictor_beta: Option<f64>,
    /// Singer predictor: manoeuvre acceleration σ_a (m/s², > 0). Default 1.
    pub predictor_accel_sigma_mps2: Option<f64>,
    /// Singer predictor: its correlation time τ (s, > 0). Default 1.
    pub predictor_tau_s: Option<f64>,
    /// Track timeout (s). Default 1.
    pub track_timeout_s: Option<f64>,
    /// Oldest information a UAV forwards of the navigator (`radio.relay_navigator`), s, > 0.
    /// Default 10.
    pub relay_max_age_s: Option<f64>,
    /// Longest a missing neighbour coasts on its track (s, ≥ 0). Default 0.5.
    pub coast_s: Option<f64>,
    /// How long a coasting neighbour's acceleration is extrapolated (s, ≥ 0). Default 0.2.
    pub coast_accel_s: Option<f64>,
    /// Fading time of a coasting neighbour's weight (s, > 0). Default 0.1.
    pub coast_decay_s: Option<f64>,
    /// Course or heading frame: the formation turns as one rigid body at the reference's turn
    /// rate (W's velocity part carries ω × r). Default: on for the fixed wing and the
    /// multirotor, off for the kinematic vehicle. `bank_turn_feedforward` is its older name.
    #[serde(alias = "bank_turn_feedforward")]
    pub turn_feedforward: Option<bool>,
    /// A report older than one period (delayed, relayed, coasting) is brought forward beyond
    /// it as the mission plan moves; false: by its track's rates (the paper's). Default true.
    pub plan_forward: Option<bool>,
    /// With relative sensing, radio reports count only for a UAV that hears nobody onboard.
    /// Default: on where position fixes carry a bias (`noise.gnss_bias_m`), off otherwise.
    pub radio_fallback: Option<bool>,
    /// Limit the closing velocity to what braking stops within the gap. Default: on for the
    /// kinematic vehicle, off for the fixed wing.
    pub stop_closing: Option<bool>,
    /// Gain of the own-state filter, in (0, 1]; 1 uses raw measurements. Default 1.
    pub own_filter_gain: Option<f64>,
    /// Separation keeping distance (m, ≥ 0; 0 off). Default twice `safety_distance_m`.
    pub separation_m: Option<f64>,
    /// Collision avoidance distance (m); 0 switches it off. Default: the safety distance.
    pub avoid_m: Option<f64>,
    /// Horizon H of the predictive input (1 to 50). Default 1.
    pub horizon: Option<i64>,
    /// Robust fusion's gate in permissible errors (> 0; 0 off). Default off.
    pub isolation_gate: Option<f64>,
    /// Own-sensor check's gate (m, > 0; 0 off). Default off.
    pub own_gate_m: Option<f64>,
    /// How fast the own-sensor gate widens while measurements are refused, once one of them
    /// was frozen (m/s, ≥ 0; while they move, 0.25 m/s or this where lower). Default 1.
    pub own_gate_growth_mps: Option<f64>,
    /// Formation control method: "proximity" (default), "paper" (the proximity method with the
    /// paper's choices where proxform's defaults go beyond it), "leader_follower", "consensus"
    /// or "flocking" (baselines, default gains; the radio then carries what they need).
    pub method: Option<String>,
    /// Gains of a baseline method (keys of its gains table; omitted ones keep their
    /// defaults), e.g. `{ pd = { kp = 2.0, kv = 2.8 } }`.
    pub gains: Option<toml::Table>,
    /// Permissible errors Δ.
    pub thresholds: Option<ThresholdsSpec>,
}

/// `[controller.thresholds]`: permissible errors Δ, all > 0.
#[derive(Debug, Clone, Default, PartialEq, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
#[allow(missing_docs)]
pub struct ThresholdsSpec {
    pub x_m: Option<f64>,
    pub y_m: Option<f64>,
    pub z_m: Option<f64>,
    pub vx_kmh: Option<f64>,
    pub vy_kmh: Option<f64>,
    pub vz_kmh: Option<f64>,
    pub alpha_deg: Option<f64>,
    pub beta_deg: Option<f64>,
    pub gamma_deg: Option<f64>,
}

/// `[vehicle]`.
#[derive(Debug, Clone, Default, PartialEq, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct VehicleSpec {
    /// "kinematic" (default), "fixed_wing" or "multirotor".
    pub model: Option<String>,
    /// Forward speed limits (km/h). Default 180, 360.
    pub vx_min_kmh: Option<f64>,
    /// See `vx_min_kmh`.
    pub vx_max_kmh: Option<f64>,
    /// Lateral and vertical speed limits (km/h). Default 72, 54.
    pub vy_max_kmh: Option<f64>,
    /// See `vy_max_kmh`.
    pub vz_max_kmh: Option<f64>,
    /// Attitude limits α, β, γ (deg). Default 45, 15, 30.
    pub attitude_max_deg: Option<[f64; 3]>,
    /// Adjusting rates of vx, vy, vz (km/h per second). Default 18 each.
    pub accel_kmh_s: Option<[f64; 3]>,
    /// Adjusting rates of α, β, γ (deg/s). Default 3, 2, 2.
    pub attitude_rate_deg_s: Option<[f64; 3]>,
    /// Fixed wing: stall speed (km/h). Default 90.
    pub stall_speed_kmh: Option<f64>,
    /// Fixed wing: maximum airspeed (km/h), default 300; multirotor: maximum horizontal speed
    /// over the ground (km/h), default 54.
    pub max_speed_kmh: Option<f64>,
    /// Fixed wing: bank limit (deg). Default 45.
    pub bank_max_deg: Option<f64>,
    /// Fixed wing: structural load-factor limit (≥ 1). Default 2.5.
    pub load_factor_max: Option<f64>,
    /// Fixed wing: pitch limit (deg). Default 20.
    pub pitch_max_deg: Option<f64>,
    /// Fixed wing: roll rate at full aileron (deg/s). Default 45.
    pub roll_rate_max_deg_s: Option<f64>,
    /// Fixed wing: pitch rate at full elevator (deg/s). Default 15.
    pub pitch_rate_max_deg_s: Option<f64>,
    /// Fixed wing: yaw rate at full rudder (deg/s), default 10; multirotor: yaw-rate limit
    /// (deg/s), default 60.
    pub yaw_rate_max_deg_s: Option<f64>,
    /// Fixed wing: airspeed change at full throttle (km/h per second). Default 10.8.
    pub throttle_accel_kmh_s: Option<f64>,
    /// Multirotor: climb-rate limit (km/h). Default 10.8 (3 m/s).
    pub climb_max_kmh: Option<f64>,
    /// Multirotor: descent-rate limit (km/h). Default 7.2 (2 m/s).
    pub descent_max_kmh: Option<f64>,
    /// Multirotor: horizontal acceleration limit (m/s²). Default 5.
    pub accel_max_mps2: Option<f64>,
    /// Multirotor: vertical acceleration limit (m/s²). Default 3.
    pub vertical_accel_max_mps2: Option<f64>,
    /// Multirotor: tilt limit (deg). Default 35.
    pub tilt_max_deg: Option<f64>,
    /// Multirotor: thrust-to-weight ratio (> 1). Default 2.
    pub thrust_to_weight: Option<f64>,
    /// Multirotor: velocity-loop time constant (s). Default 0.5.
    pub velocity_time_constant_s: Option<f64>,
    /// Multirotor: attitude lag (s). Default 0.1.
    pub attitude_time_constant_s: Option<f64>,
    /// Multirotor: yaw lag (s). Default 0.2.
    pub yaw_time_constant_s: Option<f64>,
    /// Multirotor: linear drag per unit mass (1/s). Default 0.1.
    pub drag_linear_per_s: Option<f64>,
    /// Multirotor: quadratic drag per unit mass (1/m). Default 0.015.
    pub drag_quadratic_per_m: Option<f64>,
}

/// `[wind]`.
#[derive(Debug, Clone, Default, PartialEq, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct WindSpec {
    /// Steady wind `[x, y, z]` (km/h, world frame). Default calm.
    pub steady_kmh: Option<[f64; 3]>,
    /// Dryden turbulence: "none" (default), "light", "moderate", "severe".
    pub turbulence: Option<String>,
    /// Altitude above ground for the turbulence model (m). Default 300.
    pub altitude_m: Option<f64>,
    /// A 1 − cos gust: start (s).
    pub gust_at_s: Option<f64>,
    /// Gust duration (s).
    pub gust_duration_s: Option<f64>,
    /// Gust peak `[x, y, z]` (km/h, world frame).
    pub gust_peak_kmh: Option<[f64; 3]>,
}

/// `[noise]`.
#[derive(Debug, Clone, Default, PartialEq, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct NoiseSpec {
    /// Position noise 1σ (m). Default 0.02.
    pub position_m: Option<f64>,
    /// Velocity noise 1σ (km/h). Default 0.18 (0.05 m/s).
    pub velocity_kmh: Option<f64>,
    /// Attitude noise 1σ (deg). Default 0.01.
    pub attitude_deg: Option<f64>,
    /// Actuation error: relative, uniform in ±e, in [0, 1]. Default 0.1.
    pub actuation_error: Option<f64>,
    /// Factor on the three measurement noises above (≥ 0). Default 1.
    pub scale: Option<f64>,
    /// GNSS-like correlated bias of each UAV's own position fix, 1σ (m). Default none.
    pub gnss_bias_m: Option<f64>,
    /// Correlation time of that bias (s). Default 60.
    pub gnss_tau_s: Option<f64>,
}

/// `[sensing]`.
#[derive(Debug, Clone, Default, PartialEq, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct SensingSpec {
    /// Probability that an onboard observation is lost, per observation and step, in [0, 1].
    /// Default 0.
    pub dropout: Option<f64>,
    /// Probability that an observation of one of the UAV's main references is lost, per
    /// observation and step, in [0, 1]. Default: `dropout`.
    pub reference_dropout: Option<f64>,
    /// Onboard observations measured relative to the observer and placed in the world with its
    /// own measured state (its position-fix bias and noise included). Default false.
    pub relative: Option<bool>,
}

/// `[network]`: faults of the transport between the world and the agents of a distributed run
/// (`proxform run --distributed`); an in-process run has no transport and ignores them.
#[derive(Debug, Clone, Default, PartialEq, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct NetworkSpec {
    /// Probability that a message between the world and an agent is lost, each direction,
    /// in [0, 1). Default 0.
    pub loss: Option<f64>,
    /// Delay added to every such message (s, real-time clock only), in [0, 10]. Default 0.
    pub delay_s: Option<f64>,
}

/// `[radio]`.
#[derive(Debug, Clone, Default, PartialEq, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct RadioSpec {
    /// UAVs that broadcast their state to every UAV (regardless of `broadcast_all`).
    pub beacons: Option<Vec<u32>>,
    /// Every UAV broadcasts its state each period. Default false.
    pub broadcast_all: Option<bool>,
    /// Range of a message (m). Default unlimited.
    pub range_m: Option<f64>,
    /// Delay of every message (s, a multiple of dt_s). Default 0.
    pub delay_s: Option<f64>,
    /// i.i.d. loss probability per message, in [0, 1]. Default 0.
    pub loss: Option<f64>,
    /// Gilbert-Elliott channel per receiver: probability per period of good → bad.
    pub burst_p_good_to_bad: Option<f64>,
    /// … of bad → good.
    pub burst_p_bad_to_good: Option<f64>,
    /// … loss probability in the bad state. Default 1.
    pub burst_loss_bad: Option<f64>,
    /// Every UAV forwards what it knows of the navigator (its track, with its age) each period.
    /// Default false.
    pub relay_navigator: Option<bool>,
}

/// `[allowable]`: pass criterion, all > 0.
#[derive(Debug, Clone, Default, PartialEq, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
#[allow(missing_docs)]
pub struct AllowableSpec {
    pub x_m: Option<f64>,
    pub y_m: Option<f64>,
    pub z_m: Option<f64>,
    pub alpha_deg: Option<f64>,
    pub beta_deg: Option<f64>,
    pub gamma_deg: Option<f64>,
    /// How far the formation's navigator slot may leave its planned path (m, > 0). Default: ten
    /// times the largest allowable position error.
    pub path_m: Option<f64>,
}

/// One `[[fault]]`.
#[derive(Debug, Clone, Default, PartialEq, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct FaultSpec {
    /// "remove", "join", "glitch", "stuck_sensor", "radio_blackout" (required).
    pub kind: Option<String>,
    /// The UAV concerned (all but radio_blackout).
    pub uav: Option<u32>,
    /// Start time (s) (required).
    pub at_s: Option<f64>,
    /// Duration (s) of a glitch, stuck sensor or blackout (required for those).
    pub duration_s: Option<f64>,
    /// Position offset of a glitch (m).
    pub offset_m: Option<[f64; 3]>,
}

impl FaultSpec {
    /// `kind = "remove"`: UAV `uav` (from 1) vanishes at `at_s`.
    pub fn remove(uav: u32, at_s: f64) -> Self {
        Self { kind: Some("remove".into()), uav: Some(uav), at_s: Some(at_s), ..Self::default() }
    }

    /// `kind = "radio_blackout"` from `at_s` for `duration_s`.
    pub fn radio_blackout(at_s: f64, duration_s: f64) -> Self {
        Self { kind: Some("radio_blackout".into()), at_s: Some(at_s), duration_s: Some(duration_s), ..Self::default() }
    }
}

impl ScenarioSpec {
    /// The spec edited by `f`: `paper_spec().with(|s| s.duration_s = Some(20.0))`.
    pub fn with(mut self, f: impl FnOnce(&mut Self)) -> Self {
        f(&mut self);
        self
    }
}
