//! Python values ↔ TOML values: a dict becomes the same TOML a file would hold (so it meets
//! the same parser, checks and error messages), and resolved TOML comes back as dicts.

use pyo3::exceptions::PyTypeError;
use pyo3::prelude::*;
use pyo3::types::{PyBool, PyDict, PyFloat, PyInt, PyList, PyString, PyTuple};
use toml::Value;

/// Why a Python value has no TOML form: the key path and what was found.
#[derive(Debug)]
pub struct ValueError {
    /// The key path (`controller.lambda`, `fault[2].at_s`).
    pub key: String,
    /// What is wrong.
    pub message: String,
}

/// Deepest nesting of dicts and lists a scenario value may have: a scenario's deepest key is a
/// few levels down; deeper is a mistake, or a list or dict that contains itself (followed
/// without end, it would exhaust the stack).
pub const MAX_DEPTH: usize = 32;

/// Converts `obj` at key path `key` (empty at the top) into a TOML value.
pub fn to_toml(obj: &Bound<'_, PyAny>, key: &str) -> Result<Value, ValueError> {
    to_toml_at(obj, key, 0)
}

fn to_toml_at(obj: &Bound<'_, PyAny>, key: &str, depth: usize) -> Result<Value, ValueError> {
    let fail = |message: String| ValueError { key: key.to_string(), message };
    if depth > MAX_DEPTH {
        return Err(fail(format!(
            "nested more than {MAX_DEPTH} lists or dicts deep (one that contains itself?): a scenario's values are a \
             few levels deep"
        )));
    }
    if obj.is_none() {
        return Err(fail("None has no meaning in a scenario: leave the key out for its default".into()));
    }
    // bool before int: Python's bool is an int.
    if let Ok(b) = obj.cast::<PyBool>() {
        return Ok(Value::Boolean(b.is_true()));
    }
    if obj.is_instance_of::<PyInt>() {
        return obj.extract::<i64>().map(Value::Integer).map_err(|_| fail("whole number out of range".into()));
    }
    if obj.is_instance_of::<PyFloat>() {
        let v: f64 = obj.extract().map_err(|_| fail("not a number".into()))?;
        return Ok(Value::Float(v));
    }
    if obj.is_instance_of::<PyString>() {
        return obj.extract::<String>().map(Value::String).map_err(|_| fail("text that is not UTF-8".into()));
    }
    if let Ok(d) = obj.cast::<PyDict>() {
        let mut table = toml::Table::new();
        for (k, v) in d.iter() {
            // Dependency tables are keyed by UAV number: an int key is written as TOML writes it.
            let name: String = if k.is_instance_of::<PyString>() {
                k.extract::<String>().map_err(|_| fail("a key that is not UTF-8".into()))?
            } else if k.is_instance_of::<PyInt>() && !k.is_instance_of::<PyBool>() {
                k.str().map_err(|_| fail("a key that cannot be written".into()))?.to_string()
            } else {
                return Err(fail(format!("keys must be text, found {}", type_name(&k))));
            };
            let path = if key.is_empty() { name.clone() } else { format!("{key}.{name}") };
            table.insert(name, to_toml_at(&v, &path, depth + 1)?);
        }
        return Ok(Value::Table(table));
    }
    let items: Option<Vec<Bound<'_, PyAny>>> = if let Ok(l) = obj.cast::<PyList>() {
        Some(l.iter().collect())
    } else if let Ok(t) = obj.cast::<PyTuple>() {
        Some(t.iter().collect())
    } else {
        None
    };
    if let Some(items) = items {
        let mut out = Vec::with_capacity(items.len());
        for (i, v) in items.iter().enumerate() {
            // Lists of tables are numbered from 1, as the located errors number them.
            let path = if v.is_instance_of::<PyDict>() {
                let (parent, last) = key.rsplit_once('.').map_or(("", key), |(p, l)| (p, l));
                let item = format!("{last}[{}]", i + 1);
                if parent.is_empty() {
                    item
                } else {
                    format!("{parent}.{item}")
                }
            } else {
                key.to_string()
            };
            out.push(to_toml_at(v, &path, depth + 1)?);
        }
        return Ok(Value::Array(out));
    }
    // numpy scalars and arrays, and other numbers: through the number protocols.
    if let Ok(tolist) = obj.getattr("tolist") {
        if let Ok(v) = tolist.call0() {
            return to_toml_at(&v, key, depth + 1);
        }
    }
    if obj.hasattr("__index__").unwrap_or(false) {
        return obj.extract::<i64>().map(Value::Integer).map_err(|_| fail("whole number out of range".into()));
    }
    if obj.hasattr("__float__").unwrap_or(false) {
        return obj.extract::<f64>().map(Value::Float).map_err(|_| fail("not a number".into()));
    }
    Err(fail(format!("a scenario holds numbers, text, true/false, lists and tables, not {}", type_name(obj))))
}

fn type_name(obj: &Bound<'_, PyAny>) -> String {
    obj.get_type().name().map(|n| n.to_string()).unwrap_or_else(|_| "this value".into())
}

/// A TOML value as plain Python objects (dicts, lists, numbers, text).
pub fn to_python<'py>(py: Python<'py>, v: &Value) -> PyResult<Bound<'py, PyAny>> {
    Ok(match v {
        Value::String(s) => s.into_pyobject(py)?.into_any(),
        Value::Integer(i) => i.into_pyobject(py)?.into_any(),
        Value::Float(f) => f.into_pyobject(py)?.into_any(),
        Value::Boolean(b) => b.into_pyobject(py)?.to_owned().into_any(),
        Value::Datetime(d) => d.to_string().into_pyobject(py)?.into_any(),
        Value::Array(a) => {
            let list = PyList::empty(py);
            for x in a {
                list.append(to_python(py, x)?)?;
            }
            list.into_any()
        }
        Value::Table(t) => {
            let dict = PyDict::new(py);
            for (k, x) in t {
                dict.set_item(k, to_python(py, x)?)?;
            }
            dict.into_any()
        }
    })
}

/// Merges `over` into `base`: tables key by key, anything else replaced.
pub fn merge(base: &mut Value, over: Value) {
    match (base, over) {
        (Value::Table(b), Value::Table(o)) => {
            for (k, v) in o {
                match b.get_mut(&k) {
                    Some(slot) => merge(slot, v),
                    None => {
                        b.insert(k, v);
                    }
                }
            }
        }
        (b, o) => *b = o,
    }
}

/// A TypeError for an argument that is not a dict.
pub fn not_a_dict(what: &str, obj: &Bound<'_, PyAny>) -> PyErr {
    PyTypeError::new_err(format!("{what} must be a dict, not {}", type_name(obj)))
}
