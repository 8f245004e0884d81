//! `[path]`: the paper's scripted profile, segments, or waypoints joined by turns.

use proxform_core::angle::{deg, kmh};

use super::values::{distance, distance3, err, finite, non_negative, positive, required, speed_kmh, SpecError};
use crate::defaults;
use crate::path::waypoints::waypoint_segments_at;
use crate::path::{NavigatorPath, PaperPath, Segment, SegmentsPath};
use crate::spec::PathSpec;

/// Longest lead-in of the paper path (s): about eleven days, far beyond any flight, and small
/// enough that the profile's positions stay finite.
const MAX_LEAD_IN_S: f64 = 1e6;

fn paper_keys(p: &PathSpec) -> bool {
    p.height_amplitude_m.is_some()
        || p.pitch_swing_deg.is_some()
        || p.yaw_amplitude_deg.is_some()
        || p.roll_amplitude_deg.is_some()
        || p.lead_in_s.is_some()
}

/// The navigator's path, covering the flight.
pub fn path(p: &PathSpec) -> Result<NavigatorPath, SpecError> {
    match p.kind.as_deref() {
        None | Some("paper") => {
            if p.speed_kmh.is_some()
                || p.course_deg.is_some()
                || p.transition_s.is_some()
                || !p.segment.is_empty()
                || p.points_m.is_some()
                || p.turn_radius_m.is_some()
                || p.leg_speeds_kmh.is_some()
            {
                return Err(err("path", "the paper path takes no speed, course or segments (use kind = \"segments\")"));
            }
            let d = PaperPath::default();
            let amplitude = |key: &str, v: Option<f64>, default: f64, scale: fn(f64) -> f64| {
                v.map_or(Ok(default), |v| non_negative(&format!("path.{key}"), v).map(scale))
            };
            let id = |v| v;
            Ok(NavigatorPath::Paper(PaperPath {
                height_amplitude_m: amplitude("height_amplitude_m", p.height_amplitude_m, d.height_amplitude_m, id)?,
                pitch_swing_rad: amplitude("pitch_swing_deg", p.pitch_swing_deg, d.pitch_swing_rad, deg)?,
                yaw_amplitude_rad: amplitude("yaw_amplitude_deg", p.yaw_amplitude_deg, d.yaw_amplitude_rad, deg)?,
                roll_amplitude_rad: amplitude("roll_amplitude_deg", p.roll_amplitude_deg, d.roll_amplitude_rad, deg)?,
                lead_in_s: match p.lead_in_s {
                    Some(v) if v > MAX_LEAD_IN_S => {
                        return Err(err("path.lead_in_s", format!("must be at most {MAX_LEAD_IN_S:e} s, found {v:e}")))
                    }
                    v => amplitude("lead_in_s", v, d.lead_in_s, id)?,
                },
                ..d
            }))
        }
        Some("segments") | Some("waypoints") if paper_keys(p) => {
            Err(err("path", "amplitudes and lead_in_s apply to the paper path only (kind = \"paper\")"))
        }
        Some("segments") => {
            for (key, set) in [
                ("path.points_m", p.points_m.is_some()),
                ("path.turn_radius_m", p.turn_radius_m.is_some()),
                ("path.leg_speeds_kmh", p.leg_speeds_kmh.is_some()),
            ] {
                if set {
                    return Err(err(key, "applies to a waypoints path only (kind = \"waypoints\")"));
                }
            }
            // 0 is a hover: only a vehicle that can hover flies it (the path is then checked
            // against the vehicle's speed range).
            let v0 = kmh(speed_kmh(
                "path.speed_kmh",
                non_negative("path.speed_kmh", required("path.speed_kmh", p.speed_kmh)?)?,
            )?);
            let course = deg(finite("path.course_deg", p.course_deg.unwrap_or(0.0))?);
            let mut speed = v0;
            let mut segments = Vec::new();
            for (k, s) in p.segment.iter().enumerate() {
                let key = format!("path.segment[{}]", k + 1);
                let d = positive(&format!("{key}.duration_s"), required(&format!("{key}.duration_s"), s.duration_s)?)?;
                let w = deg(finite(&format!("{key}.turn_rate_deg_s"), s.turn_rate_deg_s.unwrap_or(0.0))?);
                let c = kmh(finite(&format!("{key}.climb_kmh"), s.climb_kmh.unwrap_or(0.0))?);
                if let Some(v) = s.speed_kmh {
                    speed = kmh(speed_kmh(&format!("{key}.speed_kmh"), non_negative(&format!("{key}.speed_kmh"), v)?)?);
                }
                segments.push(Segment {
                    duration_s: d,
                    turn_rate_radps: w,
                    climb_mps: c,
                    end_speed_mps: speed,
                    start_blend_s: None,
                });
            }
            let transition = positive("path.transition_s", p.transition_s.unwrap_or(defaults::PATH_TRANSITION_S))?;
            Ok(NavigatorPath::Segments(SegmentsPath::new(v0, course, segments, transition)))
        }
        Some("waypoints") => {
            if !p.segment.is_empty() {
                return Err(err("path.segment", "a waypoints path takes points_m, not segments"));
            }
            let v = kmh(speed_kmh(
                "path.speed_kmh",
                positive("path.speed_kmh", required("path.speed_kmh", p.speed_kmh)?)?,
            )?);
            let r = distance(
                "path.turn_radius_m",
                positive("path.turn_radius_m", required("path.turn_radius_m", p.turn_radius_m)?)?,
            )?;
            // Below a metre the turn is a corner: its rates and accelerations are not numbers a
            // vehicle is checked against (1e-300 was accepted).
            if r < 1.0 {
                return Err(err(
                    "path.turn_radius_m",
                    format!("{} m is under 1 m: give the radius the navigator turns with", super::values::show(r)),
                ));
            }
            let points = required("path.points_m", p.points_m.clone())?;
            let transition = positive("path.transition_s", p.transition_s.unwrap_or(defaults::PATH_TRANSITION_S))?;
            for (k, pt) in points.iter().enumerate() {
                distance3(&format!("path.points_m[{}]", k + 1), *pt)?;
            }
            let leg_speeds = match &p.leg_speeds_kmh {
                Some(speeds) => {
                    let mut out = Vec::with_capacity(speeds.len());
                    for (k, &s) in speeds.iter().enumerate() {
                        let key = format!("path.leg_speeds_kmh[{}]", k + 1);
                        out.push(kmh(speed_kmh(&key, positive(&key, s)?)?));
                    }
                    Some(out)
                }
                None => None,
            };
            let segments = waypoint_segments_at(&points, v, leg_speeds.as_deref(), r, transition).map_err(|e| {
                let key = match e.point {
                    Some(k) => format!("path.points_m[{k}]"),
                    None if leg_speeds.is_some() => "path.leg_speeds_kmh".into(),
                    None => "path.points_m".into(),
                };
                err(key, e.message)
            })?;
            let course = segments.1;
            Ok(NavigatorPath::Segments(SegmentsPath::new(v, course, segments.0, transition)))
        }
        Some(o) => {
            Err(err("path.kind", format!("unknown path \"{o}\" (expected \"paper\", \"segments\" or \"waypoints\")")))
        }
    }
}
