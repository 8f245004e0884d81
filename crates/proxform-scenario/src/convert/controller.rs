//! `[controller]`: the proximity controller's parameters and the followers' method.

use proxform_core::angle::{deg, kmh};
use proxform_core::controller::MAX_HORIZON;
use proxform_core::state;
use proxform_core::{ControllerParams, Envelope, Method, PredictorKind, VehicleModel};

use super::values::{distance, err, finite, non_negative, or_default, positive, probability, SpecError};
use crate::spec::ControllerSpec;

/// A threshold's state index, key, value as written and unit conversion.
type ThresholdKey<'a> = (usize, &'a str, Option<f64>, fn(f64) -> f64);

/// Most azimuth areas.
pub const MAX_AREAS: i64 = 1024;

/// α of the default α-β predictor.
const DEFAULT_ALPHA: f64 = match PredictorKind::DEFAULT {
    PredictorKind::AlphaBeta { alpha, .. } | PredictorKind::Singer { alpha, .. } => alpha,
    PredictorKind::ConstantVelocity => 1.0,
};

/// The controller's parameters; unset permissible errors take the vehicle's defaults, and the
/// turn feed-forward is on for the fixed wing and the multirotor. The separation distance is
/// resolved by the caller.
pub fn params(c: &ControllerSpec, dt_s: f64, vehicle: &VehicleModel) -> Result<ControllerParams, SpecError> {
    let mut p = ControllerParams { dt_s, ..ControllerParams::default() };
    let fixed_wing = matches!(vehicle, VehicleModel::FixedWing(_));
    match vehicle {
        VehicleModel::Kinematic(_) => {}
        VehicleModel::FixedWing(_) => p.envelope.thresholds = ControllerParams::fixed_wing_thresholds(),
        VehicleModel::Multirotor(_) => p.envelope.thresholds = ControllerParams::multirotor_thresholds(),
    }
    if let Some(m) = c.areas {
        if !(1..=MAX_AREAS).contains(&m) {
            return Err(err("controller.areas", format!("m must be between 1 and {MAX_AREAS}, found {m}")));
        }
        p.areas.areas = m as usize;
    }
    if let Some(v) = c.sensing_range_m {
        p.areas.sensing_range_m = distance("controller.sensing_range_m", positive("controller.sensing_range_m", v)?)?;
    }
    if let Some(v) = c.lambda {
        let v = finite("controller.lambda", v)?;
        if !(0.0..=1.0).contains(&v) {
            return Err(err("controller.lambda", format!("λ must be in [0, 1], found {}", super::values::show(v))));
        }
        p.lambda = v;
    }
    if let Some(v) = c.rho {
        let v = positive("controller.rho", v)?;
        if v > 1.0 {
            return Err(err("controller.rho", format!("ρ must be in (0, 1], found {}", super::values::show(v))));
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
    if let Some(v) = c.relay_max_age_s {
        p.relay_max_age_s = positive("controller.relay_max_age_s", v)?;
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
        if !(1..=i64::from(MAX_HORIZON)).contains(&v) {
            return Err(err("controller.horizon", format!("must be an integer from 1 to {MAX_HORIZON}, found {v}")));
        }
        p.horizon = v as u32;
    }
    if let Some(v) = c.separation_m {
        p.separation_m = Some(distance("controller.separation_m", non_negative("controller.separation_m", v)?)?);
    }
    if let Some(v) = c.avoid_m {
        p.avoid_m = Some(distance("controller.avoid_m", non_negative("controller.avoid_m", v)?)?);
    }
    if let Some(v) = c.own_filter_gain {
        let v = positive("controller.own_filter_gain", v)?;
        if v > 1.0 {
            return Err(err(
                "controller.own_filter_gain",
                format!("must be in (0, 1], found {}", super::values::show(v)),
            ));
        }
        p.own_filter_gain = v;
    }
    if let Some(v) = c.isolation_gate {
        p.isolation_gate = Some(non_negative("controller.isolation_gate", v)?).filter(|&g| g > 0.0);
    }
    if let Some(v) = c.own_gate_m {
        let v = distance("controller.own_gate_m", non_negative("controller.own_gate_m", v)?)?;
        p.own_gate_m = Some(v).filter(|&g| g > 0.0);
    }
    if let Some(v) = c.own_gate_growth_mps {
        p.own_gate_growth_mps = non_negative("controller.own_gate_growth_mps", v)?;
        if c.own_gate_m.is_some() && p.own_gate_m.is_none() {
            return Err(err("controller.own_gate_growth_mps", "applies with controller.own_gate_m > 0 only"));
        }
    }
    let gains = || -> Result<(f64, f64), SpecError> {
        let alpha = c.predictor_alpha.unwrap_or(DEFAULT_ALPHA);
        let alpha = positive("controller.predictor_alpha", alpha)?;
        if alpha > 1.0 {
            return Err(err("controller.predictor_alpha", format!("must be in (0, 1], found {alpha}")));
        }
        let beta = match c.predictor_beta {
            Some(b) => probability("controller.predictor_beta", b)?,
            None => alpha * alpha / (2.0 - alpha),
        };
        Ok((alpha, beta))
    };
    let singer_keys = c.predictor_accel_sigma_mps2.is_some() || c.predictor_tau_s.is_some();
    p.predictor = match c.predictor.as_deref() {
        _ if singer_keys && c.predictor.as_deref() != Some("singer") => {
            return Err(err("controller.predictor_tau_s", "applies to predictor = \"singer\" only"));
        }
        None | Some("alpha_beta") => {
            let (alpha, beta) = gains()?;
            PredictorKind::AlphaBeta { alpha, beta }
        }
        Some("constant_velocity") => PredictorKind::ConstantVelocity,
        Some("singer") => {
            let (alpha, beta) = gains()?;
            PredictorKind::Singer {
                accel_sigma_mps2: or_default(
                    "controller.predictor_accel_sigma_mps2",
                    c.predictor_accel_sigma_mps2,
                    PredictorKind::SINGER_ACCEL_SIGMA_MPS2,
                    positive,
                )?,
                tau_s: or_default(
                    "controller.predictor_tau_s",
                    c.predictor_tau_s,
                    PredictorKind::SINGER_TAU_S,
                    positive,
                )?,
                // The measurement noise is the scenario's, filled in with it.
                position_sigma_m: f64::NAN,
                velocity_sigma_mps: f64::NAN,
                alpha,
                beta,
            }
        }
        Some(o) => {
            return Err(err(
                "controller.predictor",
                format!("unknown predictor \"{o}\" (expected \"alpha_beta\", \"constant_velocity\" or \"singer\")"),
            ))
        }
    };
    if let Some(v) = c.plan_forward {
        p.plan_forward = v;
    }
    p.turn_feedforward = c.turn_feedforward.unwrap_or(!matches!(vehicle, VehicleModel::Kinematic(_)));
    // The fixed wing's braking is a rough figure (it avoids by turning): off unless asked.
    p.stop_closing = c.stop_closing.unwrap_or(!fixed_wing);
    if let Some(t) = &c.thresholds {
        let mut d = p.envelope.thresholds;
        let keys: [ThresholdKey; 9] = [
            (state::X, "x_m", t.x_m, |v| v),
            (state::Y, "y_m", t.y_m, |v| v),
            (state::Z, "z_m", t.z_m, |v| v),
            (state::VX, "vx_kmh", t.vx_kmh, kmh),
            (state::VY, "vy_kmh", t.vy_kmh, kmh),
            (state::VZ, "vz_kmh", t.vz_kmh, kmh),
            (state::ALPHA, "alpha_deg", t.alpha_deg, deg),
            (state::BETA, "beta_deg", t.beta_deg, deg),
            (state::GAMMA, "gamma_deg", t.gamma_deg, deg),
        ];
        for (k, key, v, scale) in keys {
            if let Some(v) = v {
                d[k] = scale(positive(&format!("controller.thresholds.{key}"), v)?);
            }
        }
        p.envelope = Envelope { thresholds: d, ..p.envelope };
    }
    Ok(p)
}

/// The followers' method: `controller.method` with its `controller.gains` ("paper" is the
/// proximity method with the paper's choices, [`paper_method`]).
pub fn method(c: &ControllerSpec) -> Result<Method, SpecError> {
    match c.method.as_deref() {
        None | Some(PAPER) => match &c.gains {
            Some(_) => Err(err("controller.gains", "the proximity method's parameters are the [controller] keys")),
            None => Ok(Method::Proximity),
        },
        Some(label) => method_from(label, c.gains.as_ref()).map_err(|(sub, message)| {
            let message = if sub {
                message
            } else {
                format!("{message} or \"{PAPER}\" (the proximity method as the paper has it)")
            };
            err(if sub { "controller.gains" } else { "controller.method" }, message)
        }),
    }
}

/// `controller.method = "paper"`: the proximity method with the paper's choices where
/// proxform's defaults go beyond it (METHOD §8): derived tables without the navigator, plain
/// means wherever UAVs fly, reports carried by their tracks' rates. Keys the file sets win.
pub const PAPER: &str = "paper";

/// Whether `c` asks for the paper's method.
pub fn paper_method(c: &ControllerSpec) -> bool {
    c.method.as_deref() == Some(PAPER)
}

/// The method of `label` with `gains` (keys of its gains struct; omitted ones keep their
/// defaults). On error: whether the gains are at fault (else the label), and the message.
pub fn method_from(label: &str, gains: Option<&toml::Table>) -> Result<Method, (bool, String)> {
    let method = Method::from_label(label)
        .ok_or_else(|| (false, format!("unknown method '{label}' (known: {})", Method::LABELS.join(", "))))?;
    let Some(g) = gains else { return Ok(method) };
    let value = toml::Value::Table(g.clone());
    let parsed = match method {
        Method::Proximity => Err("the proximity method's parameters are the [controller] keys".to_string()),
        Method::LeaderFollower(_) => value.try_into().map(Method::LeaderFollower).map_err(|e| e.to_string()),
        Method::Consensus(_) => value.try_into().map(Method::Consensus).map_err(|e| e.to_string()),
        Method::Flocking(_) => value.try_into().map(Method::Flocking).map_err(|e| e.to_string()),
    };
    let method = parsed.map_err(|msg| (true, msg.trim().to_string()))?;
    method.validate().map_err(|e| (true, e.to_string()))?;
    Ok(method)
}
