//! Spec → checked scenario: the one place where a [`ScenarioSpec`] becomes a [`Scenario`].
//!
//! Parsing (serde) has already rejected unknown keys and wrong types; [`TryFrom`] checks every
//! value (finite, in range, consistent), fills every default ([`crate::defaults`]), converts
//! units once (km/h → m/s, degrees → radians) and checks that the followers' vehicle can fly
//! the navigator's path. Every error names its key (`controller.lambda`, `fault[2].at_s`).
//! Each section has a converter of its own in this folder.

mod controller;
mod feasibility;
mod formation;
mod path;
mod placement;
mod values;
mod vehicle;
mod world;

use std::sync::Arc;

use proxform_core::{AgentSetup, ControllerSetup, Formation, RadioNeed, VehicleModel};

use crate::defaults;
use crate::scenario::Scenario;
use crate::spec::ScenarioSpec;

pub use controller::{method_from, paper_method, PAPER};
pub use values::SpecError;
use values::{err, non_negative, or_default, positive, show, uav};

/// Longest flight accepted, in update periods.
pub const MAX_STEPS: f64 = 1e8;
/// Shortest and longest update period accepted (s).
pub const MIN_DT_S: f64 = 1e-3;
/// See [`MIN_DT_S`].
pub const MAX_DT_S: f64 = 1.0;
/// Longest warm start (s).
pub const MAX_WARMUP_S: f64 = 600.0;
/// Most UAVs that may all broadcast to all.
pub const MAX_BROADCAST_ALL_UAVS: usize = 20_000;
/// Most radio messages in flight (sent, not yet arrived).
pub const MAX_MESSAGES_IN_FLIGHT: usize = 10_000_000;
/// Most UAVs a scenario may have.
pub const MAX_UAVS: usize = 10_000_000;

impl TryFrom<ScenarioSpec> for Scenario {
    type Error = SpecError;

