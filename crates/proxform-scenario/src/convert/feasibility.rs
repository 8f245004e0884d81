//! Whether the scenario can be flown at all: slots apart by the safety distance, initial
//! speeds within the vehicle's range, and a navigator path within the followers' limits.

use proxform_core::angle::{kmh, wrap_pi};
use proxform_core::grid::NeighbourGrid;
use proxform_core::state::{self, State9};
use proxform_core::vehicle::G;
use proxform_core::{Formation, FormationSlot, UavId, VehicleModel};

use super::values::{err, positive, SpecError};
use crate::path::NavigatorPath;
use crate::scenario::in_slots;
use crate::spec::ScenarioSpec;

/// Refuses slots closer than the safety distance.
pub fn separated(slots: &[FormationSlot], safety_distance_m: f64) -> Result<(), SpecError> {
    match closest_pair_within(slots, safety_distance_m) {
        Some((a, b, d)) => Err(err(
            "formation",
            format!(
                "UAVs {} and {} are {d:.1} m apart, closer than the safety distance {} m",
                a + 1,
                b + 1,
                safety_distance_m
            ),
        )),
        None => Ok(()),
    }
}

/// Every UAV in its slot on the navigator's initial state (at `initial.speed_kmh` when set),
/// refused when a speed is outside the vehicle's range or a state is not finite.
pub fn initial_states(
    spec: &ScenarioSpec,
    formation: &Formation,
    navigator: UavId,
    path: &NavigatorPath,
    vehicle: &VehicleModel,
) -> Result<Vec<State9>, SpecError> {
    let nav0 = path.state_at(0.0, [0.0; 3]);
    let speed = match spec.initial.speed_kmh {
        Some(v) => Some(kmh(super::values::speed_kmh("initial.speed_kmh", positive("initial.speed_kmh", v)?)?)),
        None => None,
    };
    let mut initial = in_slots(formation, navigator, &nav0);
    if let Some(v) = speed {
        let h = nav0[state::VX].hypot(nav0[state::VY]).max(1e-9);
        for x in &mut initial {
            x[state::VX] = v * nav0[state::VX] / h;
            x[state::VY] = v * nav0[state::VY] / h;
        }
    }
    let (vmin, vmax) = vehicle.forward_speed_range();
    let kinematic = matches!(vehicle, VehicleModel::Kinematic(_));
    for (i, x) in initial.iter().enumerate() {
        let v = vehicle.forward_speed(x);
        if v < vmin - 1e-9 || v > vmax + 1e-9 {
            // Blame the key that set the speed: the initial speed, the path's, or the
            // vehicle's bound for the paper's fixed-speed path.
            let path_speed = spec.path.speed_kmh.is_some();
            // A waypoints path whose first leg heads back along −x starts the kinematic vehicle
            // at a negative vx: the points, not the speed, are what to change.
            let backwards = kinematic && spec.path.points_m.is_some() && x[state::VX] < 0.0;
            let key = match (speed.is_some(), path_speed, kinematic, v < vmin) {
                _ if backwards => "path.points_m[2]",
                (true, ..) => "initial.speed_kmh",
                (false, true, ..) => "path.speed_kmh",
                (false, false, true, true) => "vehicle.vx_min_kmh",
                (false, false, true, false) => "vehicle.vx_max_kmh",
                (false, false, false, true) => "vehicle.stall_speed_kmh",
                (false, false, false, false) => "vehicle.max_speed_kmh",
            };
            let what = match vehicle {
                VehicleModel::Kinematic(_) => "vx",
                VehicleModel::FixedWing(_) => "airspeed",
                VehicleModel::Multirotor(_) => "horizontal speed",
            };
            let along_x = x[state::VY].abs() <= 1e-9 * x[state::VX].abs().max(1.0);
            let hint = if backwards {
                " (the first leg heads back along -x: the kinematic vehicle flies forward along x, so a \
                 waypoints path starts along +x; turn the points around or start from the other end)"
            } else if kinematic && !along_x {
                " (the kinematic vehicle's limits are on vx, the world x component of its velocity: \
                 its paths start along x)"
            } else {
                ""
            };
            return Err(err(
                key,
                format!(
                    "UAV {} starts at {what} {:.1} km/h, outside the vehicle's {:.1}-{:.1} km/h{hint}",
                    i + 1,
                    v * 3.6,
                    vmin * 3.6,
                    vmax * 3.6
                ),
            ));
        }
    }
    if let Some(i) = initial.iter().position(|x| !state::is_finite(x)) {
        return Err(err("formation", format!("UAV {}'s initial state is not finite (an offset too large?)", i + 1)));
    }
    Ok(initial)
}

