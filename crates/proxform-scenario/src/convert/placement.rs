//! `[initial]`'s placement: where the followers start, checked before anything flies. Random
//! regions must hold the formation's UAVs the safety distance apart with room to spare (the
//! simulator draws each start away from those already placed); explicit starts must keep every
//! pair of UAVs the safety distance apart.

use proxform_core::assignment::AssignBy;
use proxform_core::state::{self, State9};
use proxform_core::UavId;

use super::values::{distance, err, non_negative, positive, show, SpecError};
use crate::placement::Placement;
use crate::spec::InitialSpec;

/// A random region must offer at least this many cells of the safety distance (twice over) per
/// UAV: random sequential placement jams at about half of a dense packing.
const ROOM_PER_UAV: f64 = 2.0;

/// `[initial] form_within_s`: for a formation not starting in its slots, the time by which it
/// must have formed (default [`crate::defaults::FORM_WITHIN_S`], at most the flight; a longer
/// one given asks for a formation formed by the end).
pub fn form_within(spec: &InitialSpec, placement: &Placement, duration_s: f64) -> Result<Option<f64>, SpecError> {
    if placement.in_slots() {
        if spec.form_within_s.is_some() {
            return Err(err("initial.form_within_s", "applies to formations that do not start in their slots"));
        }
        return Ok(None);
    }
    let t = match spec.form_within_s {
        // Longer than the flight: the formation must have formed by its end.
        Some(v) => positive("initial.form_within_s", v)?,
        None => crate::defaults::FORM_WITHIN_S.min(duration_s),
    };
    Ok(Some(t))
}

/// `[initial] assign_by`: what slot assignments minimise (default the total distance).
pub fn assign_by(spec: &InitialSpec) -> Result<AssignBy, SpecError> {
    match spec.assign_by.as_deref() {
        None | Some("total") => Ok(AssignBy::Total),
        Some("largest") => Ok(AssignBy::Largest),
        Some(other) => Err(err(
            "initial.assign_by",
            format!("unknown objective {other:?}: \"total\" (the total distance) or \"largest\" (the largest)"),
        )),
    }
}

