//! Side-by-side comparisons: formation control methods × conditions × seeds.
//!
//! A comparison takes one base scenario, a list of methods (the proximity method with its
//! horizon, and the baselines of [`proxform_core::baseline`]) and a list of conditions (radio
//! loss and delay, sensor noise, a radio blackout, a failed UAV, onboard dropout), and runs
//! every method under every condition for the same seeds, so that every cell sees the same
//! disturbances. The raw file form is [`ComparisonSpec`] (TOML); [`Comparison`] is the checked
//! form, whose every cell is a checked scenario. Running it is the simulator's.

use proxform_core::controller::MAX_HORIZON;
use proxform_core::{Method, UavId};
use serde::Deserialize as _;

mod condition;

pub use condition::Condition;

use crate::convert::{method_from, SpecError};
use crate::defaults;
use crate::load::{locate, syntax_error, LoadError};
use crate::scenario::Scenario;
use crate::spec::ScenarioSpec;

/// Why a comparison is invalid.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum CompareError {
    /// A problem with the file: its syntax, a key's type, or a value; located by file, line
    /// and key (indices from 1, as in scenario files).
    #[error(transparent)]
    File(#[from] LoadError),
    /// A condition made the base scenario invalid.
    #[error("condition '{condition}', method '{method}': {problem}")]
    Scenario {
        /// The condition's name.
        condition: String,
        /// The method's name.
        method: String,
        /// The scenario's complaint (shown in the message, not as a cause: it would print twice).
        problem: SpecError,
    },
}

/// Most seeds per cell, in a file or from the command line.
pub const MAX_SEEDS: u64 = 1_000_000;
/// Most runs of a comparison (methods × conditions × seeds): every run's row is kept.
pub const MAX_RUNS: u64 = 2_000_000;
/// Most cells of a comparison (methods × conditions).
pub const MAX_CELLS: u64 = 2_000;

/// A value error at `key` of comparison file `file` (the line is found by the caller).
fn value_error(file: &str, key: &str, message: String) -> CompareError {
    CompareError::File(LoadError { source_name: file.into(), line: None, key: Some(key.into()), message })
}

/// A method entry of a comparison file: a label, or a table with options. A table's errors
/// name its key (`methods[2]: broadcast: invalid type: string "yes", expected a boolean`).
#[derive(Debug, Clone, PartialEq)]
pub enum MethodSpec {
    /// `"proximity"`, `"leader_follower"`, `"consensus"` or `"flocking"`, default gains.
    Label(String),
    /// `{ method = "proximity", horizon = 5, name = "proximity H=5" }`.
    Table(MethodTable),
}

/// A method entry's table.
#[derive(Debug, Clone, PartialEq, serde::Deserialize)]
#[serde(deny_unknown_fields)]
pub struct MethodTable {
    /// The method's label.
    pub method: String,
    /// Name in reports (default: the label, with the horizon when > 1).
    pub name: Option<String>,
    /// Horizon H of the proximity method (updates, 1 to 50).
    pub horizon: Option<u32>,
    /// A baseline's gains (keys of its gains struct; omitted ones keep their defaults),
    /// e.g. `{ pd = { kp = 2.0, kv = 2.8 } }` or `{ leader_share = 0.5 }`.
    pub gains: Option<toml::Table>,
    /// The neighbour predictor: `"alpha_beta"` (default), `"constant_velocity"` or
    /// `"singer"` (the Kalman tracks, fed by every channel).
    pub predictor: Option<String>,
    /// Further `[controller]` keys for this method, over the base scenario's, e.g.
    /// `{ isolation_gate = 1.0, own_gate_m = 3.0 }`.
    pub controller: Option<toml::Table>,
    /// Every UAV broadcasts its state each period (`radio.broadcast_all`), so that the
    /// method also hears its neighbours over the radio. Default false.
    pub broadcast: Option<bool>,
}

