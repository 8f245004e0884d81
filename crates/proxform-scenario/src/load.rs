//! Scenario files: TOML text → [`ScenarioSpec`] → checked [`Scenario`], with every error
//! located in its source (file name, line and key).

use std::collections::BTreeMap;

use crate::scenario::Scenario;
use crate::spec::ScenarioSpec;

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

/// Parses and checks a scenario file's text; `source_name` names it in errors.
pub fn parse(text: &str, source_name: &str) -> Result<Scenario, LoadError> {
    check(parse_spec(text, source_name)?, text, source_name)
}

/// Parses a scenario file's text into its spec (TOML syntax, known keys, value types only);
/// the name defaults to the file's stem.
pub fn parse_spec(text: &str, source_name: &str) -> Result<ScenarioSpec, LoadError> {
    let spec: ScenarioSpec = toml::from_str(text).map_err(|e| syntax_error(text, source_name, &e))?;
    let default_name =
        std::path::Path::new(source_name).file_stem().and_then(|s| s.to_str()).unwrap_or("scenario").to_string();
    Ok(ScenarioSpec { name: spec.name.clone().or(Some(default_name)), ..spec })
}

/// Converts `spec` (read from `text`, or from `text` and then overridden) into a checked
/// scenario; an error names the source, the key and the line where that key stands.
pub fn check(spec: ScenarioSpec, text: &str, source_name: &str) -> Result<Scenario, LoadError> {
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

/// A TOML or type error located in `text`: its line, the key that line assigns, and the
/// message in the user's words.
pub fn syntax_error(text: &str, source_name: &str, e: &toml::de::Error) -> LoadError {
    let line = e.span().map(|s| line_of(text, s.start));
    let key = line.and_then(|l| key_at(text, l));
    let mut message = plain_words(e.message());
    // A count beyond any whole number a key takes: the limit of the key itself, where it has one.
    if key.as_deref().is_some_and(|k| k.ends_with(".uavs") || k == "uavs") {
        message = message.replace(
            "from 0 to 4294967295 (within that, the key's own limit applies)",
            &format!("from 1 to {} (the most UAVs a scenario flies)", crate::convert::MAX_UAVS),
        );
    }
    LoadError { source_name: source_name.into(), line, key, message }
}

/// Serde's and TOML's words for types, in the words of a file's author.
pub fn plain_words(message: &str) -> String {
    let mut m = message.trim().replace('\n', " ");
    const WORDS: [(&str, &str); 19] = [
        ("expected f64", "expected a number"),
        ("expected u32", "expected a whole number from 0 to 4294967295 (within that, the key's own limit applies)"),
        ("expected u64", "expected a whole number from 0 to 18446744073709551615"),
        ("expected i64", "expected a whole number"),
        ("expected a boolean", "expected true or false"),
        ("expected a string", "expected text in quotes"),
        ("expected a sequence", "expected a list [ … ]"),
        ("expected a map", "expected a table"),
        ("expected an array of length 3", "expected a list of 3 numbers"),
        ("invalid type: string", "found the text"),
        ("invalid type: floating point", "found the number"),
        ("invalid type: integer", "found the whole number"),
        (" as i128,", ", beyond any whole number a key takes,"),
        ("invalid type: boolean", "found"),
        ("invalid type: sequence", "found a list"),
        ("invalid type: map", "found a table"),
        ("invalid value: integer", "found"),
        ("invalid length", "found a list of length"),
        ("unknown field", "unknown key"),
    ];
    for (rust, plain) in WORDS {
        m = m.replace(rust, plain);
    }
    // "expected struct FooSpec" and "expected one of `a`, `b`".
    if let Some(i) = m.find("expected struct ") {
        let end = m[i + 16..].find(|c: char| !c.is_alphanumeric()).map_or(m.len(), |e| i + 16 + e);
        m.replace_range(i..end, "expected a table");
    }
    m.replace("missing field", "missing key").replace('`', "")
}

/// The key path that line `line` (from 1) of `text` assigns, as `locate` reads it:
/// `controller.lambda`, `fault[2].at_s`; the table's own path on a header line.
pub fn key_at(text: &str, line: usize) -> Option<String> {
    let mut header: Vec<String> = Vec::new();
    let mut counts: BTreeMap<String, usize> = BTreeMap::new();
    for (n, raw) in text.lines().enumerate() {
        let l = raw.split('#').next().unwrap_or("").trim();
        let here = n + 1 == line;
        if let Some(h) = l.strip_prefix("[[").and_then(|x| x.strip_suffix("]]")) {
            let name = h.trim().to_string();
            let k = *counts.entry(name.clone()).and_modify(|c| *c += 1).or_insert(1);
            header = name.split('.').map(|s| s.trim().to_string()).collect();
            if let Some(last) = header.last_mut() {
                *last = format!("{last}[{k}]");
            }
        } else if let Some(h) = l.strip_prefix('[').and_then(|x| x.strip_suffix(']')) {
            header = h.split('.').map(|s| s.trim().to_string()).collect();
        } else if here {
            let key = l.split_once('=').map(|(k, _)| k.trim().trim_matches('"').to_string());
            let mut path = header.clone();
            path.extend(key);
            return (!path.is_empty()).then(|| path.join("."));
        }
        if here {
            return (!header.is_empty()).then(|| header.join("."));
        }
    }
    None
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
        assert_eq!(key_at(text, 4).as_deref(), Some("controller.lambda"));
        assert_eq!(key_at(text, 11).as_deref(), Some("fault[2].at_s"));
        assert_eq!(key_at(text, 1).as_deref(), Some("name"));
    }

    #[test]
    fn type_errors_name_the_key_in_the_users_words() {
        let cases = [
            ("[controller]\nlambda = \"x\"\n", "controller.lambda", "expected a number"),
            ("[vehicle]\nattitude_max_deg = [1.0, 2.0]\n", "vehicle.attitude_max_deg", "a list of 3 numbers"),
            ("[controller]\nareas = 8.5\n", "controller.areas", "expected a whole number"),
            ("navigator = -1\n", "navigator", "a whole number from 0"),
            ("formation = 3\n", "formation", "expected a table"),
            ("[[fault]]\nkind = \"remove\"\n[[fault]]\nat_s = true\n", "fault[2].at_s", "found true"),
            ("[controller]\nlamda = 0.5\n", "controller.lamda", "unknown key lamda"),
        ];
        for (text, key, words) in cases {
            let e = parse(text, "t.toml").expect_err(key);
            assert_eq!(e.key.as_deref(), Some(key), "{e}");
            assert!(e.message.contains(words), "{e} should say «{words}»");
            for rust in ["f64", "u32", "i64", "sequence", "struct", "`"] {
                assert!(!e.message.contains(rust), "{e} speaks Rust ({rust})");
            }
        }
    }
}
