//! Scenario files: TOML text → [`ScenarioSpec`] → checked [`Scenario`].
//!
//! Parsing rejects malformed TOML, unknown keys and wrong types; [`TryFrom`] then checks every
//! value (finite, in range, consistent) and converts units once (km/h → m/s, degrees →
//! radians). Every error names the key path (`controller.lambda`, `fault[2].at_s`), and
//! [`parse`] adds the source name and the line where that key stands.

use std::collections::BTreeMap;
use std::sync::Arc;

use nalgebra::Vector3;
use proxform_core::angle::{deg, kmh};
use proxform_core::state::{self, State9};
use proxform_core::{
    ControllerParams, DependencySet, Envelope, Formation, FormationFrame, FormationSlot, KinematicLimits,
    KinematicModel, PredictorKind, UavId, VehicleModel,
};

use crate::faults::Fault;
use crate::path::{NavigatorPath, PaperPath, Segment, SegmentsPath};
use crate::scenario::{AllowableErrors, MeasurementNoise, Scenario};
use crate::shapes::Shape;
use crate::spec::{self, ScenarioSpec};

/// A problem with one key of a scenario.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[error("{key}: {message}")]
pub struct SpecError {
    /// Dotted key path, with array indices from 1 (`fault[2].at_s`).
    pub key: String,
    /// What is wrong.
    pub message: String,
}

/// A scenario that could not be loaded, located in its source.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub struct LoadError {
    /// The file name (or other source name).
    pub source_name: String,
    /// 1-based line of the offending key, when known.
    pub line: Option<usize>,
    /// The key path, when known.
    pub key: Option<String>,
    /// What is wrong.
    pub message: String,
}

impl std::fmt::Display for LoadError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "{}", self.source_name)?;
        if let Some(line) = self.line {
            write!(f, ":{line}")?;
        }
        if let Some(key) = &self.key {
            write!(f, ": {key}")?;
        }
        write!(f, ": {}", self.message)
    }
}

/// A slot's `depends_on` table as written: UAV number → degree.
type ExplicitRefs = BTreeMap<String, f64>;