/// The first pair of slots (in index order) closer than `limit`, found with the grid.
fn closest_pair_within(slots: &[FormationSlot], limit: f64) -> Option<(usize, usize, f64)> {
    let mut grid = NeighbourGrid::new();
    grid.rebuild(slots.iter().map(|s| [s.offset_m.x, s.offset_m.y, s.offset_m.z]), limit);
    let mut found: Option<(usize, usize, f64)> = None;
    for (a, s) in slots.iter().enumerate() {
        grid.for_each_within([s.offset_m.x, s.offset_m.y, s.offset_m.z], limit, |b, _, d2| {
            let b = b as usize;
            let d = d2.sqrt();
            if b > a && d < limit && found.is_none_or(|f| (a, b) < (f.0, f.1)) {
                found = Some((a, b, d));
            }
        });
        if found.is_some() {
            break;
        }
    }
    found
}

/// One limit of the followers' vehicle, on the navigator's state or on its rate of change.
struct Limit {
    /// The key of `[vehicle]` that sets it.
    key: &'static str,
    /// What it bounds, in words.
    what: &'static str,
    /// The bound (SI).
    bound: f64,
    /// True for a lower bound.
    below: bool,
    /// True when the value is a rate of change (needs two instants).
    rate: bool,
    /// Report units per SI unit (3.6 for km/h, degrees per radian), and the unit.
    scale: f64,
    unit: &'static str,
    /// The value from (previous state, state, seconds between them).
    value: Reading,
}

/// Reads a value from (previous state, state, seconds between them).
type Reading = Box<dyn Fn(&State9, &State9, f64) -> f64>;

const DEG: f64 = 180.0 / std::f64::consts::PI;

fn airspeed(x: &State9) -> f64 {
    (x[state::VX] * x[state::VX] + x[state::VY] * x[state::VY] + x[state::VZ] * x[state::VZ]).sqrt()
}

