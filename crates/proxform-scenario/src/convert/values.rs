//! The value checks every converter uses, and the error that names the offending key.

use nalgebra::Vector3;
use proxform_core::UavId;

/// A problem with one key of a scenario.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[error("{key}: {message}")]
pub struct SpecError {
    /// Dotted key path, with array indices from 1 (`fault[2].at_s`).
    pub key: String,
    /// What is wrong.
    pub message: String,
}

/// A [`SpecError`] for `key`.
pub fn err(key: impl Into<String>, message: impl Into<String>) -> SpecError {
    SpecError { key: key.into(), message: message.into() }
}

/// A number as a message shows it: plainly in the usual range, in scientific notation far
/// outside it (`1e308`, not 309 digits).
pub fn show(v: f64) -> String {
    let a = v.abs();
    if a != 0.0 && a.is_finite() && !(1e-4..1e9).contains(&a) {
        format!("{v:e}")
    } else {
        format!("{v}")
    }
}

/// A finite number.
pub fn finite(key: &str, v: f64) -> Result<f64, SpecError> {
    if v.is_finite() {
        Ok(v)
    } else {
        Err(err(key, format!("{v} is not a finite number")))
    }
}

/// A finite number > 0.
pub fn positive(key: &str, v: f64) -> Result<f64, SpecError> {
    let v = finite(key, v)?;
    if v > 0.0 {
        Ok(v)
    } else {
        Err(err(key, format!("must be > 0, found {}", show(v))))
    }
}

/// A finite number ≥ 0.
pub fn non_negative(key: &str, v: f64) -> Result<f64, SpecError> {
    let v = finite(key, v)?;
    if v >= 0.0 {
        Ok(v)
    } else {
        Err(err(key, format!("must be ≥ 0, found {}", show(v))))
    }
}

/// A probability in [0, 1].
pub fn probability(key: &str, v: f64) -> Result<f64, SpecError> {
    let v = finite(key, v)?;
    if (0.0..=1.0).contains(&v) {
        Ok(v)
    } else {
        Err(err(key, format!("must be a probability in [0, 1], found {}", show(v))))
    }
}

/// Three finite numbers.
pub fn vec3(key: &str, v: [f64; 3]) -> Result<Vector3<f64>, SpecError> {
    for (k, x) in v.iter().enumerate() {
        finite(&format!("{key}[{}]", k + 1), *x)?;
    }
    Ok(Vector3::new(v[0], v[1], v[2]))
}

/// Three finite numbers > 0.
pub fn positive3(key: &str, v: [f64; 3]) -> Result<Vector3<f64>, SpecError> {
    let out = vec3(key, v)?;
    for k in 0..3 {
        positive(&format!("{key}[{}]", k + 1), out[k])?;
    }
    Ok(out)
}

/// A key that must be present.
pub fn required<T>(key: &str, v: Option<T>) -> Result<T, SpecError> {
    v.ok_or_else(|| err(key, "is required"))
}

/// A UAV number (from 1) of a formation of `n`.
pub fn uav(key: &str, number: u32, n: usize) -> Result<UavId, SpecError> {
    if number >= 1 && (number as usize) <= n {
        Ok(UavId(number - 1))
    } else {
        Err(err(key, format!("UAV {number} is not in the formation (UAVs are numbered 1 to {n})")))
    }
}

/// `Some(check(key, v))` when the key is set, else `default`.
pub fn or_default(
    key: &str,
    v: Option<f64>,
    default: f64,
    check: fn(&str, f64) -> Result<f64, SpecError>,
) -> Result<f64, SpecError> {
    v.map_or(Ok(default), |v| check(key, v))
}

/// Farthest distance a formation, path or sensor may span (m): beyond it the flat-earth
/// models mean nothing (and numbers overflow when squared).
pub const MAX_DISTANCE_M: f64 = 1e6;
/// Fastest speed a vehicle or path may have (km/h).
pub const MAX_SPEED_KMH: f64 = 3000.0;

/// A value no larger in magnitude than `max` (`unit` and `meaning` explain the bound).
pub fn within(key: &str, v: f64, max: f64, unit: &str, meaning: &str) -> Result<f64, SpecError> {
    if v.is_nan() {
        Err(err(key, "is not a number"))
    } else if v.abs() <= max {
        Ok(v)
    } else {
        Err(err(key, format!("{} {unit} is beyond ±{} {unit}: {meaning}", show(v), show(max))))
    }
}

/// A distance within [`MAX_DISTANCE_M`].
pub fn distance(key: &str, v: f64) -> Result<f64, SpecError> {
    within(key, v, MAX_DISTANCE_M, "m", "the models are for formations and flights of up to 1000 km")
}

/// A position or offset: three distances within [`MAX_DISTANCE_M`] (`key[1]`, `key[2]`,
/// `key[3]` named where one is not).
pub fn distance3(key: &str, v: [f64; 3]) -> Result<Vector3<f64>, SpecError> {
    let out = vec3(key, v)?;
    for k in 0..3 {
        distance(&format!("{key}[{}]", k + 1), out[k])?;
    }
    Ok(out)
}

/// A speed within [`MAX_SPEED_KMH`].
pub fn speed_kmh(key: &str, v: f64) -> Result<f64, SpecError> {
    within(key, v, MAX_SPEED_KMH, "km/h", "faster than any vehicle the models describe")
}