impl<'de> serde::Deserialize<'de> for MethodSpec {
    fn deserialize<D: serde::Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        use serde::de::Error;
        const KEYS: &str = "method (required), name, horizon, gains, predictor, controller, broadcast";
        match toml::Value::deserialize(d)? {
            toml::Value::String(l) => Ok(MethodSpec::Label(l)),
            toml::Value::Table(t) => {
                // Each key alone first, so that an error names it.
                for (k, v) in &t {
                    let mut one = toml::Table::new();
                    one.insert("method".into(), toml::Value::String("proximity".into()));
                    one.insert(k.clone(), v.clone());
                    if let Err(e) = MethodTable::deserialize(toml::Value::Table(one)) {
                        let why = e.message().trim().to_string();
                        return Err(match why.starts_with("unknown field") {
                            true => {
                                D::Error::custom(format!("unknown key {k} in a method table, expected one of {KEYS}"))
                            }
                            false => D::Error::custom(format!("{k}: {why}")),
                        });
                    }
                }
                MethodTable::deserialize(toml::Value::Table(t)).map(MethodSpec::Table).map_err(|e| {
                    D::Error::custom(format!("a method table has the keys {KEYS}: {}", e.message().trim()))
                })
            }
            other => Err(D::Error::custom(format!(
                "each method is a name (\"proximity\", \"leader_follower\", \"consensus\", \"flocking\") or a table \
                 with the keys {KEYS}, found {}",
                match other {
                    toml::Value::Integer(_) | toml::Value::Float(_) => "a number",
                    toml::Value::Boolean(_) => "true or false",
                    toml::Value::Array(_) => "a list",
                    _ => "a date",
                }
            ))),
        }
    }
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
    /// Every channel a method uses loses this fraction, independently: each onboard detection
    /// and each radio message, in [0, 1] (sets both `dropout` and `radio_loss`; give neither
    /// with it). The like-for-like loss: a method that senses onboard is touched by it as much
    /// as one that listens to the radio.
    pub channel_loss: Option<f64>,
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
    /// The conditions (none is refused by name, not as a missing key).
    #[serde(rename = "condition", default)]
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
    /// A baseline's gains as written (None: its defaults).
    pub gains: Option<toml::Table>,
    /// The neighbour predictor (None: the base scenario's).
    pub predictor: Option<String>,
    /// Further `[controller]` keys, as written (checked).
    pub controller: Option<toml::Table>,
    /// Every UAV broadcasts (the method hears its neighbours over the radio too).
    pub broadcast: bool,
}

/// A checked comparison.
#[derive(Debug, Clone)]
pub struct Comparison {
    /// Name in reports.
    pub name: String,
    /// The base scenario's spec (each cell applies its condition to it).
    pub base_spec: ScenarioSpec,
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

/// The built-in comparison: the paper's experiment under every condition, for the proximity
/// method (H = 1 and H = 5) and the three baselines.
pub const BUILT_IN: &str = crate::builtin::COMPARE_PAPER;

impl Comparison {
    /// Parses a comparison file; `resolve` turns its `scenario` entry into the base scenario's
    /// spec (already checked where it was read, so its errors name its own file).
    pub fn parse(
        text: &str,
        file: &str,
        resolve: impl FnOnce(&str) -> Result<ScenarioSpec, String>,
    ) -> Result<Self, CompareError> {
        Self::from_spec(Self::parse_spec(text, file)?, text, file, resolve)
    }

    /// Parses a comparison file's text into its spec (syntax and types only).
    pub fn parse_spec(text: &str, file: &str) -> Result<ComparisonSpec, CompareError> {
        toml::from_str(text).map_err(|e| syntax_error(text, file, &e).into())
    }

    /// Checks a comparison spec read from `text` (and perhaps edited since, like `seeds` from
    /// the command line); errors name the file, the line and the key.
    pub fn from_spec(
        spec: ComparisonSpec,
        text: &str,
        file: &str,
        resolve: impl FnOnce(&str) -> Result<ScenarioSpec, String>,
    ) -> Result<Self, CompareError> {
        let located = |e: CompareError| match e {
            CompareError::File(mut l) if l.line.is_none() => {
                l.line = l.key.as_deref().and_then(|k| locate(text, k));
                CompareError::File(l)
            }
            other => other,
        };
        let base = resolve(&spec.scenario).map_err(|message| located(value_error(file, "scenario", message)))?;
        Self::check(spec, base, file).map_err(located)
    }