fn limits(vehicle: &VehicleModel) -> Vec<Limit> {
    let of = |k: usize| move |_: &State9, x: &State9, _: f64| x[k];
    // An angle's size (wrapped), a speed's (not: a speed is no angle).
    let abs = |k: usize| move |_: &State9, x: &State9, _: f64| wrap_pi(x[k]).abs();
    let size = |k: usize| move |_: &State9, x: &State9, _: f64| x[k].abs();
    let rate = |k: usize| move |a: &State9, b: &State9, h: f64| (wrap_pi(b[k] - a[k]) / h).abs();
    let accel = |k: usize| move |a: &State9, b: &State9, h: f64| ((b[k] - a[k]) / h).abs();
    let kmh = (3.6, " km/h");
    let kmh_s = (3.6, " km/h per s");
    let degrees = (DEG, "°");
    let deg_s = (DEG, "°/s");
    let limit = |key, what, bound, below, rate, (scale, unit): (f64, &'static str), value: Reading| Limit {
        key,
        what,
        bound,
        below,
        rate,
        scale,
        unit,
        value,
    };
    match vehicle {
        VehicleModel::Kinematic(m) => {
            let l = &m.limits;
            let mut out = vec![
                limit("vx_min_kmh", "vx", l.vx_min_mps, true, false, kmh, Box::new(of(state::VX))),
                limit("vx_max_kmh", "vx", l.vx_max_mps, false, false, kmh, Box::new(of(state::VX))),
                limit("vy_max_kmh", "|vy|", l.vy_max_mps, false, false, kmh, Box::new(size(state::VY))),
                limit("vz_max_kmh", "|vz|", l.vz_max_mps, false, false, kmh, Box::new(size(state::VZ))),
            ];
            const ANGLE: [&str; 3] = ["attitude_max_deg[1]", "attitude_max_deg[2]", "attitude_max_deg[3]"];
            const RATE: [&str; 3] = ["attitude_rate_deg_s[1]", "attitude_rate_deg_s[2]", "attitude_rate_deg_s[3]"];
            const ACCEL: [&str; 3] = ["accel_kmh_s[1]", "accel_kmh_s[2]", "accel_kmh_s[3]"];
            for a in 0..3 {
                let k = state::ALPHA + a;
                let (angle, rate_of, change) = (
                    ["|pitch|", "|yaw|", "|roll|"][a],
                    ["pitch rate", "yaw rate", "roll rate"][a],
                    ["change of vx", "change of vy", "change of vz"][a],
                );
                out.push(limit(ANGLE[a], angle, l.attitude_max_rad[a], false, false, degrees, Box::new(abs(k))));
                out.push(limit(RATE[a], rate_of, l.attitude_rate_max_radps[a], false, true, deg_s, Box::new(rate(k))));
                out.push(limit(
                    ACCEL[a],
                    change,
                    l.accel_max_mps2[a],
                    false,
                    true,
                    kmh_s,
                    Box::new(accel(state::VX + a)),
                ));
            }
            out
        }
        VehicleModel::FixedWing(m) => vec![
            limit("stall_speed_kmh", "airspeed", m.stall_speed_mps, true, false, kmh, Box::new(|_, x, _| airspeed(x))),
            limit("max_speed_kmh", "airspeed", m.max_speed_mps, false, false, kmh, Box::new(|_, x, _| airspeed(x))),
            limit("bank_max_deg", "|bank|", m.bank_max_rad, false, false, degrees, Box::new(abs(state::GAMMA))),
            limit("pitch_max_deg", "|pitch|", m.pitch_max_rad, false, false, degrees, Box::new(abs(state::ALPHA))),
            limit(
                "roll_rate_max_deg_s",
                "roll rate",
                m.roll_rate_max_radps,
                false,
                true,
                deg_s,
                Box::new(rate(state::GAMMA)),
            ),
            limit(
                "pitch_rate_max_deg_s",
                "pitch rate",
                m.pitch_rate_max_radps,
                false,
                true,
                deg_s,
                Box::new(rate(state::ALPHA)),
            ),
            limit(
                "throttle_accel_kmh_s",
                "change of airspeed",
                m.accel_max_mps2,
                false,
                true,
                kmh_s,
                Box::new(|a, b, h| ((airspeed(b) - airspeed(a)) / h).abs()),
            ),
        ],
        VehicleModel::Multirotor(m) => vec![
            limit(
                "max_speed_kmh",
                "horizontal speed",
                m.max_speed_mps,
                false,
                false,
                kmh,
                Box::new(|_, x, _| ground(x)),
            ),
            limit("climb_max_kmh", "climb rate", m.climb_max_mps, false, false, kmh, Box::new(of(state::VZ))),
            limit(
                "descent_max_kmh",
                "descent rate",
                m.descent_max_mps,
                false,
                false,
                kmh,
                Box::new(|_, x: &State9, _| -x[state::VZ]),
            ),
            limit(
                "accel_max_mps2",
                "horizontal acceleration",
                m.accel_max_mps2,
                false,
                true,
                (1.0, " m/s²"),
                Box::new(|a, b, h| (b[state::VX] - a[state::VX]).hypot(b[state::VY] - a[state::VY]) / h),
            ),
            limit(
                "vertical_accel_max_mps2",
                "vertical acceleration",
                m.vertical_accel_max_mps2,
                false,
                true,
                (1.0, " m/s²"),
                Box::new(accel(state::VZ)),
            ),
            limit(
                "yaw_rate_max_deg_s",
                "yaw rate",
                m.yaw_rate_max_radps,
                false,
                true,
                deg_s,
                Box::new(rate(state::BETA)),
            ),
        ],
    }
}

