//! The world's sections: `[noise]`, `[sensing]`, `[radio]`, `[allowable]`, `[wind]` and the
//! `[[fault]]` schedule.

use nalgebra::Vector3;
use proxform_core::angle::{deg, kmh};
use proxform_core::UavId;

use super::values::{
    distance3, err, non_negative, or_default, positive, probability, required, show, uav, vec3, within, SpecError,
};
use crate::defaults;
use crate::faults::Fault;
use crate::radio::{GilbertElliott, RadioModel};
use crate::scenario::{AllowableErrors, CorrelatedNoise, MeasurementNoise};
use crate::spec::{AllowableSpec, FaultSpec, NoiseSpec, RadioSpec, SensingSpec, WindSpec};
use crate::wind::{Gust, Severity, Turbulence, Wind};

/// Measurement noise (each σ times `noise.scale`), the GNSS-like bias and the actuation error.
pub fn noise(n: &NoiseSpec) -> Result<(MeasurementNoise, Option<CorrelatedNoise>, f64), SpecError> {
    // Beyond these the sensors measure nothing: the noise would be the whole signal.
    const LIMITS: [(&str, f64, &str); 4] = [
        ("noise.position_m", 1000.0, "m"),
        ("noise.velocity_kmh", 360.0, "km/h"),
        ("noise.attitude_deg", 90.0, "°"),
        ("noise.gnss_bias_m", 1000.0, "m"),
    ];
    for ((key, max, unit), v) in LIMITS.iter().zip([n.position_m, n.velocity_kmh, n.attitude_deg, n.gnss_bias_m]) {
        if let Some(v) = v {
            within(key, v, *max, unit, "noise that large measures nothing")?;
        }
    }
    let scale = or_default("noise.scale", n.scale, 1.0, non_negative)?;
    within("noise.scale", scale, 1e3, "times", "noise that large measures nothing")?;
    let noise = MeasurementNoise {
        position_m: or_default("noise.position_m", n.position_m, defaults::NOISE_POSITION_M, non_negative)? * scale,
        velocity_mps: kmh(or_default(
            "noise.velocity_kmh",
            n.velocity_kmh,
            defaults::NOISE_VELOCITY_KMH,
            non_negative,
        )?) * scale,
        attitude_rad: deg(or_default(
            "noise.attitude_deg",
            n.attitude_deg,
            defaults::NOISE_ATTITUDE_DEG,
            non_negative,
        )?) * scale,
    };
    // The same limits hold for the noise flown, scaled: a scaled σ beyond them is refused as
    // `noise.scale` (and a printed scenario, whose σ are the scaled ones, loads again).
    let scaled = [noise.position_m, noise.velocity_mps * 3.6, noise.attitude_rad.to_degrees()];
    for ((key, max, unit), v) in LIMITS.iter().zip(scaled) {
        if v > *max * (1.0 + 1e-12) {
            return Err(err(
                "noise.scale",
                format!(
                    "{} times {key} is {} {unit}, beyond {} {unit}: noise that large measures nothing",
                    show(scale),
                    show(v),
                    show(*max)
                ),
            ));
        }
    }
    let actuation = or_default("noise.actuation_error", n.actuation_error, defaults::ACTUATION_ERROR, probability)?;
    let gnss = match (n.gnss_bias_m, n.gnss_tau_s) {
        (Some(sigma), tau) => Some(CorrelatedNoise {
            sigma_m: non_negative("noise.gnss_bias_m", sigma)?,
            tau_s: positive("noise.gnss_tau_s", tau.unwrap_or(defaults::GNSS_TAU_S))?,
        }),
        (None, Some(_)) => return Err(err("noise.gnss_tau_s", "needs noise.gnss_bias_m")),
        (None, None) => None,
    };
    Ok((noise, gnss, actuation))
}

/// Onboard dropout, the dropout of observations of main references when it differs, and
/// whether observations are relative to the observer.
pub fn sensing(s: &SensingSpec) -> Result<(f64, Option<f64>, bool), SpecError> {
    let dropout = or_default("sensing.dropout", s.dropout, 0.0, probability)?;
    let reference = s.reference_dropout.map(|v| probability("sensing.reference_dropout", v)).transpose()?;
    Ok((dropout, reference, s.relative.unwrap_or(false)))
}

