//! Side-by-side comparisons: formation control methods × conditions × seeds.
//!
//! A comparison takes one base scenario, a list of methods (the proximity method with its
//! horizon, and the baselines of [`proxform_core::baseline`]) and a list of conditions (radio
//! loss and delay, sensor noise, a radio blackout, a failed UAV, onboard dropout), and runs
//! every method under every condition for the same seeds, so that every cell sees the same
//! disturbances. The raw file form is [`ComparisonSpec`] (TOML); [`Comparison`] is the checked
//! form. Rows come back in (method, condition, seed) order whatever the thread count.

use proxform_core::{Method, RadioNeed, UavId};
use rayon::prelude::*;

use crate::batch::run_one;
use crate::faults::Fault;
use crate::scenario::{Scenario, ScenarioError};

/// Why a comparison is invalid or could not run.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum CompareError {
    /// The file is not valid TOML or has unknown keys / wrong types.
    #[error("{file}: {message}")]
    Parse {
        /// The file's name.
        file: String,
        /// The parser's message (with line and key).
        message: String,
    },
    /// A value outside its domain.
    #[error("{file}: {key}: {message}")]
    Value {
        /// The file's name.
        file: String,
        /// Key path of the value.
        key: String,
        /// What is wrong.
        message: String,
    },
    /// A condition made the base scenario invalid.
    #[error("condition '{condition}', method '{method}': {source}")]
    Scenario {
        /// The condition's name.
        condition: String,
        /// The method's name.
        method: String,
        /// The scenario's complaint.
        source: ScenarioError,
    },
}

/// A method entry of a comparison file: a label, or a table with options.
#[derive(Debug, Clone, PartialEq, serde::Deserialize)]
#[serde(untagged)]
pub enum MethodSpec {
    /// `"proximity"`, `"leader_follower"`, `"consensus"` or `"flocking"`, default gains.
    Label(String),
    /// `{ method = "proximity", horizon = 5, name = "proximity H=5" }`.
    Table {
        /// The method's label.
        method: String,
        /// Name in reports (default: the label, with the horizon when > 1).
        name: Option<String>,
        /// Horizon H of the proximity method (updates, 1 to 50).
        horizon: Option<u32>,
        /// A baseline's gains (keys of its gains struct; omitted ones keep their defaults),
        /// e.g. `{ pd = { kp = 2.0, kv = 2.8 } }` or `{ leader_share = 0.5 }`.
        gains: Option<toml::Table>,
    },
}

/// A condition of a comparison file; every key is optional.
#[derive(Debug, Clone, Default, PartialEq, serde::Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ConditionSpec {
    /// Name in reports.
    pub name: String,
    /// i.i.d. loss probability of each radio message, in [0, 1]. Default 0.
    pub radio_loss: Option<f64>,
    /// Delay of every radio message (s, ≥ 0, a multiple of Δt). Default 0.
    pub radio_delay_s: Option<f64>,
    /// Factor on the scenario's measurement noise (≥ 0). Default 1.
    pub noise_scale: Option<f64>,
    /// Radio down for the whole flight. Default false.
    pub blackout: Option<bool>,
    /// UAV (numbered from 1, as in reports) that fails and leaves the formation.
    pub fail_uav: Option<u32>,
    /// When it fails (s). Default 40 s.
    pub fail_at_s: Option<f64>,
    /// Probability of losing each onboard observation, in [0, 1]. Default 0.
    pub dropout: Option<f64>,
}

/// A comparison file (TOML).
#[derive(Debug, Clone, PartialEq, serde::Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ComparisonSpec {
    /// Name in reports and the default output directory.
    pub name: String,
    /// The base scenario: a built-in name or a scenario file (relative to this file).
    pub scenario: String,
    /// Seeds (runs) per cell, ≥ 1.
    pub seeds: u64,
    /// Base seed. Default 1.
    pub seed: Option<u64>,
    /// The methods.
    pub methods: Vec<MethodSpec>,
    /// The conditions.
    #[serde(rename = "condition")]
    pub conditions: Vec<ConditionSpec>,
}