fn ground(x: &State9) -> f64 {
    x[state::VX].hypot(x[state::VY])
}

/// Refuses a course frame over a path that slows below 1 m/s (a hover): the course, the
/// direction of travel, is then undefined, and the formation would spin with the noise.
pub fn course_defined(path: &NavigatorPath, formation: &Formation, duration_s: f64) -> Result<(), SpecError> {
    if formation.frame != proxform_core::FormationFrame::Course {
        return Ok(());
    }
    let samples = (duration_s / 0.1).ceil().clamp(1.0, 20_000.0) as u64;
    for k in 0..=samples {
        let t = duration_s * k as f64 / samples as f64;
        let x = path.state_at(t, [0.0; 3]);
        if x[state::VX].hypot(x[state::VY]) < 1.0 {
            return Err(err(
                "formation.frame",
                format!(
                    "\"course\" follows the direction of travel, which the path leaves undefined at t = {t:.1} s \
                     (slower than 1 m/s): use \"heading\" (the multirotor's default) or \"world\""
                ),
            ));
        }
    }
    Ok(())
}

/// The share of a multirotor's tilt limit a slot may use for its path, its drag and a typical
/// gust: the rest is kept for the corrections of formation keeping (measured: on a 12-UAV V
/// circuit whose rear slot needs 31.2° noise-free, the default measurement noise and
/// actuation error alone take it to 33.8°; a tenth of 35° is 3.5°).
pub const MULTIROTOR_TILT_IN_USE: f64 = 0.9;

