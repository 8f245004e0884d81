//! A checked scenario: everything one simulated flight needs, in SI units.
//!
//! [`Scenario::paper`] is the paper's six-UAV experiment as METHOD §9 fixes it. A scenario is
//! built once, checked by [`Scenario::validate`], and then shared read-only by every run.

use std::sync::Arc;

use proxform_core::angle::{deg, kmh};
use proxform_core::state::{self, State9};
use proxform_core::{
    ConfigError, ControllerParams, DependencySet, Formation, FormationFrame, FormationSlot, KinematicModel, Method,
    RadioNeed, UavId, VehicleModel,
};

use crate::path::{NavigatorPath, PaperPath};

/// Why a scenario is invalid.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum ScenarioError {
    /// A parameter outside its domain.
    #[error(transparent)]
    Config(#[from] ConfigError),
    /// Per-UAV lists of different lengths, or too few UAVs.
    #[error("{what}: expected {expected}, found {found}")]
    Shape {
        /// Which list.
        what: &'static str,
        /// Expected length.
        expected: usize,
        /// Found length.
        found: usize,
    },
    /// A non-finite or out-of-range scenario value.
    #[error("{field} = {value} is invalid: expected {expected}")]
    Value {
        /// The field.
        field: &'static str,
        /// The value.
        value: f64,
        /// What was expected.
        expected: &'static str,
    },
}

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

/// Allowable formation errors, the pass criterion (METHOD §7, §9).
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct AllowableErrors {
    /// x, y, z (m).
    pub position_m: [f64; 3],
    /// α, β, γ (rad).
    pub attitude_rad: [f64; 3],
}

impl AllowableErrors {
    /// As a 6-vector: x, y, z (m), α, β, γ (rad).
    pub fn as_array(&self) -> [f64; 6] {
        let (p, a) = (self.position_m, self.attitude_rad);
        [p[0], p[1], p[2], a[0], a[1], a[2]]
    }
}

/// A checked scenario.
#[derive(Debug, Clone)]
pub struct Scenario {
    /// Short name used in reports.
    pub name: String,
    /// Update period Δt (s).
    pub dt_s: f64,
    /// Flight duration (s).
    pub duration_s: f64,
    /// The formation (one slot per UAV).
    pub formation: Arc<Formation>,
    /// The navigator, which flies `path` and runs no controller.
    pub navigator: UavId,
    /// The navigator's path.
    pub path: NavigatorPath,
    /// Initial state of every UAV.
    pub initial: Vec<State9>,
    /// Dependency table of every UAV (the navigator's is unused).
    pub dependencies: Vec<DependencySet>,
    /// Controller parameters shared by every follower.
    pub controller: ControllerParams,
    /// Vehicle model shared by every UAV.
    pub vehicle: VehicleModel,
    /// Measurement noise σn.
    pub noise: MeasurementNoise,
    /// Correlated own-position error, if any.
    pub gnss_bias: Option<CorrelatedNoise>,
    /// Actuation error: each applied input component is scaled by `1 + ε`, ε uniform in
    /// `[−e, e]` (dimensionless). Paper scenario: 0.1.
    pub actuation_error: f64,
    /// Pass criterion.
    pub allowable: AllowableErrors,
    /// When false the followers' inputs are discarded: the method switched off, to show
    /// that the pass criterion can fail.
    pub adjustment_enabled: bool,
    /// Pairs closer than this are reported as unsafe (m). Paper scenario: 50 m.
    pub safety_distance_m: f64,
    /// How long the formation has been flying before t = 0 (s, ≥ 0): the controllers watch
    /// that ideal flight so their neighbour tracks are established at t = 0. Default 1 s.
    pub warmup_s: f64,
    /// Probability that an onboard observation is lost, per observation and step.
    pub dropout: f64,
    /// The same for observations of the UAV's own main references (the UAVs of its
    /// dependency table), when they differ: a UAV may track its references with a more
    /// reliable sensor than the one that scans its areas. `None`: [`Self::dropout`].
    pub reference_dropout: Option<f64>,
    /// Scheduled faults.
    pub faults: Vec<crate::faults::Fault>,
    /// UAVs whose state every UAV hears over the radio each period (ideal link, the
    /// broadcaster's measurement noise). Empty in the paper scenario.
    pub beacons: Vec<UavId>,
    /// Wind, turbulence and gusts.
    pub wind: crate::disturbance::Wind,
    /// The radio: broadcasters, range, delay and losses.
    pub radio: crate::radio::RadioModel,
    /// How the sensors find candidates: the grid, or all pairs (reference only).
    pub neighbour_search: crate::sensing::NeighbourSearch,
    /// The followers' formation control method. Default: the proximity method. Set it with
    /// [`Scenario::set_method`], which also makes the radio carry what the method needs.
    pub method: Method,
}