/// A checked method entry.
#[derive(Debug, Clone, PartialEq)]
pub struct MethodEntry {
    /// Name in reports.
    pub name: String,
    /// The method.
    pub method: Method,
    /// Horizon of the proximity method.
    pub horizon: u32,
}

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

    /// True when only the radio delay differs from [`Condition::ideal`].
    pub fn is_delay_only(&self) -> bool {
        Self { name: String::new(), radio_delay_s: 0.0, ..self.clone() } == Self::ideal("")
    }

    /// The base scenario under this condition, flown by `method`.
    pub fn apply(&self, base: &Scenario, method: &MethodEntry) -> Result<Scenario, ScenarioError> {
        let mut sc = base.clone();
        sc.radio.loss = self.radio_loss;
        sc.radio.delay_steps = (self.radio_delay_s / sc.dt_s).round() as u32;
        let n = &mut sc.noise;
        n.position_m *= self.noise_scale;
        n.velocity_mps *= self.noise_scale;
        n.attitude_rad *= self.noise_scale;
        if self.blackout {
            sc.faults.push(Fault::RadioBlackout { at_s: 0.0, duration_s: sc.duration_s + 1.0 });
        }
        if let Some((uav, at_s)) = self.fail {
            sc.faults.push(Fault::Remove { uav, at_s });
        }
        sc.dropout = self.dropout;
        sc.controller.horizon = method.horizon;
        sc.set_method(method.method);
        sc.name = format!("{} / {} / {}", base.name, method.name, self.name);
        sc.validate()?;
        Ok(sc)
    }
}

/// A checked comparison.
#[derive(Debug, Clone)]
pub struct Comparison {
    /// Name in reports.
    pub name: String,
    /// The base scenario.
    pub base: Scenario,
    /// Seeds per cell.
    pub seeds: u64,
    /// Base seed.
    pub seed: u64,
    /// The methods.
    pub methods: Vec<MethodEntry>,
    /// The conditions.
    pub conditions: Vec<Condition>,
}

/// The built-in comparison: the paper's experiment under every condition of the issue that
/// asked for it, for the proximity method (H = 1 and H = 5) and the three baselines.
pub const BUILT_IN: &str = include_str!("../../../scenarios/compare-paper.toml");

impl Comparison {
    /// Parses a comparison file; `resolve` turns its `scenario` entry into the base scenario.
    pub fn parse(
        text: &str,
        file: &str,
        resolve: impl FnOnce(&str) -> Result<Scenario, String>,
    ) -> Result<Self, CompareError> {
        let spec: ComparisonSpec =
            toml::from_str(text).map_err(|e| CompareError::Parse { file: file.into(), message: e.to_string() })?;
        let base = resolve(&spec.scenario).map_err(|message| CompareError::Value {
            file: file.into(),
            key: "scenario".into(),
            message,
        })?;
        Self::check(spec, base, file)
    }

