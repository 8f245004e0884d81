//! What every controller of a swarm shares, and the input step all of them use.

use std::sync::Arc;

use crate::azimuth::AreaClassifier;
use crate::control::{solve, Hessian};
use crate::error::ConfigError;
use crate::formation::FormationFrame;
use crate::horizon::{solve_horizon, HorizonProblem};
use crate::plan::{Carry, Plan};
use crate::state::{Input, State9};
use crate::vehicle::VehicleModel;

use super::ControllerParams;

/// What every controller of a swarm shares: the parameters, the vehicle model, and what is
/// derived from them once (weights, area boundaries, the cost Hessian when B is constant).
#[derive(Debug, Clone)]
pub struct ControllerSetup {
    pub(super) params: ControllerParams,
    pub(super) vehicle: VehicleModel,
    q: State9,
    input_weights: Input,
    pub(super) classifier: AreaClassifier,
    hessian: Option<Hessian>,
    /// The deceleration the stopping limit and collision avoidance count on (m/s²): their
    /// share ([`super::AVOID_BRAKING_SHARE`]) of the vehicle's braking.
    pub(super) braking_mps2: f64,
    /// The mission plan, when the UAVs know it, and how it carries reports older than a period
    /// in a formation of each frame (world, course, heading): shared by every UAV's tracks
    /// ([`crate::plan`]).
    carries: Option<[Arc<Carry>; 3]>,
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
        let braking_mps2 = super::AVOID_BRAKING_SHARE * vehicle.braking_mps2();
        Ok(Arc::new(Self { params, vehicle, q, input_weights, classifier, hessian, braking_mps2, carries: None }))
    }

    /// [`Self::new`], knowing the mission `plan` (the navigator's planned motion).
    pub fn with_plan(
        params: ControllerParams,
        vehicle: VehicleModel,
        plan: Arc<dyn Plan>,
    ) -> Result<Arc<Self>, ConfigError> {
        let mut s = Arc::unwrap_or_clone(Self::new(params, vehicle)?);
        let dt = s.params.dt_s;
        let carry = |frame| Arc::new(Carry::new(plan.clone(), frame, dt));
        let carries = [carry(FormationFrame::World), carry(FormationFrame::Course), carry(FormationFrame::Heading)];
        s.carries = Some(carries);
        Ok(Arc::new(s))
    }

    /// The mission plan, when the UAVs know it.
    pub fn plan(&self) -> Option<&Arc<dyn Plan>> {
        self.carries.as_ref().map(|c| c[0].plan())
    }

    /// How reports older than a period are brought forward in a formation of frame `frame`:
    /// with the plan, when the UAVs know it and `plan_forward` is on.
    pub fn carry(&self, frame: FormationFrame) -> Option<Arc<Carry>> {
        self.carry_by_plan(frame).filter(|_| self.params.plan_forward)
    }

    /// How the plan brings a report forward in a formation of frame `frame`, when the UAVs know
    /// the plan, whatever `plan_forward` says: for spans that are not the method's to predict
    /// (a network agent's latency, from the update to the instant its command acts).
    pub fn carry_by_plan(&self, frame: FormationFrame) -> Option<Arc<Carry>> {
        Some(self.carries.as_ref()?[frame as usize].clone())
    }

    /// The parameters.
    pub fn params(&self) -> &ControllerParams {
        &self.params
    }

    /// The vehicle model.
    pub fn vehicle(&self) -> &VehicleModel {
        &self.vehicle
    }

    /// The azimuth areas' classifier.
    pub fn classifier(&self) -> &AreaClassifier {
        &self.classifier
    }

    /// Whether a UAV keeps the formation's turn trend from one period to the next
    /// ([`super::TurnTrend`]): for a vehicle that lags its setpoints, with the turn
    /// feed-forward on.
    pub fn keeps_turn_trend(&self) -> bool {
        self.params.turn_feedforward && self.vehicle.setpoint_lag_s() > 0.0
    }

    /// The deceleration the stopping limit and collision avoidance count on (m/s²).
    pub fn braking_mps2(&self) -> f64 {
        self.braking_mps2
    }

    /// The envelope's weights `1/Δ²` per parameter.
    pub fn q(&self) -> &State9 {
        &self.q
    }

    /// The input weights (per input, over its per-step limit squared).
    pub fn input_weights(&self) -> &Input {
        &self.input_weights
    }

    /// The navigator's autopilot on its path (METHOD §5): the input that brings the UAV at
    /// `own` toward the path's state one period ahead, within the vehicle's limits
    /// ([`Self::input_toward`] with `r = F·X − target`); `path(s)` is the path's state `s`
    /// seconds from now. A vehicle that lags its setpoints ([`VehicleModel::setpoint_lag_s`])
    /// is asked for the path's velocity that much later. A navigator that flies its path this
    /// way is moved by the wind like every other UAV, and its followers keep station on where
    /// it is, not on where its path says it should be.
    pub fn input_along_path(&self, own: &State9, path: impl Fn(f64) -> State9) -> Input {
        self.input_on_path(own, path, None)
    }

    /// The autopilot of a UAV that leads from a slot of the formation (the navigator's
    /// successor, METHOD §8): as [`Self::input_along_path`] toward its slot's state on the
    /// path, with the velocity closing the position gap over the closing time τ
    /// (`closing_time_s`, as the controller's step 4 does): a vehicle whose input moves its
    /// position only through its velocity (the fixed wing's bank) would otherwise match the
    /// slot's velocity and keep any gap it took over.
    pub fn input_to_slot_on_path(&self, own: &State9, path: impl Fn(f64) -> State9) -> Input {
        self.input_on_path(own, path, self.params.closing_time_s)
    }

    fn input_on_path(&self, own: &State9, path: impl Fn(f64) -> State9, closing_s: Option<f64>) -> Input {
        let dt = self.params.dt_s;
        let mut target = path(dt);
        let lag = self.vehicle.setpoint_lag_s();
        if lag > 0.0 {
            let ahead = path(dt + lag);
            for k in crate::state::VX..crate::state::ALPHA {
                target[k] = ahead[k];
            }
        }
        let held = self.vehicle.hold(own, dt);
        if let Some(tau) = closing_s {
            for k in crate::state::X..crate::state::VX {
                target[k + 3] += (target[k] - held[k]) / tau;
            }
        }
        let r = crate::state::difference(&held, &target);
        self.input_toward(own, &r)
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
