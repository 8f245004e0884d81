//! Recording a run's trajectories in memory, one row per UAV per step.

use proxform_core::state::State9;

use proxform_scenario::Scenario;

use super::observer::{formation_error_to, navigator_reference, Observer, StepFrame};

/// One UAV at one step.
#[derive(Debug, Clone, PartialEq)]
pub struct TrajectoryRow {
    /// Time (s).
    pub t: f64,
    /// UAV index.
    pub uav: u32,
    /// True state (SI, rad).
    pub state: State9,
    /// Formation error x, y, z (m), α, β, γ (rad); zero for the navigator.
    pub error: [f64; 6],
    /// The decision's outcome at the previous update: "held", "adjusted", "alone", or
    /// "navigator"/"initial".
    pub outcome: &'static str,
    /// True when the UAV's course was inside its envelope (it held).
    pub in_envelope: bool,
    /// True when every formation error is within the allowable error.
    pub within_allowable: bool,
}

/// UAVs recorded by default: all of a small formation, the first ones of a large swarm.
pub const DEFAULT_SAMPLE: usize = 64;

/// Observer collecting the rows of a run for the first `sample` UAVs.
#[derive(Debug, Clone)]
pub struct Trajectory {
    /// Rows in time order, then UAV order.
    pub rows: Vec<TrajectoryRow>,
    /// Number of UAVs recorded (the first ones).
    pub sample: usize,
}

impl Default for Trajectory {
    fn default() -> Self {
        Self { rows: Vec::new(), sample: DEFAULT_SAMPLE }
    }
}

impl Observer for Trajectory {
    fn on_step(&mut self, scenario: &Scenario, frame: &StepFrame<'_>) {
        let nav = scenario.navigator().index();
        let allowable = scenario.allowable().as_array();
        let reference = navigator_reference(scenario, frame.states, frame.active);
        for (i, s) in frame.states.iter().enumerate().take(self.sample) {
            if !frame.active[i] {
                continue;
            }
            let error = if i == nav { [0.0; 6] } else { formation_error_to(scenario, frame.states, &reference, i) };
            let (outcome, in_envelope) = match frame.uavs[i].outcome {
                Some(o) => (o.label(), o == proxform_core::Outcome::Held),
                None if i == nav => ("navigator", false),
                None => ("initial", false),
            };
            let within_allowable = error.iter().zip(&allowable).all(|(e, a)| e.abs() <= *a);
            self.rows.push(TrajectoryRow {
                t: frame.t,
                uav: i as u32,
                state: *s,
                error,
                outcome,
                in_envelope,
                within_allowable,
            });
        }
    }
}