    /// Checks a parsed specification against its base scenario.
    pub fn check(spec: ComparisonSpec, base: Scenario, file: &str) -> Result<Self, CompareError> {
        let bad = |key: String, message: String| CompareError::Value { file: file.into(), key, message };
        if spec.seeds == 0 {
            return Err(bad("seeds".into(), "must be at least 1".into()));
        }
        if spec.methods.is_empty() {
            return Err(bad("methods".into(), "name at least one method".into()));
        }
        if spec.conditions.is_empty() {
            return Err(bad("condition".into(), "give at least one [[condition]]".into()));
        }
        let mut methods = Vec::new();
        for (k, m) in spec.methods.iter().enumerate() {
            let (label, name, horizon, gains) = match m {
                MethodSpec::Label(l) => (l.as_str(), None, None, None),
                MethodSpec::Table { method, name, horizon, gains } => {
                    (method.as_str(), name.clone(), *horizon, gains.clone())
                }
            };
            let key = format!("methods[{k}]");
            let mut method = Method::from_label(label).ok_or_else(|| {
                bad(key.clone(), format!("unknown method '{label}' (known: {})", Method::LABELS.join(", ")))
            })?;
            if let Some(g) = gains {
                let gkey = format!("{key}.gains");
                let value = toml::Value::Table(g);
                let parsed = match method {
                    Method::Proximity => {
                        Err("the proximity method's parameters are the scenario's [controller] keys".to_string())
                    }
                    Method::LeaderFollower(_) => {
                        value.try_into().map(Method::LeaderFollower).map_err(|e| e.to_string())
                    }
                    Method::Consensus(_) => value.try_into().map(Method::Consensus).map_err(|e| e.to_string()),
                    Method::Flocking(_) => value.try_into().map(Method::Flocking).map_err(|e| e.to_string()),
                };
                method = parsed.map_err(|msg| bad(gkey.clone(), msg.trim().to_string()))?;
                method.validate().map_err(|e| bad(gkey, e.to_string()))?;
            }
            let horizon = horizon.unwrap_or(1);
            if !(1..=proxform_core::controller::MAX_HORIZON).contains(&horizon) {
                return Err(bad(format!("{key}.horizon"), format!("must be 1 to 50, found {horizon}")));
            }
            if horizon > 1 && method != Method::Proximity {
                return Err(bad(format!("{key}.horizon"), "applies to the proximity method only".into()));
            }
            let name =
                name.unwrap_or_else(|| if horizon > 1 { format!("{label} H={horizon}") } else { label.to_string() });
            if methods.iter().any(|e: &MethodEntry| e.name == name) {
                return Err(bad(key, format!("duplicate method name '{name}'")));
            }
            methods.push(MethodEntry { name, method, horizon });
        }
        let mut conditions: Vec<Condition> = Vec::new();
        for (k, c) in spec.conditions.iter().enumerate() {
            let key = |f: &str| format!("condition[{k}].{f}");
            let probability = |f: &str, v: Option<f64>| match v {
                Some(p) if !(0.0..=1.0).contains(&p) => {
                    Err(bad(key(f), format!("must be a probability in [0, 1], found {p}")))
                }
                Some(p) => Ok(p),
                None => Ok(0.0),
            };
            let radio_loss = probability("radio_loss", c.radio_loss)?;
            let dropout = probability("dropout", c.dropout)?;
            let radio_delay_s = c.radio_delay_s.unwrap_or(0.0);
            let steps = radio_delay_s / base.dt_s;
            if !(radio_delay_s.is_finite() && radio_delay_s >= 0.0) || (steps - steps.round()).abs() > 1e-6 {
                return Err(bad(
                    key("radio_delay_s"),
                    format!("must be ≥ 0 s and a multiple of the update period {} s, found {radio_delay_s}", base.dt_s),
                ));
            }
            let noise_scale = c.noise_scale.unwrap_or(1.0);
            if !(noise_scale.is_finite() && noise_scale >= 0.0) {
                return Err(bad(key("noise_scale"), format!("must be a finite factor ≥ 0, found {noise_scale}")));
            }
            let fail = match c.fail_uav {
                Some(u) if u == 0 || u as usize > base.len() => {
                    return Err(bad(key("fail_uav"), format!("UAVs are numbered 1 to {}, found {u}", base.len())))
                }
                Some(u) => {
                    let at = c.fail_at_s.unwrap_or(40.0);
                    if !(at.is_finite() && at >= 0.0) {
                        return Err(bad(key("fail_at_s"), format!("must be a time ≥ 0 s, found {at}")));
                    }
                    Some((UavId(u - 1), at))
                }
                None if c.fail_at_s.is_some() => {
                    return Err(bad(key("fail_at_s"), "needs fail_uav".into()));
                }
                None => None,
            };
            if c.name.trim().is_empty() || conditions.iter().any(|d| d.name == c.name) {
                return Err(bad(key("name"), format!("needs a unique, non-empty name, found '{}'", c.name)));
            }
            conditions.push(Condition {
                name: c.name.clone(),
                radio_loss,
                radio_delay_s,
                noise_scale,
                blackout: c.blackout.unwrap_or(false),
                fail,
                dropout,
            });
        }
        let cmp = Self { name: spec.name, base, seeds: spec.seeds, seed: spec.seed.unwrap_or(1), methods, conditions };
        // Every cell's scenario must be valid before anything runs.
        for m in &cmp.methods {
            for c in &cmp.conditions {
                c.apply(&cmp.base, m).map_err(|source| CompareError::Scenario {
                    condition: c.name.clone(),
                    method: m.name.clone(),
                    source,
                })?;
            }
        }
        Ok(cmp)
    }