/// The allowable errors (SI).
pub fn allowable(a: &AllowableSpec, vehicle: &proxform_core::VehicleModel) -> Result<AllowableErrors, SpecError> {
    let ([x, y, z], [al, be, ga]) = match vehicle {
        proxform_core::VehicleModel::Multirotor(_) => {
            (defaults::MULTIROTOR_ALLOWABLE_POSITION_M, defaults::MULTIROTOR_ALLOWABLE_ATTITUDE_DEG)
        }
        proxform_core::VehicleModel::FixedWing(_) => {
            (defaults::FIXED_WING_ALLOWABLE_POSITION_M, defaults::FIXED_WING_ALLOWABLE_ATTITUDE_DEG)
        }
        proxform_core::VehicleModel::Kinematic(_) => (defaults::ALLOWABLE_POSITION_M, defaults::ALLOWABLE_ATTITUDE_DEG),
    };
    let position_m = [
        or_default("allowable.x_m", a.x_m, x, positive)?,
        or_default("allowable.y_m", a.y_m, y, positive)?,
        or_default("allowable.z_m", a.z_m, z, positive)?,
    ];
    let path_default = defaults::PATH_PER_ALLOWABLE * position_m.iter().copied().fold(0.0, f64::max);
    Ok(AllowableErrors {
        position_m,
        path_m: or_default("allowable.path_m", a.path_m, path_default, positive)?,
        attitude_rad: [
            deg(or_default("allowable.alpha_deg", a.alpha_deg, al, positive)?),
            deg(or_default("allowable.beta_deg", a.beta_deg, be, positive)?),
            deg(or_default("allowable.gamma_deg", a.gamma_deg, ga, positive)?),
        ],
    })
}

/// The fault schedule of a flight of `duration_s` with `n` UAVs.
pub fn faults(specs: &[FaultSpec], n: usize, duration_s: f64) -> Result<Vec<Fault>, SpecError> {
    let faults: Vec<Fault> = specs.iter().enumerate().map(|(k, f)| fault(k + 1, f, n)).collect::<Result<_, _>>()?;
    // A UAV joins once and is removed once: a second of either would be a silent no-op, or
    // move the first (whichever comes later wins).
    for (k, f) in faults.iter().enumerate() {
        let (uav, kind) = match *f {
            Fault::Join { uav, .. } => (uav, "joins"),
            Fault::Remove { uav, .. } => (uav, "is removed"),
            _ => continue,
        };
        let same = |g: &Fault| std::mem::discriminant(g) == std::mem::discriminant(f) && g.uav() == Some(uav);
        if let Some(first) = faults[..k].iter().position(same) {
            return Err(err(
                format!("fault[{}].uav", k + 1),
                format!(
                    "UAV {} {kind} twice (fault[{}] and fault[{}]): a UAV joins at most once and is removed at \
                     most once",
                    uav.0 + 1,
                    first + 1,
                    k + 1
                ),
            ));
        }
    }
    // A UAV flies from its join (if it has one) to its removal (if it has one): a removal at or
    // before its join would leave it never flying, silently.
    for (k, f) in faults.iter().enumerate() {
        let Fault::Remove { uav, at_s: removed } = *f else { continue };
        let joins = faults.iter().filter_map(|g| match *g {
            Fault::Join { uav: u, at_s, .. } if u == uav => Some(at_s),
            _ => None,
        });
        if let Some(joined) = joins.filter(|&j| j >= removed).reduce(f64::min) {
            return Err(err(
                format!("fault[{}].at_s", k + 1),
                format!(
                    "UAV {} is removed at {removed} s, {} it joins at {joined} s: a UAV flies from its join to \
                     its removal, so it would never fly (remove it after it joins, or give the one that comes \
                     back its own id)",
                    uav.0 + 1,
                    if joined > removed { "before" } else { "as" }
                ),
            ));
        }
    }
    // A sensor fault strikes a UAV that flies: after its join (before it a stuck sensor froze a
    // reading of a UAV not yet in the air), before its removal (after it, nothing).
    for (k, f) in faults.iter().enumerate() {
        let (uav, at_s, what) = match *f {
            Fault::Glitch { uav, at_s, .. } => (uav, at_s, "position glitch"),
            Fault::StuckSensor { uav, at_s, .. } => (uav, at_s, "stuck sensor"),
            _ => continue,
        };
        for (j, g) in faults.iter().enumerate() {
            let wrong = match *g {
                Fault::Join { uav: u, at_s: joined, .. } if u == uav && at_s <= joined => Some(format!(
                    "{} it joins at {joined} s (fault[{}])",
                    if at_s < joined { "before" } else { "as" },
                    j + 1
                )),
                Fault::Remove { uav: u, at_s: removed } if u == uav && at_s >= removed => Some(format!(
                    "{} it is removed at {removed} s (fault[{}])",
                    if at_s > removed { "after" } else { "as" },
                    j + 1
                )),
                _ => None,
            };
            if let Some(when) = wrong {
                return Err(err(
                    format!("fault[{}].at_s", k + 1),
                    format!(
                        "UAV {}'s {what} starts at {at_s} s, {when}: a sensor fault strikes a UAV in flight, after its \
                         join and before its removal",
                        uav.0 + 1
                    ),
                ));
            }
        }
    }
    somebody_flies(&faults, n, duration_s)?;
    Ok(faults)
}