impl Scenario {
    /// Number of UAVs.
    pub fn len(&self) -> usize {
        self.initial.len()
    }

    /// True when the scenario has no UAVs.
    pub fn is_empty(&self) -> bool {
        self.initial.is_empty()
    }

    /// Number of update periods in the flight.
    pub fn steps(&self) -> u64 {
        (self.duration_s / self.dt_s).round() as u64
    }

    /// Switches the followers to `method` and makes the radio carry what it needs: the
    /// navigator's broadcasts (leader-follower, flocking) or everybody's (consensus). The
    /// radio's range, delay and losses stay as they are.
    pub fn set_method(&mut self, method: Method) {
        self.method = method;
        match method.radio_need() {
            RadioNeed::None => {}
            RadioNeed::Navigator => {
                if !self.radio.broadcast_all && !self.beacons.contains(&self.navigator) {
                    self.beacons.push(self.navigator);
                }
            }
            RadioNeed::All => self.radio.broadcast_all = true,
        }
    }

    /// Checks the scenario's consistency.
    pub fn validate(&self) -> Result<(), ScenarioError> {
        let n = self.initial.len();
        if n < 2 {
            return Err(ScenarioError::Shape { what: "number of UAVs", expected: 2, found: n });
        }
        if self.formation.len() != n {
            return Err(ScenarioError::Shape { what: "formation slots", expected: n, found: self.formation.len() });
        }
        if self.dependencies.len() != n {
            return Err(ScenarioError::Shape {
                what: "dependency tables",
                expected: n,
                found: self.dependencies.len(),
            });
        }
        if self.navigator.index() >= n {
            return Err(ConfigError::UnknownUav { id: self.navigator, size: n }.into());
        }
        positive("dt_s", self.dt_s)?;
        positive("duration_s", self.duration_s)?;
        if (self.controller.dt_s - self.dt_s).abs() > 1e-12 {
            return Err(ScenarioError::Value {
                field: "controller.dt_s",
                value: self.controller.dt_s,
                expected: "the scenario's dt_s",
            });
        }
        for s in &self.initial {
            if !state::is_finite(s) {
                return Err(ScenarioError::Value {
                    field: "initial state",
                    value: f64::NAN,
                    expected: "finite values",
                });
            }
        }
        let noise = self.noise;
        for (field, v) in [
            ("noise.position_m", noise.position_m),
            ("noise.velocity_mps", noise.velocity_mps),
            ("noise.attitude_rad", noise.attitude_rad),
            ("actuation_error", self.actuation_error),
        ] {
            if !(v.is_finite() && v >= 0.0) {
                return Err(ScenarioError::Value { field, value: v, expected: "a finite value ≥ 0" });
            }
        }
        positive("safety_distance_m", self.safety_distance_m)?;
        if !(self.warmup_s.is_finite() && self.warmup_s >= 0.0) {
            return Err(ScenarioError::Value {
                field: "warmup_s",
                value: self.warmup_s,
                expected: "a finite time ≥ 0 s",
            });
        }
        if !(0.0..=1.0).contains(&self.dropout) {
            return Err(ScenarioError::Value {
                field: "dropout",
                value: self.dropout,
                expected: "a probability in [0, 1]",
            });
        }
        if let Some(p) = self.reference_dropout.filter(|p| !(0.0..=1.0).contains(p)) {
            return Err(ScenarioError::Value {
                field: "reference_dropout",
                value: p,
                expected: "a probability in [0, 1]",
            });
        }
        for f in &self.faults {
            if let Some(u) = f.uav() {
                if u.index() >= n {
                    return Err(ConfigError::UnknownUav { id: u, size: n }.into());
                }
            }
        }
        for b in &self.beacons {
            if b.index() >= n {
                return Err(ConfigError::UnknownUav { id: *b, size: n }.into());
            }
        }
        for v in self.allowable.as_array() {
            positive("allowable error", v)?;
        }
        self.controller.validate()?;
        self.vehicle.validate()?;
        self.method.validate()?;
        let heard = match self.method.radio_need() {
            RadioNeed::None => true,
            RadioNeed::Navigator => self.radio.broadcast_all || self.beacons.contains(&self.navigator),
            RadioNeed::All => self.radio.broadcast_all,
        };
        if !heard {
            return Err(ScenarioError::Value {
                field: "method",
                value: f64::NAN,
                expected: "a radio that carries what the method needs (use Scenario::set_method)",
            });
        }
        Ok(())
    }