    /// Number of runs (cells × seeds, before sharing).
    pub fn runs(&self) -> u64 {
        self.methods.len() as u64 * self.conditions.len() as u64 * self.seeds
    }

    /// Number of flights actually flown (distinct cells × seeds).
    pub fn flights(&self) -> u64 {
        distinct_cells(self) as u64 * self.seeds
    }
}

/// One run of a comparison (a CSV row).
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct CompareRow {
    /// The method's name.
    pub method: String,
    /// The condition's name.
    pub condition: String,
    /// Run index (the seed stream of the base seed).
    pub run: u64,
    /// Every follower within every allowable error for the whole flight.
    pub pass: bool,
    /// Largest position error over the followers and the flight (m, the largest axis).
    pub max_error_m: f64,
    /// Largest error over the allowable error, any axis (≤ 1 passes).
    pub max_error_ratio: f64,
    /// Largest |error| per axis: x, y, z (m).
    pub max_x_m: f64,
    /// See `max_x_m`.
    pub max_y_m: f64,
    /// See `max_x_m`.
    pub max_z_m: f64,
    /// RMS position error over the three axes (m).
    pub rms_error_m: f64,
    /// Smallest separation (m).
    pub min_separation_m: f64,
    /// Adjustments per follower per minute.
    pub adjustments_per_uav_min: f64,
    /// Radio messages received per UAV per minute.
    pub messages_per_uav_min: f64,
    /// Mean control effort (inputs over their per-step limits, RSS).
    pub control_effort: f64,
    /// Seconds per follower flown with nothing perceived.
    pub alone_s_per_uav: f64,
}

/// The condition as it reaches `method`: for a method that uses no radio, in a base scenario
/// where nobody broadcasts, the radio's loss, delay and blackout change nothing, and are
/// dropped so that such cells share their runs (bit-identical either way).
pub fn effective(c: &Condition, method: &MethodEntry, base: &Scenario) -> Condition {
    let deaf = method.method.radio_need() == RadioNeed::None && base.beacons.is_empty() && !base.radio.broadcast_all;
    if deaf {
        Condition { name: String::new(), radio_loss: 0.0, radio_delay_s: 0.0, blackout: false, ..c.clone() }
    } else {
        Condition { name: String::new(), ..c.clone() }
    }
}

