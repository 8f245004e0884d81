//! What one update period decided: held, adjusted (with the input) or alone.

use crate::state::{Input, State9};
use crate::vehicle::{Setpoint, VehicleModel};

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
    /// Neighbours whose implied estimate X̂_ij the robust fusion left out this period
    /// (`ControllerParams::isolation_gate`; always 0 without it).
    pub isolated: u16,
    /// The UAV did not trust its own measurement this period and flew on its own prediction
    /// (`ControllerParams::own_gate_m`; always false without it).
    pub own_suspect: bool,
    /// How far the UAV was from where its neighbours place it: `Σ (g_k/Δ_k)²` over x, y, z of
    /// the gap `g` to the envelope centre's position (before a wide gap's closing velocity
    /// replaces it; after separation keeping), in permissible errors. 0 when nothing was
    /// perceived, and for decisions that do not say (the baselines', one read from the wire).
    pub gap_sq: f64,
    /// For a vehicle flown by velocity and yaw setpoints (the multirotor), what its autopilot
    /// flies from now on: the input applied to the state the agent believed it had when it
    /// adjusted, the last such setpoint while it holds (an autopilot keeps flying its last
    /// setpoint), None before its first (the autopilot holds the velocity and yaw it has). The
    /// world applies it to the true state, a MAVLink agent sends it. Always None for the other
    /// vehicles, whose inputs act on the state they have.
    pub setpoint: Option<Setpoint>,
}

impl Decision {
    /// Whether every number in it is finite (a decision from outside the process may not be:
    /// a non-finite one is refused, never applied).
    pub fn is_finite(&self) -> bool {
        let sq = match self.outcome {
            Outcome::Adjusted { normalised_sq } => normalised_sq,
            _ => 0.0,
        };
        sq.is_finite()
            && self.input.iter().all(|u| u.is_finite())
            && self.setpoint.is_none_or(|s| s.yaw_rad.is_finite() && s.velocity_mps.iter().all(|v| v.is_finite()))
    }

    /// Takes the setpoint that a vehicle flown by setpoints flies after this decision: a new one
    /// when the controller adjusted, chosen at the state `own` the UAV believes it has (over a
    /// period `dt`); otherwise `held`, the one its autopilot flies already. Sets
    /// [`Self::setpoint`] and returns it (None for the vehicles flown by their inputs). Every
    /// engine and agent keeps `held` from one period to the next.
    pub fn take_setpoint(
        &mut self,
        vehicle: &VehicleModel,
        own: &State9,
        dt: f64,
        held: Option<&Setpoint>,
    ) -> Option<Setpoint> {
        if !vehicle.takes_velocity_setpoints() {
            return None;
        }
        self.setpoint = match self.outcome {
            Outcome::Adjusted { .. } => vehicle.setpoint(own, &self.input, dt),
            _ => held.copied(),
        };
        self.setpoint
    }

    /// The input the vehicle flies over the coming period from state `at`: what flies the
    /// decision's setpoint from there (a vehicle flown by setpoints, whatever state its agent
    /// believed when it chose it), else the decision's input.
    pub fn flown_input(&self, vehicle: &VehicleModel, at: &State9) -> Input {
        self.setpoint.and_then(|sp| vehicle.input_flying(at, &sp)).unwrap_or(self.input)
    }

    /// Nothing perceived: fly on (METHOD §6 step 8, §8).
    pub fn alone() -> Self {
        Self::without_areas(Outcome::Alone, Input::zeros())
    }

    /// A decision that reports no areas, references or isolation (the baselines', a held
    /// placeholder's).
    pub fn without_areas(outcome: Outcome, input: Input) -> Self {
        Decision {
            outcome,
            input,
            occupied_areas: 0,
            main_refs: 0,
            isolated: 0,
            own_suspect: false,
            gap_sq: 0.0,
            setpoint: None,
        }
    }
}
