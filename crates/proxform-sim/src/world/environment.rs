//! Per-UAV environment state that only some scenarios need: the wind where each UAV flies
//! (turbulence filters), the bias of its own position fix, and its radio channel's
//! Gilbert-Elliott state. The engine keeps it in a separate buffer, allocated only when the
//! scenario has wind, a correlated position error or bursty radio losses, and advances it in
//! a pass of its own before the UAVs update, so a calm swarm of a million pays nothing for it.

use nalgebra::Vector3;
use proxform_core::state::State9;

use proxform_scenario::Scenario;

use super::wind::{course_to_world, TurbulenceState};
use crate::random::{RunKey, Source, StreamKey, Ziggurat};

/// One UAV's environment.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct UavEnv {
    /// Wind where it is at the start of the step (m/s, world frame).
    pub wind_now: Vector3<f64>,
    /// Wind where it will be at the end of the step.
    pub wind_next: Vector3<f64>,
    /// Its turbulence filters.
    pub turbulence: TurbulenceState,
    /// Bias of its own position fix (m).
    pub gnss_bias: Vector3<f64>,
    /// Its radio channel is in the Gilbert-Elliott bad state.
    pub channel_bad: bool,
}

/// Step counter offset of the channel draws, apart from the radio stream's loss draws.
const CHANNEL_STEP_BASE: u64 = 1 << 61;

/// True when the scenario needs per-UAV environment state.
pub fn needed(sc: &Scenario) -> bool {
    !sc.wind().is_calm() || sc.gnss_bias().is_some() || sc.radio().burst.is_some()
}

/// The environment of every UAV at t = 0.
pub fn initial(sc: &Scenario) -> Vec<UavEnv> {
    if !needed(sc) {
        return Vec::new();
    }
    let w0 = sc.wind().common(0.0);
    vec![UavEnv { wind_now: w0, wind_next: w0, ..UavEnv::default() }; sc.len()]
}

/// One step of every UAV's environment, from `t` to `t + Δt`.
#[derive(Debug, Clone, Copy)]
pub struct EnvStep<'a> {
    sc: &'a Scenario,
    /// The step's wind and position-fix draws.
    key: StreamKey,
    /// The step's radio-channel draws (apart from the radio stream's loss draws).
    channel: StreamKey,
    t: f64,
}

impl<'a> EnvStep<'a> {
    /// Step `k` (at time `t`) of the run `run`.
    pub fn new(sc: &'a Scenario, run: &RunKey, k: u64, t: f64) -> Self {
        Self { sc, key: run.at(k), channel: run.at(CHANNEL_STEP_BASE + k), t }
    }

    /// Advances UAV `i`'s environment over the step, given its state `x`.
    pub fn advance(&self, i: usize, x: &State9, env: &mut UavEnv) {
        let sc = self.sc;
        let dt = sc.dt_s();
        let uav = i as u64;
        env.wind_now = env.wind_next;
        let wind = sc.wind();
        if !wind.is_calm() {
            let mut w = wind.common(self.t + dt);
            if let Some(turb) = &wind.turbulence {
                let mut rng = self.key.rng(uav, Source::Wind);
                let speed = (x[3] * x[3] + x[4] * x[4] + x[5] * x[5]).sqrt();
                w += course_to_world(x, &env.turbulence.step(turb, speed, dt, &mut rng));
            }
            env.wind_next = w;
        }
        if let Some(g) = sc.gnss_bias() {
            // First-order Gauss-Markov bias, exactly discretised.
            let mut rng = self.key.rng(uav, Source::Gnss);
            let phi = (-dt / g.tau_s).exp();
            let kick = g.sigma_m * (1.0 - phi * phi).sqrt();
            let z = Ziggurat::get();
            for a in 0..3 {
                env.gnss_bias[a] = phi * env.gnss_bias[a] + kick * z.sample(&mut rng);
            }
        }
        let mut rng = self.channel.rng(uav, Source::Radio);
        super::radio::step_channel(sc.radio(), &mut env.channel_bad, &mut rng);
    }
}