/// Runs every (method, condition, seed) on the current rayon pool, calling `progress` after
/// each run. Rows are in (method, condition, seed) order. Cells that [`effective`] makes equal
/// are run once.
pub fn run_comparison(cmp: &Comparison, progress: &(dyn Fn() + Sync)) -> Result<Vec<CompareRow>, CompareError> {
    let (unique, uses) = plan(cmp);
    let unique: Vec<(usize, Scenario)> = unique
        .into_iter()
        .map(|(mi, ci)| {
            let (m, c) = (&cmp.methods[mi], &cmp.conditions[ci]);
            c.apply(&cmp.base, m).map(|sc| (mi, sc)).map_err(|source| CompareError::Scenario {
                condition: c.name.clone(),
                method: m.name.clone(),
                source,
            })
        })
        .collect::<Result<_, _>>()?;
    let tasks: Vec<(usize, u64)> = (0..unique.len()).flat_map(|k| (0..cmp.seeds).map(move |r| (k, r))).collect();
    // One flight per work item: cells differ in cost by 100× (the horizon QP), and rayon's
    // adaptive splitting would otherwise leave a whole chunk of expensive cells to one thread.
    let runs: Vec<crate::metrics::RunSummary> = tasks
        .par_iter()
        .with_max_len(1)
        .map(|&(k, r)| {
            let sc = &unique[k].1;
            let (s, _) = run_one(sc, cmp.seed, r, false).map_err(|source| CompareError::Scenario {
                condition: sc.name.clone(),
                method: cmp.methods[unique[k].0].name.clone(),
                source,
            })?;
            progress();
            Ok(s)
        })
        .collect::<Result<_, CompareError>>()?;
    let seeds = cmp.seeds as usize;
    let allowable = cmp.base.allowable.as_array();
    Ok(uses
        .iter()
        .flat_map(|&(mi, ci, k)| {
            let (m, c) = (&cmp.methods[mi], &cmp.conditions[ci]);
            runs[k * seeds..(k + 1) * seeds].iter().map(move |s| {
                let e = s.max_abs_error;
                let ratio = (0..6).map(|a| e[a] / allowable[a]).fold(0.0, f64::max);
                let per_min = 60.0 / s.duration_s.max(f64::MIN_POSITIVE);
                CompareRow {
                    method: m.name.clone(),
                    condition: c.name.clone(),
                    run: s.run,
                    pass: s.pass,
                    max_error_m: e[0].max(e[1]).max(e[2]),
                    max_error_ratio: ratio,
                    max_x_m: e[0],
                    max_y_m: e[1],
                    max_z_m: e[2],
                    rms_error_m: ((s.rms_error[0].powi(2) + s.rms_error[1].powi(2) + s.rms_error[2].powi(2)) / 3.0)
                        .sqrt(),
                    min_separation_m: s.min_separation_m,
                    adjustments_per_uav_min: s.adjustments as f64 / s.followers.max(1) as f64 * per_min,
                    messages_per_uav_min: s.radio_msgs_per_uav_s * 60.0,
                    control_effort: s.control_effort,
                    alone_s_per_uav: s.alone_s_per_uav,
                }
            })
        })
        .collect())
}

/// What [`plan`] returns: the distinct cells to fly, as (method, condition) indices of a
/// representative, and for every (method, condition) in order, the distinct cell whose runs it
/// reports, as (method, condition, cell).
type Plan = (Vec<(usize, usize)>, Vec<(usize, usize, usize)>);

/// Which cells to fly and which runs each cell reports.
fn plan(cmp: &Comparison) -> Plan {
    let mut unique: Vec<(usize, usize, Condition)> = Vec::new();
    let mut uses = Vec::new();
    for (mi, m) in cmp.methods.iter().enumerate() {
        for (ci, c) in cmp.conditions.iter().enumerate() {
            let eff = effective(c, m, &cmp.base);
            let k = unique.iter().position(|u| u.0 == mi && u.2 == eff).unwrap_or_else(|| {
                unique.push((mi, ci, eff));
                unique.len() - 1
            });
            uses.push((mi, ci, k));
        }
    }
    (unique.into_iter().map(|(mi, ci, _)| (mi, ci)).collect(), uses)
}

/// Number of distinct cells [`run_comparison`] flies (after sharing, see [`effective`]).
pub fn distinct_cells(cmp: &Comparison) -> usize {
    plan(cmp).0.len()
}

/// Median and 95th percentile of one cell's runs.
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct CellSummary {
    /// The method's name.
    pub method: String,
    /// The condition's name.
    pub condition: String,
    /// Runs in the cell.
    pub runs: u64,
    /// Fraction of runs that passed.
    pub pass_fraction: f64,
    /// Median of the largest position error (m).
    pub max_error_m_median: f64,
    /// 95th percentile of the largest position error (m).
    pub max_error_m_p95: f64,
    /// Median of the largest error over its allowable error (any axis; ≤ 1 passes).
    pub error_ratio_median: f64,
    /// 95th percentile of the same.
    pub error_ratio_p95: f64,
    /// Median of the smallest separation (m).
    pub min_separation_m_median: f64,
    /// 5th percentile of the smallest separation (m): the close end.
    pub min_separation_m_p05: f64,
    /// Median adjustments per follower per minute.
    pub adjustments_per_uav_min: f64,
    /// Median radio messages received per UAV per minute.
    pub messages_per_uav_min: f64,
    /// Median control effort.
    pub control_effort: f64,
}