/// The placement of `[initial]`, for `initial` (every UAV in its slot) and the navigator.
pub fn placement(
    spec: &InitialSpec,
    initial: &[State9],
    navigator: UavId,
    safety_distance_m: f64,
    can_hover: bool,
) -> Result<Placement, SpecError> {
    let kind = spec.placement.as_deref().unwrap_or("slots");
    let only = |key: &str, given: bool, for_kind: &str| -> Result<(), SpecError> {
        if given && kind != for_kind {
            return Err(err(format!("initial.{key}"), format!("applies to placement = \"{for_kind}\" only")));
        }
        Ok(())
    };
    only("box_m", spec.box_m.is_some(), "box")?;
    only("radius_m", spec.radius_m.is_some(), "disc")?;
    only("height_m", spec.height_m.is_some(), "disc")?;
    only("uav", !spec.uavs.is_empty(), "explicit")?;
    only("row_spacing_m", spec.row_spacing_m.is_some(), "row")?;
    only("ground_below_m", spec.ground_below_m.is_some(), "row")?;
    if spec.assign_slots.is_some() && !matches!(kind, "box" | "disc" | "row") {
        return Err(err("initial.assign_slots", "applies to placement = \"box\", \"disc\" or \"row\" only"));
    }
    let assign = spec.assign_slots.unwrap_or(false).then(|| assign_by(spec)).transpose()?;
    let n = initial.len() as f64;
    let cell = 2.0 * safety_distance_m;
    let room = |extent: [f64; 3]| extent.iter().map(|e| (e / cell).floor() + 1.0).product::<f64>();
    match kind {
        "slots" => Ok(Placement::Slots),
        "box" => {
            let Some(b) = spec.box_m else {
                return Err(err("initial.box_m", "is required with placement = \"box\": its size [x, y, z] in m"));
            };
            let mut size_m = [0.0; 3];
            for k in 0..3 {
                size_m[k] = distance("initial.box_m", non_negative("initial.box_m", b[k])?)?;
            }
            if room(size_m) < ROOM_PER_UAV * n {
                return Err(err(
                    "initial.box_m",
                    format!(
                        "a box of {} × {} × {} m is too small to scatter {} UAVs {} m apart (the safety distance): \
                         make it larger",
                        show(size_m[0]),
                        show(size_m[1]),
                        show(size_m[2]),
                        initial.len(),
                        show(safety_distance_m)
                    ),
                ));
            }
            Ok(Placement::Box { size_m, assign })
        }
        "disc" => {
            let Some(r) = spec.radius_m else {
                return Err(err("initial.radius_m", "is required with placement = \"disc\""));
            };
            let radius_m = distance("initial.radius_m", positive("initial.radius_m", r)?)?;
            let height_m =
                distance("initial.height_m", non_negative("initial.height_m", spec.height_m.unwrap_or(0.0))?)?;
            let cells = std::f64::consts::PI * radius_m * radius_m / (cell * cell) * ((height_m / cell).floor() + 1.0);
            if cells < ROOM_PER_UAV * n {
                return Err(err(
                    "initial.radius_m",
                    format!(
                        "a disc of radius {} m is too small to scatter {} UAVs {} m apart (the safety distance): \
                         make it larger",
                        show(radius_m),
                        initial.len(),
                        show(safety_distance_m)
                    ),
                ));
            }
            Ok(Placement::Disc { radius_m, height_m, assign })
        }
        "row" => {
            if !can_hover {
                return Err(err(
                    "initial.placement",
                    "a take-off row starts the UAVs at rest: it needs a vehicle that can hover \
                     (model = \"kinematic\" with vehicle.vx_min_kmh = 0)",
                ));
            }
            let Some(spacing) = spec.row_spacing_m else {
                return Err(err("initial.row_spacing_m", "is required with placement = \"row\""));
            };
            let spacing_m = distance("initial.row_spacing_m", positive("initial.row_spacing_m", spacing)?)?;
            if spacing_m < safety_distance_m {
                return Err(err(
                    "initial.row_spacing_m",
                    format!("{} m is closer than the safety distance ({} m)", show(spacing_m), show(safety_distance_m)),
                ));
            }
            let Some(below) = spec.ground_below_m else {
                return Err(err("initial.ground_below_m", "is required with placement = \"row\""));
            };
            let below_m = distance("initial.ground_below_m", non_negative("initial.ground_below_m", below)?)?;
            if below_m < safety_distance_m {
                return Err(err(
                    "initial.ground_below_m",
                    format!(
                        "{} m: the navigator would start within the safety distance ({} m) of the row",
                        show(below_m),
                        show(safety_distance_m)
                    ),
                ));
            }
            Ok(Placement::Row { spacing_m, below_m, assign })
        }
        "explicit" => {
            if spec.uavs.is_empty() {
                return Err(err("initial.uav", "give at least one [[initial.uav]] with placement = \"explicit\""));
            }
            let nav = &initial[navigator.index()];
            let mut at: Vec<[f64; 3]> = initial.iter().map(|s| [s[state::X], s[state::Y], s[state::Z]]).collect();
            let mut listed = Vec::new();
            for (k, u) in spec.uavs.iter().enumerate() {
                let key = |f: &str| format!("initial.uav[{}].{f}", k + 1);
                let Some(id) = u.id else { return Err(err(key("id"), "is required")) };
                if id == 0 || id as usize > initial.len() {
                    return Err(err(key("id"), format!("UAV {id} is not in the formation (1 to {})", initial.len())));
                }
                let uav = UavId(id - 1);
                if uav == navigator {
                    return Err(err(key("id"), format!("UAV {id} is the navigator, which starts on its path")));
                }
                if listed.iter().any(|(v, _): &(UavId, [f64; 3])| *v == uav) {
                    return Err(err(key("id"), format!("UAV {id} is listed twice")));
                }
                let Some(p) = u.position_m else { return Err(err(key("position_m"), "is required")) };
                let mut q = [0.0; 3];
                for j in 0..3 {
                    q[j] = distance(&key("position_m"), p[j])?;
                }
                at[uav.index()] = [nav[state::X] + q[0], nav[state::Y] + q[1], nav[state::Z] + q[2]];
                listed.push((uav, q));
            }
            for (k, &(uav, _)) in listed.iter().enumerate() {
                let p = at[uav.index()];
                for (j, q) in at.iter().enumerate() {
                    let d = ((p[0] - q[0]).powi(2) + (p[1] - q[1]).powi(2) + (p[2] - q[2]).powi(2)).sqrt();
                    if j != uav.index() && d < safety_distance_m {
                        return Err(err(
                            format!("initial.uav[{}].position_m", k + 1),
                            format!(
                                "UAV {} starts {} m from UAV {}, closer than the safety distance {} m",
                                uav.0 + 1,
                                show((d * 10.0).round() / 10.0),
                                j + 1,
                                show(safety_distance_m)
                            ),
                        ));
                    }
                }
            }
            Ok(Placement::Explicit(listed))
        }
        other => Err(err(
            "initial.placement",
            format!("unknown placement \"{other}\" (expected \"slots\", \"box\", \"disc\", \"row\" or \"explicit\")"),
        )),
    }
}