/// Refuses a navigator path that the followers' vehicle cannot fly: its velocity or attitude
/// leaves the vehicle's limits at some instant (the followers would be held at the limit and
/// fall behind, silently). Checked every update period, at most 200 000 instants.
fn within_vehicle(s: &Scenario) -> Result<(), SpecError> {
    let steps = (s.duration_s / s.dt_s).ceil().max(1.0);
    let samples = steps.min(200_000.0) as u64;
    let tol = 1e-6;
    for k in 0..=samples {
        let t = s.duration_s * k as f64 / samples as f64;
        let x = s.path.state_at(t, [0.0; 3]);
        let mut out: Option<(&str, String, f64, f64)> = None;
        match &s.vehicle {
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
                        let angle = proxform_core::angle::wrap_pi(x[state::ALPHA + a]).abs();
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
                let (v, vmin, vmax) = (s.vehicle.forward_speed(&x), m.stall_speed_mps, m.max_speed_mps);
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
            let hint = if matches!(s.vehicle, VehicleModel::Kinematic(_)) {
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

fn err(key: impl Into<String>, message: impl Into<String>) -> SpecError {
    SpecError { key: key.into(), message: message.into() }
}

/// Parses and checks a scenario file's text; `source_name` names it in errors.
pub fn parse(text: &str, source_name: &str) -> Result<Scenario, LoadError> {
    let spec: ScenarioSpec = toml::from_str(text).map_err(|e| {
        let line = e.span().map(|s| line_of(text, s.start));
        LoadError { source_name: source_name.into(), line, key: None, message: e.message().trim().replace('\n', " ") }
    })?;
    let default_name =
        std::path::Path::new(source_name).file_stem().and_then(|s| s.to_str()).unwrap_or("scenario").to_string();
    let spec = ScenarioSpec { name: spec.name.clone().or(Some(default_name)), ..spec };
    Scenario::try_from(spec).map_err(|e| {
        // A missing key is reported where its table starts.
        let mut line = locate(text, &e.key);
        let mut key = e.key.as_str();
        while line.is_none() {
            match key.rsplit_once('.') {
                Some((parent, _)) => {
                    key = parent;
                    line = locate(text, key);
                }
                None => break,
            }
        }
        LoadError { source_name: source_name.into(), line, key: Some(e.key.clone()), message: e.message }
    })
}

/// Longest flight accepted, in update periods.
const MAX_STEPS: f64 = 1e8;
/// Most UAVs a generated shape may have.
const MAX_UAVS: usize = 10_000_000;
/// Most azimuth areas.
const MAX_AREAS: i64 = 1024;

/// The first pair of slots (in index order) closer than `limit`, found with the grid.
fn closest_pair_within(slots: &[FormationSlot], limit: f64) -> Option<(usize, usize, f64)> {
    let mut grid = crate::grid::NeighbourGrid::new();
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

fn line_of(text: &str, offset: usize) -> usize {
    text[..offset.min(text.len())].bytes().filter(|b| *b == b'\n').count() + 1
}

/// Finds the line of a key path such as `controller.lambda` or `fault[2].at_s`: under the
/// matching `[table]` or the n-th `[[array]]` header, the line that assigns the first key
/// component not in the header (a key inside an inline table is reported at its table's line).
pub fn locate(text: &str, key: &str) -> Option<usize> {
    let parts: Vec<(String, Option<usize>)> = key
        .split('.')
        .map(|p| match p.split_once('[') {
            Some((name, idx)) => (name.to_string(), idx.trim_end_matches(']').parse().ok()),
            None => (p.to_string(), None),
        })
        .collect();
    let mut header: Vec<String> = Vec::new();
    let mut counts: BTreeMap<String, usize> = BTreeMap::new();
    let mut best: Option<usize> = None;
    // A sub-table of the key (`[[formation.slot]]` for `formation`) stands for it if the key
    // has no header of its own.
    let mut sub: Option<usize> = None;
    let names: Vec<&str> = parts.iter().map(|p| p.0.as_str()).collect();
    for (n, raw) in text.lines().enumerate() {
        let line = raw.split('#').next().unwrap_or("").trim();
        if let Some(h) = line.strip_prefix("[[").and_then(|l| l.strip_suffix("]]")) {
            let name = h.trim().to_string();
            *counts.entry(name.clone()).or_default() += 1;
            header = name.split('.').map(|s| s.trim().to_string()).collect();
            if sub.is_none() && header.len() > names.len() && header.iter().zip(&names).all(|(h, p)| h == p) {
                sub = Some(n + 1);
            }
            let idx = counts[&name];
            // An array-of-tables header matches `name[idx]` prefixes.
            if header_matches(&header, Some(idx), &parts) && parts.len() == header.len() {
                best = Some(n + 1);
            }
            header.push(format!("#{idx}"));
            continue;
        }
        if let Some(h) = line.strip_prefix('[').and_then(|l| l.strip_suffix(']')) {
            header = h.split('.').map(|s| s.trim().to_string()).collect();
            if sub.is_none() && header.len() > names.len() && header.iter().zip(&names).all(|(h, p)| h == p) {
                sub = Some(n + 1);
            }
            if header_matches(&header, None, &parts) && parts.len() == header.len() {
                best = Some(n + 1);
            }
            continue;
        }
        let Some((k, _)) = line.split_once('=') else { continue };
        let k = k.trim().trim_matches('"');
        let mut path: Vec<String> = header.clone();
        path.extend(k.split('.').map(|s| s.trim().to_string()));
        if path_matches(&path, &parts) {
            return Some(n + 1);
        }
    }
    best.or(sub)
}

fn header_matches(header: &[String], idx: Option<usize>, parts: &[(String, Option<usize>)]) -> bool {
    if header.len() > parts.len() {
        return false;
    }
    for (k, h) in header.iter().enumerate() {
        if parts[k].0 != *h {
            return false;
        }
    }
    match idx {
        Some(i) => parts[header.len() - 1].1 == Some(i),
        None => true,
    }
}

/// Whether a flattened line path (header components, `#n` array markers, key components) is a
/// prefix-compatible match for the wanted key path.
fn path_matches(path: &[String], parts: &[(String, Option<usize>)]) -> bool {
    let mut p = 0;
    let mut k = 0;
    while p < path.len() {
        if k >= parts.len() {
            return false;
        }
        if parts[k].0 != path[p] {
            return false;
        }
        p += 1;
        if let Some(i) = parts[k].1 {
            if p < path.len() && path[p] == format!("#{i}") {
                p += 1;
            } else if p < path.len() && path[p].starts_with('#') {
                return false;
            }
        } else if p < path.len() && path[p].starts_with('#') {
            p += 1;
        }
        k += 1;
    }
    k >= 1
}

/// Checks a float is finite.
fn finite(key: &str, v: f64) -> Result<f64, SpecError> {
    if v.is_finite() {
        Ok(v)
    } else {
        Err(err(key, format!("{v} is not a finite number")))
    }
}

fn positive(key: &str, v: f64) -> Result<f64, SpecError> {
    let v = finite(key, v)?;
    if v > 0.0 {
        Ok(v)
    } else {
        Err(err(key, format!("must be > 0, found {v}")))
    }
}

fn non_negative(key: &str, v: f64) -> Result<f64, SpecError> {
    let v = finite(key, v)?;
    if v >= 0.0 {
        Ok(v)
    } else {
        Err(err(key, format!("must be ≥ 0, found {v}")))
    }
}

fn probability(key: &str, v: f64) -> Result<f64, SpecError> {
    let v = finite(key, v)?;
    if (0.0..=1.0).contains(&v) {
        Ok(v)
    } else {
        Err(err(key, format!("must be a probability in [0, 1], found {v}")))
    }
}

fn vec3(key: &str, v: [f64; 3]) -> Result<Vector3<f64>, SpecError> {
    for (k, x) in v.iter().enumerate() {
        finite(&format!("{key}[{}]", k + 1), *x)?;
    }
    Ok(Vector3::new(v[0], v[1], v[2]))
}

fn required<T>(key: &str, v: Option<T>) -> Result<T, SpecError> {
    v.ok_or_else(|| err(key, "is required"))
}

fn uav(key: &str, number: u32, n: usize) -> Result<UavId, SpecError> {
    if number >= 1 && (number as usize) <= n {
        Ok(UavId(number - 1))
    } else {
        Err(err(key, format!("UAV {number} is not in the formation (UAVs are numbered 1 to {n})")))
    }
}

impl TryFrom<ScenarioSpec> for Scenario {
    type Error = SpecError;

    fn try_from(spec: ScenarioSpec) -> Result<Self, SpecError> {
        let mut s = Scenario::paper();
        s.name = spec.name.clone().unwrap_or_else(|| "scenario".into());
        if let Some(v) = spec.dt_s {
            s.dt_s = positive("dt_s", v)?;
        }
        if let Some(v) = spec.duration_s {
            s.duration_s = positive("duration_s", v)?;
        }
        if s.duration_s / s.dt_s > MAX_STEPS {
            return Err(err(
                "duration_s",
                format!("{} s at Δt = {} s is more than {MAX_STEPS:e} steps", s.duration_s, s.dt_s),
            ));
        }
        if let Some(v) = spec.safety_distance_m {
            s.safety_distance_m = positive("safety_distance_m", v)?;
        }
        if let Some(v) = spec.warmup_s {
            s.warmup_s = non_negative("warmup_s", v)?;
        }
        s.vehicle = vehicle(spec.vehicle.clone().unwrap_or_default())?;
        let fixed_wing = matches!(s.vehicle, VehicleModel::FixedWing(_));
        s.controller = controller(spec.controller.clone().unwrap_or_default(), s.dt_s, fixed_wing)?;
        s.controller.bank_turn_feedforward =
            spec.controller.as_ref().and_then(|c| c.bank_turn_feedforward).unwrap_or(fixed_wing);

        // Formation and dependency tables.
        let fspec = required("formation", spec.formation.clone())?;
        let (slots, explicit_deps) = formation_slots(&fspec)?;
        let n = slots.len();
        if n < 2 {
            return Err(err("formation", format!("needs at least 2 UAVs, found {n}")));
        }
        s.navigator = uav("navigator", spec.navigator.unwrap_or(1), n)?;
        let frame = match fspec.frame.as_deref() {
            None | Some("world") => FormationFrame::World,
            Some("course") => FormationFrame::Course,
            Some(other) => {
                return Err(err(
                    "formation.frame",
                    format!("unknown frame \"{other}\" (expected \"world\" or \"course\")"),
                ))
            }
        };
        if let Some((a, b, d)) = closest_pair_within(&slots, s.safety_distance_m) {
            return Err(err(
                "formation",
                format!(
                    "UAVs {} and {} are {d:.1} m apart, closer than the safety distance {} m",
                    a + 1,
                    b + 1,
                    s.safety_distance_m
                ),
            ));
        }
        let auto = fspec.dependencies.clone().unwrap_or_default();
        let k = auto.k.unwrap_or(2) as usize;
        if k == 0 {
            return Err(err("formation.dependencies.k", "must be ≥ 1"));
        }
        let max_d = match auto.max_distance_m {
            Some(v) => positive("formation.dependencies.max_distance_m", v)?,
            None => s.controller.areas.sensing_range_m,
        };
        let nav_degree = match auto.navigator_degree {
            Some(v) => {
                let v = probability("formation.dependencies.navigator_degree", v)?;
                if v >= 1.0 {
                    return Err(err("formation.dependencies.navigator_degree", "must be below 1"));
                }
                v
            }
            None => 0.0,
        };
        let derived = crate::autodeps::derive(&slots, s.navigator, k, max_d, nav_degree)
            .map_err(|e| err("formation.dependencies", e.to_string()))?;
        s.dependencies = (0..n)
            .map(|i| match &explicit_deps[i] {
                Some(refs) => {
                    let key = format!("formation.slot[{}].depends_on", i + 1);
                    let mut out = Vec::new();
                    for (id, degree) in refs {
                        let j: u32 = id.parse().map_err(|_| err(&key, format!("\"{id}\" is not a UAV number")))?;
                        let j = uav(&key, j, n)?;
                        if j.index() == i {
                            return Err(err(&key, format!("UAV {} cannot depend on itself", i + 1)));
                        }
                        let d = finite(&key, *degree)?;
                        if d <= 0.0 {
                            return Err(err(&key, format!("degree of UAV {id} must be > 0, found {d}")));
                        }
                        out.push((j, d));
                    }
                    DependencySet::new(UavId(i as u32), n, out).map_err(|e| err(&key, e.to_string()))
                }
                None => Ok(derived[i].clone()),
            })
            .collect::<Result<_, _>>()?;
        s.formation = Arc::new(Formation { slots: slots.clone(), frame });

        // Path and initial states.
        s.path = path(spec.path.clone().unwrap_or_default(), s.duration_s)?;
        let nav0 = s.path.state_at(0.0, [0.0; 3]);
        let speed = match spec.initial.as_ref().and_then(|i| i.speed_kmh) {
            Some(v) => Some(kmh(positive("initial.speed_kmh", v)?)),
            None => None,
        };
        s.initial = crate::scenario::in_slots(&s.formation, s.navigator, &nav0);
        if let Some(v) = speed {
            let h = nav0[state::VX].hypot(nav0[state::VY]).max(1e-9);
            for x in &mut s.initial {
                x[state::VX] = v * nav0[state::VX] / h;
                x[state::VY] = v * nav0[state::VY] / h;
            }
        }
        let (vmin, vmax) = s.vehicle.forward_speed_range();
        let kinematic = matches!(s.vehicle, VehicleModel::Kinematic(_));
        for (i, x) in s.initial.iter().enumerate() {
            let v = s.vehicle.forward_speed(x);
            if v < vmin - 1e-9 || v > vmax + 1e-9 {
                // Blame the key that set the speed: the initial speed, the path's, or the
                // vehicle's bound for the paper's fixed-speed path.
                let path_speed = spec.path.as_ref().is_some_and(|p| p.speed_kmh.is_some());
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

        within_vehicle(&s)?;

        // Noise, sensing, radio, pass criterion, faults.
        let noise = spec.noise.clone().unwrap_or_default();
        if let Some(v) = noise.position_m {
            s.noise.position_m = non_negative("noise.position_m", v)?;
        }
        if let Some(v) = noise.velocity_kmh {
            s.noise.velocity_mps = kmh(non_negative("noise.velocity_kmh", v)?);
        }
        if let Some(v) = noise.attitude_deg {
            s.noise.attitude_rad = deg(non_negative("noise.attitude_deg", v)?);
        }
        if let Some(v) = noise.actuation_error {
            s.actuation_error = probability("noise.actuation_error", v)?;
        }
        match (noise.gnss_bias_m, noise.gnss_tau_s) {
            (Some(sigma), tau) => {
                s.gnss_bias = Some(crate::scenario::CorrelatedNoise {
                    sigma_m: non_negative("noise.gnss_bias_m", sigma)?,
                    tau_s: positive("noise.gnss_tau_s", tau.unwrap_or(60.0))?,
                });
            }
            (None, Some(_)) => return Err(err("noise.gnss_tau_s", "needs noise.gnss_bias_m")),
            (None, None) => {}
        }
        s.noise = MeasurementNoise { ..s.noise };
        if let Some(v) = spec.sensing.as_ref().and_then(|x| x.dropout) {
            s.dropout = probability("sensing.dropout", v)?;
        }
        if let Some(v) = spec.sensing.as_ref().and_then(|x| x.reference_dropout) {
            s.reference_dropout = Some(probability("sensing.reference_dropout", v)?);
        }
        if let Some(r) = spec.radio.clone() {
            if let Some(b) = &r.beacons {
                s.beacons = b.iter().map(|&id| uav("radio.beacons", id, n)).collect::<Result<_, _>>()?;
            }
            s.radio = radio(&r, s.dt_s)?;
        }
        let a = spec.allowable.clone().unwrap_or_default();
        let cur = s.allowable;
        s.allowable = AllowableErrors {
            position_m: [
                a.x_m.map_or(Ok(cur.position_m[0]), |v| positive("allowable.x_m", v))?,
                a.y_m.map_or(Ok(cur.position_m[1]), |v| positive("allowable.y_m", v))?,
                a.z_m.map_or(Ok(cur.position_m[2]), |v| positive("allowable.z_m", v))?,
            ],
            attitude_rad: [
                a.alpha_deg.map_or(Ok(cur.attitude_rad[0]), |v| positive("allowable.alpha_deg", v).map(deg))?,
                a.beta_deg.map_or(Ok(cur.attitude_rad[1]), |v| positive("allowable.beta_deg", v).map(deg))?,
                a.gamma_deg.map_or(Ok(cur.attitude_rad[2]), |v| positive("allowable.gamma_deg", v).map(deg))?,
            ],
        };
        if let Some(w) = spec.wind.clone() {
            s.wind = wind(&w)?;
        }
        s.faults = spec.fault.iter().enumerate().map(|(k, f)| fault(k + 1, f, n)).collect::<Result<_, _>>()?;
        if let Some(label) = spec.controller.as_ref().and_then(|c| c.method.as_deref()) {
            let m = proxform_core::Method::from_label(label).ok_or_else(|| {
                err(
                    "controller.method",
                    format!("unknown method '{label}' (known: {})", proxform_core::Method::LABELS.join(", ")),
                )
            })?;
            s.set_method(m);
        }
        s.validate().map_err(|e| err("scenario", e.to_string()))?;
        Ok(s)
    }
}

fn formation_slots(f: &spec::FormationSpec) -> Result<(Vec<FormationSlot>, Vec<Option<ExplicitRefs>>), SpecError> {
    match (&f.shape, f.slot.is_empty()) {
        (Some(_), false) => {
            Err(err("formation", "give either [[formation.slot]] entries or a [formation.shape], not both"))
        }
        (None, true) => Err(err("formation", "needs [[formation.slot]] entries or a [formation.shape]")),
        (Some(shape), true) => {
            let slots = shape_of(shape)?.slots();
            let n = slots.len();
            Ok((slots, vec![None; n]))
        }
        (None, false) => {
            let n = f.slot.len();
            let mut slots = vec![None; n];
            let mut deps = vec![None; n];
            for (k, s) in f.slot.iter().enumerate() {
                let key = format!("formation.slot[{}]", k + 1);
                let id = required(&format!("{key}.id"), s.id)?;
                if id == 0 || id as usize > n {
                    return Err(err(
                        format!("{key}.id"),
                        format!("UAV numbers run from 1 to {n} (the number of slots), found {id}"),
                    ));
                }
                let i = id as usize - 1;
                if slots[i].is_some() {
                    return Err(err(format!("{key}.id"), format!("duplicate id {id}")));
                }
                let offset = vec3(&format!("{key}.offset_m"), required(&format!("{key}.offset_m"), s.offset_m)?)?;
                let att = match s.attitude_offset_deg {
                    Some(a) => vec3(&format!("{key}.attitude_offset_deg"), a)?.map(deg),
                    None => Vector3::zeros(),
                };
                slots[i] = Some(FormationSlot { offset_m: offset, attitude_offset_rad: att });
                deps[i] = s.depends_on.clone();
            }
            let slots = slots.into_iter().map(|s| s.unwrap_or(FormationSlot::at(0.0, 0.0, 0.0))).collect();
            Ok((slots, deps))
        }
    }
}

fn shape_of(s: &spec::ShapeSpec) -> Result<Shape, SpecError> {
    let kind = required("formation.shape.kind", s.kind.clone())?;
    let uavs = || -> Result<usize, SpecError> {
        let n = required("formation.shape.uavs", s.uavs)? as usize;
        if !(2..=MAX_UAVS).contains(&n) {
            return Err(err("formation.shape.uavs", format!("needs 2 to {MAX_UAVS} UAVs, found {n}")));
        }
        Ok(n)
    };
    let spacing = || positive("formation.shape.spacing_m", required("formation.shape.spacing_m", s.spacing_m)?);
    let angle = || -> Result<f64, SpecError> {
        let a = finite("formation.shape.angle_deg", s.angle_deg.unwrap_or(30.0))?;
        if a <= 0.0 || a >= 90.0 {
            return Err(err("formation.shape.angle_deg", format!("must be in (0, 90), found {a}")));
        }
        Ok(deg(a))
    };
    let level = || finite("formation.shape.level_step_m", s.level_step_m.unwrap_or(0.0));
    Ok(match kind.as_str() {
        "triangle" => {
            let rows = required("formation.shape.rows", s.rows)? as usize;
            if !(2..=4000).contains(&rows) {
                return Err(err("formation.shape.rows", format!("needs 2 to 4000 rows, found {rows}")));
            }
            Shape::Triangle { rows, spacing: spacing()?, level_step: level()? }
        }
        "v" => Shape::V { uavs: uavs()?, spacing: spacing()?, angle: angle()?, level_step: level()? },
        "echelon" => {
            let left = match s.side.as_deref() {
                None | Some("right") => false,
                Some("left") => true,
                Some(o) => return Err(err("formation.shape.side", format!("unknown side \"{o}\" (expected \"left\" or \"right\")"))),
            };
            Shape::Echelon { uavs: uavs()?, spacing: spacing()?, angle: angle()?, left, level_step: level()? }
        }
        "line_abreast" => Shape::LineAbreast { uavs: uavs()?, spacing: spacing()?, level_step: level()? },
        "column" => Shape::Column { uavs: uavs()?, spacing: spacing()?, level_step: level()? },
        "diamond" => Shape::Diamond { uavs: uavs()?, spacing: spacing()? },
        "grid" => Shape::Grid { uavs: uavs()?, spacing: spacing()? },
        "circle" => Shape::Circle { uavs: uavs()?, radius: spacing()? },
        "lattice" => {
            let n = uavs()?;
            let levels = match s.levels {
                Some(0) => return Err(err("formation.shape.levels", "must be ≥ 1")),
                Some(l) => l as usize,
                None => crate::swarm::default_levels(n),
            };
            Shape::Lattice { uavs: n, spacing: spacing()?, levels, level_step: level()? }
        }
        other => {
            return Err(err(
                "formation.shape.kind",
                format!("unknown shape \"{other}\" (expected triangle, v, echelon, line_abreast, column, diamond, grid, lattice or circle)"),
            ))
        }
    })
}

/// The controller's parameters; unset permissible errors take the vehicle's defaults.
fn controller(c: spec::ControllerSpec, dt_s: f64, fixed_wing: bool) -> Result<ControllerParams, SpecError> {
    let mut p = ControllerParams { dt_s, ..ControllerParams::default() };
    if fixed_wing {
        p.envelope.thresholds = ControllerParams::fixed_wing_thresholds();
    }
    if let Some(m) = c.areas {
        if !(1..=MAX_AREAS).contains(&m) {
            return Err(err("controller.areas", format!("m must be between 1 and {MAX_AREAS}, found {m}")));
        }
        p.areas.areas = m as usize;
    }
    if let Some(v) = c.sensing_range_m {
        p.areas.sensing_range_m = positive("controller.sensing_range_m", v)?;
    }
    if let Some(v) = c.lambda {
        let v = finite("controller.lambda", v)?;
        if !(0.0..=1.0).contains(&v) {
            return Err(err("controller.lambda", format!("λ must be in [0, 1], found {v}")));
        }
        p.lambda = v;
    }
    if let Some(v) = c.rho {
        let v = positive("controller.rho", v)?;
        if v > 1.0 {
            return Err(err("controller.rho", format!("ρ must be in (0, 1], found {v}")));
        }
        p.envelope.rho = v;
    }
    if let Some(v) = c.closing_time_s {
        let v = non_negative("controller.closing_time_s", v)?;
        p.closing_time_s = (v > 0.0).then_some(v);
    }
    if let Some(v) = c.input_weight {
        p.input_weight = non_negative("controller.input_weight", v)?;
    }
    if let Some(v) = c.track_timeout_s {
        p.track_timeout_s = positive("controller.track_timeout_s", v)?;
    }
    if let Some(v) = c.coast_s {
        p.coast_s = non_negative("controller.coast_s", v)?;
    }
    if let Some(v) = c.coast_accel_s {
        p.coast_accel_s = non_negative("controller.coast_accel_s", v)?;
    }
    if let Some(v) = c.coast_decay_s {
        p.coast_decay_s = positive("controller.coast_decay_s", v)?;
    }
    if let Some(v) = c.horizon {
        if !(1..=i64::from(proxform_core::controller::MAX_HORIZON)).contains(&v) {
            return Err(err("controller.horizon", format!("must be an integer from 1 to 50, found {v}")));
        }
        p.horizon = v as u32;
    }
    if let Some(v) = c.separation_m {
        p.separation_m = Some(non_negative("controller.separation_m", v)?);
    }
    if let Some(v) = c.own_filter_gain {
        let v = positive("controller.own_filter_gain", v)?;
        if v > 1.0 {
            return Err(err("controller.own_filter_gain", format!("must be in (0, 1], found {v}")));
        }
        p.own_filter_gain = v;
    }
    p.predictor = match c.predictor.as_deref() {
        None | Some("alpha_beta") => {
            let alpha = c.predictor_alpha.unwrap_or(0.8);
            let alpha = positive("controller.predictor_alpha", alpha)?;
            if alpha > 1.0 {
                return Err(err("controller.predictor_alpha", format!("must be in (0, 1], found {alpha}")));
            }
            let beta = match c.predictor_beta {
                Some(b) => probability("controller.predictor_beta", b)?,
                None => alpha * alpha / (2.0 - alpha),
            };
            PredictorKind::AlphaBeta { alpha, beta }
        }
        Some("constant_velocity") => PredictorKind::ConstantVelocity,
        Some(o) => {
            return Err(err(
                "controller.predictor",
                format!("unknown predictor \"{o}\" (expected \"alpha_beta\" or \"constant_velocity\")"),
            ))
        }
    };
    if let Some(t) = c.thresholds {
        let mut d = p.envelope.thresholds;
        let set =
            |d: &mut State9, k: usize, key: &str, v: Option<f64>, scale: fn(f64) -> f64| -> Result<(), SpecError> {
                if let Some(v) = v {
                    d[k] = scale(positive(key, v)?);
                }
                Ok(())
            };
        let id = |v| v;
        set(&mut d, 0, "controller.thresholds.x_m", t.x_m, id)?;
        set(&mut d, 1, "controller.thresholds.y_m", t.y_m, id)?;
        set(&mut d, 2, "controller.thresholds.z_m", t.z_m, id)?;
        set(&mut d, 3, "controller.thresholds.vx_kmh", t.vx_kmh, kmh)?;
        set(&mut d, 4, "controller.thresholds.vy_kmh", t.vy_kmh, kmh)?;
        set(&mut d, 5, "controller.thresholds.vz_kmh", t.vz_kmh, kmh)?;
        set(&mut d, 6, "controller.thresholds.alpha_deg", t.alpha_deg, deg)?;
        set(&mut d, 7, "controller.thresholds.beta_deg", t.beta_deg, deg)?;
        set(&mut d, 8, "controller.thresholds.gamma_deg", t.gamma_deg, deg)?;
        p.envelope = Envelope { thresholds: d, ..p.envelope };
    }
    Ok(p)
}

fn vehicle(v: spec::VehicleSpec) -> Result<VehicleModel, SpecError> {
    let kinematic_keys = [
        ("vx_min_kmh", v.vx_min_kmh.is_some()),
        ("vx_max_kmh", v.vx_max_kmh.is_some()),
        ("vy_max_kmh", v.vy_max_kmh.is_some()),
        ("vz_max_kmh", v.vz_max_kmh.is_some()),
        ("attitude_max_deg", v.attitude_max_deg.is_some()),
        ("accel_kmh_s", v.accel_kmh_s.is_some()),
        ("attitude_rate_deg_s", v.attitude_rate_deg_s.is_some()),
    ];
    let fixed_keys = [
        ("stall_speed_kmh", v.stall_speed_kmh.is_some()),
        ("max_speed_kmh", v.max_speed_kmh.is_some()),
        ("bank_max_deg", v.bank_max_deg.is_some()),
        ("load_factor_max", v.load_factor_max.is_some()),
        ("pitch_max_deg", v.pitch_max_deg.is_some()),
        ("roll_rate_max_deg_s", v.roll_rate_max_deg_s.is_some()),
        ("pitch_rate_max_deg_s", v.pitch_rate_max_deg_s.is_some()),
        ("yaw_rate_max_deg_s", v.yaw_rate_max_deg_s.is_some()),
        ("throttle_accel_kmh_s", v.throttle_accel_kmh_s.is_some()),
    ];
    let model = v.model.as_deref().unwrap_or("kinematic");
    let foreign = match model {
        "kinematic" => fixed_keys.iter().find(|k| k.1).map(|k| (k.0, "fixed_wing")),
        "fixed_wing" => kinematic_keys.iter().find(|k| k.1).map(|k| (k.0, "kinematic")),
        o => {
            return Err(err(
                "vehicle.model",
                format!("unknown model \"{o}\" (expected \"kinematic\" or \"fixed_wing\")"),
            ))
        }
    };
    if let Some((key, owner)) = foreign {
        return Err(err(format!("vehicle.{key}"), format!("applies to model = \"{owner}\", not \"{model}\"")));
    }
    if model == "fixed_wing" {
        let mut m = proxform_core::FixedWingModel::default();
        let set = |key: &str, v: Option<f64>, scale: fn(f64) -> f64, dst: &mut f64| -> Result<(), SpecError> {
            if let Some(x) = v {
                *dst = scale(positive(&format!("vehicle.{key}"), x)?);
            }
            Ok(())
        };
        set("stall_speed_kmh", v.stall_speed_kmh, kmh, &mut m.stall_speed_mps)?;
        set("max_speed_kmh", v.max_speed_kmh, kmh, &mut m.max_speed_mps)?;
        set("bank_max_deg", v.bank_max_deg, deg, &mut m.bank_max_rad)?;
        set("load_factor_max", v.load_factor_max, |x| x, &mut m.load_factor_max)?;
        set("pitch_max_deg", v.pitch_max_deg, deg, &mut m.pitch_max_rad)?;
        set("roll_rate_max_deg_s", v.roll_rate_max_deg_s, deg, &mut m.roll_rate_max_radps)?;
        set("pitch_rate_max_deg_s", v.pitch_rate_max_deg_s, deg, &mut m.pitch_rate_max_radps)?;
        set("yaw_rate_max_deg_s", v.yaw_rate_max_deg_s, deg, &mut m.yaw_rate_max_radps)?;
        set("throttle_accel_kmh_s", v.throttle_accel_kmh_s, kmh, &mut m.accel_max_mps2)?;
        if m.stall_speed_mps >= m.max_speed_mps {
            return Err(err("vehicle.stall_speed_kmh", "must be below vehicle.max_speed_kmh"));
        }
        if m.load_factor_max < 1.0 {
            return Err(err("vehicle.load_factor_max", format!("must be ≥ 1, found {}", m.load_factor_max)));
        }
        return Ok(VehicleModel::FixedWing(m));
    }
    let mut l = KinematicLimits::default();
    if let Some(x) = v.vx_min_kmh {
        l.vx_min_mps = kmh(positive("vehicle.vx_min_kmh", x)?);
    }
    if let Some(x) = v.vx_max_kmh {
        l.vx_max_mps = kmh(positive("vehicle.vx_max_kmh", x)?);
    }
    if l.vx_min_mps >= l.vx_max_mps {
        return Err(err("vehicle.vx_min_kmh", "must be below vehicle.vx_max_kmh"));
    }
    if let Some(x) = v.vy_max_kmh {
        l.vy_max_mps = kmh(positive("vehicle.vy_max_kmh", x)?);
    }
    if let Some(x) = v.vz_max_kmh {
        l.vz_max_mps = kmh(positive("vehicle.vz_max_kmh", x)?);
    }
    let pos3 = |key: &str, a: [f64; 3]| -> Result<Vector3<f64>, SpecError> {
        let v = vec3(key, a)?;
        for k in 0..3 {
            positive(&format!("{key}[{}]", k + 1), v[k])?;
        }
        Ok(v)
    };
    if let Some(a) = v.attitude_max_deg {
        l.attitude_max_rad = pos3("vehicle.attitude_max_deg", a)?.map(deg);
    }
    if let Some(a) = v.accel_kmh_s {
        l.accel_max_mps2 = pos3("vehicle.accel_kmh_s", a)?.map(kmh);
    }
    if let Some(a) = v.attitude_rate_deg_s {
        l.attitude_rate_max_radps = pos3("vehicle.attitude_rate_deg_s", a)?.map(deg);
    }
    Ok(VehicleModel::Kinematic(KinematicModel { limits: l }))
}

fn path(p: spec::PathSpec, duration_s: f64) -> Result<NavigatorPath, SpecError> {
    match p.kind.as_deref() {
        None | Some("paper") => {
            if p.speed_kmh.is_some()
                || p.course_deg.is_some()
                || p.transition_s.is_some()
                || !p.segment.is_empty()
                || p.points_m.is_some()
                || p.turn_radius_m.is_some()
            {
                return Err(err("path", "the paper path takes no speed, course or segments (use kind = \"segments\")"));
            }
            Ok(NavigatorPath::Paper(PaperPath::default()))
        }
        Some("segments") => {
            let v0 = kmh(positive("path.speed_kmh", required("path.speed_kmh", p.speed_kmh)?)?);
            let course = deg(finite("path.course_deg", p.course_deg.unwrap_or(0.0))?);
            let mut speed = v0;
            let mut segments = Vec::new();
            for (k, s) in p.segment.iter().enumerate() {
                let key = format!("path.segment[{}]", k + 1);
                let d = positive(&format!("{key}.duration_s"), required(&format!("{key}.duration_s"), s.duration_s)?)?;
                let w = deg(finite(&format!("{key}.turn_rate_deg_s"), s.turn_rate_deg_s.unwrap_or(0.0))?);
                let c = kmh(finite(&format!("{key}.climb_kmh"), s.climb_kmh.unwrap_or(0.0))?);
                if let Some(v) = s.speed_kmh {
                    speed = kmh(positive(&format!("{key}.speed_kmh"), v)?);
                }
                segments.push(Segment { duration_s: d, turn_rate_radps: w, climb_mps: c, end_speed_mps: speed });
            }
            let transition = positive("path.transition_s", p.transition_s.unwrap_or(8.0))?;
            Ok(NavigatorPath::Segments(SegmentsPath::new(v0, course, segments, transition, duration_s + 1.0)))
        }
        Some("waypoints") => {
            if !p.segment.is_empty() {
                return Err(err("path.segment", "a waypoints path takes points_m, not segments"));
            }
            let v = kmh(positive("path.speed_kmh", required("path.speed_kmh", p.speed_kmh)?)?);
            let r = positive("path.turn_radius_m", required("path.turn_radius_m", p.turn_radius_m)?)?;
            let points = required("path.points_m", p.points_m.clone())?;
            let transition = positive("path.transition_s", p.transition_s.unwrap_or(8.0))?;
            let segments = waypoint_segments(&points, v, r, transition)?;
            let course = segments.1;
            Ok(NavigatorPath::Segments(SegmentsPath::new(v, course, segments.0, transition, duration_s + 1.0)))
        }
        Some(o) => {
            Err(err("path.kind", format!("unknown path \"{o}\" (expected \"paper\", \"segments\" or \"waypoints\")")))
        }
    }
}

fn wind(w: &spec::WindSpec) -> Result<crate::disturbance::Wind, SpecError> {
    use crate::disturbance::{Gust, Severity, Turbulence, Wind};
    let mut out = Wind::default();
    if let Some(v) = w.steady_kmh {
        out.steady_mps = vec3("wind.steady_kmh", v)?.map(kmh);
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
    let altitude = positive("wind.altitude_m", w.altitude_m.unwrap_or(300.0))?;
    out.turbulence = severity.map(|severity| Turbulence { severity, altitude_m: altitude });
    match (w.gust_at_s, w.gust_duration_s, w.gust_peak_kmh) {
        (None, None, None) => {}
        (Some(at), Some(d), Some(peak)) => {
            out.gust = Some(Gust {
                at_s: non_negative("wind.gust_at_s", at)?,
                duration_s: positive("wind.gust_duration_s", d)?,
                peak_mps: vec3("wind.gust_peak_kmh", peak)?.map(kmh),
            });
        }
        _ => return Err(err("wind.gust_at_s", "a gust needs gust_at_s, gust_duration_s and gust_peak_kmh")),
    }
    Ok(out)
}

fn radio(r: &spec::RadioSpec, dt_s: f64) -> Result<crate::radio::RadioModel, SpecError> {
    let mut m = crate::radio::RadioModel { broadcast_all: r.broadcast_all.unwrap_or(false), ..Default::default() };
    if let Some(v) = r.range_m {
        m.range_m = positive("radio.range_m", v)?;
    }
    if let Some(v) = r.delay_s {
        let v = non_negative("radio.delay_s", v)?;
        let steps = (v / dt_s).round();
        if (v / dt_s - steps).abs() > 1e-6 || steps > 10_000.0 {
            return Err(err(
                "radio.delay_s",
                format!("{v} s is not a multiple of dt_s = {dt_s} s (at most 10000 periods)"),
            ));
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
            m.burst = Some(crate::radio::GilbertElliott {
                p_good_to_bad: probability("radio.burst_p_good_to_bad", gb)?,
                p_bad_to_good: probability("radio.burst_p_bad_to_good", bg)?,
                loss_bad: probability("radio.burst_loss_bad", r.burst_loss_bad.unwrap_or(1.0))?,
            });
        }
        (None, Some(_)) => return Err(err("radio.burst_p_good_to_bad", "is required with burst_p_bad_to_good")),
        (Some(_), None) => return Err(err("radio.burst_p_bad_to_good", "is required with burst_p_good_to_bad")),
    }
    Ok(m)
}

/// Turns waypoints (relative to the start) into straight legs joined by turns of radius `r`
/// at speed `v`; returns the segments and the initial course. Each leg's height change is
/// flown as a constant climb over its straight part. Turn rates blend in over `transition_s`,
/// which delays a turn by half of it; each turn therefore starts that much earlier.
fn waypoint_segments(points: &[[f64; 3]], v: f64, r: f64, transition_s: f64) -> Result<(Vec<Segment>, f64), SpecError> {
    if points.is_empty() {
        return Err(err("path.points_m", "needs at least one point"));
    }
    let mut all = vec![[0.0f64; 3]];
    for (k, p) in points.iter().enumerate() {
        vec3(&format!("path.points_m[{}]", k + 1), *p)?;
        // A list that starts with the start itself, [0, 0, 0], names it twice.
        if k == 0 && *p == [0.0; 3] && points.len() > 1 {
            continue;
        }
        all.push(*p);
    }
    let legs: Vec<(f64, f64, f64)> = all
        .windows(2)
        .map(|w| {
            let (dx, dy) = (w[1][0] - w[0][0], w[1][1] - w[0][1]);
            (dx.hypot(dy), dy.atan2(dx), w[1][2] - w[0][2])
        })
        .collect();
    if let Some(k) = legs.iter().position(|l| l.0 < 1e-6) {
        return Err(err(
            format!("path.points_m[{}]", k + 1),
            "repeats the previous point (legs need a horizontal length)",
        ));
    }
    // Turn at each inner waypoint: course change, and the tangent length it takes off each leg.
    let turns: Vec<f64> = legs.windows(2).map(|w| proxform_core::angle::wrap_pi(w[1].1 - w[0].1)).collect();
    let cut = |k: usize| -> f64 { turns.get(k).map_or(0.0, |d| r * (d.abs() / 2.0).tan()) };
    let mut segments = Vec::new();
    let lead = 0.5 * transition_s * v;
    for (k, leg) in legs.iter().enumerate() {
        let before = if k == 0 { 0.0 } else { cut(k - 1) };
        let straight = leg.0 - before - cut(k);
        // Start the next turn early by the blend's delay, and end this leg's part late by it.
        let shift = |k: usize| if turns.get(k).is_some_and(|d| d.abs() > 1e-9) { lead } else { 0.0 };
        let straight = straight - shift(k) + if k == 0 { 0.0 } else { shift(k - 1) };
        if straight < -1e-6 {
            return Err(err(
                format!("path.points_m[{}]", k + 1),
                format!("leg {} is too short for turns of radius {r} m at its ends", k + 1),
            ));
        }
        let t = straight.max(0.0) / v;
        if t > 1e-9 {
            segments.push(Segment { duration_s: t, turn_rate_radps: 0.0, climb_mps: leg.2 / t, end_speed_mps: v });
        } else if leg.2.abs() > 1e-9 {
            return Err(err(format!("path.points_m[{}]", k + 1), "has no straight part to climb on"));
        }
        if let Some(d) = turns.get(k) {
            if d.abs() > 1e-9 {
                let w = d.signum() * v / r;
                segments.push(Segment {
                    duration_s: d.abs() / (v / r),
                    turn_rate_radps: w,
                    climb_mps: 0.0,
                    end_speed_mps: v,
                });
            }
        }
    }
    Ok((segments, legs[0].1))
}

fn fault(k: usize, f: &spec::FaultSpec, n: usize) -> Result<Fault, SpecError> {
    let key = format!("fault[{k}]");
    let kind = required(&format!("{key}.kind"), f.kind.clone())?;
    let at_s = non_negative(&format!("{key}.at_s"), required(&format!("{key}.at_s"), f.at_s)?)?;
    let who = || -> Result<UavId, SpecError> { uav(&format!("{key}.uav"), required(&format!("{key}.uav"), f.uav)?, n) };
    let duration = || positive(&format!("{key}.duration_s"), required(&format!("{key}.duration_s"), f.duration_s)?);
    let offset = || -> Result<Vector3<f64>, SpecError> {
        match f.offset_m {
            Some(o) => vec3(&format!("{key}.offset_m"), o),
            None => Ok(Vector3::zeros()),
        }
    };
    Ok(match kind.as_str() {
        "remove" => Fault::Remove { uav: who()?, at_s },
        "join" => Fault::Join { uav: who()?, at_s, offset_m: offset()? },
        "glitch" => Fault::Glitch { uav: who()?, at_s, duration_s: duration()?, offset_m: offset()? },
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

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn locates_keys_in_tables_and_arrays() {
        let text = "name = \"x\"\n[controller]\nareas = 8\nlambda = 2.0\n\n[[fault]]\nkind = \"remove\"\nat_s = 1\n[[fault]]\nkind = \"join\"\nat_s = -1\n";
        assert_eq!(locate(text, "controller.lambda"), Some(4));
        assert_eq!(locate(text, "fault[2].at_s"), Some(11));
        assert_eq!(locate(text, "fault[1].at_s"), Some(8));
        assert_eq!(locate(text, "name"), Some(1));
        assert_eq!(locate(text, "controller"), Some(2));
    }
}

#[cfg(test)]
mod waypoint_tests {
    use super::*;

    #[test]
    fn waypoints_become_legs_and_turns_of_the_given_radius() {
        let v = kmh(200.0);
        let (segs, course) =
            waypoint_segments(&[[2000.0, 0.0, 0.0], [2000.0, 2000.0, 100.0]], v, 300.0, 2.0).expect("valid");
        assert_eq!(course, 0.0);
        // Straight 1700 m (less the blend's lead), a 90° left turn at v/300 rad/s, straight
        // 1700 m climbing 100 m.
        assert_eq!(segs.len(), 3);
        assert!((segs[0].duration_s - (1700.0 / v - 1.0)).abs() < 1e-9);
        assert!((segs[1].turn_rate_radps * segs[1].duration_s - std::f64::consts::FRAC_PI_2).abs() < 1e-9);
        assert!((segs[2].climb_mps * segs[2].duration_s - 100.0).abs() < 1e-9);
        let path = SegmentsPath::new(v, course, segs, 2.0, 200.0);
        let end = path.state_at(100.0, [0.0; 3]);
        assert!((end[state::BETA] - std::f64::consts::FRAC_PI_2).abs() < 1e-9);
        assert!((end[0] - 2000.0).abs() < 15.0, "x {}", end[0]);
        assert!(waypoint_segments(&[[100.0, 0.0, 0.0], [100.0, 100.0, 0.0]], v, 300.0, 2.0).is_err(), "legs too short");
        // The start may be listed as the first point.
        let with_start = [[0.0, 0.0, 0.0], [2000.0, 0.0, 0.0], [2000.0, 2000.0, 100.0]];
        assert_eq!(
            waypoint_segments(&with_start, v, 300.0, 2.0).expect("valid").0,
            waypoint_segments(&with_start[1..], v, 300.0, 2.0).expect("valid").0
        );
    }
}