    fn try_from(spec: ScenarioSpec) -> Result<Self, SpecError> {
        let name = spec.name.clone().unwrap_or_else(|| "scenario".into());
        // A name is printed in reports and terminals and names output folders: control
        // characters (escape sequences that rewrite a terminal) and empty or endless names are
        // refused here, once.
        if let Some(c) = name.chars().find(|c| c.is_control()) {
            return Err(err("name", format!("holds the control character {:?}: use printable text", c)));
        }
        if name.trim().is_empty() || name.chars().count() > 200 {
            return Err(err("name", "1 to 200 printable characters"));
        }
        let dt_s = or_default("dt_s", spec.dt_s, defaults::DT_S, positive)?;
        if !(MIN_DT_S..=MAX_DT_S).contains(&dt_s) {
            return Err(err(
                "dt_s",
                format!(
                    "{} s is outside {MIN_DT_S} to {MAX_DT_S} s: the vehicle models advance one update period at a \
                     time and the controllers act once a period, which holds for periods of milliseconds to a second",
                    values::show(dt_s)
                ),
            ));
        }
        let duration_s = or_default("duration_s", spec.duration_s, defaults::DURATION_S, positive)?;
        if duration_s / dt_s > MAX_STEPS {
            return Err(err(
                "duration_s",
                format!("{} s at Δt = {dt_s} s is more than {MAX_STEPS:e} steps", values::show(duration_s)),
            ));
        }
        if (duration_s / dt_s).round() < 1.0 {
            return Err(err(
                "duration_s",
                format!(
                    "{} s is shorter than one update period (dt_s = {dt_s} s): nothing would fly",
                    values::show(duration_s)
                ),
            ));
        }
        let vehicle = vehicle::vehicle(&spec.vehicle)?;
        let safety_default = match vehicle {
            VehicleModel::Multirotor(_) => defaults::MULTIROTOR_SAFETY_DISTANCE_M,
            _ => defaults::SAFETY_DISTANCE_M,
        };
        let safety_distance_m = or_default("safety_distance_m", spec.safety_distance_m, safety_default, positive)?;
        values::distance("safety_distance_m", safety_distance_m)?;
        let warmup_s = or_default("warmup_s", spec.warmup_s, defaults::WARMUP_S, non_negative)?;
        if warmup_s > MAX_WARMUP_S {
            return Err(err(
                "warmup_s",
                format!(
                    "{} s is more than {MAX_WARMUP_S} s: the warm start only lets the tracks learn their rates",
                    values::show(warmup_s)
                ),
            ));
        }
        let engine = match spec.engine.as_deref() {
            None | Some("auto") => crate::scenario::EngineChoice::Auto,
            Some("reference") => crate::scenario::EngineChoice::Reference,
            Some("fast") => crate::scenario::EngineChoice::Fast,
            Some(other) => {
                return Err(err(
                    "engine",
                    format!("unknown engine \"{other}\" (expected \"auto\", \"reference\" or \"fast\")"),
                ))
            }
        };
        let fixed_wing = matches!(vehicle, VehicleModel::FixedWing(_));
        let mut params = controller::params(&spec.controller, dt_s, &vehicle)?;

        let mut formation_spec = spec.formation.clone();
        let formation::Slots { slots, mut frame, explicit } = formation::slots(&formation_spec, safety_distance_m)?;
        if spec.formation.frame.is_none() {
            // A formation of vehicles that turn turns with them: the fixed wing's with its course,
            // the multirotor's with its nose (which need not follow its course).
            frame = match vehicle {
                VehicleModel::Kinematic(_) => frame,
                VehicleModel::FixedWing(_) => proxform_core::FormationFrame::Course,
                VehicleModel::Multirotor(_) => proxform_core::FormationFrame::Heading,
            };
        }
        let n = slots.len();
        let navigator = uav("navigator", spec.navigator.unwrap_or(defaults::NAVIGATOR), n)?;
        // Derived tables lean on the navigator by default, whatever the vehicle: a deep
        // formation's errors would otherwise grow rank by rank (README "Robust formation
        // keeping"); a multirotor or fixed-wing formation hears the navigator in any case.
        // Tables written out for every follower (`depends_on`, the paper's) are flown as written.
        let derived = explicit.iter().enumerate().any(|(i, t)| i != navigator.index() && t.is_none());
        let paper = controller::paper_method(&spec.controller);
        if !paper && (derived || !matches!(vehicle, VehicleModel::Kinematic(_))) {
            let d = formation_spec.dependencies.get_or_insert_with(Default::default);
            d.navigator_degree = d.navigator_degree.or(Some(defaults::NAVIGATOR_DEGREE));
        }
        feasibility::separated(&slots, safety_distance_m)?;
        let dependencies =
            formation::dependencies(&formation_spec, &slots, &explicit, navigator, params.areas.sensing_range_m)?;
        let formation = Arc::new(Formation { slots, frame });
        let mut schedule_warnings = Vec::new();
        let schedule = formation::schedule(
            &formation_spec,
            &formation,
            navigator,
            safety_distance_m,
            duration_s,
            params.areas.sensing_range_m,
            &mut schedule_warnings,
        )?;

        let path = path::path(&spec.path)?;
        let wind = world::wind(&spec.wind)?;
        let mut initial = feasibility::initial_states(&spec, &formation, navigator, &path, &vehicle)?;
        if !wind.is_calm() {
            // In the wind of the start (a fixed wing crabs into it).
            let w = wind.common(0.0).into();
            for x in &mut initial {
                *x = vehicle.on_path_in_wind(x, w);
            }
        }
        let can_hover = vehicle.forward_speed_range().0 == 0.0;
        let placement = placement::placement(&spec.initial, &initial, navigator, safety_distance_m, can_hover)?;
        let form_within_s = placement::form_within(&spec.initial, &placement, duration_s)?;
        let reassign_on_loss = spec.formation.reassign_on_loss.unwrap_or(false);
        if spec.initial.assign_by.is_some() && spec.initial.assign_slots != Some(true) && !reassign_on_loss {
            return Err(err(
                "initial.assign_by",
                "applies with initial.assign_slots = true or formation.reassign_on_loss = true only",
            ));
        }
        let reassign_on_loss = reassign_on_loss.then(|| placement::assign_by(&spec.initial)).transpose()?;
        placement::assignment_within_bounds(&placement, reassign_on_loss, n)?;
        feasibility::path_within_vehicle(&path, &vehicle, duration_s, dt_s)?;
        feasibility::course_defined(&path, &formation, duration_s)?;
        feasibility::slots_within_vehicle(
            &path,
            &formation,
            navigator,
            &vehicle,
            params.turn_feedforward,
            &wind,
            duration_s,
        )?;

        let (noise, gnss_bias, actuation_error) = world::noise(&spec.noise)?;
        if let proxform_core::PredictorKind::Singer { position_sigma_m, velocity_sigma_mps, .. } = &mut params.predictor
        {
            // The filter weighs measurements by the sensors' noise (a floor keeps it proper).
            *position_sigma_m = noise.position_m.max(1e-4);
            *velocity_sigma_mps = noise.velocity_mps.max(1e-4);
        }
        let (dropout, reference_dropout, relative_sensing) = world::sensing(&spec.sensing)?;
        let (mut radio, mut beacons) = world::radio(&spec.radio, dt_s, duration_s, n)?;
        let network = world::network(&spec.network)?;
        let allowable = world::allowable(&spec.allowable, &vehicle)?;
        let faults = world::faults(&spec.fault, n, duration_s)?;
        if let Some(by) = reassign_on_loss {
            placement::reassignments_within_bounds(by, n, &faults)?;
        }
        if let Some(k) =
            faults.iter().position(|f| matches!(f, crate::faults::Fault::Join { uav, .. } if *uav == navigator))
        {
            return Err(err(
                format!("fault[{}].uav", k + 1),
                format!(
                    "UAV {} is the navigator: it leads from the start and cannot join later (a UAV that joins \
                     takes a follower's slot; to fly without a navigator for a while, remove it: a successor leads)",
                    navigator.0 + 1
                ),
            ));
        }
        let method = controller::method(&spec.controller)?;
        // With relative sensing and biased fixes the rear ranks beyond the navigator's sensing
        // range cannot take its broadcast (its own fix, in its frame): the navigator reaches
        // them relayed, each relay placed by the receiver's own view of its sender (METHOD §8).
        // Not for the paper's method, nor a predictor that keeps no tracks to relay from.
        let biased = gnss_bias.as_ref().is_some_and(|b| b.sigma_m > 0.0);
        let tracked = !matches!(params.predictor, proxform_core::PredictorKind::ConstantVelocity);
        if spec.radio.relay_navigator.is_none()
            && relative_sensing
            && biased
            && !paper
            && tracked
            && n <= MAX_BROADCAST_ALL_UAVS
            && matches!(method, proxform_core::Method::Proximity)
            && formation::beyond_sensing_of_navigator(&formation.slots, navigator, params.areas.sensing_range_m)
        {
            radio.relay_navigator = true;
        }
        let relay_warning = (spec.radio.relay_navigator.is_none()
            && relative_sensing
            && biased
            && !paper
            && !tracked
            && formation::beyond_sensing_of_navigator(&formation.slots, navigator, params.areas.sensing_range_m))
        .then(|| {
            err(
                "controller.predictor",
                "\"constant_velocity\" keeps no tracks to relay the navigator from: with biased fixes and relative \
                 sensing, followers beyond the navigator's sensing range cannot take its broadcast (its own fix) and \
                 lean on their neighbours alone (METHOD §8, relays with relative sensing)",
            )
        });
        if spec.radio.relay_navigator == Some(true) && !tracked {
            return Err(err(
                "radio.relay_navigator",
                "the constant-velocity predictor keeps no tracks to relay the navigator from (controller.predictor)",
            ));
        }
        // Derived tables that lean on the navigator hear it over the radio where it is out of
        // sensing range: the navigator broadcasts, unless the file names the beacons without it
        // (then a warning says who cannot hear it).
        let leans_on_navigator =
            formation_spec.dependencies.as_ref().and_then(|d| d.navigator_degree).is_some_and(|v| v > 0.0);
        let silenced = leans_on_navigator && spec.radio.beacons.is_some() && !beacons.contains(&navigator);
        let navigator_by_radio = leans_on_navigator && !silenced;
        if navigator_by_radio && !radio.broadcast_all && !beacons.contains(&navigator) {
            beacons.push(navigator);
        }
        // Followers scattered out of sight of their references, and UAVs joining wherever they
        // appear, head for the formation on the navigator's broadcast (METHOD §8, homing): it
        // broadcasts unless the file names the beacons (`beacons = []` for none).
        let joins = faults.iter().any(|f| matches!(f, crate::faults::Fault::Join { .. }));
        let homing = (!placement.in_slots() || joins) && spec.radio.beacons.is_none();
        if homing && !radio.broadcast_all && !beacons.contains(&navigator) {
            beacons.push(navigator);
        }
        // The radio carries what the method needs: the navigator's broadcasts or everybody's.
        match method.radio_need() {
            RadioNeed::None => {}
            RadioNeed::Navigator => {
                if !radio.broadcast_all && !beacons.contains(&navigator) {
                    beacons.push(navigator);
                }
            }
            RadioNeed::All => radio.broadcast_all = true,
        }
        // Every receiver checks every message: all-to-all broadcast is O(N²) a step, and a delayed
        // radio keeps every message of the delay.
        if radio.relay_navigator && n > MAX_BROADCAST_ALL_UAVS {
            return Err(err(
                "radio.relay_navigator",
                format!("{n} UAVs all relaying is {n}² message checks a step: at most {MAX_BROADCAST_ALL_UAVS} UAVs"),
            ));
        }
        let senders = if radio.broadcast_all { n } else { beacons.len() } + if radio.relay_navigator { n } else { 0 };
        if radio.broadcast_all && n > MAX_BROADCAST_ALL_UAVS {
            return Err(err(
                "radio.broadcast_all",
                format!(
                    "{n} UAVs all broadcasting is {n}² message checks a step: at most {MAX_BROADCAST_ALL_UAVS} UAVs; \
                     name a few radio.beacons instead{}",
                    if spec.controller.method.as_deref() == Some("consensus") {
                        " (consensus needs every UAV's broadcasts)"
                    } else {
                        ""
                    }
                ),
            ));
        }
        if (radio.delay_steps as usize + 1).saturating_mul(senders) > MAX_MESSAGES_IN_FLIGHT {
            return Err(err(
                "radio.delay_s",
                format!(
                    "{} periods of delay with {senders} broadcasting UAVs keep {} messages in flight, more than {MAX_MESSAGES_IN_FLIGHT}",
                    radio.delay_steps,
                    (radio.delay_steps as usize + 1).saturating_mul(senders)
                ),
            ));
        }
        params.separation_m = Some(params.separation_m.unwrap_or(defaults::SEPARATION_PER_SAFETY * safety_distance_m));
        // Robust fusion by default (METHOD §8), whichever engine flies: a neighbour far from its
        // own slot (its sensor failed; it joins, forms or was re-assigned) must not drag the
        // UAVs that lean on it.
        if spec.controller.isolation_gate.is_none() && !paper {
            params.isolation_gate = Some(defaults::ISOLATION_GATE);
        }
        // Collision avoidance by default for the kinematic vehicle; the fixed wing's braking is a
        // rough figure (it avoids by turning), so there it is asked for, like the stopping limit.
        let avoid_default = match vehicle {
            VehicleModel::Kinematic(_) | VehicleModel::Multirotor(_) => defaults::AVOID_PER_SAFETY * safety_distance_m,
            VehicleModel::FixedWing(_) => 0.0,
        };
        params.avoid_m = Some(params.avoid_m.unwrap_or(avoid_default));
        params.relative_sensing = relative_sensing;
        // Each UAV's fix biased on its own: a radio report is in a frame ~√2 biases away.
        params.radio_fallback = spec.controller.radio_fallback.unwrap_or(relative_sensing && biased);
        if paper && spec.controller.plan_forward.is_none() {
            params.plan_forward = false;
        }
        // The own-sensor check by default (METHOD §8) for every method but the paper's,
        // whichever engine flies. Its gate widens at least as fast as the turbulence can move a
        // UAV off its prediction.
        // A gate within the position noise refuses clean readings: the default lies above it.
        let noise_floor_m = defaults::own_gate_floor_m(noise.position_m);
        if spec.controller.own_gate_m.is_none() && !paper {
            params.own_gate_m = Some(defaults::OWN_GATE_M.max(noise_floor_m));
        }
        if spec.controller.own_gate_growth_mps.is_none() {
            let sigma_u = wind.turbulence.map_or(0.0, |t| t.scales().1[0]);
            params.own_gate_growth_mps = defaults::OWN_GATE_GROWTH_MPS + defaults::OWN_GATE_GROWTH_SIGMAS * sigma_u;
        }
        // Every UAV knows the mission: reports are brought forward with the navigator's plan
        // (METHOD §3, "Reports brought forward").
        let s0 = initial[navigator.index()];
        let plan = Arc::new(crate::path::MissionPlan(path.clone(), [s0[0], s0[1], s0[2]]));
        let setup = ControllerSetup::with_plan(params, vehicle, plan).map_err(|e| err("controller", e.to_string()))?;
        let mut warnings = world::faults_after(&faults, duration_s);
        warnings.append(&mut schedule_warnings);
        if let Some(g) = spec.controller.own_gate_m.filter(|g| *g > 0.0 && *g < noise_floor_m) {
            warnings.push(err(
                "controller.own_gate_m",
                format!(
                    "{} m is within the position noise (σ = {} m): clean readings will be refused \
                     and their UAVs fly, and broadcast, a held reading's error; {} m or more refuses only \
                     what the noise seldom does (the default)",
                    show(g),
                    show(noise.position_m),
                    show((noise_floor_m * 100.0).ceil() / 100.0)
                ),
            ));
        }
        if navigator_by_radio {
            warnings.extend(formation::beyond_the_navigators_radio(
                &formation.slots,
                navigator,
                radio.range_m,
                setup.params().areas.sensing_range_m,
                radio.relay_navigator,
            ));
        }
        if silenced && !radio.broadcast_all {
            warnings.push(err(
                "radio.beacons",
                format!(
                    "the derived tables lean on the navigator (formation.dependencies.navigator_degree, 0.8 by \
                     default) but the beacons named leave it silent: followers beyond its sensing range cannot \
                     hear it (name UAV {} among the beacons, or set navigator_degree = 0)",
                    navigator.0 + 1
                ),
            ));
        }
        // Every UAV hearing every other within the radio's range: n² reports a step.
        if radio.broadcast_all && n > BROADCAST_ALL_SAYS_ABOVE {
            warnings.push(err(
                "radio.broadcast_all",
                format!(
                    "{n} UAVs each hear every other{}: up to {:.1e} radio reports a step, work that grows with the \
                     square of the swarm (a flight of thousands takes minutes); a shorter radio.range_m bounds what \
                     each hears",
                    match radio.range_m.is_finite() {
                        true => format!(" within {} m", show(radio.range_m)),
                        false => String::new(),
                    },
                    (n as f64) * (n as f64 - 1.0)
                ),
            ));
        }
        // Every UAV perceiving every other: a sensing range that spans the formation.
        if n > BROADCAST_ALL_SAYS_ABOVE {
            let (lo, hi) = formation.slots.iter().fold(([f64::INFINITY; 3], [f64::NEG_INFINITY; 3]), |(lo, hi), s| {
                let o = s.offset_m;
                ([lo[0].min(o.x), lo[1].min(o.y), lo[2].min(o.z)], [hi[0].max(o.x), hi[1].max(o.y), hi[2].max(o.z)])
            });
            let span = ((hi[0] - lo[0]).powi(2) + (hi[1] - lo[1]).powi(2) + (hi[2] - lo[2]).powi(2)).sqrt();
            let range = setup.params().areas.sensing_range_m;
            if range >= span {
                warnings.push(err(
                    "controller.sensing_range_m",
                    format!(
                        "{} m spans the whole formation ({:.0} m across): each of the {n} UAVs scans every other, \
                         {:.1e} pairs a step, work that grows with the square of the swarm (a flight of thousands \
                         takes minutes); a range of a few spacings finds the same nearest neighbours",
                        show(range),
                        span,
                        (n as f64) * (n as f64 - 1.0)
                    ),
                ));
            }
        }
        warnings.extend(formation::drifting_groups(&dependencies, navigator, &formation_spec));
        if spec.controller.turn_feedforward == Some(true) && formation.frame == proxform_core::FormationFrame::World {
            warnings.push(err(
                "controller.turn_feedforward",
                "does nothing in a world frame, which does not turn (formation.frame = \"course\" or \"heading\")",
            ));
        }
        if !setup.params().plan_forward && senders > 0 && (radio.delay_steps > 0 || radio.relay_navigator) {
            warnings.push(err(
                if spec.controller.plan_forward.is_none() { "controller.method" } else { "controller.plan_forward" },
                format!(
                    "{} with radio reports that arrive old ({}): their tracks' rates carry them over the delay, which \
                     feeds each follower's corrections back amplified (METHOD §3, \"Reports brought forward\"); with \
                     plan_forward = true they are brought forward as the mission plan moves",
                    if spec.controller.plan_forward.is_none() {
                        "\"paper\" carries reports by their tracks' rates (plan_forward = false, the paper's prediction)"
                    } else {
                        "false (the paper's prediction)"
                    },
                    if radio.delay_steps > 0 { "radio.delay_s" } else { "radio.relay_navigator" }
                ),
            ));
        }
        warnings.extend(relay_warning);
        if biased && !relative_sensing {
            warnings.push(err(
                "noise.gnss_bias_m",
                "without sensing.relative = true: neighbours are observed where they truly are while each UAV's own \
                 fix carries its bias, so every follower flies off its slot by its own bias (METHOD §8); onboard \
                 sensors measure neighbours relative to the UAV, which sensing.relative models",
            ));
        }
        if spec.controller.radio_fallback.is_some() && !relative_sensing {
            warnings.push(err("controller.radio_fallback", "does nothing without sensing.relative = true"));
        }
        if fixed_wing && formation.frame == proxform_core::FormationFrame::Heading && !wind.is_calm() {
            warnings.push(err(
                "formation.frame",
                "\"heading\" turns the formation with the navigator's nose, which a fixed wing crabs into the wind: \
                 the formation turns with the crab (\"course\", the fixed wing's default, follows its track)",
            ));
        }
        if matches!(setup.vehicle(), VehicleModel::Kinematic(_)) && wind.steady_mps != nalgebra::Vector3::zeros() {
            // METHOD §5: the kinematic vehicle's velocity is over the ground, so only changes of
            // the wind (gusts, turbulence) move it.
            warnings.push(err(
                "wind.steady_kmh",
                "does nothing to the kinematic vehicle (its velocity is over the ground; only gusts and \
                 turbulence move it): fly model = \"multirotor\" or \"fixed_wing\" for a vehicle that flies \
                 through the air",
            ));
        }
        if fixed_wing && !placement.in_slots() {
            // Forming is built and measured for the kinematic vehicle: a fixed wing cannot
            // stop or hover, and turns only by banking (METHOD §8).
            warnings.push(err(
                "initial.placement",
                "the fixed wing does not form from scattered starts by this method (measured: none of 50 runs \
                 formed from an 800 m disc in 80 s); it needs a path to its slot that the method does not plan",
            ));
        }
        let agents = AgentSetup::new(method, navigator, setup, formation, dependencies)
            .map_err(|e| err("controller.method", e.to_string()))?
            .with_schedule(schedule)
            .map_err(|e| err("formation.change", e.to_string()))?;
        let sc = Scenario {
            spec,
            name,
            dt_s,
            duration_s,
            agents: Arc::new(agents),
            path,
            initial,
            placement,
            form_within_s,
            reassign_on_loss,
            noise,
            gnss_bias,
            actuation_error,
            allowable,
            safety_distance_m,
            warmup_s,
            engine,
            dropout,
            reference_dropout,
            relative_sensing,
            faults,
            beacons,
            wind,
            radio,
            network,
            warnings,
        };
        joins_clear_of_the_others(&sc)?;
        Ok(sc)
    }
}

