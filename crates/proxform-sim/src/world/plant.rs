//! The plant's side of a step, for both engines: the input a follower's vehicle is given for
//! its decision at the state it truly has (a vehicle flown by setpoints flies its setpoint from
//! there, whatever its agent believed), the actuation error on it, the vehicle's next state in
//! the wind, the model error the error caused and the effort the decision asked for; and where
//! a scripted navigator is set on its path. The random draws are the caller's (each engine has
//! its own streams): everything else about the plant is written here once.

use proxform_core::state::{self, Input, State9};
use proxform_core::{Decision, Outcome};
use proxform_scenario::Scenario;

use super::environment::UavEnv;

/// The input the vehicle at its true state `truth` is given for decision `d` (None: no
/// decision): nothing without one or with adjustment off (`adjust`); else what flies the
/// decision ([`Decision::flown_input`]: its setpoint from `truth`, or its input).
#[inline]
pub fn commanded(sc: &Scenario, truth: &State9, d: Option<&Decision>, adjust: bool) -> Input {
    match d {
        Some(d) if adjust => d.flown_input(sc.vehicle(), truth),
        _ => Input::zeros(),
    }
}

/// The input applied for `commanded` (as [`commanded`] gives it for decision `d`): with the
/// actuation error when the UAV adjusted, each component scaled by `1 + ε·r` with `r` drawn
/// uniformly in [−1, 1] by `draw` (in the order of the components); for a vehicle flown by
/// setpoints, the error scales the change the agent asked for, on top of its setpoint.
#[inline]
pub fn actuated(
    sc: &Scenario,
    commanded: Input,
    d: Option<&Decision>,
    adjust: bool,
    mut draw: impl FnMut() -> f64,
) -> Input {
    let adjusted = d.is_some_and(|d| matches!(d.outcome, Outcome::Adjusted { .. }));
    let epsilon = sc.actuation_error();
    if !adjusted || epsilon <= 0.0 {
        return commanded;
    }
    let mut error = || epsilon * draw();
    match d.and_then(|d| d.setpoint.map(|_| d.input)) {
        Some(asked) if adjust => commanded + asked.map(|u| u * error()),
        _ => commanded.map(|u| u * (1.0 + error())),
    }
}

/// The state after one period of a UAV at `me` given input `u`: through its vehicle, in the
/// wind where it flies (`e`; the calm-air plant when the scenario has none).
#[inline]
pub fn next_state(sc: &Scenario, me: &State9, u: &Input, e: &UavEnv) -> State9 {
    let (vehicle, dt) = (sc.vehicle(), sc.dt_s());
    if sc.wind().is_calm() {
        vehicle.propagate(me, u, dt)
    } else {
        vehicle.propagate_in_wind(me, u, dt, e.wind_now.into(), e.wind_next.into())
    }
}

/// The model error of a period: the state `next` that the applied input reached from `me`
/// less the state the commanded input would have; zero when they are the same input.
#[inline]
pub fn model_error(
    sc: &Scenario,
    me: &State9,
    (applied, commanded): (&Input, &Input),
    next: &State9,
    e: &UavEnv,
) -> [f32; 9] {
    if applied == commanded {
        return [0.0; 9];
    }
    let error = state::difference(next, &next_state(sc, me, commanded, e));
    std::array::from_fn(|k| error[k] as f32)
}

/// How hard decision input `u` asks the vehicle: the norm of its components, each in its
/// largest per-step magnitude.
#[inline]
pub fn effort(sc: &Scenario, u: &Input) -> f32 {
    let vehicle = sc.vehicle();
    let scale = vehicle.input_scale(sc.dt_s());
    (0..vehicle.n_inputs()).map(|j| if scale[j] > 0.0 { (u[j] / scale[j]).powi(2) } else { 0.0 }).sum::<f64>().sqrt()
        as f32
}

/// A scripted navigator's state at `t`: on the path that starts at `start`, as its vehicle
/// sits on it in the wind there (a fixed wing crabs into it).
#[inline]
pub fn on_path(sc: &Scenario, start: [f64; 3], t: f64) -> State9 {
    let s = sc.path().state_at(t, start);
    if sc.wind().is_calm() {
        s
    } else {
        sc.vehicle().on_path_in_wind(&s, sc.wind().common(t).into())
    }
}