/// Refuses a formation whose slots the vehicle cannot fly where the path turns, when the
/// formation turns as one rigid body (`turn_feedforward` in a course or heading frame), and,
/// for the multirotor, at any time its tilt cannot hold a slot's acceleration against its drag
/// through the steady wind and gust: at
/// every update period (at most 20 000 instants, fewer for a large formation: 2·10^7
/// slot-instants at most) each slot flies at the navigator's velocity
/// plus `ω × R_f(d_i − d_nav)`, ω the path's rate of heading, and must keep within the
/// vehicle's speed range, and turn at ω at that speed within its bank (fixed wing) or
/// acceleration and tilt limits (multirotor). Names the slot, the time, the turn rate and the
/// figure.
pub fn slots_within_vehicle(
    path: &NavigatorPath,
    formation: &Formation,
    navigator: UavId,
    vehicle: &VehicleModel,
    turning: bool,
    wind: &crate::wind::Wind,
    duration_s: f64,
) -> Result<(), SpecError> {
    let rigid = turning && formation.frame != proxform_core::FormationFrame::World;
    if !rigid && !matches!(vehicle, VehicleModel::Multirotor(_)) {
        return Ok(());
    }
    // A typical gust: 1σ of the turbulence's horizontal air speed (m/s).
    let gust_mps = wind.turbulence.map_or(0.0, |t| t.scales().1[0]);
    // At most 2·10^7 slot-instants (a second or so), and at least 50 instants.
    let most = (2e7 / formation.len().max(1) as f64).max(50.0);
    let samples = (duration_s / 0.1).ceil().clamp(1.0, most.min(20_000.0)) as u64;
    let h = duration_s / samples as f64;
    let (vmin, vmax) = vehicle.forward_speed_range();
    let nav = &formation.slots[navigator.index()];
    // The worst excess over a limit (relative), with the slot, time, turn rate and figure.
    let mut worst: Option<(f64, usize, f64, f64, String)> = None;
    let mut prev = path.state_at(0.0, [0.0; 3]);
    // Each slot's velocity at the instant before (for its acceleration).
    let mut before: Vec<[f64; 3]> = Vec::new();
    for k in 1..=samples {
        let t = h * k as f64;
        let x = path.state_at(t, [0.0; 3]);
        let omega = if rigid { wrap_pi(x[state::BETA] - prev[state::BETA]) / h } else { 0.0 };
        prev = x;
        let w: [f64; 3] = wind.common(t).into();
        for (i, slot) in formation.slots.iter().enumerate() {
            let mut s = x;
            formation.add_w_turning(slot, nav, &x, omega, &mut s);
            let vel = [s[state::VX], s[state::VY], s[state::VZ]];
            let accel = before.get(i).map(|b| [(vel[0] - b[0]) / h, (vel[1] - b[1]) / h, (vel[2] - b[2]) / h]);
            if before.len() < formation.len() {
                before.push(vel);
            } else {
                before[i] = vel;
            }
            let v = vehicle.forward_speed(&s);
            let lateral = omega.abs() * s[state::VX].hypot(s[state::VY]);
            let mut excess = vec![
                ((v - vmax) / vmax, format!("{:.1} km/h, beyond the vehicle's {:.1} km/h", v * 3.6, vmax * 3.6)),
                (
                    (vmin - v) / vmin.max(1e-9),
                    format!("{:.1} km/h, below the vehicle's {:.1} km/h", v * 3.6, vmin * 3.6),
                ),
            ];
            match vehicle {
                VehicleModel::FixedWing(m) => {
                    let bank = (lateral / G).atan();
                    excess.push((
                        (bank - m.bank_limit()) / m.bank_limit(),
                        format!(
                            "a bank of {:.1}°, beyond the vehicle's {:.1}°",
                            bank.to_degrees(),
                            m.bank_limit().to_degrees()
                        ),
                    ));
                }
                VehicleModel::Multirotor(m) => {
                    excess.push((
                        (lateral - m.accel_max_mps2) / m.accel_max_mps2,
                        format!(
                            "{lateral:.2} m/s² toward the turn's centre, beyond vehicle.accel_max_mps2 = {:.2} m/s²",
                            m.accel_max_mps2
                        ),
                    ));
                    // The tilt that holds its acceleration against its drag through the steady
                    // wind and the gust, and against a typical gust of the turbulence (1σ of
                    // its horizontal air speed, the drag's change with it), within the share of
                    // the tilt limit not kept for corrections.
                    if let Some(a) = accel {
                        let va = [vel[0] - w[0], vel[1] - w[1], vel[2] - w[2]];
                        let air = (va[0] * va[0] + va[1] * va[1] + va[2] * va[2]).sqrt();
                        let k = m.drag_linear_per_s + m.drag_quadratic_per_m * air;
                        let (fx, fy, fz) = (a[0] + k * va[0], a[1] + k * va[1], G + a[2] + k * va[2]);
                        let dk = m.drag_linear_per_s + 2.0 * m.drag_quadratic_per_m * air;
                        let tilt = (fx.hypot(fy) + dk * gust_mps).atan2(fz);
                        let limit = MULTIROTOR_TILT_IN_USE * m.tilt_max_rad;
                        let gusty = if gust_mps > 0.0 {
                            format!(", a typical gust of {gust_mps:.1} m/s")
                        } else {
                            String::new()
                        };
                        excess.push((
                            (tilt - limit) / limit,
                            format!(
                                "a tilt of {:.1}° (its drag at {:.1} km/h through the air{gusty}, and its acceleration), \
                                 beyond {:.1}° ({:.0} % of vehicle.tilt_max_deg = {:.1}°: the rest is kept for corrections)",
                                tilt.to_degrees(),
                                air * 3.6,
                                limit.to_degrees(),
                                MULTIROTOR_TILT_IN_USE * 100.0,
                                m.tilt_max_rad.to_degrees()
                            ),
                        ));
                    }
                }
                VehicleModel::Kinematic(_) => {}
            }
            for (e, what) in excess {
                if e > 1e-6 && worst.as_ref().is_none_or(|w| e > w.0) {
                    worst = Some((e, i, t, omega, what));
                }
            }
        }
    }
    if let Some((_, i, t, omega, what)) = worst {
        // The navigator's own slot is its path's (and vehicle's) matter; the others' the
        // formation's.
        let (key, whose, nearer) = if i == navigator.index() {
            ("path", format!("the navigator (UAV {}) would need", i + 1), "")
        } else {
            ("formation", format!("UAV {}'s slot would need", i + 1), ", or bring the slot nearer the navigator")
        };
        let turn = if omega.abs() > 1e-9 {
            format!("turning at {:.1}°/s, t = {t:.1} s): fly a wider turn (path.turn_radius_m) or ", omega.to_degrees())
        } else {
            format!("t = {t:.1} s): fly ")
        };
        return Err(err(key, format!("{whose} {what} ({turn}slower, in less wind, with less drag{nearer}")));
    }
    Ok(())
}