/// Refuses a UAV that joins (`[[fault]] kind = "join"`) closer than the safety distance to
/// where another UAV flies then (its slot in the formation flown at that time): it would
/// appear on top of it.
/// Beyond this many UAVs broadcasting to all, the scenario says what that costs.
const BROADCAST_ALL_SAYS_ABOVE: usize = 1000;

fn joins_clear_of_the_others(sc: &Scenario) -> Result<(), SpecError> {
    use crate::faults::{allows, Fault};
    use std::collections::{BTreeMap, HashMap};
    // The joins by instant: where every UAV flies then is found once per instant, on a grid of
    // cells the size of the safety distance (linear in the UAVs and the joins, whatever their
    // number).
    let mut instants: BTreeMap<u64, Vec<usize>> = BTreeMap::new();
    for (k, f) in sc.faults().iter().enumerate() {
        if let Fault::Join { at_s, .. } = *f {
            instants.entry(at_s.to_bits()).or_default().push(k);
        }
    }
    if instants.is_empty() {
        return Ok(());
    }
    // Each UAV's own faults (those that say when it flies).
    let mut own: Vec<Vec<&Fault>> = vec![Vec::new(); sc.len()];
    for f in sc.faults() {
        if let Some(u) = f.uav().filter(|u| u.index() < sc.len()) {
            own[u.index()].push(f);
        }
    }
    let safety = sc.safety_distance_m();
    let cell = |p: &[f64; 3]| -> [i64; 3] { p.map(|v| (v / safety.max(1e-9)).floor() as i64) };
    for (bits, joins) in instants {
        let at_s = f64::from_bits(bits);
        let formation = sc.formation_at(at_s);
        let nav_slot = &formation.slots[sc.navigator().index()];
        let nav = sc.path().state_at(at_s, [0.0; 3]);
        let at = |i: usize| {
            let s = nav + formation.w(&formation.slots[i], nav_slot, &nav);
            [s[0], s[1], s[2]]
        };
        let mut grid: HashMap<[i64; 3], Vec<(usize, [f64; 3])>> = HashMap::new();
        for (i, faults) in own.iter().enumerate() {
            if faults.iter().all(|f| allows(f, at_s)) {
                let p = at(i);
                grid.entry(cell(&p)).or_default().push((i, p));
            }
        }
        for k in joins {
            let Fault::Join { uav, offset_m, .. } = sc.faults()[k] else { continue };
            let slot = at(uav.index());
            let appears = [slot[0] + offset_m.x, slot[1] + offset_m.y, slot[2] + offset_m.z];
            let c = cell(&appears);
            let near = (-1..=1)
                .flat_map(|dx| (-1..=1).flat_map(move |dy| (-1..=1).map(move |dz| [c[0] + dx, c[1] + dy, c[2] + dz])));
            let closest = near
                .filter_map(|c| grid.get(&c))
                .flatten()
                .filter(|(j, _)| *j != uav.index())
                .map(|(j, p)| {
                    (
                        *j,
                        ((appears[0] - p[0]).powi(2) + (appears[1] - p[1]).powi(2) + (appears[2] - p[2]).powi(2))
                            .sqrt(),
                    )
                })
                .filter(|(_, d)| *d < safety)
                .min_by(|a, b| a.1.total_cmp(&b.1).then(a.0.cmp(&b.0)));
            if let Some((j, d)) = closest {
                return Err(err(
                    format!("fault[{}].offset_m", k + 1),
                    format!(
                        "UAV {} joins at {} s {d:.3} m from where UAV {} flies then (its slot), closer than the \
                         safety distance {} m",
                        uav.0 + 1,
                        show(at_s),
                        j + 1,
                        show(safety)
                    ),
                ));
            }
        }
    }
    Ok(())
}
