//! `[vehicle]`: the kinematic vehicle (the paper's) or the fixed wing, with their limits.

use proxform_core::angle::{deg, kmh};
use proxform_core::{FixedWingModel, KinematicLimits, KinematicModel, VehicleModel};

use super::values::{err, positive, positive3, speed_kmh, SpecError};
use crate::spec::VehicleSpec;

/// The vehicle model; keys of the other model are refused.
pub fn vehicle(v: &VehicleSpec) -> Result<VehicleModel, SpecError> {
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
        let mut m = FixedWingModel::default();
        let set = |key: &str, v: Option<f64>, scale: fn(f64) -> f64, dst: &mut f64| -> Result<(), SpecError> {
            if let Some(x) = v {
                *dst = scale(positive(&format!("vehicle.{key}"), x)?);
            }
            Ok(())
        };
        set("stall_speed_kmh", v.stall_speed_kmh, kmh, &mut m.stall_speed_mps)?;
        if let Some(x) = v.max_speed_kmh {
            speed_kmh("vehicle.max_speed_kmh", x)?;
        }
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