/// Summarises rows cell by cell, in the order cells first appear.
pub fn summarise(rows: &[CompareRow]) -> Vec<CellSummary> {
    let mut keys: Vec<(&str, &str)> = Vec::new();
    for r in rows {
        if !keys.contains(&(r.method.as_str(), r.condition.as_str())) {
            keys.push((&r.method, &r.condition));
        }
    }
    keys.iter()
        .map(|&(m, c)| {
            let cell: Vec<&CompareRow> = rows.iter().filter(|r| r.method == m && r.condition == c).collect();
            let col = |f: fn(&CompareRow) -> f64| {
                let mut v: Vec<f64> = cell.iter().map(|r| f(r)).collect();
                v.sort_by(f64::total_cmp);
                v
            };
            let err = col(|r| r.max_error_m);
            let sep = col(|r| r.min_separation_m);
            let ratio = col(|r| r.max_error_ratio);
            CellSummary {
                method: m.into(),
                condition: c.into(),
                runs: cell.len() as u64,
                pass_fraction: cell.iter().filter(|r| r.pass).count() as f64 / cell.len().max(1) as f64,
                max_error_m_median: quantile(&err, 0.5),
                max_error_m_p95: quantile(&err, 0.95),
                error_ratio_median: quantile(&ratio, 0.5),
                error_ratio_p95: quantile(&ratio, 0.95),
                min_separation_m_median: quantile(&sep, 0.5),
                min_separation_m_p05: quantile(&sep, 0.05),
                adjustments_per_uav_min: quantile(&col(|r| r.adjustments_per_uav_min), 0.5),
                messages_per_uav_min: quantile(&col(|r| r.messages_per_uav_min), 0.5),
                control_effort: quantile(&col(|r| r.control_effort), 0.5),
            }
        })
        .collect()
}

/// Quantile `q` of sorted values (nearest rank; NaN when empty).
pub fn quantile(sorted: &[f64], q: f64) -> f64 {
    if sorted.is_empty() {
        return f64::NAN;
    }
    let k = ((q * sorted.len() as f64).ceil() as usize).clamp(1, sorted.len()) - 1;
    sorted[k]
}

#[cfg(test)]
mod tests {
    use super::*;

    fn parse(text: &str) -> Result<Comparison, CompareError> {
        Comparison::parse(text, "test.toml", |name| match name {
            "paper" => Ok(Scenario::paper()),
            other => Err(format!("unknown scenario '{other}'")),
        })
    }

    #[test]
    fn the_built_in_comparison_parses() {
        let c = parse(BUILT_IN).expect("valid");
        assert!(c.seeds >= 50);
        assert!(c.methods.iter().any(|m| m.horizon > 1));
        assert!(c.conditions.iter().any(|c| c.blackout));
        assert!(c.conditions.iter().any(|c| c.fail.is_some()));
        assert!(c.conditions.iter().filter(|c| c.is_loss_only()).count() >= 3);
        assert!(c.conditions.iter().filter(|c| c.is_delay_only()).count() >= 3);
    }