/// Refuses a scenario whose slot assignments (at the start with `initial.assign_slots`, after
/// each loss with `formation.reassign_on_loss`) would take more than seconds for its `n` UAVs
/// ([`proxform_core::assignment::max_assigned`]).
pub fn assignment_within_bounds(
    placement: &Placement,
    reassign_on_loss: Option<AssignBy>,
    n: usize,
) -> Result<(), SpecError> {
    use proxform_core::assignment::{max_assigned, MAX_CANDIDATES};
    let at_start = match placement {
        Placement::Box { assign, .. } | Placement::Disc { assign, .. } | Placement::Row { assign, .. } => *assign,
        Placement::Slots | Placement::Explicit(_) => None,
    };
    let followers = n.saturating_sub(1);
    if let Some(by) = at_start {
        let max = max_assigned(by, false);
        if followers > max {
            return Err(err(
                "initial.assign_slots",
                format!(
                    "{followers} followers are more than the {max} an assignment by the {} distance takes \
                     (its work grows with the cube of their number: 10 000 would take hours); \
                     assign_slots = false flies them to the slots in draw order{}",
                    by.label(),
                    match by {
                        AssignBy::Largest =>
                            format!(", and assign_by = \"total\" takes up to {}", max_assigned(AssignBy::Total, false)),
                        AssignBy::Total => String::new(),
                    }
                ),
            ));
        }
    }
    if let Some(by) = reassign_on_loss {
        let max = max_assigned(by, true);
        if n > max {
            return Err(err(
                "formation.reassign_on_loss",
                format!(
                    "{n} UAVs are more than the {max} re-assigned after a loss by the {} distance \
                     (each loss solves up to {MAX_CANDIDATES} assignments, whose work grows with the cube of their number)",
                    by.label()
                ),
            ));
        }
    }
    Ok(())
}

/// With `reassign_on_loss`, the work of every loss together: each instant at which UAVs are
/// removed re-assigns the formation (up to [`proxform_core::assignment::MAX_CANDIDATES`]
/// assignments of `n` UAVs), so `L` such instants may take the UAVs that one loss takes at
/// most divided by L^(1/3) (the work grows with the cube of their number). Refused when read,
/// naming the limit for that many losses.
pub fn reassignments_within_bounds(by: AssignBy, n: usize, faults: &[crate::faults::Fault]) -> Result<(), SpecError> {
    use proxform_core::assignment::max_assigned;
    let mut instants: Vec<u64> = faults
        .iter()
        .filter_map(|f| match f {
            crate::faults::Fault::Remove { at_s, .. } => Some(at_s.to_bits()),
            _ => None,
        })
        .collect();
    instants.sort_unstable();
    instants.dedup();
    let losses = instants.len();
    if losses < 2 {
        return Ok(());
    }
    let max = (max_assigned(by, true) as f64 / (losses as f64).cbrt()).floor() as usize;
    if n > max {
        return Err(err(
            "formation.reassign_on_loss",
            format!(
                "{n} UAVs re-assigned after each of {losses} losses (removals at {losses} instants): more work than \
                 {} UAVs after one; with {losses} losses at most {max} UAVs (the work of each grows with the cube \
                 of their number); remove them at fewer instants, or set reassign_on_loss = false",
                max_assigned(by, true)
            ),
        ));
    }
    Ok(())
}
