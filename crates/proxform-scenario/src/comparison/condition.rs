//! A checked condition of a comparison: what it changes in the base scenario's spec (radio
//! loss and delay, sensor noise, a blackout, a failed UAV, onboard dropout, loss on every
//! channel), and which sweep it is a point of.

use proxform_core::UavId;

use super::{CompareError, MethodEntry};
use crate::defaults;
use crate::scenario::Scenario;
use crate::spec::{FaultSpec, ScenarioSpec};

/// A checked condition: what it changes in the base scenario.
#[derive(Debug, Clone, PartialEq)]
pub struct Condition {
    /// Name in reports.
    pub name: String,
    /// i.i.d. radio loss probability.
    pub radio_loss: f64,
    /// Radio delay (s).
    pub radio_delay_s: f64,
    /// Factor on the measurement noise.
    pub noise_scale: f64,
    /// Radio down for the whole flight.
    pub blackout: bool,
    /// The UAV that fails, and when (s).
    pub fail: Option<(UavId, f64)>,
    /// Onboard observation dropout.
    pub dropout: f64,
}

impl Condition {
    /// A condition that changes nothing.
    pub fn ideal(name: &str) -> Self {
        Self {
            name: name.into(),
            radio_loss: 0.0,
            radio_delay_s: 0.0,
            noise_scale: 1.0,
            blackout: false,
            fail: None,
            dropout: 0.0,
        }
    }

    /// True when only the radio loss differs from [`Condition::ideal`] (a point of the
    /// error-against-loss curve).
    pub fn is_loss_only(&self) -> bool {
        Self { name: String::new(), radio_loss: 0.0, ..self.clone() } == Self::ideal("")
    }

    /// The loss of every channel when it is the only difference from [`Condition::ideal`]
    /// (onboard dropout equal to the radio loss: a point of the error-against-channel-loss
    /// curve; the ideal condition is its 0).
    pub fn channel_loss(&self) -> Option<f64> {
        let same = self.radio_loss == self.dropout;
        let rest = Self { name: String::new(), radio_loss: 0.0, dropout: 0.0, ..self.clone() } == Self::ideal("");
        (same && rest).then_some(self.radio_loss)
    }

    /// True when only the radio delay differs from [`Condition::ideal`].
    pub fn is_delay_only(&self) -> bool {
        Self { name: String::new(), radio_delay_s: 0.0, ..self.clone() } == Self::ideal("")
    }

    /// The base scenario's spec under this condition, flown by `method`.
    pub fn apply(&self, base: &ScenarioSpec, method: &MethodEntry) -> ScenarioSpec {
        let mut sc = base.clone();
        sc.radio.loss = Some(self.radio_loss);
        sc.radio.delay_s = Some(self.radio_delay_s);
        sc.noise.scale = Some(self.noise_scale * base.noise.scale.unwrap_or(1.0));
        if self.blackout {
            let duration = base.duration_s.unwrap_or(defaults::DURATION_S);
            sc.fault.push(FaultSpec::radio_blackout(0.0, duration + 1.0));
        }
        if let Some((uav, at_s)) = self.fail {
            sc.fault.push(FaultSpec::remove(uav.0 + 1, at_s));
        }
        sc.sensing.dropout = Some(self.dropout);
        sc.controller.horizon = Some(i64::from(method.horizon));
        if let Some(p) = &method.predictor {
            sc.controller.predictor = Some(p.clone());
        }
        sc.controller.method = Some(method.method.label().into());
        sc.controller.gains = method.gains.clone();
        if let Some(extra) = &method.controller {
            sc.controller = overlay(&sc.controller, extra);
        }
        if method.broadcast {
            sc.radio.broadcast_all = Some(true);
        }
        let base_name = base.name.as_deref().unwrap_or("scenario");
        sc.name = Some(format!("{base_name} / {} / {}", method.name, self.name));
        sc
    }

    /// The checked scenario of this condition flown by `method`.
    pub fn scenario(&self, base: &ScenarioSpec, method: &MethodEntry) -> Result<Scenario, CompareError> {
        Scenario::try_from(self.apply(base, method)).map_err(|problem| CompareError::Scenario {
            condition: self.name.clone(),
            method: method.name.clone(),
            problem,
        })
    }
}

/// `base` with the keys of `extra` written over it. Both are `[controller]` tables that were
/// checked as such when the comparison was loaded, so the merge is one too.
fn overlay(base: &crate::spec::ControllerSpec, extra: &toml::Table) -> crate::spec::ControllerSpec {
    use serde::Deserialize as _;
    let mut t = toml::Table::try_from(base).expect("a [controller] spec is a TOML table");
    for (k, v) in extra {
        t.insert(k.clone(), v.clone());
    }
    crate::spec::ControllerSpec::deserialize(toml::Value::Table(t))
        .expect("checked [controller] keys over a checked [controller] spec make a [controller] spec")
}
