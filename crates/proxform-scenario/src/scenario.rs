//! The checked scenario: everything one flight needs, in SI units, every default resolved.
//!
//! A [`Scenario`] is made only by converting a [`ScenarioSpec`] ([`crate::convert`]): its fields
//! cannot be changed from outside, so a scenario that exists has passed every check. To change
//! one, edit its spec ([`Scenario::spec`]) and convert again.

use std::sync::Arc;

use proxform_core::state::State9;
use proxform_core::{Agent, AgentSetup, ControllerParams, DependencySet, Formation, Method, UavId, VehicleModel};

use crate::convert::SpecError;
use crate::faults::Fault;
use crate::path::NavigatorPath;
use crate::radio::RadioModel;
use crate::spec::ScenarioSpec;
use crate::wind::Wind;

/// White measurement noise, 1σ per axis, on every observation and on each UAV's own estimate.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct MeasurementNoise {
    /// Position (m). Paper scenario: 0.02 m.
    pub position_m: f64,
    /// Velocity (m/s). Paper scenario: 0.05 m/s.
    pub velocity_mps: f64,
    /// Attitude (rad). Paper scenario: 0.01°.
    pub attitude_rad: f64,
}

impl MeasurementNoise {
    /// σn per state parameter.
    pub fn sigma(&self) -> State9 {
        let (p, v, a) = (self.position_m, self.velocity_mps, self.attitude_rad);
        State9::from_column_slice(&[p, p, p, v, v, v, a, a, a])
    }
}

/// Time-correlated error of each UAV's own position fix (GNSS-like): a first-order
/// Gauss-Markov bias per axis, added to the white noise.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct CorrelatedNoise {
    /// Standard deviation of the bias (m).
    pub sigma_m: f64,
    /// Correlation time (s).
    pub tau_s: f64,
}

/// Faults of the transport between the world and the agents of a distributed run (an
/// in-process run has no transport).
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct NetworkFaults {
    /// Probability that a message is lost, each direction, in [0, 1).
    pub loss: f64,
    /// Delay added to every message (s; real-time clock only).
    pub delay_s: f64,
}

/// Allowable formation errors, the pass criterion (METHOD §7, §9).
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct AllowableErrors {
    /// x, y, z (m).
    pub position_m: [f64; 3],
    /// α, β, γ (rad).
    pub attitude_rad: [f64; 3],
    /// How far the navigator (or, once it is gone, the formation's estimate of its slot) may be
    /// from its planned path (m).
    pub path_m: f64,
}

impl AllowableErrors {
    /// As a 6-vector: x, y, z (m), α, β, γ (rad).
    pub fn as_array(&self) -> [f64; 6] {
        let (p, a) = (self.position_m, self.attitude_rad);
        [p[0], p[1], p[2], a[0], a[1], a[2]]
    }
}

/// Which engine steps a flight (the scenario's `engine` key).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum EngineChoice {
    /// The fast engine from [`EngineChoice::AUTO_FAST_FROM`] UAVs when it runs the scenario,
    /// else the reference.
    #[default]
    Auto,
    /// The reference engine: one agent object per UAV.
    Reference,
    /// The fast engine: every phase over arrays (an error if it does not run the scenario).
    Fast,
}

impl EngineChoice {
    /// Swarms at least this large run on the fast engine under `engine = "auto"`.
    pub const AUTO_FAST_FROM: usize = 10_000;

    /// The key's value as written in a scenario file.
    pub fn name(self) -> &'static str {
        match self {
            EngineChoice::Auto => "auto",
            EngineChoice::Reference => "reference",
            EngineChoice::Fast => "fast",
        }
    }
}

/// A checked scenario. Built by [`Scenario::try_from`] a [`ScenarioSpec`].
#[derive(Debug, Clone)]
pub struct Scenario {
    pub(crate) spec: ScenarioSpec,
    pub(crate) name: String,
    pub(crate) dt_s: f64,
    pub(crate) duration_s: f64,
    pub(crate) agents: Arc<AgentSetup>,
    pub(crate) path: NavigatorPath,
    pub(crate) initial: Vec<State9>,
    pub(crate) placement: crate::placement::Placement,
    pub(crate) form_within_s: Option<f64>,
    pub(crate) reassign_on_loss: Option<proxform_core::assignment::AssignBy>,
    pub(crate) noise: MeasurementNoise,
    pub(crate) gnss_bias: Option<CorrelatedNoise>,
    pub(crate) actuation_error: f64,
    pub(crate) allowable: AllowableErrors,
    pub(crate) safety_distance_m: f64,
    pub(crate) warmup_s: f64,
    pub(crate) engine: EngineChoice,
    pub(crate) dropout: f64,
    pub(crate) reference_dropout: Option<f64>,
    pub(crate) relative_sensing: bool,
    pub(crate) faults: Vec<Fault>,
    pub(crate) beacons: Vec<UavId>,
    pub(crate) wind: Wind,
    pub(crate) radio: RadioModel,
    pub(crate) network: NetworkFaults,
    pub(crate) warnings: Vec<SpecError>,
}