    #[test]
    fn bad_comparisons_name_the_key() {
        let head = "name = 'x'\nscenario = 'paper'\nseeds = 2\nmethods = ['proximity']\n";
        let cases = [
            (format!("{head}[[condition]]\nname = 'a'\nradio_loss = 1.5\n"), "condition[0].radio_loss"),
            (format!("{head}[[condition]]\nname = 'a'\nradio_delay_s = 0.05\n"), "condition[0].radio_delay_s"),
            (format!("{head}[[condition]]\nname = 'a'\nfail_uav = 9\n"), "condition[0].fail_uav"),
            (format!("{head}[[condition]]\nname = 'a'\nwind = 3\n"), "wind"),
            (
                "name = 'x'\nscenario = 'paper'\nseeds = 2\n\
                 methods = [{ method = 'consensus', gains = { leader_share = -1.0 } }]\n[[condition]]\nname = 'a'\n"
                    .into(),
                "methods[0].gains",
            ),
            (
                "name = 'x'\nscenario = 'paper'\nseeds = 2\n\
                 methods = [{ method = 'flocking', gains = { c3 = 1.0 } }]\n[[condition]]\nname = 'a'\n"
                    .into(),
                "methods[0].gains",
            ),
            (
                "name = 'x'\nscenario = 'paper'\nseeds = 2\nmethods = ['pid']\n[[condition]]\nname = 'a'\n".into(),
                "methods[0]",
            ),
            (
                "name = 'x'\nscenario = 'moon'\nseeds = 2\nmethods = ['proximity']\n[[condition]]\nname = 'a'\n".into(),
                "scenario",
            ),
        ];
        for (text, key) in cases {
            let e = parse(&text).expect_err(key).to_string();
            assert!(e.contains(key), "{e} should name {key}");
        }
    }

    #[test]
    fn gains_given_in_the_file_reach_the_method() {
        let text = "name = 'x'\nscenario = 'paper'\nseeds = 1\n\
                    methods = [{ method = 'leader_follower', name = 'lf fast', gains = { pd = { kp = 4.0 } } }]\n\
                    [[condition]]\nname = 'a'\n";
        let c = parse(text).expect("valid");
        match c.methods[0].method {
            Method::LeaderFollower(g) => {
                assert_eq!(g.pd.kp, 4.0);
                assert_eq!(g.pd.kv, 2.0, "omitted gains keep their defaults");
            }
            m => panic!("{m:?}"),
        }
        assert_eq!(c.methods[0].name, "lf fast");
    }

    #[test]
    fn rows_do_not_depend_on_the_thread_count() {
        let text = "name = 'x'\nscenario = 'paper'\nseeds = 3\nmethods = ['proximity', 'leader_follower']\n\
                    [[condition]]\nname = 'lossy'\nradio_loss = 0.5\nradio_delay_s = 0.2\n";
        let mut c = parse(text).expect("valid");
        c.base.duration_s = 10.0;
        let one = rayon::ThreadPoolBuilder::new().num_threads(1).build().expect("pool");
        let two = rayon::ThreadPoolBuilder::new().num_threads(2).build().expect("pool");
        let a = one.install(|| run_comparison(&c, &|| {})).expect("runs");
        let b = two.install(|| run_comparison(&c, &|| {})).expect("runs");
        assert_eq!(a.len(), 6);
        assert_eq!(a, b);
    }

    #[test]
    fn radio_conditions_are_shared_only_by_methods_without_radio_and_change_nothing_for_them() {
        let text = "name = 'x'\nscenario = 'paper'\nseeds = 2\nmethods = ['proximity', 'leader_follower']\n\
                    [[condition]]\nname = 'ideal'\n[[condition]]\nname = 'lossy'\nradio_loss = 0.9\n";
        let mut c = parse(text).expect("valid");
        c.base.duration_s = 20.0;
        // Proximity shares one cell; leader-follower runs both.
        assert_eq!(distinct_cells(&c), 3);
        let rows = run_comparison(&c, &|| {}).expect("runs");
        let cell =
            |m: &str, k: &str| rows.iter().filter(|r| r.method == m && r.condition == k).cloned().collect::<Vec<_>>();
        let lf_ideal = cell("leader_follower", "ideal");
        let lf_lossy = cell("leader_follower", "lossy");
        assert!(lf_lossy[0].max_error_m > lf_ideal[0].max_error_m);
        // Sharing is exact: flying the lossy proximity cell for real gives the same numbers.
        let m = &c.methods[0];
        let sc = c.conditions[1].apply(&c.base, m).expect("valid");
        let (real, _) = run_one(&sc, c.seed, 0, false).expect("runs");
        let shared = &cell("proximity", "lossy")[0];
        assert_eq!(real.max_abs_error[0].max(real.max_abs_error[1]).max(real.max_abs_error[2]), shared.max_error_m);
        assert_eq!(real.min_separation_m, shared.min_separation_m);
    }
}