/// Refuses a navigator path that the followers' vehicle cannot fly: at some instant its
/// velocity or attitude leaves the vehicle's limits, or changes faster than the vehicle's
/// adjusting rates (the followers would be held at the limit and fall behind, silently).
/// Checked at every update period (at most 200 000 instants), naming the limit, the value and
/// the time.
pub fn path_within_vehicle(
    path: &NavigatorPath,
    vehicle: &VehicleModel,
    duration_s: f64,
    dt_s: f64,
) -> Result<(), SpecError> {
    let steps = (duration_s / dt_s).ceil().max(1.0);
    let samples = steps.min(200_000.0) as u64;
    let limits = limits(vehicle);
    // The worst excess of each limit: (excess over the bound in bounds, value, time).
    let mut worst: Vec<Option<(f64, f64, f64)>> = vec![None; limits.len()];
    let mut prev = path.state_at(0.0, [0.0; 3]);
    let h = duration_s / samples as f64;
    for k in 0..=samples {
        let t = duration_s * k as f64 / samples as f64;
        let x = path.state_at(t, [0.0; 3]);
        for (l, w) in limits.iter().zip(worst.iter_mut()).filter(|(l, _)| k > 0 || !l.rate) {
            let v = (l.value)(&prev, &x, h);
            // A tolerance keeps rounding from refusing a path that flies at a limit.
            let excess = if l.below { l.bound - v } else { v - l.bound } / l.bound.abs().max(1e-9);
            if excess > 1e-6 && w.is_none_or(|(e, _, _)| excess > e) {
                *w = Some((excess, v, t));
            }
        }
        prev = x;
    }
    let Some((l, (_, v, t))) =
        limits.iter().zip(worst).filter_map(|(l, w)| w.map(|w| (l, w))).max_by(|a, b| a.1 .0.total_cmp(&b.1 .0))
    else {
        return Ok(());
    };
    let hint = match (vehicle, l.rate) {
        (_, true) => {
            " (a longer path.transition_s, a larger path.turn_radius_m, longer legs or smaller changes of \
             path.leg_speeds_kmh, or gentler segments ask less of the followers)"
        }
        (VehicleModel::Kinematic(_), false) => {
            " (the kinematic vehicle's limits are on the world axes and on its attitude: a path that turns far \
             from +x leaves them; turn less, raise the limits, or fly model = \"fixed_wing\")"
        }
        _ => "",
    };
    Err(err(
        "path",
        format!(
            "the navigator's {} reaches {:.1}{unit} at t = {t:.1} s, {} vehicle.{} = {:.1}{unit}: the followers fly \
             the same vehicle and could not keep their slots{hint}",
            l.what,
            v * l.scale,
            if l.below { "below" } else { "beyond" },
            l.key,
            l.bound * l.scale,
            unit = l.unit,
        ),
    ))
}