/// Refuses a schedule under which, at some moment of the flight, no UAV flies (every one
/// removed, or not joined yet): that stretch would be judged on nothing. A UAV flies from its
/// join (or the start) until its removal (or the end); removals at or after the end never
/// happen. Each UAV joins and is removed at most once (checked before).
fn somebody_flies(faults: &[Fault], n: usize, duration_s: f64) -> Result<(), SpecError> {
    // Per UAV with a join or a removal: (its join, its removal), each (fault index, time).
    type Span = (Option<(usize, f64)>, Option<(usize, f64)>);
    let mut spans: std::collections::BTreeMap<usize, Span> = std::collections::BTreeMap::new();
    for (k, f) in faults.iter().enumerate() {
        match *f {
            Fault::Join { uav, at_s, .. } => spans.entry(uav.index()).or_default().0 = Some((k, at_s)),
            Fault::Remove { uav, at_s } => spans.entry(uav.index()).or_default().1 = Some((k, at_s)),
            _ => {}
        }
    }
    // A UAV with neither flies throughout.
    if spans.len() < n {
        return Ok(());
    }
    // (time, +1 a join / −1 a removal, fault index), in time order; at one time the joins
    // first (a UAV that joins as another is removed keeps the sky occupied).
    let mut events: Vec<(f64, i32, usize)> = Vec::new();
    let mut flying = 0i64;
    for (join, remove) in spans.values() {
        match join {
            Some((k, t)) => events.push((*t, 1, *k)),
            None => flying += 1,
        }
        if let Some((k, t)) = remove {
            events.push((*t, -1, *k));
        }
    }
    events.sort_by(|a, b| a.0.total_cmp(&b.0).then(b.1.cmp(&a.1)));
    let next_join = |after: f64| events.iter().find(|e| e.1 > 0 && e.0 > after).map(|e| e.0);
    let mut i = 0;
    if flying == 0 {
        // Nobody at the start: every UAV joins later.
        if let Some(&(t, _, k)) = events.first().filter(|e| e.0 > 1e-9) {
            return Err(err(
                format!("fault[{}].at_s", k + 1),
                format!("no UAV flies before {} s (every one joins later): nothing would be flown or judged", show(t)),
            ));
        }
    }
    while i < events.len() && events[i].0 < duration_s - 1e-9 {
        let t = events[i].0;
        let mut last = events[i].2;
        while i < events.len() && (events[i].0 - t).abs() <= 1e-9 {
            flying += i64::from(events[i].1);
            last = events[i].2;
            i += 1;
        }
        if flying <= 0 {
            let until = match next_join(t + 1e-9).filter(|&t2| t2 < duration_s) {
                Some(t2) => format!("until {} s", show(t2)),
                None => "to the end".into(),
            };
            return Err(err(
                format!("fault[{}].at_s", last + 1),
                format!(
                    "no UAV flies from {} s {until} (every one of the {n} is removed or has not joined yet): \
                     nothing would be flown or judged then",
                    show(t)
                ),
            ));
        }
    }
    Ok(())
}