impl Scenario {
    /// What the scenario allows but probably did not mean (a fault after the flight, UAVs whose
    /// references never lead to the navigator), each naming its key.
    pub fn warnings(&self) -> &[SpecError] {
        &self.warnings
    }

    /// The spec this scenario was converted from, as given (defaults not filled in); edit a
    /// clone and convert it again to change the scenario. [`crate::resolved`] gives the spec
    /// with every default filled in.
    pub fn spec(&self) -> &ScenarioSpec {
        &self.spec
    }

    /// Short name used in reports.
    pub fn name(&self) -> &str {
        &self.name
    }

    /// Update period Δt (s).
    pub fn dt_s(&self) -> f64 {
        self.dt_s
    }

    /// Flight duration (s).
    pub fn duration_s(&self) -> f64 {
        self.duration_s
    }

    /// Number of update periods in the flight.
    pub fn steps(&self) -> u64 {
        (self.duration_s / self.dt_s).round() as u64
    }

    /// Number of UAVs.
    pub fn len(&self) -> usize {
        self.initial.len()
    }

    /// Always false: a checked scenario has at least two UAVs.
    pub fn is_empty(&self) -> bool {
        self.initial.is_empty()
    }

    /// What every follower's agent shares: method, navigator, controller setup, formation
    /// and dependency tables. [`Agent::new`] with it and a UAV's id gives that UAV's agent.
    pub fn agents(&self) -> &Arc<AgentSetup> {
        &self.agents
    }

    /// The agent of follower `id` (the simulator and a network agent build theirs here).
    pub fn agent(&self, id: UavId) -> Agent {
        Agent::new(&self.agents, id).expect("a checked scenario's agents are valid")
    }

    /// The formation (one slot per UAV).
    pub fn formation(&self) -> &Arc<Formation> {
        self.agents.formation()
    }

    /// The formation in force at `t_s` (the first one, or a `[[formation.change]]`'s).
    pub fn formation_at(&self, t_s: f64) -> &Arc<Formation> {
        self.agents.schedule().at(t_s).map_or(self.agents.formation(), |s| &s.formation)
    }

    /// Every UAV's dependency table in force at `t_s` (the first ones, or a
    /// `[[formation.change]]`'s).
    pub fn dependencies_at(&self, t_s: f64) -> &[DependencySet] {
        self.agents.schedule().at(t_s).map_or(self.agents.dependencies(), |s| &s.dependencies)
    }

    /// The changes of formation in flight.
    pub fn schedule(&self) -> &proxform_core::FormationSchedule {
        self.agents.schedule()
    }

    /// The navigator, which flies [`Self::path`] and runs no controller.
    pub fn navigator(&self) -> UavId {
        self.agents.navigator()
    }

    /// The navigator's path.
    pub fn path(&self) -> &NavigatorPath {
        &self.path
    }

    /// True when the navigator flies its path through its vehicle and the wind, its autopilot
    /// tracking the path ([`proxform_core::ControllerSetup::input_along_path`]), so that the
    /// wind moves it as it moves every other UAV: the multirotor. The kinematic vehicle's
    /// navigator is set on its path (the paper's), as is the fixed wing's (METHOD §5).
    pub fn navigator_flies(&self) -> bool {
        matches!(self.vehicle(), VehicleModel::Multirotor(_))
    }

    /// Initial state of every UAV.
    pub fn initial(&self) -> &[State9] {
        &self.initial
    }

    /// Where the followers start (`[initial] placement`); [`Scenario::initial`] is every UAV
    /// in its slot, from which the simulator draws or sets the other starts.
    pub fn placement(&self) -> &crate::placement::Placement {
        &self.placement
    }

    /// For a formation that does not start in its slots: the time (s) by which a run must have
    /// formed to pass (`[initial] form_within_s`); None for in-slot starts.
    pub fn form_within_s(&self) -> Option<f64> {
        self.form_within_s
    }

    /// `[formation] reassign_on_loss`: when a UAV is lost, the others are re-assigned slots
    /// minimising this ([`proxform_core::assignment::after_loss`]); None: slots stay fixed.
    pub fn reassign_on_loss(&self) -> Option<proxform_core::assignment::AssignBy> {
        self.reassign_on_loss
    }

