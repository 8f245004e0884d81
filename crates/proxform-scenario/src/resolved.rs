//! The checked scenario written back as a spec with every default filled in: what
//! `proxform run --print-scenario` prints, and a file that converts to the same scenario.
//!
//! Units go back to the file's (km/h, degrees) as the shortest decimal that converts back to
//! the same SI value bit for bit, so the printed file runs the same as the scenario. Values
//! that follow other keys stay unset when the file left them so (the reference dropout, the
//! separation and avoidance distances, the isolation gate off the slots, the initial speed): the
//! printed file says each as a comment with its value and the key it follows, and editing the
//! key it follows moves it. Shapes and derived dependency tables are written out (every slot
//! with its `depends_on`); a waypoint path is written as its points.

use std::collections::BTreeMap;

use proxform_core::state::{self, State9};
use proxform_core::{FormationFrame, Method, PredictorKind, VehicleModel};

use crate::faults::Fault;
use crate::path::NavigatorPath;
use crate::scenario::Scenario;
use crate::spec::{
    AllowableSpec, ControllerSpec, FaultSpec, FormationSpec, InitialSpec, NetworkSpec, NoiseSpec, PathSpec, RadioSpec,
    ScenarioSpec, SegmentSpec, SensingSpec, SlotSpec, ThresholdsSpec, VehicleSpec, WindSpec,
};

/// `v` (m/s) in km/h: the shortest decimal that the file format converts back to `v` exactly.
fn kmh(v: f64) -> f64 {
    exact(v, proxform_core::angle::kmh, v * 3.6)
}

/// `v` (rad) in degrees: the shortest decimal that converts back to `v` exactly.
fn deg(v: f64) -> f64 {
    exact(v, proxform_core::angle::deg, v.to_degrees())
}

fn deg3(v: &nalgebra::Vector3<f64>) -> [f64; 3] {
    [deg(v.x), deg(v.y), deg(v.z)]
}

/// A value `y` near `guess` with `to_si(y) == v` bit for bit: the one of fewest significant
/// digits, else the nearest within 64 units in the last place; `guess` when there is none (a
/// computed value may fall between two conversions: every value read from a file has one).
fn exact(v: f64, to_si: fn(f64) -> f64, guess: f64) -> f64 {
    if !v.is_finite() || !guess.is_finite() {
        return guess;
    }
    let same = |y: f64| to_si(y).to_bits() == v.to_bits();
    for digits in 1..=17 {
        if let Ok(y) = format!("{:.*e}", digits - 1, guess).parse::<f64>() {
            if same(y) {
                return y;
            }
        }
    }
    let (mut up, mut down) = (guess, guess);
    for _ in 0..64 {
        up = next_float(up, true);
        down = next_float(down, false);
        for y in [up, down] {
            if same(y) {
                return y;
            }
        }
    }
    guess
}

/// The next float above (`up`) or below a finite `x`.
fn next_float(x: f64, up: bool) -> f64 {
    if x == 0.0 {
        let tiny = f64::from_bits(1);
        return if up { tiny } else { -tiny };
    }
    let bits = x.to_bits();
    // Away from zero is one more in the bits, toward zero one less.
    f64::from_bits(if (x > 0.0) == up { bits + 1 } else { bits - 1 })
}

