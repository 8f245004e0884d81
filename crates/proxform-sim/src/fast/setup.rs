//! What the fast engine derives once from a scenario: which scenarios it runs (the rest stay
//! with the reference engine) and the constants every UAV's update reads.

use proxform_core::state::VX;
use proxform_core::{Method, PredictorKind};
use proxform_scenario::wind::Wind;
use proxform_scenario::Scenario;

use super::tracks::{Filter, MAX_AGE_STEPS, MAX_ID};

/// Why the fast engine does not run a scenario (it then runs on the reference engine).
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[error("the fast engine does not run {0} (use the reference engine)")]
pub struct Unsupported(pub String);

/// Checks that the fast engine runs every feature `sc` uses. Its controller step is the
/// reference's own ([`proxform_core::controller::UavView::step`]), so every controller setting
/// runs (the robust fusion, the horizon, separation keeping, the stopping limit, collision
/// avoidance, the turn feed-forward, every formation frame) but what its records or its world
/// cannot represent: its tracks are α-β filters or none (the constant-velocity predictor; no Singer filter), and its world flies every vehicle (the plant written once
/// for both engines, [`crate::world::plant`]; a UAV flown by setpoints keeps its setpoint and
/// its turn trend from step to step) with measurement noise, actuation error, onboard dropout, beacons and radio loss (i.i.d. and bursty), wind
/// (steady, gusts, turbulence), the position fix's bias, changes of formation (every UAV at
/// once, at the change's time), scattered starts (the reference's own placement) and the
/// own-sensor check and filter (each UAV's [`proxform_core::own_estimate::OwnEstimate`]), and
/// a delayed radio (the reference's own delay line; its tracks updated at a report's
/// measurement), relays of the navigator (each follower's from its records), and faults, the
/// navigator's succession and slot re-assignment (the reference's own
/// [`crate::world::membership::Membership`]), and relative sensing (each UAV's last own fix,
/// [`proxform_core::controller::OwnFix`], and a flag a track for a report of its own sensors).
/// The baselines and the Singer predictor stay with the reference engine.
pub fn supports(sc: &Scenario) -> Result<(), Unsupported> {
    let p = sc.controller();
    let tracks = p.areas.areas + max_refs(sc);
    let too_many = format!(
        "more than {MAX_TRACKS} areas and main references of a UAV ({} areas and up to {} main references)",
        p.areas.areas,
        max_refs(sc)
    );
    let checks: [(bool, &str); 5] = [
        (matches!(sc.method(), Method::Proximity), "a baseline method"),
        (!matches!(p.predictor, PredictorKind::Singer { .. }), "the Singer predictor (controller.predictor)"),
        (sc.len() <= MAX_ID as usize, "more than 16 777 214 UAVs"),
        (tracks <= MAX_TRACKS, &too_many),
        (
            oldest_steps(sc) <= MAX_AGE_STEPS as f64,
            "a track timeout, radio delay and relayed age over 120 update periods together",
        ),
    ];
    // Every reason, in this order: the first alone misled (a formation change's file was told
    // of a setting the change turned on by default, not of the change).
    let missing: Vec<&str> = checks.iter().filter(|c| !c.0).map(|c| c.1).collect();
    match missing.is_empty() {
        true => Ok(()),
        false => Err(Unsupported(missing.join(", "))),
    }
}

/// How many update periods back the measurement a track still uses may lie: a report arrives
/// as old as the radio's delay, or a relay as old as what its sender may forward besides
/// ([`proxform_core::controller::navigator_track`]: `relay_max_age_s` where the plan brings
/// reports forward, the track timeout otherwise); the track is used until its timeout after.
pub fn oldest_steps(sc: &Scenario) -> f64 {
    let p = sc.controller();
    let relayed_s = match (sc.radio().relay_navigator, sc.agents().controller().carry(sc.formation().frame)) {
        (false, _) => 0.0,
        (true, Some(_)) => p.relay_max_age_s,
        (true, None) => p.track_timeout_s,
    };
    (p.track_timeout_s + relayed_s) / p.dt_s + f64::from(sc.radio().delay_steps)
}

/// Most tracks a UAV keeps in the fast engine (its areas and its main references).
pub const MAX_TRACKS: usize = 16;

/// The most main references any UAV has, in the first formation or a later one.
fn max_refs(sc: &Scenario) -> usize {
    let stages = sc.schedule().stages().iter().map(|s| &s.dependencies[..]);
    std::iter::once(sc.dependencies()).chain(stages).flatten().map(|d| d.refs().len()).max().unwrap_or(0)
}

/// The largest acceleration the wind may give a UAV along an axis (m/s²), which its
/// neighbours' tracks must be able to hold: the gust's steepest rise, `π·|peak|/duration`, plus
/// eight standard deviations of the turbulence's change over one period `Δt` (a filter's jump,
/// `σ·√(1.5·(1 − e^(−2Δt·V/L)))`, at the fastest speed `V`), over `Δt`. Zero in calm air.
pub fn wind_acceleration(wind: &Wind, fastest_mps: f64, dt: f64) -> f64 {
    let gust = wind.gust.map_or(0.0, |g| std::f64::consts::PI * g.peak_mps.norm() / g.duration_s.max(dt));
    let turbulence = wind.turbulence.map_or(0.0, |t| {
        let (l, sigma) = t.scales();
        (0..3)
            .map(|k| sigma[k] * (1.5 * (1.0 - (-2.0 * dt * fastest_mps.max(1.0) / l[k]).exp())).sqrt())
            .fold(0.0, f64::max)
    });
    gust + 8.0 * turbulence / dt
}