    /// Dependency table of every UAV (the navigator's is unused).
    pub fn dependencies(&self) -> &[DependencySet] {
        self.agents.dependencies()
    }

    /// Controller parameters shared by every follower, every default resolved (the
    /// separation distance included).
    pub fn controller(&self) -> &ControllerParams {
        self.agents.controller().params()
    }

    /// Vehicle model shared by every UAV.
    pub fn vehicle(&self) -> &VehicleModel {
        self.agents.controller().vehicle()
    }

    /// Measurement noise σn.
    pub fn noise(&self) -> &MeasurementNoise {
        &self.noise
    }

    /// Correlated own-position error, if any.
    pub fn gnss_bias(&self) -> Option<&CorrelatedNoise> {
        self.gnss_bias.as_ref()
    }

    /// Actuation error: each applied input component is scaled by `1 + ε`, ε uniform in
    /// `[−e, e]` (dimensionless).
    pub fn actuation_error(&self) -> f64 {
        self.actuation_error
    }

    /// The pass criterion.
    pub fn allowable(&self) -> &AllowableErrors {
        &self.allowable
    }

    /// Pairs closer than this are reported as unsafe (m).
    pub fn safety_distance_m(&self) -> f64 {
        self.safety_distance_m
    }

    /// Which engine the scenario asks for.
    pub fn engine(&self) -> EngineChoice {
        self.engine
    }

    /// How long the formation has been flying before t = 0 (s): the controllers watch that
    /// ideal flight so their neighbour tracks are established at t = 0.
    pub fn warmup_s(&self) -> f64 {
        self.warmup_s
    }

    /// Probability that an onboard observation is lost, per observation and step.
    pub fn dropout(&self) -> f64 {
        self.dropout
    }

    /// The same for observations of a UAV's own main references (`dropout` unless set).
    pub fn reference_dropout(&self) -> f64 {
        self.reference_dropout.unwrap_or(self.dropout)
    }

    /// `sensing.reference_dropout` when the spec sets it. The warm-up's otherwise ideal sensing
    /// applies it (as it always has: changing that would change every result of a scenario
    /// that sets the key).
    pub fn reference_dropout_set(&self) -> Option<f64> {
        self.reference_dropout
    }

    /// Whether onboard observations are measured relative to the observer and placed in the
    /// world with its own measured state (`sensing.relative`): its position-fix bias and
    /// noise then enter its own state and its view of every neighbour alike.
    pub fn relative_sensing(&self) -> bool {
        self.relative_sensing
    }

    /// Scheduled faults.
    pub fn faults(&self) -> &[Fault] {
        &self.faults
    }

    /// UAVs whose state every UAV hears over the radio each period.
    pub fn beacons(&self) -> &[UavId] {
        &self.beacons
    }

    /// Wind, turbulence and gusts.
    pub fn wind(&self) -> &Wind {
        &self.wind
    }

    /// The radio: broadcasters, range, delay and losses.
    pub fn radio(&self) -> &RadioModel {
        &self.radio
    }

    /// Whether the followers' tracks fuse every report of a UAV (the Singer predictor of the
    /// proximity method): a radio report of a UAV perceived onboard is then passed too;
    /// otherwise the radio only fills in what onboard sensing missed. The simulator's sensor
    /// and a network agent's radio both follow it.
    pub fn fuses_radio(&self) -> bool {
        matches!(self.controller().predictor, proxform_core::PredictorKind::Singer { .. })
            && matches!(self.method(), proxform_core::Method::Proximity)
    }

    /// Faults of the transport between the world and the agents of a distributed run.
    pub fn network(&self) -> &NetworkFaults {
        &self.network
    }

    /// The followers' formation control method.
    pub fn method(&self) -> &Method {
        self.agents.method()
    }

    /// UAV `i`'s slot state around the navigator's state `nav`: `X_nav + W_i,nav`.
    pub fn slot_state(&self, i: usize, nav: &State9) -> State9 {
        let f = self.formation();
        nav + f.w(&f.slots[i], &f.slots[self.navigator().index()], nav)
    }
}

/// Every UAV in its slot around the navigator's state `nav0`, with the navigator's velocity
/// and attitude (plus its attitude offset).
pub fn in_slots(formation: &Formation, navigator: UavId, nav0: &State9) -> Vec<State9> {
    let nav = &formation.slots[navigator.index()];
    formation.slots.iter().map(|slot| nav0 + formation.w(slot, nav, nav0)).collect()
}
