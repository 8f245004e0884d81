//! Every default of a scenario, in one place.
//!
//! A key a file (or a Python dict) leaves out takes the value below when the spec is
//! converted ([`crate::convert`]); the checked [`crate::Scenario`] shows the value that runs, and
//! `proxform run --print-scenario` prints it. The defaults are the paper experiment's (METHOD
//! §9). The controller's and the vehicles' own defaults are their parameter structs' `Default`
//! impls in `proxform-core` ([`proxform_core::ControllerParams`],
//! [`proxform_core::KinematicLimits`], [`proxform_core::FixedWingModel`]); the scenario only
//! chooses between them (the vehicles' permissible errors, the turn feed-forward, the frame)
//! in the converters, and here gives the multirotor's allowable errors.

/// Update period Δt (s).
pub const DT_S: f64 = 0.1;
/// Flight duration (s).
pub const DURATION_S: f64 = 100.0;
/// Number (from 1) of the navigator.
pub const NAVIGATOR: u32 = 1;
/// Pairs closer than this are unsafe (m).
pub const SAFETY_DISTANCE_M: f64 = 50.0;
/// A multirotor formation's safety distance (m): small vehicles fly metres apart.
pub const MULTIROTOR_SAFETY_DISTANCE_M: f64 = 3.0;
/// How long the formation has flown before t = 0 (s).
pub const WARMUP_S: f64 = 1.0;
/// Separation keeping distance, in safety distances (when `controller.separation_m` is unset).
pub const SEPARATION_PER_SAFETY: f64 = 2.0;
/// A formation not starting in its slots must have formed by this time to pass (s).
pub const FORM_WITHIN_S: f64 = 120.0;
/// Collision avoidance distance, in safety distances (when `controller.avoid_m` is unset): a
/// quarter more, since the avoidance holds its distance only to within the lag of the UAVs'
/// rate-limited inputs.
pub const AVOID_PER_SAFETY: f64 = 1.25;
/// Robust fusion's gate (in permissible errors) when `controller.isolation_gate` is unset: a
/// neighbour far from its own slot (one whose own sensor failed, one joining, re-assigned or
/// forming) must not drag the UAVs that lean on it (METHOD §8). Unset with `method = "paper"`.
pub const ISOLATION_GATE: f64 = 1.0;

/// The own-sensor check's gate (m) when `controller.own_gate_m` is unset (METHOD §8): a reading
/// of the UAV's own position this far from its prediction is refused (or the noise's floor,
/// [`own_gate_floor_m`], where that is larger). Unset with `method = "paper"`.
pub const OWN_GATE_M: f64 = 3.0;
/// The own-sensor gate is at least this many standard deviations of the difference of two
/// position readings (√2 σ of the position noise, per axis): a clean reading lies farther than
/// that from the last one's prediction (a distance in three axes) in about 1 of 1 000 steps,
/// where a gate within the noise refused clean readings and flew on a held one's error. (3 m up
/// to σ = 0.53 m.) The price: a jump up to about the gate is not seen.
pub const OWN_GATE_NOISE_SIGMAS: f64 = 4.0;

/// The own-sensor gate that noise of σ `position_m` (m) alone seldom exceeds (m).
pub fn own_gate_floor_m(position_m: f64) -> f64 {
    OWN_GATE_NOISE_SIGMAS * std::f64::consts::SQRT_2 * position_m
}

/// How fast the own-sensor gate widens while readings are refused, once one of them was frozen
/// (m/s), when `controller.own_gate_growth_mps` is unset, in calm air; turbulence adds 3 σ_u of
/// its horizontal wind (METHOD §8): a UAV flying on its prediction without velocity readings
/// drifts from it by as much as the wind changed, and a gate that widens more slowly never
/// takes a good reading again. (While the refused readings move, the gate widens at the dead
/// reckoning's drift, [`proxform_core::own_estimate::OWN_DRIFT_MPS`].)
pub const OWN_GATE_GROWTH_MPS: f64 = 1.0;
/// See [`OWN_GATE_GROWTH_MPS`]: the turbulence's horizontal σ counts this many times.
pub const OWN_GATE_GROWTH_SIGMAS: f64 = 3.0;

