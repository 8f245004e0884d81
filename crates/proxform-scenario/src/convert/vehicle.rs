//! `[vehicle]`: the kinematic vehicle (the paper's), the fixed wing or the multirotor, with
//! their limits.

use proxform_core::angle::{deg, kmh};
use proxform_core::{FixedWingModel, KinematicLimits, KinematicModel, MultirotorModel, VehicleModel};

use super::values::{err, non_negative, positive, positive3, show, speed_kmh, SpecError};
use crate::spec::VehicleSpec;
use proxform_core::vehicle::G;

/// The vehicle model; keys of the other models are refused.
pub fn vehicle(v: &VehicleSpec) -> Result<VehicleModel, SpecError> {
    const K: u8 = 1; // kinematic
    const F: u8 = 2; // fixed wing
    const M: u8 = 4; // multirotor
    let keys: [(&str, bool, u8); 27] = [
        ("vx_min_kmh", v.vx_min_kmh.is_some(), K),
        ("vx_max_kmh", v.vx_max_kmh.is_some(), K),
        ("vy_max_kmh", v.vy_max_kmh.is_some(), K),
        ("vz_max_kmh", v.vz_max_kmh.is_some(), K),
        ("attitude_max_deg", v.attitude_max_deg.is_some(), K),
        ("accel_kmh_s", v.accel_kmh_s.is_some(), K),
        ("attitude_rate_deg_s", v.attitude_rate_deg_s.is_some(), K),
        ("stall_speed_kmh", v.stall_speed_kmh.is_some(), F),
        ("max_speed_kmh", v.max_speed_kmh.is_some(), F | M),
        ("bank_max_deg", v.bank_max_deg.is_some(), F),
        ("load_factor_max", v.load_factor_max.is_some(), F),
        ("pitch_max_deg", v.pitch_max_deg.is_some(), F),
        ("roll_rate_max_deg_s", v.roll_rate_max_deg_s.is_some(), F),
        ("pitch_rate_max_deg_s", v.pitch_rate_max_deg_s.is_some(), F),
        ("yaw_rate_max_deg_s", v.yaw_rate_max_deg_s.is_some(), F | M),
        ("throttle_accel_kmh_s", v.throttle_accel_kmh_s.is_some(), F),
        ("climb_max_kmh", v.climb_max_kmh.is_some(), M),
        ("descent_max_kmh", v.descent_max_kmh.is_some(), M),
        ("accel_max_mps2", v.accel_max_mps2.is_some(), M),
        ("vertical_accel_max_mps2", v.vertical_accel_max_mps2.is_some(), M),
        ("tilt_max_deg", v.tilt_max_deg.is_some(), M),
        ("thrust_to_weight", v.thrust_to_weight.is_some(), M),
        ("velocity_time_constant_s", v.velocity_time_constant_s.is_some(), M),
        ("attitude_time_constant_s", v.attitude_time_constant_s.is_some(), M),
        ("yaw_time_constant_s", v.yaw_time_constant_s.is_some(), M),
        ("drag_linear_per_s", v.drag_linear_per_s.is_some(), M),
        ("drag_quadratic_per_m", v.drag_quadratic_per_m.is_some(), M),
    ];
    let model = v.model.as_deref().unwrap_or("kinematic");
    let this = match model {
        "kinematic" => K,
        "fixed_wing" => F,
        "multirotor" => M,
        o => {
            return Err(err(
                "vehicle.model",
                format!("unknown model \"{o}\" (expected \"kinematic\", \"fixed_wing\" or \"multirotor\")"),
            ))
        }
    };
    if let Some((key, _, owners)) = keys.iter().find(|k| k.1 && k.2 & this == 0) {
        let names: Vec<&str> = [(K, "\"kinematic\""), (F, "\"fixed_wing\""), (M, "\"multirotor\"")]
            .iter()
            .filter(|(b, _)| owners & b != 0)
            .map(|(_, n)| *n)
            .collect();
        return Err(err(
            format!("vehicle.{key}"),
            format!("applies to model = {}, not \"{model}\"", names.join(" or ")),
        ));
    }
    if model == "multirotor" {
        return multirotor(v);
    }
    if model == "fixed_wing" {
        let mut m = FixedWingModel::default();
        let set = |key: &str, v: Option<f64>, scale: fn(f64) -> f64, dst: &mut f64| -> Result<(), SpecError> {
            if let Some(x) = v {
                *dst = scale(positive(&format!("vehicle.{key}"), x)?);
            }
            Ok(())
        };
        set("stall_speed_kmh", v.stall_speed_kmh, kmh, &mut m.stall_speed_mps)?;
        set("max_speed_kmh", v.max_speed_kmh, kmh, &mut m.max_speed_mps)?;
        if let Some(x) = v.max_speed_kmh {
            speed_kmh("vehicle.max_speed_kmh", x)?;
        }
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
        // 0: a vehicle that can hover (a multirotor), which a take-off row needs.
        l.vx_min_mps = kmh(super::values::non_negative("vehicle.vx_min_kmh", x)?);
    }
    if let Some(x) = v.vx_max_kmh {
        l.vx_max_mps = kmh(speed_kmh("vehicle.vx_max_kmh", positive("vehicle.vx_max_kmh", x)?)?);
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
    if let Some(a) = v.attitude_max_deg {
        l.attitude_max_rad = positive3("vehicle.attitude_max_deg", a)?.map(deg);
    }
    if let Some(a) = v.accel_kmh_s {
        l.accel_max_mps2 = positive3("vehicle.accel_kmh_s", a)?.map(kmh);
    }
    if let Some(a) = v.attitude_rate_deg_s {
        l.attitude_rate_max_radps = positive3("vehicle.attitude_rate_deg_s", a)?.map(deg);
    }
    Ok(VehicleModel::Kinematic(KinematicModel { limits: l }))
}

/// The multirotor: every key in its unit, checked, over [`MultirotorModel::default`].
fn multirotor(v: &VehicleSpec) -> Result<VehicleModel, SpecError> {
    let mut m = MultirotorModel::default();
    let set = |key: &str, v: Option<f64>, scale: fn(f64) -> f64, dst: &mut f64| -> Result<(), SpecError> {
        if let Some(x) = v {
            *dst = scale(positive(&format!("vehicle.{key}"), x)?);
        }
        Ok(())
    };
    set("max_speed_kmh", v.max_speed_kmh, kmh, &mut m.max_speed_mps)?;
    if let Some(x) = v.max_speed_kmh {
        speed_kmh("vehicle.max_speed_kmh", x)?;
    }
    set("climb_max_kmh", v.climb_max_kmh, kmh, &mut m.climb_max_mps)?;
    set("descent_max_kmh", v.descent_max_kmh, kmh, &mut m.descent_max_mps)?;
    set("accel_max_mps2", v.accel_max_mps2, |x| x, &mut m.accel_max_mps2)?;
    set("vertical_accel_max_mps2", v.vertical_accel_max_mps2, |x| x, &mut m.vertical_accel_max_mps2)?;
    set("tilt_max_deg", v.tilt_max_deg, deg, &mut m.tilt_max_rad)?;
    if let Some(x) = v.thrust_to_weight {
        // Its own rule (> 1) below names it better than "> 0".
        m.thrust_to_weight = super::values::finite("vehicle.thrust_to_weight", x)?;
    }
    set("yaw_rate_max_deg_s", v.yaw_rate_max_deg_s, deg, &mut m.yaw_rate_max_radps)?;
    set("velocity_time_constant_s", v.velocity_time_constant_s, |x| x, &mut m.velocity_time_constant_s)?;
    set("attitude_time_constant_s", v.attitude_time_constant_s, |x| x, &mut m.attitude_time_constant_s)?;
    set("yaw_time_constant_s", v.yaw_time_constant_s, |x| x, &mut m.yaw_time_constant_s)?;
    if let Some(x) = v.drag_linear_per_s {
        m.drag_linear_per_s = non_negative("vehicle.drag_linear_per_s", x)?;
    }
    if let Some(x) = v.drag_quadratic_per_m {
        m.drag_quadratic_per_m = non_negative("vehicle.drag_quadratic_per_m", x)?;
    }
    if m.velocity_time_constant_s < proxform_core::vehicle::MIN_VELOCITY_TIME_CONSTANT_S {
        return Err(err(
            "vehicle.velocity_time_constant_s",
            format!(
                "must be at least {} s (no multirotor's velocity loop is faster), found {}",
                proxform_core::vehicle::MIN_VELOCITY_TIME_CONSTANT_S,
                show(m.velocity_time_constant_s)
            ),
        ));
    }
    for (key, tau) in [
        ("vehicle.velocity_time_constant_s", m.velocity_time_constant_s),
        ("vehicle.attitude_time_constant_s", m.attitude_time_constant_s),
        ("vehicle.yaw_time_constant_s", m.yaw_time_constant_s),
    ] {
        let most = proxform_core::vehicle::MAX_TIME_CONSTANT_S;
        if tau > most {
            return Err(err(
                key,
                format!("must be at most {most} s (a multirotor's loops answer within seconds), found {}", show(tau)),
            ));
        }
    }
    // The attitude loop is the inner one of the cascade: slower than the velocity loop, the
    // two oscillate (measured on the 12-UAV circuit, τ_v 0.5 s: τ_att 0.5 s passes 10 of 10 runs
    // within 0.42 m, 0.75 s 8 of 10, 1 s none, 1.5 s collides).
    if m.attitude_time_constant_s > m.velocity_time_constant_s {
        return Err(err(
            "vehicle.attitude_time_constant_s",
            format!(
                "{} s is longer than vehicle.velocity_time_constant_s = {} s: the attitude loop is the inner one of \
                 the cascade and must be at least as fast as the velocity loop, or the two oscillate",
                show(m.attitude_time_constant_s),
                show(m.velocity_time_constant_s)
            ),
        ));
    }
    if m.tilt_max_rad >= deg(90.0) {
        return Err(err(
            "vehicle.tilt_max_deg",
            format!("must be below 90°, found {}", show(m.tilt_max_rad.to_degrees())),
        ));
    }
    if m.thrust_to_weight <= 1.0 {
        return Err(err(
            "vehicle.thrust_to_weight",
            format!("must be above 1 (the vehicle must lift itself), found {}", show(m.thrust_to_weight)),
        ));
    }
    let lift = G * (m.thrust_to_weight - 1.0);
    if m.vertical_accel_max_mps2 >= lift {
        return Err(err(
            "vehicle.vertical_accel_max_mps2",
            format!(
                "{} m/s² is more than the thrust can give, g·(thrust_to_weight − 1) = {:.2} m/s²",
                show(m.vertical_accel_max_mps2),
                lift
            ),
        ));
    }
    // Whatever is left unchecked above is checked by the model itself, named as its key.
    m.validate().map_err(|e| err("vehicle", e.to_string()))?;
    Ok(VehicleModel::Multirotor(m))
}