/// Values left to follow other keys: (section, key, value, what it follows), printed as comments.
type Derived = Vec<(&'static str, &'static str, String, &'static str)>;

/// The spec's own value of a key that follows others, noting the resolved value when unset.
fn follows(
    set: Option<f64>,
    resolved: f64,
    (section, key, why): (&'static str, &'static str, &'static str),
    notes: &mut Derived,
) -> Option<f64> {
    if set.is_none() {
        // Twelve significant digits: a derived value computed in SI need not have a short
        // decimal, and a comment is read, not loaded.
        let shown: f64 = format!("{resolved:.11e}").parse().unwrap_or(resolved);
        notes.push((section, key, format!("{shown:?}"), why));
    }
    set
}

/// [`follows`] for a switch.
fn follows_flag(
    set: Option<bool>,
    resolved: bool,
    (section, key, why): (&'static str, &'static str, &'static str),
    notes: &mut Derived,
) -> Option<bool> {
    if set.is_none() {
        notes.push((section, key, resolved.to_string(), why));
    }
    set
}

/// The scenario as a spec with every key that has a value (keys that follow others only when
/// the file set them).
pub fn resolved(sc: &Scenario) -> ScenarioSpec {
    resolved_with_notes(sc, Slots::All).0
}

/// Which slots the spec holds: all of them, or one marker per list of slots (the formation's,
/// each change's), which [`write_toml`] replaces with the slots written one at a time.
#[derive(Debug, Clone, Copy, PartialEq)]
enum Slots {
    All,
    Marked,
}

/// The id of list `i`'s marker (0: the formation's, then each change's): never a UAV's (ids
/// are at most the UAVs' count, which is below 2^24 for any scenario that loads).
fn marker(i: usize) -> u32 {
    u32::MAX - i as u32
}

fn resolved_with_notes(sc: &Scenario, slots: Slots) -> (ScenarioSpec, Derived) {
    let mut notes = Derived::new();
    let spec = ScenarioSpec {
        name: Some(sc.name().to_string()),
        dt_s: Some(sc.dt_s()),
        duration_s: Some(sc.duration_s()),
        navigator: Some(sc.navigator().0 + 1),
        safety_distance_m: Some(sc.safety_distance_m()),
        warmup_s: Some(sc.warmup_s()),
        engine: Some(sc.engine().name().into()),
        formation: formation(sc, slots),
        path: path(sc),
        initial: initial(sc, &mut notes),
        controller: controller(sc, &mut notes),
        vehicle: vehicle(sc.vehicle()),
        noise: noise(sc),
        sensing: SensingSpec {
            dropout: Some(sc.dropout()),
            reference_dropout: follows(
                sc.reference_dropout_set(),
                sc.reference_dropout(),
                ("sensing", "reference_dropout", "sensing.dropout"),
                &mut notes,
            ),
            relative: Some(sc.relative_sensing()),
        },
        radio: radio(sc, &mut notes),
        network: NetworkSpec { loss: Some(sc.network().loss), delay_s: Some(sc.network().delay_s) },
        wind: wind(sc),
        allowable: allowable(sc, &mut notes),
        fault: sc.faults().iter().map(fault).collect(),
    };
    (spec, notes)
}

/// A scenario that could not be written as TOML.
#[derive(Debug, thiserror::Error)]
pub enum WriteError {
    /// The spec does not serialise.
    #[error(transparent)]
    Toml(#[from] toml::ser::Error),
    /// The writer failed.
    #[error(transparent)]
    Io(#[from] std::io::Error),
}

/// [`resolved`] as TOML text, each value that follows other keys noted as a comment in its
/// section ([`write_toml`] into a string).
pub fn to_toml(sc: &Scenario) -> Result<String, WriteError> {
    let mut out = Vec::new();
    write_toml(sc, &mut out)?;
    String::from_utf8(out).map_err(|e| WriteError::Io(std::io::Error::other(e)))
}

/// Writes [`resolved`] as TOML to `w`, each value that follows other keys noted as a comment
/// in its section. The slots are written one at a time (a swarm of 10^6 UAVs is ~370 MB of
/// them): memory does not grow with the formation, and the text is the `toml` crate's own
/// for the whole spec, byte for byte (test `slots_are_written_as_the_toml_crate_writes_them`).
pub fn write_toml(sc: &Scenario, w: &mut impl std::io::Write) -> Result<(), WriteError> {
    // A follower without main references writes an empty table, which is left to the crate.
    let plain = sc.dependencies().iter().enumerate().all(|(i, d)| i == sc.navigator().index() || !d.refs().is_empty())
        && sc.schedule().stages().iter().all(|s| {
            s.dependencies.iter().enumerate().all(|(i, d)| i == sc.navigator().index() || !d.refs().is_empty())
        });
    let slots = if plain { Slots::Marked } else { Slots::All };
    let (spec, notes) = resolved_with_notes(sc, slots);
    let text = toml::to_string(&spec)?;
    let mut lines = text.lines().peekable();
    while let Some(line) = lines.next() {
        // A marker's table (its header and its id) stands for its list of slots.
        if let (Slots::Marked, Some(table)) = (slots, line.strip_prefix("[[").and_then(|l| l.strip_suffix("]]"))) {
            let list = lines.peek().and_then(|l| l.strip_prefix("id = ")).and_then(|id| id.parse::<u32>().ok());
            if let Some(i) = list.and_then(|id| (0..=sc.schedule().stages().len()).find(|i| marker(*i) == id)) {
                lines.next();
                let (f, deps) = match i {
                    0 => (sc.formation(), sc.dependencies()),
                    _ => {
                        let stage = &sc.schedule().stages()[i - 1];
                        (&stage.formation, &stage.dependencies[..])
                    }
                };
                write_slots(sc, table, f, deps, w)?;
                continue;
            }
        }
        writeln!(w, "{line}")?;
        let section = line.strip_prefix('[').and_then(|l| l.strip_suffix(']'));
        for (_, key, value, why) in notes.iter().filter(|n| Some(n.0) == section) {
            writeln!(w, "# {key} = {value}    # unset: follows {why}")?;
        }
    }
    Ok(())
}

/// The slots of `f` as `[[table]]`s, as the `toml` crate writes [`slot_specs`]'s (the blank line
/// before the first is the marker's).
fn write_slots(
    sc: &Scenario,
    table: &str,
    f: &proxform_core::Formation,
    deps: &[proxform_core::DependencySet],
    w: &mut impl std::io::Write,
) -> std::io::Result<()> {
    let mut keys: Vec<(String, f64)> = Vec::new();
    for (i, (s, d)) in f.slots.iter().zip(deps).enumerate() {
        if i > 0 {
            writeln!(w)?;
        }
        writeln!(w, "[[{table}]]\nid = {}", i + 1)?;
        let o = [s.offset_m.x, s.offset_m.y, s.offset_m.z];
        writeln!(w, "offset_m = [{}, {}, {}]", Float(o[0]), Float(o[1]), Float(o[2]))?;
        let a = deg3(&s.attitude_offset_rad);
        writeln!(w, "attitude_offset_deg = [{}, {}, {}]", Float(a[0]), Float(a[1]), Float(a[2]))?;
        if i != sc.navigator().index() {
            // As a map keyed by the number as text: in the order of the text.
            keys.clear();
            keys.extend(d.refs().iter().map(|(j, c)| ((j.0 + 1).to_string(), *c)));
            keys.sort_by(|x, y| x.0.cmp(&y.0));
            writeln!(w, "\n[{table}.depends_on]")?;
            for (k, c) in &keys {
                writeln!(w, "{k} = {}", Float(*c))?;
            }
        }
    }
    Ok(())
}

/// A float as TOML writes it: `-0.0`, `0.0`, an integral value with `.0`, else Rust's shortest
/// decimal.
struct Float(f64);

impl std::fmt::Display for Float {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let x = self.0;
        match (x.is_sign_negative(), x.is_nan(), x == 0.0) {
            (true, true, _) => f.write_str("-nan"),
            (false, true, _) => f.write_str("nan"),
            (true, false, true) => f.write_str("-0.0"),
            (false, false, true) => f.write_str("0.0"),
            _ if x % 1.0 == 0.0 => write!(f, "{x}.0"),
            _ => write!(f, "{x}"),
        }
    }
}

fn formation(sc: &Scenario, slots: Slots) -> FormationSpec {
    let f = sc.formation();
    let frame = match f.frame {
        FormationFrame::World => "world",
        FormationFrame::Course => "course",
        FormationFrame::Heading => "heading",
    };
    let change = sc
        .schedule()
        .stages()
        .iter()
        .enumerate()
        .map(|(i, s)| crate::spec::FormationChangeSpec {
            at_s: Some(s.at_s),
            slot: match slots {
                Slots::All => slot_specs(sc, &s.formation, &s.dependencies),
                Slots::Marked => vec![SlotSpec { id: Some(marker(i + 1)), ..SlotSpec::default() }],
            },
            shape: None,
            dependencies: None,
        })
        .collect();
    FormationSpec {
        frame: Some(frame.into()),
        reassign_on_loss: Some(sc.reassign_on_loss().is_some()),
        slot: match slots {
            Slots::All => slot_specs(sc, f, sc.dependencies()),
            Slots::Marked => vec![SlotSpec { id: Some(marker(0)), ..SlotSpec::default() }],
        },
        shape: None,
        dependencies: None,
        change,
    }
}

fn slot_specs(sc: &Scenario, f: &proxform_core::Formation, deps: &[proxform_core::DependencySet]) -> Vec<SlotSpec> {
    f.slots
        .iter()
        .zip(deps)
        .enumerate()
        .map(|(i, (s, d))| SlotSpec {
            id: Some(i as u32 + 1),
            offset_m: Some([s.offset_m.x, s.offset_m.y, s.offset_m.z]),
            attitude_offset_deg: Some(deg3(&s.attitude_offset_rad)),
            depends_on: (i != sc.navigator().index())
                .then(|| d.refs().iter().map(|(j, c)| ((j.0 + 1).to_string(), *c)).collect::<BTreeMap<_, _>>()),
        })
        .collect()
}

fn path(sc: &Scenario) -> PathSpec {
    let (p, set) = (sc.path(), &sc.spec.path);
    match p {
        // A waypoint path as the file wrote it (its turns and ramps follow the points).
        NavigatorPath::Segments(p) if set.kind.as_deref() == Some("waypoints") => PathSpec {
            kind: set.kind.clone(),
            points_m: set.points_m.clone(),
            turn_radius_m: set.turn_radius_m,
            leg_speeds_kmh: set.leg_speeds_kmh.clone(),
            speed_kmh: set.speed_kmh,
            transition_s: Some(p.transition_s),
            ..PathSpec::default()
        },
        NavigatorPath::Paper(p) => PathSpec {
            kind: Some("paper".into()),
            height_amplitude_m: Some(p.height_amplitude_m),
            pitch_swing_deg: Some(deg(p.pitch_swing_rad)),
            yaw_amplitude_deg: Some(deg(p.yaw_amplitude_rad)),
            roll_amplitude_deg: Some(deg(p.roll_amplitude_rad)),
            lead_in_s: (p.lead_in_s > 0.0).then_some(p.lead_in_s),
            ..PathSpec::default()
        },
        NavigatorPath::Segments(p) => PathSpec {
            kind: Some("segments".into()),
            speed_kmh: Some(kmh(p.start_speed_mps)),
            course_deg: Some(deg(p.start_course_rad)),
            transition_s: Some(p.transition_s),
            segment: p
                .segments
                .iter()
                .map(|s| SegmentSpec {
                    duration_s: Some(s.duration_s),
                    turn_rate_deg_s: Some(deg(s.turn_rate_radps)),
                    climb_kmh: Some(kmh(s.climb_mps)),
                    speed_kmh: Some(kmh(s.end_speed_mps)),
                })
                .collect(),
            ..PathSpec::default()
        },
    }
}

fn controller(sc: &Scenario, notes: &mut Derived) -> ControllerSpec {
    let p = sc.controller();
    let set = &sc.spec.controller;
    let d: &State9 = &p.envelope.thresholds;
    let (predictor, alpha, beta, singer) = match p.predictor {
        PredictorKind::ConstantVelocity => ("constant_velocity", None, None, None),
        PredictorKind::AlphaBeta { alpha, beta } => ("alpha_beta", Some(alpha), Some(beta), None),
        PredictorKind::Singer { accel_sigma_mps2, tau_s, alpha, beta, .. } => {
            ("singer", Some(alpha), Some(beta), Some((accel_sigma_mps2, tau_s)))
        }
    };
    let method = sc.method();
    let gains = match method {
        Method::Proximity => None,
        Method::LeaderFollower(g) => toml::Table::try_from(g).ok(),
        Method::Consensus(g) => toml::Table::try_from(g).ok(),
        Method::Flocking(g) => toml::Table::try_from(g).ok(),
    };
    ControllerSpec {
        areas: Some(p.areas.areas as i64),
        sensing_range_m: Some(p.areas.sensing_range_m),
        lambda: Some(p.lambda),
        rho: Some(p.envelope.rho),
        closing_time_s: Some(p.closing_time_s.unwrap_or(0.0)),
        input_weight: Some(p.input_weight),
        predictor: Some(predictor.into()),
        predictor_alpha: alpha,
        predictor_beta: beta,
        predictor_accel_sigma_mps2: singer.map(|s| s.0),
        predictor_tau_s: singer.map(|s| s.1),
        track_timeout_s: Some(p.track_timeout_s),
        relay_max_age_s: Some(p.relay_max_age_s),
        coast_s: Some(p.coast_s),
        coast_accel_s: Some(p.coast_accel_s),
        coast_decay_s: Some(p.coast_decay_s),
        turn_feedforward: Some(p.turn_feedforward),
        plan_forward: Some(p.plan_forward),
        radio_fallback: follows_flag(
            set.radio_fallback,
            p.radio_fallback,
            ("controller", "radio_fallback", "sensing.relative and noise.gnss_bias_m"),
            notes,
        ),
        stop_closing: Some(p.stop_closing),
        own_filter_gain: Some(p.own_filter_gain),
        separation_m: follows(
            set.separation_m,
            p.separation_m.unwrap_or(0.0),
            ("controller", "separation_m", "safety_distance_m"),
            notes,
        ),
        avoid_m: follows(
            set.avoid_m,
            p.avoid_m.unwrap_or(0.0),
            ("controller", "avoid_m", "safety_distance_m and vehicle.model"),
            notes,
        ),
        horizon: Some(i64::from(p.horizon)),
        isolation_gate: follows(
            set.isolation_gate,
            p.isolation_gate.unwrap_or(0.0),
            ("controller", "isolation_gate", "the method"),
            notes,
        ),
        own_gate_m: follows(
            set.own_gate_m,
            p.own_gate_m.unwrap_or(0.0),
            ("controller", "own_gate_m", "the method and the position noise"),
            notes,
        ),
        own_gate_growth_mps: match p.own_gate_m {
            // Derived from the turbulence unless the file sets it: it stays derived.
            Some(_) => follows(
                set.own_gate_growth_mps,
                p.own_gate_growth_mps,
                ("controller", "own_gate_growth_mps", "wind.turbulence"),
                notes,
            ),
            None => set.own_gate_growth_mps,
        },
        method: Some(if crate::convert::paper_method(set) { crate::convert::PAPER } else { method.label() }.into()),
        gains,
        thresholds: Some(ThresholdsSpec {
            x_m: Some(d[state::X]),
            y_m: Some(d[state::Y]),
            z_m: Some(d[state::Z]),
            vx_kmh: Some(kmh(d[state::VX])),
            vy_kmh: Some(kmh(d[state::VY])),
            vz_kmh: Some(kmh(d[state::VZ])),
            alpha_deg: Some(deg(d[state::ALPHA])),
            beta_deg: Some(deg(d[state::BETA])),
            gamma_deg: Some(deg(d[state::GAMMA])),
        }),
    }
}

fn vehicle(v: &VehicleModel) -> VehicleSpec {
    match v {
        VehicleModel::Kinematic(m) => {
            let l = &m.limits;
            VehicleSpec {
                model: Some("kinematic".into()),
                vx_min_kmh: Some(kmh(l.vx_min_mps)),
                vx_max_kmh: Some(kmh(l.vx_max_mps)),
                vy_max_kmh: Some(kmh(l.vy_max_mps)),
                vz_max_kmh: Some(kmh(l.vz_max_mps)),
                attitude_max_deg: Some(deg3(&l.attitude_max_rad)),
                accel_kmh_s: Some([kmh(l.accel_max_mps2.x), kmh(l.accel_max_mps2.y), kmh(l.accel_max_mps2.z)]),
                attitude_rate_deg_s: Some(deg3(&l.attitude_rate_max_radps)),
                ..VehicleSpec::default()
            }
        }
        VehicleModel::FixedWing(m) => VehicleSpec {
            model: Some("fixed_wing".into()),
            stall_speed_kmh: Some(kmh(m.stall_speed_mps)),
            max_speed_kmh: Some(kmh(m.max_speed_mps)),
            bank_max_deg: Some(deg(m.bank_max_rad)),
            load_factor_max: Some(m.load_factor_max),
            pitch_max_deg: Some(deg(m.pitch_max_rad)),
            roll_rate_max_deg_s: Some(deg(m.roll_rate_max_radps)),
            pitch_rate_max_deg_s: Some(deg(m.pitch_rate_max_radps)),
            yaw_rate_max_deg_s: Some(deg(m.yaw_rate_max_radps)),
            throttle_accel_kmh_s: Some(kmh(m.accel_max_mps2)),
            ..VehicleSpec::default()
        },
        VehicleModel::Multirotor(m) => VehicleSpec {
            model: Some("multirotor".into()),
            max_speed_kmh: Some(kmh(m.max_speed_mps)),
            climb_max_kmh: Some(kmh(m.climb_max_mps)),
            descent_max_kmh: Some(kmh(m.descent_max_mps)),
            accel_max_mps2: Some(m.accel_max_mps2),
            vertical_accel_max_mps2: Some(m.vertical_accel_max_mps2),
            tilt_max_deg: Some(deg(m.tilt_max_rad)),
            thrust_to_weight: Some(m.thrust_to_weight),
            yaw_rate_max_deg_s: Some(deg(m.yaw_rate_max_radps)),
            velocity_time_constant_s: Some(m.velocity_time_constant_s),
            attitude_time_constant_s: Some(m.attitude_time_constant_s),
            yaw_time_constant_s: Some(m.yaw_time_constant_s),
            drag_linear_per_s: Some(m.drag_linear_per_s),
            drag_quadratic_per_m: Some(m.drag_quadratic_per_m),
            ..VehicleSpec::default()
        },
    }
}

fn noise(sc: &Scenario) -> NoiseSpec {
    let n = sc.noise();
    NoiseSpec {
        position_m: Some(n.position_m),
        velocity_kmh: Some(kmh(n.velocity_mps)),
        attitude_deg: Some(deg(n.attitude_rad)),
        actuation_error: Some(sc.actuation_error()),
        scale: None,
        gnss_bias_m: sc.gnss_bias().map(|g| g.sigma_m),
        gnss_tau_s: sc.gnss_bias().map(|g| g.tau_s),
    }
}

fn initial(sc: &Scenario, notes: &mut Derived) -> InitialSpec {
    use crate::placement::Placement;
    let speed_kmh = follows(
        sc.spec.initial.speed_kmh,
        kmh(sc.vehicle().forward_speed(&sc.initial()[sc.navigator().index()])),
        ("initial", "speed_kmh", "the navigator's path"),
        notes,
    );
    let assign_by = sc
        .reassign_on_loss()
        .or(match sc.placement() {
            Placement::Box { assign, .. } | Placement::Disc { assign, .. } | Placement::Row { assign, .. } => *assign,
            _ => None,
        })
        .map(|by| by.label().to_string());
    let base = InitialSpec { speed_kmh, form_within_s: sc.form_within_s(), assign_by, ..InitialSpec::default() };
    match sc.placement() {
        Placement::Slots => InitialSpec { placement: Some("slots".into()), ..base },
        Placement::Box { size_m, assign } => InitialSpec {
            placement: Some("box".into()),
            box_m: Some(*size_m),
            assign_slots: Some(assign.is_some()),
            ..base
        },
        Placement::Disc { radius_m, height_m, assign } => InitialSpec {
            placement: Some("disc".into()),
            radius_m: Some(*radius_m),
            height_m: Some(*height_m),
            assign_slots: Some(assign.is_some()),
            ..base
        },
        Placement::Row { spacing_m, below_m, assign } => InitialSpec {
            placement: Some("row".into()),
            row_spacing_m: Some(*spacing_m),
            ground_below_m: Some(*below_m),
            assign_slots: Some(assign.is_some()),
            ..base
        },
        Placement::Explicit(list) => InitialSpec {
            placement: Some("explicit".into()),
            uavs: list
                .iter()
                .map(|(id, p)| crate::spec::InitialUavSpec { id: Some(id.0 + 1), position_m: Some(*p) })
                .collect(),
            ..base
        },
    }
}

fn radio(sc: &Scenario, notes: &mut Derived) -> RadioSpec {
    let r = sc.radio();
    RadioSpec {
        beacons: Some(sc.beacons().iter().map(|b| b.0 + 1).collect()),
        broadcast_all: Some(r.broadcast_all),
        range_m: r.range_m.is_finite().then_some(r.range_m),
        delay_s: Some(f64::from(r.delay_steps) * sc.dt_s()),
        loss: Some(r.loss),
        burst_p_good_to_bad: r.burst.map(|b| b.p_good_to_bad),
        burst_p_bad_to_good: r.burst.map(|b| b.p_bad_to_good),
        burst_loss_bad: r.burst.map(|b| b.loss_bad),
        relay_navigator: follows_flag(
            sc.spec.radio.relay_navigator,
            r.relay_navigator,
            ("radio", "relay_navigator", "sensing.relative, noise.gnss_bias_m and the formation's depth"),
            notes,
        ),
    }
}

fn wind(sc: &Scenario) -> WindSpec {
    use crate::wind::Severity;
    let w = sc.wind();
    let s = w.steady_mps;
    WindSpec {
        steady_kmh: Some([kmh(s.x), kmh(s.y), kmh(s.z)]),
        turbulence: Some(
            match w.turbulence.map(|t| t.severity) {
                None => "none",
                Some(Severity::Light) => "light",
                Some(Severity::Moderate) => "moderate",
                Some(Severity::Severe) => "severe",
            }
            .into(),
        ),
        altitude_m: w.turbulence.map(|t| t.altitude_m),
        gust_at_s: w.gust.map(|g| g.at_s),
        gust_duration_s: w.gust.map(|g| g.duration_s),
        gust_peak_kmh: w.gust.map(|g| [kmh(g.peak_mps.x), kmh(g.peak_mps.y), kmh(g.peak_mps.z)]),
    }
}

fn allowable(sc: &Scenario, notes: &mut Derived) -> AllowableSpec {
    let a = sc.allowable();
    AllowableSpec {
        path_m: follows(
            sc.spec.allowable.path_m,
            a.path_m,
            ("allowable", "path_m", "ten times the largest allowable position error"),
            notes,
        ),
        x_m: Some(a.position_m[0]),
        y_m: Some(a.position_m[1]),
        z_m: Some(a.position_m[2]),
        alpha_deg: Some(deg(a.attitude_rad[0])),
        beta_deg: Some(deg(a.attitude_rad[1])),
        gamma_deg: Some(deg(a.attitude_rad[2])),
    }
}

fn fault(f: &Fault) -> FaultSpec {
    let o = |v: &nalgebra::Vector3<f64>| Some([v.x, v.y, v.z]);
    match f {
        Fault::Remove { uav, at_s } => FaultSpec::remove(uav.0 + 1, *at_s),
        Fault::Join { uav, at_s, offset_m } => FaultSpec {
            kind: Some("join".into()),
            uav: Some(uav.0 + 1),
            at_s: Some(*at_s),
            offset_m: o(offset_m),
            ..FaultSpec::default()
        },
        Fault::Glitch { uav, at_s, duration_s, offset_m } => FaultSpec {
            kind: Some("glitch".into()),
            uav: Some(uav.0 + 1),
            at_s: Some(*at_s),
            duration_s: Some(*duration_s),
            offset_m: o(offset_m),
        },
        Fault::StuckSensor { uav, at_s, duration_s } => FaultSpec {
            kind: Some("stuck_sensor".into()),
            uav: Some(uav.0 + 1),
            at_s: Some(*at_s),
            duration_s: Some(*duration_s),
            ..FaultSpec::default()
        },
        Fault::RadioBlackout { at_s, duration_s } => FaultSpec::radio_blackout(*at_s, *duration_s),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::builtin;

    /// Relative closeness of two floats (unit conversions may change the last bits).
    fn close(a: f64, b: f64) -> bool {
        (a - b).abs() <= 1e-9 * a.abs().max(b.abs()).max(1e-9)
    }

    #[test]
    fn units_are_written_as_the_shortest_decimals_that_convert_back_exactly() {
        // 90 km/h is 25 m/s; 25 m/s times 3.6 is 90.00000000000001.
        assert_eq!(kmh(proxform_core::angle::kmh(90.0)), 90.0);
        let mut rng = 0x9E37_79B9_7F4A_7C15u64;
        for _ in 0..20_000 {
            rng = rng.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
            let u = (rng >> 11) as f64 / (1u64 << 53) as f64;
            // Values read from a file (km/h, degrees) come back exactly.
            let x = ((u - 0.5) * 1e6).round() / 1e3;
            let v = proxform_core::angle::kmh(x);
            assert_eq!(proxform_core::angle::kmh(kmh(v)).to_bits(), v.to_bits(), "{x} km/h");
            let a = proxform_core::angle::deg(x / 10.0);
            assert_eq!(proxform_core::angle::deg(deg(a)).to_bits(), a.to_bits(), "{} deg", x / 10.0);
            // Any other value (computed, not read) may have no exact decimal: within an ulp.
            let w = (u - 0.5) * 1e3;
            assert!((proxform_core::angle::kmh(kmh(w)) - w).abs() <= 2.0 * f64::EPSILON * w.abs(), "{w} m/s");
        }
        assert_eq!((next_float(1.0, true), next_float(-1.0, false)), (1.0 + f64::EPSILON, -1.0 - f64::EPSILON));
    }

    #[test]
    fn the_resolved_spec_converts_back_to_the_same_scenario() {
        for text in [builtin::PAPER, builtin::FIXED_WING_V, builtin::EXAMPLE] {
            let sc = crate::load::parse(text, "test.toml").expect("valid");
            let printed = to_toml(&sc).expect("serialises");
            let again = crate::load::parse(&printed, "printed.toml").expect("the printed scenario loads");
            assert_eq!(again.len(), sc.len());
            assert_eq!(again.formation().slots, sc.formation().slots);
            assert_eq!(again.dependencies(), sc.dependencies());
            assert_eq!(again.method(), sc.method());
            let (p, q) = (sc.controller(), again.controller());
            assert_eq!((p.areas, p.horizon, p.predictor), (q.areas, q.horizon, q.predictor));
            for k in 0..9 {
                assert!(close(p.envelope.thresholds[k], q.envelope.thresholds[k]), "threshold {k}");
            }
            assert!(close(p.separation_m.unwrap_or(0.0), q.separation_m.unwrap_or(0.0)));
            assert!(close(p.avoid_m.unwrap_or(0.0), q.avoid_m.unwrap_or(0.0)));
            for (a, b) in sc.initial().iter().zip(again.initial()) {
                for k in 0..9 {
                    assert!(close(a[k], b[k]), "initial state {k}: {} vs {}", a[k], b[k]);
                }
            }
            for t in [0.0, 17.3, 55.0] {
                let (a, b) = (sc.path().state_at(t, [0.0; 3]), again.path().state_at(t, [0.0; 3]));
                for k in 0..9 {
                    assert!((a[k] - b[k]).abs() < 1e-6, "path at {t} s, component {k}");
                }
            }
            // Printing is a fixed point: nothing is left to resolve.
            let twice = to_toml(&again).expect("serialises");
            assert_eq!(printed.lines().count(), twice.lines().count());
        }
    }

    #[test]
    fn switches_that_follow_other_keys_stay_derived_when_printed() {
        // A deep V with biased fixes and relative sensing: the relays and the radio fallback
        // follow the bias. Printed, they are comments; the printed file without its bias
        // turns both off, as the original would.
        let text = "name = \"deep\"\n[formation.shape]\nkind = \"v\"\nuavs = 12\nspacing_m = 80.0\n\
                    [noise]\ngnss_bias_m = 3.0\n[sensing]\nrelative = true\n";
        let sc = crate::load::parse(text, "deep.toml").expect("valid");
        assert!(sc.radio().relay_navigator && sc.controller().radio_fallback);
        let printed = to_toml(&sc).expect("serialises");
        for key in ["relay_navigator", "radio_fallback"] {
            assert!(printed.contains(&format!("# {key} = true    # unset: follows")), "{key}: {printed}");
            assert!(!printed.lines().any(|l| l.starts_with(&format!("{key} ="))), "{key} written as a value");
        }
        let unbiased = printed.replace("gnss_bias_m = 3.0", "gnss_bias_m = 0.0");
        let again = crate::load::parse(&unbiased, "printed.toml").expect("loads");
        assert!(!again.radio().relay_navigator && !again.controller().radio_fallback);
        // Set in the file, they are written as set.
        let set = format!("{text}[radio]\nrelay_navigator = false\n");
        let printed = to_toml(&crate::load::parse(&set, "set.toml").expect("valid")).expect("serialises");
        assert!(printed.lines().any(|l| l == "relay_navigator = false"), "{printed}");
    }

    /// The text the `toml` crate writes for the whole spec with every slot in it (as
    /// [`to_toml`] wrote it before the slots were written one at a time).
    fn whole(sc: &Scenario) -> String {
        let (spec, notes) = resolved_with_notes(sc, Slots::All);
        let mut out = String::new();
        for line in toml::to_string(&spec).expect("serialises").lines() {
            out.push_str(line);
            out.push('\n');
            let section = line.strip_prefix('[').and_then(|l| l.strip_suffix(']'));
            for (_, key, value, why) in notes.iter().filter(|n| Some(n.0) == section) {
                out.push_str(&format!("# {key} = {value}    # unset: follows {why}\n"));
            }
        }
        out
    }

    #[test]
    fn slots_are_written_as_the_toml_crate_writes_them() {
        // Every shipped scenario (the comparison files, of conditions, are not scenarios).
        let mut files: Vec<(String, String)> = [
            ("aggregate", include_str!("../../../scenarios/aggregate.toml")),
            ("change-v-column", include_str!("../../../scenarios/change-v-column.toml")),
            ("depth-diamond9", include_str!("../../../scenarios/depth-diamond9.toml")),
            ("depth-v20", include_str!("../../../scenarios/depth-v20.toml")),
            ("example", include_str!("../../../scenarios/example.toml")),
            ("fault-triangle10", include_str!("../../../scenarios/fault-triangle10.toml")),
            ("fixed-wing-echelon7-crosswind", include_str!("../../../scenarios/fixed-wing-echelon7-crosswind.toml")),
            ("fixed-wing-v", include_str!("../../../scenarios/fixed-wing-v.toml")),
            ("multirotor-lattice50-eight", include_str!("../../../scenarios/multirotor-lattice50-eight.toml")),
            ("multirotor-v12-circuit", include_str!("../../../scenarios/multirotor-v12-circuit.toml")),
            ("paper-dropout30-navigator", include_str!("../../../scenarios/paper-dropout30-navigator.toml")),
            ("paper-dropout30-tracked", include_str!("../../../scenarios/paper-dropout30-tracked.toml")),
            ("paper-dropout30", include_str!("../../../scenarios/paper-dropout30.toml")),
            ("paper-navigator-lost", include_str!("../../../scenarios/paper-navigator-lost.toml")),
            ("paper-remove-uav2", include_str!("../../../scenarios/paper-remove-uav2.toml")),
            ("paper-robust-loss30", include_str!("../../../scenarios/paper-robust-loss30.toml")),
            ("paper", include_str!("../../../scenarios/paper.toml")),
            ("reassign-v-loss", include_str!("../../../scenarios/reassign-v-loss.toml")),
            ("swarm", include_str!("../../../scenarios/swarm.toml")),
            ("takeoff-lattice100", include_str!("../../../scenarios/takeoff-lattice100.toml")),
        ]
        .iter()
        .map(|(name, text)| (name.to_string(), text.to_string()))
        .collect();
        // Explicit slots: ids past 9 (their references sort as text), attitude offsets,
        // negative zeros, long decimals; and two changes of formation.
        let mut explicit = String::from("name = \"explicit\"\nnavigator = 1\n");
        for i in 1..=12u32 {
            let f = f64::from(i);
            explicit.push_str(&format!(
                "[[formation.slot]]\nid = {i}\noffset_m = [{}, {}, -0.0]\nattitude_offset_deg = [0.0, {}, 1e-7]\n",
                -60.0 * f,
                (f * 0.1 + 1.0 / 3.0) * if i % 2 == 0 { 1.0 } else { -1.0 },
                f * 0.7
            ));
            if i > 1 {
                explicit.push_str(&format!("[formation.slot.depends_on]\n1 = 0.3\n{} = 0.7\n", (i + 5) % 11 + 2));
            }
        }
        explicit.push_str(
            "[[formation.change]]\nat_s = 20.0\n[formation.change.shape]\nkind = \"column\"\nuavs = 12\nspacing_m = 60.0\n\
             [[formation.change]]\nat_s = 40.0\n[formation.change.shape]\nkind = \"circle\"\nuavs = 12\nspacing_m = 150.0\n",
        );
        files.push(("explicit".into(), explicit));
        let mut scenarios: Vec<(String, Scenario)> = files
            .iter()
            .map(|(name, text)| {
                (name.clone(), crate::load::parse(text, name).unwrap_or_else(|e| panic!("{name}: {e}")))
            })
            .collect();
        for (name, uavs) in [("swarm", Some(300)), ("paper", None)] {
            let spec = builtin::spec_by_name(name, uavs).expect("built in");
            scenarios.push((name.into(), Scenario::try_from(spec).expect("valid")));
        }
        let changes = scenarios.iter().filter(|(_, sc)| !sc.schedule().is_empty()).count();
        assert!(changes >= 2, "{changes} scenarios change formation");
        for (name, sc) in &scenarios {
            let streamed = to_toml(sc).expect("written");
            assert!(!streamed.contains(&marker(0).to_string()), "{name}: a marker left");
            assert!(streamed == whole(sc), "{name}: the streamed text differs from the toml crate's");
        }
    }
}