/// Position noise 1σ (m).
pub const NOISE_POSITION_M: f64 = 0.02;
/// Velocity noise 1σ (km/h): 0.05 m/s.
pub const NOISE_VELOCITY_KMH: f64 = 0.18;
/// Attitude noise 1σ (deg).
pub const NOISE_ATTITUDE_DEG: f64 = 0.01;
/// Relative actuation error (uniform in ±e).
pub const ACTUATION_ERROR: f64 = 0.1;
/// Correlation time of a GNSS-like position bias (s).
pub const GNSS_TAU_S: f64 = 60.0;

/// Allowable errors x, y, z (m): the pass criterion.
pub const ALLOWABLE_POSITION_M: [f64; 3] = [0.5, 0.6, 0.2];
/// Allowable errors α, β, γ (deg).
pub const ALLOWABLE_ATTITUDE_DEG: [f64; 3] = [0.4, 0.3, 1.0];

/// How far the formation may leave its planned path, in largest allowable position errors: a
/// navigator flies its path within a fraction of one (a multirotor's gusts move it by tenths),
/// a formation that lost it drifts off by hundreds of metres.
pub const PATH_PER_ALLOWABLE: f64 = 10.0;

/// A multirotor's allowable errors x, y, z (m).
pub const MULTIROTOR_ALLOWABLE_POSITION_M: [f64; 3] = [1.0, 1.0, 1.0];
/// A multirotor's allowable errors α, β, γ (deg): yaw 3°; pitch and roll are its inner loop's
/// (they follow each UAV's own accelerations and drag: a wing tip flying faster in a turn tilts
/// more), judged only against 45°.
pub const MULTIROTOR_ALLOWABLE_ATTITUDE_DEG: [f64; 3] = [45.0, 3.0, 45.0];

/// A fixed wing's allowable errors x, y, z (m): five times its controller's 2 m thresholds. A
/// fixed wing corrects its position only by turning, pitching and banking, and a gust moves it
/// metres before it can answer (measured: a 4-UAV echelon through a figure-eight in calm air
/// errs by up to 4 m at the 99th percentile of 50 runs; the V of `fixed-wing-v` in moderate
/// turbulence by up to 9 m).
pub const FIXED_WING_ALLOWABLE_POSITION_M: [f64; 3] = [10.0, 10.0, 10.0];
/// A fixed wing's allowable errors α, β, γ (deg): twice its controller's thresholds (5°, 10°,
/// 10°), with 20° of roll for a wing tip that banks harder than its neighbour in a turn.
pub const FIXED_WING_ALLOWABLE_ATTITUDE_DEG: [f64; 3] = [10.0, 15.0, 20.0];

/// `navigator_degree` in derived dependency tables, for every vehicle: a deep formation's
/// errors would otherwise grow rank by rank (measured, 100 seeds each: a 20-UAV V on a climb,
/// turn and gust, last rank 16.1× the first and 0 runs passing without it, 1.05× and 100 with
/// it; a 9-UAV diamond 3.2× and 2 runs, 1.07× and 100; fixed wing, 30 seeds: a 7-UAV echelon
/// through two 90° turns in a crosswind, last rank 8.0 m against the first's 0.66 m, with the
/// navigator in the tables 0.93 against 0.55 m).
pub const NAVIGATOR_DEGREE: f64 = 0.8;

/// Main references per UAV in derived dependency tables.
pub const REFERENCES_PER_UAV: u32 = 2;
/// Half-angle of a V, angle of an echelon (deg).
pub const SHAPE_ANGLE_DEG: f64 = 30.0;
/// Blend time of turn and climb rates at each path segment's start (s).
pub const PATH_TRANSITION_S: f64 = 8.0;
/// Altitude above ground of the turbulence model (m).
pub const TURBULENCE_ALTITUDE_M: f64 = 300.0;
/// Loss probability of the Gilbert-Elliott channel's bad state.
pub const BURST_LOSS_BAD: f64 = 1.0;
/// When a comparison's failed UAV fails (s).
pub const FAIL_AT_S: f64 = 40.0;
/// The base seed.
pub const SEED: u64 = 1;
