//! JSON helpers shared by the model and parameter readers: syntax errors with line and column,
//! a JSON path tracker, value descriptions for messages, and a compact pretty printer.

use crate::error::{IoError, MAX_QUOTED_CHARS, quote};
use serde_json::{Map, Value};
use std::cell::RefCell;
use std::fmt::Write as _;

/// Parses JSON text, turning syntax errors into [`IoError::JsonSyntax`] with line and column.
///
/// Unlike `serde_json::from_str::<Value>`, which keeps the last of two equal keys, a key that
/// appears twice in one object is an error ([`IoError::DuplicateKey`]): `"degree": 2, "degree":
/// 3` is far more likely a mistake than an intended override.
pub(crate) fn parse(text: &str) -> Result<Value, IoError> {
    let state = Strict::default();
    let mut de = serde_json::Deserializer::from_str(text);
    let parsed = serde::de::DeserializeSeed::deserialize(&state, &mut de).and_then(|v| {
        de.end()?;
        Ok(v)
    });
    parsed.map_err(|e| {
        let (line, column) = (e.line(), e.column());
        if let Some((path, key)) = state.duplicate.take() {
            return IoError::DuplicateKey {
                line,
                column,
                path,
                key,
            };
        }
        let full = e.to_string();
        let suffix = format!(" at line {line} column {column}");
        let message = full.strip_suffix(&suffix).unwrap_or(&full).to_string();
        IoError::JsonSyntax {
            line,
            column,
            message,
        }
    })
}

/// The state of one strict parse: the path of the value being read (for the message of a
/// duplicate key) and the duplicate found, if any.
#[derive(Default)]
struct Strict {
    path: RefCell<Vec<Step>>,
    duplicate: RefCell<Option<(String, String)>>,
}

impl Strict {
    fn enter<T>(&self, step: Step, f: impl FnOnce() -> T) -> T {
        self.path.borrow_mut().push(step);
        let out = f();
        self.path.borrow_mut().pop();
        out
    }
}

impl<'de> serde::de::DeserializeSeed<'de> for &Strict {
    type Value = Value;
    fn deserialize<D: serde::Deserializer<'de>>(self, d: D) -> Result<Value, D::Error> {
        d.deserialize_any(self)
    }
}

impl<'de> serde::de::Visitor<'de> for &Strict {
    type Value = Value;

    fn expecting(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str("a JSON value")
    }
    fn visit_bool<E>(self, b: bool) -> Result<Value, E> {
        Ok(Value::Bool(b))
    }
    fn visit_i64<E>(self, n: i64) -> Result<Value, E> {
        Ok(Value::Number(n.into()))
    }
    fn visit_u64<E>(self, n: u64) -> Result<Value, E> {
        Ok(Value::Number(n.into()))
    }
    fn visit_f64<E>(self, x: f64) -> Result<Value, E> {
        Ok(serde_json::Number::from_f64(x).map_or(Value::Null, Value::Number))
    }
    fn visit_str<E>(self, s: &str) -> Result<Value, E> {
        Ok(Value::String(s.to_owned()))
    }
    fn visit_string<E>(self, s: String) -> Result<Value, E> {
        Ok(Value::String(s))
    }
    fn visit_unit<E>(self) -> Result<Value, E> {
        Ok(Value::Null)
    }
    fn visit_none<E>(self) -> Result<Value, E> {
        Ok(Value::Null)
    }
    fn visit_seq<A: serde::de::SeqAccess<'de>>(self, mut seq: A) -> Result<Value, A::Error> {
        let mut out = Vec::new();
        while let Some(v) = self.enter(Step::Index(out.len()), || seq.next_element_seed(self))? {
            out.push(v);
        }
        Ok(Value::Array(out))
    }
    fn visit_map<A: serde::de::MapAccess<'de>>(self, mut map: A) -> Result<Value, A::Error> {
        let mut out = Map::new();
        while let Some(key) = map.next_key::<String>()? {
            if out.contains_key(&key) {
                let path = JsonPath(self.path.borrow().clone()).to_string();
                let message = format!("duplicate key {}", quote(&key));
                *self.duplicate.borrow_mut() = Some((path, key));
                return Err(serde::de::Error::custom(message));
            }
            let v = self.enter(Step::Key(key.clone()), || map.next_value_seed(self))?;
            out.insert(key, v);
        }
        Ok(Value::Object(out))
    }
}

/// One step of a JSON path.
#[derive(Clone, Debug)]
enum Step {
    Key(String),
    Index(usize),
}

/// A JSON path such as `entities[0].control_points[2][1]`.
#[derive(Clone, Debug, Default)]
pub(crate) struct JsonPath(Vec<Step>);

impl JsonPath {
    /// The path of the `index`-th entity, always spelled `entities[index]`.
    pub(crate) fn entity(index: usize) -> Self {
        JsonPath(vec![Step::Key("entities".into()), Step::Index(index)])
    }
    /// This path followed by a field name.
    pub(crate) fn key(&self, k: &str) -> Self {
        let mut p = self.clone();
        p.0.push(Step::Key(k.into()));
        p
    }
    /// This path followed by an array index.
    pub(crate) fn index(&self, i: usize) -> Self {
        let mut p = self.clone();
        p.0.push(Step::Index(i));
        p
    }
    /// A structural error at this path.
    pub(crate) fn error(&self, message: impl Into<String>) -> IoError {
        IoError::Structure {
            path: self.to_string(),
            message: message.into(),
        }
    }
    /// "expected X, found <description of v>" at this path.
    pub(crate) fn expected(&self, what: &str, v: &Value) -> IoError {
        self.error(format!("expected {what}, found {}", describe(v)))
    }
}