/// The wind.
pub fn wind(w: &WindSpec) -> Result<Wind, SpecError> {
    let mut out = Wind::default();
    if let Some(v) = w.steady_kmh {
        out.steady_mps = wind_speeds("wind.steady_kmh", v)?.map(kmh);
    }
    let severity = match w.turbulence.as_deref() {
        None | Some("none") => None,
        Some("light") => Some(Severity::Light),
        Some("moderate") => Some(Severity::Moderate),
        Some("severe") => Some(Severity::Severe),
        Some(o) => {
            return Err(err(
                "wind.turbulence",
                format!("unknown turbulence \"{o}\" (expected none, light, moderate or severe)"),
            ))
        }
    };
    let altitude = positive("wind.altitude_m", w.altitude_m.unwrap_or(defaults::TURBULENCE_ALTITUDE_M))?;
    out.turbulence = severity.map(|severity| Turbulence { severity, altitude_m: altitude });
    match (w.gust_at_s, w.gust_duration_s, w.gust_peak_kmh) {
        (None, None, None) => {}
        (Some(at), Some(d), Some(peak)) => {
            out.gust = Some(Gust {
                at_s: non_negative("wind.gust_at_s", at)?,
                duration_s: positive("wind.gust_duration_s", d)?,
                peak_mps: wind_speeds("wind.gust_peak_kmh", peak)?.map(kmh),
            });
        }
        _ => return Err(err("wind.gust_at_s", "a gust needs gust_at_s, gust_duration_s and gust_peak_kmh")),
    }
    Ok(out)
}

/// The transport faults of a distributed run.
pub fn network(n: &crate::spec::NetworkSpec) -> Result<crate::scenario::NetworkFaults, SpecError> {
    let loss = probability("network.loss", n.loss.unwrap_or(0.0))?;
    if loss >= 1.0 {
        return Err(super::values::err("network.loss", "must be below 1: every message lost leaves nothing to fly"));
    }
    let delay_s = non_negative("network.delay_s", n.delay_s.unwrap_or(0.0))?;
    if delay_s > 10.0 {
        return Err(super::values::err("network.delay_s", format!("{delay_s} s: at most 10 s")));
    }
    Ok(crate::scenario::NetworkFaults { loss, delay_s })
}

/// The radio and its beacons.
pub fn radio(r: &RadioSpec, dt_s: f64, duration_s: f64, n: usize) -> Result<(RadioModel, Vec<UavId>), SpecError> {
    let beacons = match &r.beacons {
        Some(b) => b.iter().map(|&id| uav("radio.beacons", id, n)).collect::<Result<_, _>>()?,
        None => Vec::new(),
    };
    let mut m = RadioModel {
        broadcast_all: r.broadcast_all.unwrap_or(false),
        relay_navigator: r.relay_navigator.unwrap_or(false),
        ..Default::default()
    };
    if let Some(v) = r.range_m {
        m.range_m = super::values::distance("radio.range_m", positive("radio.range_m", v)?)?;
    }
    if let Some(v) = r.delay_s {
        let v = non_negative("radio.delay_s", v)?;
        let steps = (v / dt_s).round();
        if v >= duration_s || steps > 10_000.0 {
            return Err(err(
                "radio.delay_s",
                format!(
                    "{v} s is not shorter than the flight ({duration_s} s) or than 10000 periods: no report would \
                     arrive in time to be used"
                ),
            ));
        }
        if (v / dt_s - steps).abs() > 1e-6 {
            return Err(err("radio.delay_s", format!("{v} s is not a multiple of dt_s = {dt_s} s")));
        }
        m.delay_steps = steps as u32;
    }
    if let Some(v) = r.loss {
        m.loss = probability("radio.loss", v)?;
    }
    match (r.burst_p_good_to_bad, r.burst_p_bad_to_good) {
        (None, None) => {
            if r.burst_loss_bad.is_some() {
                return Err(err("radio.burst_loss_bad", "needs burst_p_good_to_bad and burst_p_bad_to_good"));
            }
        }
        (Some(gb), Some(bg)) => {
            m.burst = Some(GilbertElliott {
                p_good_to_bad: probability("radio.burst_p_good_to_bad", gb)?,
                p_bad_to_good: probability("radio.burst_p_bad_to_good", bg)?,
                loss_bad: probability("radio.burst_loss_bad", r.burst_loss_bad.unwrap_or(defaults::BURST_LOSS_BAD))?,
            });
        }
        (None, Some(_)) => return Err(err("radio.burst_p_good_to_bad", "is required with burst_p_bad_to_good")),
        (Some(_), None) => return Err(err("radio.burst_p_bad_to_good", "is required with burst_p_good_to_bad")),
    }
    Ok((m, beacons))
}