    /// The paper's six-UAV experiment (METHOD §9).
    pub fn paper() -> Self {
        let layout = [
            (0.0, 0.0, 0.0),
            (-86.6, 50.0, -10.0),
            (-86.6, -50.0, -10.0),
            (-173.2, 100.0, -20.0),
            (-173.2, 0.0, -20.0),
            (-173.2, -100.0, -20.0),
        ];
        let n = layout.len();
        let slots: Vec<FormationSlot> = layout.iter().map(|&(f, l, u)| FormationSlot::at(f, l, u)).collect();
        let path = PaperPath::default();
        // Every UAV starts in its slot on the navigator's initial state: [250 km/h, 0, vz, 5°, 3°, 0°]
        // with vz the path's initial climb rate (see README, Choices).
        let formation = Formation { slots, frame: FormationFrame::World };
        let initial = in_slots(&formation, UavId(0), &path.state_at(0.0, [0.0; 3]));
        let table: [&[(u32, f64)]; 6] = [
            &[],
            &[(0, 0.7), (2, 0.3)],
            &[(0, 0.7), (1, 0.3)],
            &[(1, 0.5), (4, 0.5)],
            &[(1, 0.35), (2, 0.35), (0, 0.3)],
            &[(2, 0.5), (4, 0.5)],
        ];
        let dependencies = table
            .iter()
            .enumerate()
            .map(|(i, refs)| {
                DependencySet::new(UavId(i as u32), n, refs.iter().map(|&(j, c)| (UavId(j), c)).collect())
                    .expect("the paper's Table 1 is a valid dependency table")
            })
            .collect();
        Self {
            name: "paper".into(),
            dt_s: 0.1,
            duration_s: 100.0,
            formation: Arc::new(formation),
            navigator: UavId(0),
            path: NavigatorPath::Paper(path),
            initial,
            dependencies,
            controller: ControllerParams::default(),
            vehicle: VehicleModel::Kinematic(KinematicModel::default()),
            noise: MeasurementNoise { position_m: 0.02, velocity_mps: kmh(0.18), attitude_rad: deg(0.01) },
            actuation_error: 0.1,
            gnss_bias: None,
            allowable: AllowableErrors { position_m: [0.5, 0.6, 0.2], attitude_rad: [deg(0.4), deg(0.3), deg(1.0)] },
            adjustment_enabled: true,
            safety_distance_m: 50.0,
            beacons: Vec::new(),
            radio: crate::radio::RadioModel::default(),
            wind: crate::disturbance::Wind::default(),
            warmup_s: 1.0,
            dropout: 0.0,
            reference_dropout: None,
            faults: Vec::new(),
            neighbour_search: crate::sensing::NeighbourSearch::Grid,
            method: Method::Proximity,
        }
    }
}

/// Every UAV in its slot around the navigator's state `nav0`, with the navigator's velocity
/// and attitude (plus its attitude offset).
pub fn in_slots(formation: &Formation, navigator: UavId, nav0: &State9) -> Vec<State9> {
    let nav = &formation.slots[navigator.index()];
    formation.slots.iter().map(|slot| nav0 + formation.w(slot, nav, nav0)).collect()
}

fn positive(field: &'static str, v: f64) -> Result<(), ScenarioError> {
    if v.is_finite() && v > 0.0 {
        Ok(())
    } else {
        Err(ScenarioError::Value { field, value: v, expected: "a finite value > 0" })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn paper_scenario_is_valid_and_matches_method() {
        let s = Scenario::paper();
        s.validate().expect("valid");
        assert_eq!(s.len(), 6);
        assert_eq!(s.steps(), 1000);
        assert_eq!(s.dependencies[4].degree(UavId(0)), Some(0.3));
        assert_eq!(s.dependencies[3].refs().len(), 2);
    }

    #[test]
    fn rejects_inconsistent_scenarios() {
        let mut s = Scenario::paper();
        s.dt_s = 0.0;
        assert!(s.validate().is_err());
        let mut s = Scenario::paper();
        s.initial.truncate(1);
        assert!(s.validate().is_err());
        let mut s = Scenario::paper();
        s.actuation_error = f64::NAN;
        assert!(s.validate().is_err());
        let mut s = Scenario::paper();
        s.controller.lambda = 1.5;
        assert!(matches!(s.validate(), Err(ScenarioError::Config(_))));
    }
}