    /// Checks a parsed specification against its base scenario's spec.
    pub fn check(spec: ComparisonSpec, base_spec: ScenarioSpec, file: &str) -> Result<Self, CompareError> {
        let base = Scenario::try_from(base_spec.clone()).map_err(|e| value_error(file, "scenario", e.to_string()))?;
        let bad = |key: String, message: String| value_error(file, &key, message);
        if !(1..=MAX_SEEDS).contains(&spec.seeds) {
            return Err(bad("seeds".into(), format!("must be 1 to {MAX_SEEDS}, found {}", spec.seeds)));
        }
        let cells = (spec.methods.len() as u64).saturating_mul(spec.conditions.len() as u64);
        if cells > MAX_CELLS {
            return Err(bad(
                "condition".into(),
                format!(
                    "{} methods × {} conditions = {cells} cells, more than the {MAX_CELLS} a comparison may have",
                    spec.methods.len(),
                    spec.conditions.len()
                ),
            ));
        }
        let runs = cells.saturating_mul(spec.seeds);
        if runs > MAX_RUNS {
            return Err(bad(
                "seeds".into(),
                format!(
                    "{} methods × {} conditions × {} seeds = {runs} runs, more than the {MAX_RUNS} a comparison may have",
                    spec.methods.len(),
                    spec.conditions.len(),
                    spec.seeds
                ),
            ));
        }
        if spec.methods.is_empty() {
            return Err(bad("methods".into(), "name at least one method".into()));
        }
        if spec.conditions.is_empty() {
            return Err(bad("condition".into(), "give at least one [[condition]]".into()));
        }
        let mut methods = Vec::new();
        for (k, m) in spec.methods.iter().enumerate() {
            let (label, name, horizon, gains, predictor, controller, broadcast) = match m {
                MethodSpec::Label(l) => (l.as_str(), None, None, None, None, None, None),
                MethodSpec::Table(MethodTable { method, name, horizon, gains, predictor, controller, broadcast }) => (
                    method.as_str(),
                    name.clone(),
                    *horizon,
                    gains.clone(),
                    predictor.clone(),
                    controller.clone(),
                    *broadcast,
                ),
            };
            let key = format!("methods[{}]", k + 1);
            let method = method_from(label, gains.as_ref())
                .map_err(|(sub, message)| bad(if sub { format!("{key}.gains") } else { key.clone() }, message))?;
            let horizon = horizon.unwrap_or(1);
            if !(1..=MAX_HORIZON).contains(&horizon) {
                return Err(bad(format!("{key}.horizon"), format!("must be 1 to {MAX_HORIZON}, found {horizon}")));
            }
            if horizon > 1 && method != Method::Proximity {
                return Err(bad(format!("{key}.horizon"), "applies to the proximity method only".into()));
            }
            if let Some(p) = predictor.as_deref().filter(|p| !["alpha_beta", "constant_velocity", "singer"].contains(p))
            {
                return Err(bad(
                    format!("{key}.predictor"),
                    format!("unknown predictor \"{p}\" (expected \"alpha_beta\", \"constant_velocity\" or \"singer\")"),
                ));
            }
            let mut name =
                name.unwrap_or_else(|| if horizon > 1 { format!("{label} H={horizon}") } else { label.to_string() });
            if let (Some(p), MethodSpec::Label(_) | MethodSpec::Table(MethodTable { name: None, .. })) = (&predictor, m)
            {
                name = format!("{name} {p}");
            }
            if methods.iter().any(|e: &MethodEntry| e.name == name) {
                return Err(bad(key, format!("duplicate method name '{name}'")));
            }
            if let Some(t) = &controller {
                for reserved in ["method", "gains", "horizon", "predictor"] {
                    if t.contains_key(reserved) {
                        return Err(bad(
                            format!("{key}.controller.{reserved}"),
                            format!("give {reserved} as the method entry's own key"),
                        ));
                    }
                }
                crate::spec::ControllerSpec::deserialize(toml::Value::Table(t.clone())).map_err(|e| {
                    // Named by the key at fault: the first that fails alone.
                    let alone = |k: &String, v: &toml::Value| {
                        let one = toml::Table::from_iter([(k.clone(), v.clone())]);
                        crate::spec::ControllerSpec::deserialize(toml::Value::Table(one)).is_err()
                    };
                    let at = t.iter().find(|(k, v)| alone(k, v)).map(|(k, _)| k.clone());
                    let key = at.map_or_else(|| format!("{key}.controller"), |k| format!("{key}.controller.{k}"));
                    bad(key, crate::load::plain_words(e.message().trim()))
                })?;
            }
            methods.push(MethodEntry {
                name,
                method,
                horizon,
                gains,
                predictor,
                controller,
                broadcast: broadcast.unwrap_or(false),
            });
        }
        let mut conditions: Vec<Condition> = Vec::new();
        for (k, c) in spec.conditions.iter().enumerate() {
            let key = |f: &str| format!("condition[{}].{f}", k + 1);
            let probability = |f: &str, v: Option<f64>| match v {
                Some(p) if !(0.0..=1.0).contains(&p) => {
                    Err(bad(key(f), format!("must be a probability in [0, 1], found {p}")))
                }
                Some(p) => Ok(p),
                None => Ok(0.0),
            };
            let (radio_loss, dropout) = match c.channel_loss {
                Some(_) if c.radio_loss.is_some() || c.dropout.is_some() => {
                    return Err(bad(key("channel_loss"), "sets radio_loss and dropout: give neither with it".into()));
                }
                Some(p) => {
                    let p = probability("channel_loss", Some(p))?;
                    (p, p)
                }
                None => (probability("radio_loss", c.radio_loss)?, probability("dropout", c.dropout)?),
            };
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
                    let at = c.fail_at_s.unwrap_or(defaults::FAIL_AT_S);
                    if !(at.is_finite() && at >= 0.0) {
                        return Err(bad(key("fail_at_s"), format!("must be a time ≥ 0 s, found {at}")));
                    }
                    if at >= base.duration_s() {
                        return Err(bad(
                            key("fail_at_s"),
                            format!(
                                "UAV {u} would fail at {at} s, after the flight's {} s: it never fails (a time \
                                 before the end, or a longer scenario)",
                                base.duration_s()
                            ),
                        ));
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
        let cmp = Self {
            name: spec.name,
            base_spec,
            base,
            seeds: spec.seeds,
            seed: spec.seed.unwrap_or(defaults::SEED),
            methods,
            conditions,
        };
        // Every cell's scenario must be valid before anything runs.
        for m in &cmp.methods {
            for c in &cmp.conditions {
                c.scenario(&cmp.base_spec, m)?;
            }
        }
        Ok(cmp)
    }

    /// Number of runs (cells × seeds, before sharing).
    pub fn runs(&self) -> u64 {
        self.methods.len() as u64 * self.conditions.len() as u64 * self.seeds
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn parse(text: &str) -> Result<Comparison, CompareError> {
        Comparison::parse(text, "test.toml", |name| match name {
            "paper" => Ok(crate::builtin::paper_spec()),
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
        // Like-for-like loss: every channel loses the same fraction.
        let lossy: Vec<f64> = c.conditions.iter().filter_map(|c| c.channel_loss()).filter(|p| *p > 0.0).collect();
        assert!(lossy.len() >= 3, "{lossy:?}");
    }

    #[test]
    fn bad_comparisons_name_the_key() {
        let head = "name = 'x'\nscenario = 'paper'\nseeds = 2\nmethods = ['proximity']\n";
        let cases = [
            (format!("{head}[[condition]]\nname = 'a'\nradio_loss = 1.5\n"), "condition[1].radio_loss"),
            (format!("{head}[[condition]]\nname = 'a'\nradio_delay_s = 0.05\n"), "condition[1].radio_delay_s"),
            (format!("{head}[[condition]]\nname = 'a'\nfail_uav = 9\n"), "condition[1].fail_uav"),
            (format!("{head}[[condition]]\nname = 'a'\nfail_uav = 2\nfail_at_s = 1e4\n"), "condition[1].fail_at_s"),
            (
                format!("{head}[[condition]]\nname = 'a'\nchannel_loss = 0.3\ndropout = 0.1\n"),
                "condition[1].channel_loss",
            ),
            (format!("{head}[[condition]]\nname = 'a'\nwind = 3\n"), "wind"),
            (
                "name = 'x'\nscenario = 'paper'\nseeds = 2\n\
                 methods = [{ method = 'consensus', gains = { leader_share = -1.0 } }]\n[[condition]]\nname = 'a'\n"
                    .into(),
                "methods[1].gains",
            ),
            (
                "name = 'x'\nscenario = 'paper'\nseeds = 2\n\
                 methods = [{ method = 'flocking', gains = { c3 = 1.0 } }]\n[[condition]]\nname = 'a'\n"
                    .into(),
                "methods[1].gains",
            ),
            (
                "name = 'x'\nscenario = 'paper'\nseeds = 2\nmethods = ['pid']\n[[condition]]\nname = 'a'\n".into(),
                "methods[1]",
            ),
            (
                "name = 'x'\nscenario = 'paper'\nseeds = 2\n\
                 methods = [{ method = 'proximity', controler = { isolation_gate = 1.0 } }]\n[[condition]]\nname = 'a'\n"
                    .into(),
                "methods: unknown key controler in a method table",
            ),
            (
                "name = 'x'\nscenario = 'moon'\nseeds = 2\nmethods = ['proximity']\n[[condition]]\nname = 'a'\n".into(),
                "scenario",
            ),
            // A method table's key of the wrong type is named, inside the table and out.
            (
                "name = 'x'\nscenario = 'paper'\nseeds = 2\nmethods = [{ method = 'proximity', broadcast = 'yes' }]\n\
                 [[condition]]\nname = 'a'\n"
                    .into(),
                "methods: broadcast: found the text \"yes\", expected true or false",
            ),
            (
                "name = 'x'\nscenario = 'paper'\nseeds = 2\n\
                 methods = [{ method = 'proximity', controller = { own_gate_m = 2.0, isolation_gate = 'high' } }]\n\
                 [[condition]]\nname = 'a'\n"
                    .into(),
                "methods[1].controller.isolation_gate: found the text \"high\", expected a number",
            ),
            (
                "name = 'x'\nscenario = 'paper'\nseeds = 2\nmethods = ['proximity', 7]\n[[condition]]\nname = 'a'\n".into(),
                "methods: each method is a name",
            ),
        ];
        for (text, key) in cases {
            let e = parse(&text).expect_err(key).to_string();
            assert!(e.contains(key), "{e} should name {key}");
            // Located: `test.toml:LINE: key: …`.
            let line =
                e.strip_prefix("test.toml:").and_then(|r| r.split(':').next()).and_then(|l| l.parse::<usize>().ok());
            assert!(line.is_some(), "{e} has no line");
        }
        // Seeds beyond the bound, and a product of cells that would not fit in memory.
        let e = parse(&format!("{head}[[condition]]\nname = 'a'\n").replace("seeds = 2", "seeds = 4294967296"))
            .expect_err("too many seeds")
            .to_string();
        assert!(e.contains("test.toml:3: seeds: must be 1 to 1000000"), "{e}");
        let many =
            "name = 'x'\nscenario = 'paper'\nseeds = 1000000\nmethods = ['proximity', 'consensus', 'flocking']\n\
                    [[condition]]\nname = 'a'\n[[condition]]\nname = 'b'\n";
        let e = parse(many).expect_err("too many runs").to_string();
        assert!(e.contains("6000000 runs, more than the 2000000"), "{e}");
        // No condition at all: said so, not as a key missing at line 1.
        let e = parse(head).expect_err("no condition").to_string();
        assert_eq!(e, "test.toml: condition: give at least one [[condition]]");
    }

    #[test]
    fn a_predictor_given_to_a_method_reaches_its_cells() {
        let text = "name = 'x'\nscenario = 'paper'\nseeds = 1\n\
                    methods = ['proximity', { method = 'proximity', predictor = 'singer' }]\n\
                    [[condition]]\nname = 'a'\n";
        let c = parse(text).expect("valid");
        assert_eq!(c.methods[1].name, "proximity singer");
        let sc = c.conditions[0].scenario(&c.base_spec, &c.methods[1]).expect("valid");
        assert!(matches!(sc.controller().predictor, proxform_core::PredictorKind::Singer { .. }));
        let plain = c.conditions[0].scenario(&c.base_spec, &c.methods[0]).expect("valid");
        assert!(matches!(plain.controller().predictor, proxform_core::PredictorKind::AlphaBeta { .. }));
        let bad = text.replace("'singer'", "'magic'");
        let e = parse(&bad).expect_err("unknown predictor").to_string();
        assert!(e.contains("methods[2].predictor: unknown predictor"), "{e}");
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
    fn controller_keys_and_broadcast_given_to_a_method_reach_its_cells() {
        let text = "name = 'x'\nscenario = 'paper'\nseeds = 1\n\
                    methods = ['proximity', { method = 'proximity', name = 'robust', broadcast = true, \
                    controller = { isolation_gate = 1.5, own_gate_m = 2.0 } }]\n\
                    [[condition]]\nname = 'a'\nradio_loss = 0.2\n";
        let c = parse(text).expect("valid");
        let sc = c.conditions[0].scenario(&c.base_spec, &c.methods[1]).expect("valid");
        assert_eq!((sc.controller().isolation_gate, sc.controller().own_gate_m), (Some(1.5), Some(2.0)));
        assert!(sc.radio().broadcast_all);
        assert_eq!(sc.radio().loss, 0.2);
        let plain = c.conditions[0].scenario(&c.base_spec, &c.methods[0]).expect("valid");
        assert_eq!((plain.controller().isolation_gate, plain.radio().broadcast_all), (None, false));
        for (bad, key) in [
            ("isolation_gate = 1.5", "methods[2].controller"),
            ("isolation_gate = 'high'", "methods[2].controller"),
            ("predictor = 'singer'", "methods[2].controller.predictor"),
        ] {
            let text =
                text.replace("isolation_gate = 1.5", &bad.replace("isolation_gate = 1.5", "isolation_gat = 1.5"));
            let e = parse(&text).expect_err(key).to_string();
            assert!(e.contains(key), "{e} should name {key}");
        }
    }
}