fn fault(k: usize, f: &FaultSpec, n: usize) -> Result<Fault, SpecError> {
    let key = format!("fault[{k}]");
    let kind = required(&format!("{key}.kind"), f.kind.clone())?;
    let at_s = non_negative(&format!("{key}.at_s"), required(&format!("{key}.at_s"), f.at_s)?)?;
    let who = || -> Result<UavId, SpecError> { uav(&format!("{key}.uav"), required(&format!("{key}.uav"), f.uav)?, n) };
    let duration = || positive(&format!("{key}.duration_s"), required(&format!("{key}.duration_s"), f.duration_s)?);
    let offset = || -> Result<Vector3<f64>, SpecError> {
        match f.offset_m {
            Some(o) => distance3(&format!("{key}.offset_m"), o),
            None => Ok(Vector3::zeros()),
        }
    };
    // A key the kind does not use is refused, not ignored.
    let takes: &[&str] = match kind.as_str() {
        "remove" => &["uav"],
        "join" => &["uav", "offset_m"],
        "glitch" => &["uav", "duration_s", "offset_m"],
        "stuck_sensor" => &["uav", "duration_s"],
        "radio_blackout" => &["duration_s"],
        _ => &["uav", "duration_s", "offset_m"],
    };
    for (name, given) in
        [("uav", f.uav.is_some()), ("duration_s", f.duration_s.is_some()), ("offset_m", f.offset_m.is_some())]
    {
        if given && !takes.contains(&name) {
            let why = match (kind.as_str(), name) {
                ("stuck_sensor", _) => "it holds the UAV's last reading; a shifted reading is a glitch",
                ("radio_blackout", _) => "a blackout silences every UAV's radio",
                ("remove", "duration_s") => "a removed UAV does not come back (a later join brings one in)",
                _ => "it does not use it",
            };
            return Err(err(format!("{key}.{name}"), format!("a {kind} fault takes no {name}: {why}")));
        }
    }
    Ok(match kind.as_str() {
        "remove" => Fault::Remove { uav: who()?, at_s },
        "join" => Fault::Join { uav: who()?, at_s, offset_m: offset()? },
        "glitch" => {
            let (uav, duration_s, offset_m) = (who()?, duration()?, offset()?);
            if offset_m == Vector3::zeros() {
                return Err(err(
                    format!("{key}.offset_m"),
                    "a glitch shifts the UAV's own position reading by offset_m (m): give a non-zero offset",
                ));
            }
            Fault::Glitch { uav, at_s, duration_s, offset_m }
        }
        "stuck_sensor" => Fault::StuckSensor { uav: who()?, at_s, duration_s: duration()? },
        "radio_blackout" => Fault::RadioBlackout { at_s, duration_s: duration()? },
        o => {
            return Err(err(
                format!("{key}.kind"),
                format!("unknown fault \"{o}\" (expected remove, join, glitch, stuck_sensor or radio_blackout)"),
            ))
        }
    })
}

/// Warnings for faults that start after the flight ends: they never happen.
pub fn faults_after(faults: &[Fault], duration_s: f64) -> Vec<SpecError> {
    faults
        .iter()
        .enumerate()
        .filter_map(|(k, f)| {
            let at = match *f {
                Fault::Remove { at_s, .. }
                | Fault::Join { at_s, .. }
                | Fault::Glitch { at_s, .. }
                | Fault::StuckSensor { at_s, .. }
                | Fault::RadioBlackout { at_s, .. } => at_s,
            };
            (at >= duration_s).then(|| {
                err(
                    format!("fault[{}].at_s", k + 1),
                    format!(
                        "{at} s is not before the end of the flight (duration_s = {duration_s} s): it never happens"
                    ),
                )
            })
        })
        .collect()
}

/// A wind vector (km/h), each component within what a vehicle could fly in.
fn wind_speeds(key: &str, v: [f64; 3]) -> Result<Vector3<f64>, SpecError> {
    let w = vec3(key, v)?;
    for k in 0..3 {
        within(&format!("{key}[{}]", k + 1), w[k], 500.0, "km/h", "stronger than any wind a UAV flies in")?;
    }
    Ok(w)
}
