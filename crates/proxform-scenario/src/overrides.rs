//! One key of a scenario set from outside its file (`--set controller.lambda=0.5`, a sweep's
//! cell): the spec is written as TOML, the key set in its table, and the spec read back, so
//! the value meets the same checks as in a file when the spec is converted.

use crate::spec::ScenarioSpec;

/// A value as written on a command line: TOML (`0.5`, `true`, `[1, 2]`, `"text"`), or else
/// the bare word as text (`alpha_beta`).
pub fn parse_value(text: &str) -> toml::Value {
    match toml::from_str::<toml::Table>(&format!("v = {text}")) {
        Ok(mut t) => t.remove("v").unwrap_or_else(|| toml::Value::String(text.to_string())),
        Err(_) => toml::Value::String(text.to_string()),
    }
}

/// `spec` with the dotted `key` (tables only: `controller.lambda`, `radio.delay_s`) set to
/// `value` (see [`parse_value`]). Errors name what is wrong with the key or value.
pub fn set(spec: &ScenarioSpec, key: &str, value: &str) -> Result<ScenarioSpec, String> {
    let parts: Vec<&str> = key.split('.').collect();
    if parts.iter().any(|p| p.is_empty() || !p.chars().all(|c| c.is_ascii_alphanumeric() || c == '_')) {
        return Err(format!("\"{key}\" is not a key (names of letters, digits and _, joined by dots)"));
    }
    let mut root = toml::Value::try_from(spec).map_err(|e| format!("cannot write the scenario's spec: {e}"))?;
    let mut table = &mut root;
    for (depth, part) in parts.iter().enumerate() {
        let toml::Value::Table(t) = table else {
            return Err(format!(
                "{} is not a table (a key inside a list, such as one slot's, cannot be set this way)",
                parts[..depth].join(".")
            ));
        };
        if depth + 1 == parts.len() {
            t.insert((*part).to_string(), parse_value(value));
            break;
        }
        table = t.entry((*part).to_string()).or_insert_with(|| toml::Value::Table(toml::Table::new()));
    }
    root.try_into::<ScenarioSpec>().map_err(|e| {
        let m = e.message().trim().to_string();
        format!("{key}: {m}")
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_key_is_set_in_its_table_and_checked_on_conversion() {
        let spec = crate::builtin::spec_by_name("paper", None).expect("built in");
        let s = set(&spec, "controller.lambda", "0.25").expect("a key of the controller");
        assert_eq!(s.controller.lambda, Some(0.25));
        let sc = crate::Scenario::try_from(s).expect("valid");
        assert_eq!(sc.controller().lambda, 0.25);
        // Out of range: refused when converted, naming the key.
        let s = set(&spec, "controller.lambda", "2").expect("a number");
        let e = crate::Scenario::try_from(s).expect_err("λ ≤ 1");
        assert_eq!(e.key, "controller.lambda");
        // Unknown keys and values of the wrong type are refused at once.
        assert!(set(&spec, "controller.lamda", "0.5").expect_err("unknown").contains("lamda"));
        assert!(set(&spec, "controller.lambda", "fast").is_err());
        assert!(set(&spec, "controller..lambda", "1").expect_err("empty part").contains("not a key"));
        // Bare words are text.
        let s = set(&spec, "controller.predictor", "singer").expect("text");
        assert_eq!(s.controller.predictor.as_deref(), Some("singer"));
    }
}