/// The constants of every UAV's update.
#[derive(Debug, Clone)]
pub struct Consts {
    pub nav: usize,
    pub dt: f64,
    pub areas: usize,
    /// Sensing range (m).
    pub range: f64,
    /// Track records per UAV.
    pub capacity: usize,
    pub filter: Filter,
    /// Tracks older than this (steps) are freed: the longer of the timeout and the coasting.
    pub track_limit: i64,
    /// Coasting tracks are brought forward beyond one period by the mission plan
    /// ([`proxform_core::plan`]), as the reference's.
    pub carry: Option<std::sync::Arc<proxform_core::plan::Carry>>,
    /// Measurement noise σ per parameter.
    pub sigma: [f32; 9],
    /// Collision avoidance: distance (m) and deceleration (m/s²).
    pub avoid: Option<(f64, f64)>,
    /// Each UAV keeps what its autopilot flies ([`super::update::Autopilot`]): a vehicle
    /// flown by setpoints, or one whose controller keeps the formation's turn trend.
    pub autopilot: bool,
    /// The own-sensor check or the own-state filter is on: each UAV keeps its
    /// [`proxform_core::own_estimate::OwnEstimate`].
    pub own_estimate: bool,
    /// The radio's delay (whole update periods).
    pub radio_delay_steps: usize,
}

impl Consts {
    /// The constants of `sc` (which [`supports`] accepts).
    pub fn new(sc: &Scenario) -> Self {
        let p = sc.controller();
        let setup = sc.agents().controller().clone();
        // The constant-velocity predictor keeps no tracks (the filter's gains are unused).
        let (plain, (alpha, beta)) = match p.predictor {
            PredictorKind::AlphaBeta { alpha, beta } => (false, (alpha, beta)),
            PredictorKind::ConstantVelocity => (true, (1.0, 0.0)),
            PredictorKind::Singer { .. } => unreachable!("checked by supports"),
        };
        let dt = p.dt_s;
        let nav = sc.navigator().index();
        let range = p.areas.sensing_range_m;
        let steps = |s: f64| (s / dt + 1e-6).floor() as i64;
        let timeout_steps = steps(p.track_timeout_s);
        let vehicle = sc.vehicle();
        let rates = vehicle.rate_limits(dt);
        let sigma = sc.noise().sigma();
        let wind = wind_acceleration(sc.wind(), vehicle.top_speed_mps(), dt);
        let radio = sc.radio();
        Self {
            nav,
            dt,
            areas: p.areas.areas,
            range,
            capacity: (p.areas.areas + max_refs(sc)).max(1),
            filter: Filter::new(
                alpha,
                beta,
                dt,
                timeout_steps,
                p.coast_accel_s,
                Filter::rate_span(
                    std::array::from_fn(|c| sigma[VX + c]),
                    std::array::from_fn(|c| rates[c] + if c < 3 { wind } else { 0.0 }),
                    dt,
                ),
            )
            .plain(plain),
            track_limit: timeout_steps.max(steps(p.coast_s.min(p.track_timeout_s))),
            carry: setup.carry(sc.formation().frame),
            sigma: std::array::from_fn(|k| sigma[k] as f32),
            avoid: p.avoid_m.filter(|&d| d > 0.0).map(|d| (d, setup.braking_mps2())),
            autopilot: vehicle.takes_velocity_setpoints() || setup.keeps_turn_trend(),
            own_estimate: proxform_core::own_estimate::OwnEstimate::used(p),
            radio_delay_steps: radio.delay_steps as usize,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::Vector3;
    use proxform_scenario::wind::{Gust, Severity, Turbulence};

    #[test]
    fn the_tracks_hold_what_the_wind_does() {
        let dt = 0.1;
        assert_eq!(wind_acceleration(&Wind::default(), 80.0, dt), 0.0, "calm air adds nothing");
        let steady = Wind { steady_mps: Vector3::new(10.0, 0.0, 0.0), ..Wind::default() };
        assert_eq!(wind_acceleration(&steady, 80.0, dt), 0.0, "nor does a steady wind");
        // A gust of 10 m/s over 4 s rises at most π·10/4 m/s².
        let gust = Wind {
            gust: Some(Gust { at_s: 1.0, duration_s: 4.0, peak_mps: Vector3::new(6.0, 8.0, 0.0) }),
            ..Wind::default()
        };
        assert!((wind_acceleration(&gust, 80.0, dt) - std::f64::consts::PI * 2.5).abs() < 1e-12);
        // Severe turbulence at 300 m, 80 m/s: the wind's change over one period, sampled from the
        // engine's own filters, stays within the bound (which is some eight of its σ).
        let turb = Turbulence { severity: Severity::Severe, altitude_m: 300.0 };
        let bound = wind_acceleration(&Wind { turbulence: Some(turb), ..Wind::default() }, 80.0, dt);
        let mut st = crate::world::wind::TurbulenceState::default();
        let key = crate::random::stream_key(5, 0, 0, crate::random::Source::Wind);
        let mut last = Vector3::zeros();
        let (mut sum2, mut worst, n) = (0.0, 0.0f64, 100_000u64);
        for k in 0..n {
            let g = st.step(&turb, 80.0, dt, &mut crate::random::StepRng::new(key, k));
            let rate = (g - last).amax() / dt;
            if k > 100 {
                sum2 += rate * rate;
                worst = worst.max(rate);
            }
            last = g;
        }
        let sd = (sum2 / n as f64).sqrt();
        assert!(worst < bound && bound < 12.0 * sd, "bound {bound}, largest {worst}, σ {sd}");
    }
}
