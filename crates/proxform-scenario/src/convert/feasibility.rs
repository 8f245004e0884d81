//! Whether the scenario can be flown at all: slots apart by the safety distance, initial
//! speeds within the vehicle's range, and a navigator path within the followers' limits.

use proxform_core::angle::{kmh, wrap_pi};
use proxform_core::grid::NeighbourGrid;
use proxform_core::state::{self, State9};
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
        Some(v) => Some(kmh(positive("initial.speed_kmh", v)?)),
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
            let key = match (speed.is_some(), path_speed, kinematic, v < vmin) {
                (true, ..) => "initial.speed_kmh",
                (false, true, ..) => "path.speed_kmh",
                (false, false, true, true) => "vehicle.vx_min_kmh",
                (false, false, true, false) => "vehicle.vx_max_kmh",
                (false, false, false, true) => "vehicle.stall_speed_kmh",
                (false, false, false, false) => "vehicle.max_speed_kmh",
            };
            let what = if kinematic { "vx" } else { "airspeed" };
            let along_x = x[state::VY].abs() <= 1e-9 * x[state::VX].abs().max(1.0);
            let hint = if kinematic && !along_x {
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

/// Refuses a navigator path that the followers' vehicle cannot fly: its velocity or attitude
/// leaves the vehicle's limits at some instant (the followers would be held at the limit and
/// fall behind, silently). Checked every update period, at most 200 000 instants.
pub fn path_within_vehicle(
    path: &NavigatorPath,
    vehicle: &VehicleModel,
    duration_s: f64,
    dt_s: f64,
) -> Result<(), SpecError> {
    let steps = (duration_s / dt_s).ceil().max(1.0);
    let samples = steps.min(200_000.0) as u64;
    let tol = 1e-6;
    for k in 0..=samples {
        let t = duration_s * k as f64 / samples as f64;
        let x = path.state_at(t, [0.0; 3]);
        let mut out: Option<(&str, String, f64, f64)> = None;
        match vehicle {
            VehicleModel::Kinematic(m) => {
                let l = &m.limits;
                if x[state::VX] < l.vx_min_mps - tol || x[state::VX] > l.vx_max_mps + tol {
                    let key = if x[state::VX] < l.vx_min_mps { "vx_min_kmh" } else { "vx_max_kmh" };
                    out = Some((
                        key,
                        "vx".into(),
                        x[state::VX] * 3.6,
                        if x[state::VX] < l.vx_min_mps { l.vx_min_mps } else { l.vx_max_mps } * 3.6,
                    ));
                } else if x[state::VY].abs() > l.vy_max_mps + tol {
                    out = Some(("vy_max_kmh", "|vy|".into(), x[state::VY].abs() * 3.6, l.vy_max_mps * 3.6));
                } else if x[state::VZ].abs() > l.vz_max_mps + tol {
                    out = Some(("vz_max_kmh", "|vz|".into(), x[state::VZ].abs() * 3.6, l.vz_max_mps * 3.6));
                } else {
                    for (a, name) in ["pitch", "yaw", "roll"].iter().enumerate() {
                        let angle = wrap_pi(x[state::ALPHA + a]).abs();
                        if angle > l.attitude_max_rad[a] + tol {
                            out = Some((
                                ["attitude_max_deg[1]", "attitude_max_deg[2]", "attitude_max_deg[3]"][a],
                                format!("|{name}|"),
                                angle.to_degrees(),
                                l.attitude_max_rad[a].to_degrees(),
                            ));
                            break;
                        }
                    }
                }
            }
            VehicleModel::FixedWing(m) => {
                let (v, vmin, vmax) = (vehicle.forward_speed(&x), m.stall_speed_mps, m.max_speed_mps);
                if v < vmin - tol || v > vmax + tol {
                    let key = if v < vmin { "stall_speed_kmh" } else { "max_speed_kmh" };
                    out = Some((key, "airspeed".into(), v * 3.6, if v < vmin { vmin } else { vmax } * 3.6));
                } else if x[state::GAMMA].abs() > m.bank_max_rad + tol {
                    out = Some((
                        "bank_max_deg",
                        "|bank|".into(),
                        x[state::GAMMA].abs().to_degrees(),
                        m.bank_max_rad.to_degrees(),
                    ));
                }
            }
        }
        if let Some((key, what, found, limit)) = out {
            let unit = if key.contains("_deg") { "°" } else { " km/h" };
            let hint = if matches!(vehicle, VehicleModel::Kinematic(_)) {
                " (the kinematic vehicle's limits are on the world axes and on its attitude: a path that \
                 turns far from +x leaves them; turn less, raise the limits, or fly model = \"fixed_wing\")"
            } else {
                ""
            };
            return Err(err(
                "path",
                format!(
                    "the navigator reaches {what} {found:.1}{unit} at t = {t:.1} s, beyond vehicle.{key} = \
                     {limit:.1}{unit}: the followers fly the same vehicle and could not keep their slots{hint}"
                ),
            ));
        }
    }
    Ok(())
}
