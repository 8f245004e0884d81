//! One agent in a ring of 8 neighbours, flying straight on, for each variant of the robust
//! settings (docs/METHOD.md §8): the paper's, with the collision avoidance checked (as the
//! simulator flies it), the robust fusion (`isolation_gate = 1`), the
//! own-sensor check (`own_gate_m = 3`), both, and both with the Kalman tracks. The navigator is
//! the first neighbour, so the fusion has three estimates upstream to take its median over.
//! Shared by `benches/controller.rs` (`agent_step_variant`) and `examples/agent_steps.rs`
//! (instruction counts under callgrind).

use proxform_core::state::State9;
use proxform_core::{
    Agent, AgentSetup, ControllerParams, ControllerSetup, Decision, DependencySet, KinematicModel, Method, Observation,
    Outcome, PredictorKind, UavId, VehicleModel,
};

/// The variants, by name.
pub const VARIANTS: [&str; 6] = ["paper", "avoid", "isolation", "own_check", "robust", "robust_singer"];

/// The controller parameters of `variant`.
pub fn params(variant: &str) -> ControllerParams {
    let mut p = ControllerParams::default();
    if variant == "avoid" {
        // What the simulator sets for the paper's 50 m safety distance (not binding here).
        p.avoid_m = Some(62.5);
    }
    if matches!(variant, "isolation" | "robust" | "robust_singer") {
        p.isolation_gate = Some(1.0);
    }
    if matches!(variant, "own_check" | "robust" | "robust_singer") {
        p.own_gate_m = Some(3.0);
    }
    if variant == "robust_singer" {
        p.predictor = PredictorKind::singer(0.02, 0.05);
    }
    p
}

/// The agent (UAV 0, 0.7 m off its slot so that it adjusts), its neighbours' observations
/// and its own measurement, advanced by their velocity at every step.
pub struct Flight {
    agent: Agent,
    own: State9,
    seen: Vec<Observation>,
    t: f64,
}

impl Flight {
    /// The flight of `variant`, after two steps (the tracks and the own prediction started).
    pub fn new(variant: &str) -> Self {
        let formation = super::ring::formation(8);
        let (seen, own) = super::ring::scene(&formation);
        let setup =
            ControllerSetup::new(params(variant), VehicleModel::Kinematic(KinematicModel::default())).expect("valid");
        let tables = (0..9)
            .map(|i| {
                if i == 0 {
                    DependencySet::new(UavId(0), 9, vec![(UavId(1), 0.7)]).expect("valid")
                } else {
                    DependencySet::default()
                }
            })
            .collect();
        let setup = AgentSetup::new(Method::Proximity, UavId(1), setup, formation, tables).expect("valid");
        let agent = Agent::new(&setup, UavId(0)).expect("a follower");
        let mut f = Self { agent, own, seen, t: 0.0 };
        let d = f.step();
        assert!(matches!(d.outcome, Outcome::Adjusted { .. }), "{variant}: {d:?}");
        let d = f.step();
        assert!(!d.own_suspect && d.isolated == 0, "{variant}: {d:?}");
        f
    }

    /// One update period: everyone flies on at its velocity, then the agent steps.
    pub fn step(&mut self) -> Decision {
        let d = self.agent.step(self.t, &self.own, &self.seen);
        self.t += 0.1;
        for s in std::iter::once(&mut self.own).chain(self.seen.iter_mut().map(|o| &mut o.state)) {
            for k in 0..3 {
                s[k] += 0.1 * s[k + 3];
            }
        }
        d
    }
}