impl std::fmt::Display for JsonPath {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        if self.0.is_empty() {
            return f.write_str("top level");
        }
        for (n, s) in self.0.iter().enumerate() {
            match s {
                Step::Key(k) if n == 0 => write!(f, "{}", short(k))?,
                Step::Key(k) => write!(f, ".{}", short(k))?,
                Step::Index(i) => write!(f, "[{i}]")?,
            }
        }
        Ok(())
    }
}

/// A key of a JSON path as written, or quoted and cut ([`quote`]) when it is long or holds
/// characters that would make the path ambiguous.
fn short(k: &str) -> std::borrow::Cow<'_, str> {
    let plain = |c: char| c.is_alphanumeric() || c == '_' || c == '-';
    if k.chars().count() <= MAX_QUOTED_CHARS && !k.is_empty() && k.chars().all(plain) {
        k.into()
    } else {
        quote(k).into()
    }
}

/// A short description of a JSON value for messages: `a string`, `an array of 2 elements`.
pub(crate) fn describe(v: &Value) -> String {
    match v {
        Value::Null => "null".into(),
        Value::Bool(b) => format!("a boolean ({b})"),
        Value::Number(n) => format!("a number ({n})"),
        Value::String(_) => "a string".into(),
        Value::Array(a) => match a.len() {
            0 => "an empty array".into(),
            1 => "an array of 1 element".into(),
            n => format!("an array of {n} elements"),
        },
        Value::Object(_) => "an object".into(),
    }
}

/// A finite number at `path`.
pub(crate) fn number(v: &Value, path: &JsonPath) -> Result<f64, IoError> {
    match v.as_f64() {
        Some(x) if x.is_finite() => Ok(x),
        Some(x) => Err(path.error(format!("number {x} is not finite"))),
        None => Err(path.expected("a number", v)),
    }
}

/// A non-negative integer at `path` (an integral float such as `3.0` is accepted).
pub(crate) fn integer(v: &Value, path: &JsonPath) -> Result<usize, IoError> {
    if let Some(n) = v.as_u64() {
        return usize::try_from(n).map_err(|_| path.error(format!("{n} is too large")));
    }
    match v.as_f64() {
        Some(x) if x >= 0.0 && x.fract() == 0.0 && x <= u32::MAX as f64 => Ok(x as usize),
        _ => Err(path.expected("a non-negative integer", v)),
    }
}

/// An array at `path`.
pub(crate) fn array<'a>(
    v: &'a Value,
    path: &JsonPath,
    what: &str,
) -> Result<&'a Vec<Value>, IoError> {
    v.as_array().ok_or_else(|| path.expected(what, v))
}

/// Writes `v` as indented JSON where arrays holding only scalars stay on one line, so that a
/// control point reads `[1.0, 2.0, 3.0]` and a net has one point per line.
pub(crate) fn pretty(v: &Value) -> String {
    let mut out = String::new();
    write_value(&mut out, v, 0);
    out.push('\n');
    out
}

fn is_scalar(v: &Value) -> bool {
    !matches!(v, Value::Array(_) | Value::Object(_))
}

/// Field order of the model format (serde_json maps are sorted alphabetically otherwise).
fn key_rank(k: &str) -> usize {
    const ORDER: [&str; 7] = [
        "type",
        "name",
        "degree",
        "knots",
        "control_points",
        "weights",
        "entities",
    ];
    ORDER.iter().position(|o| *o == k).unwrap_or(ORDER.len())
}

fn indent(out: &mut String, level: usize) {
    for _ in 0..level {
        out.push_str("  ");
    }
}

fn write_value(out: &mut String, v: &Value, level: usize) {
    match v {
        Value::Array(a) if a.iter().all(is_scalar) => {
            out.push('[');
            for (n, x) in a.iter().enumerate() {
                if n > 0 {
                    out.push_str(", ");
                }
                let _ = write!(out, "{x}");
            }
            out.push(']');
        }
        Value::Array(a) => {
            out.push_str("[\n");
            for (n, x) in a.iter().enumerate() {
                indent(out, level + 1);
                write_value(out, x, level + 1);
                out.push_str(if n + 1 < a.len() { ",\n" } else { "\n" });
            }
            indent(out, level);
            out.push(']');
        }
        Value::Object(o) if o.is_empty() => out.push_str("{}"),
        Value::Object(o) => {
            out.push_str("{\n");
            let mut entries: Vec<_> = o.iter().collect();
            entries.sort_by_key(|(k, _)| key_rank(k));
            for (n, (k, x)) in entries.into_iter().enumerate() {
                indent(out, level + 1);
                let _ = write!(out, "{}: ", Value::String(k.clone()));
                write_value(out, x, level + 1);
                out.push_str(if n + 1 < o.len() { ",\n" } else { "\n" });
            }
            indent(out, level);
            out.push('}');
        }
        scalar => {
            let _ = write!(out, "{scalar}");
        }
    }
}
