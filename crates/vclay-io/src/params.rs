//! Parameter lists for `vclay eval`.
//!
//! **What.** A JSON array of parameter tuples, one per evaluation: `[[u], ...]` for curves,
//! `[[u, v], ...]` for surfaces, `[[u, v, w], ...]` for volumes. For curves a tuple may also be a
//! bare number (`[0.0, 0.5, 1.0]`), and the whole file may be a single number (`0.5`).
//!
//! **How.** Parsed through `serde_json::Value`; syntax errors carry line and column, shape errors
//! name the tuple index (`parameter tuple 3: expected 2 numbers [u, v], found 3`).
//!
//! **Limitations.** Only the arity and finiteness are checked here; whether a parameter lies in
//! the domain of an entity is checked at evaluation time by the spline layer. An empty list is
//! valid and yields no tuples.

use crate::error::IoError;
use crate::json;
use serde_json::Value;
use std::path::Path;

const TUPLE_NAMES: [&str; 3] = ["[u]", "[u, v]", "[u, v, w]"];

/// Parses a parameter list for an object with `dims` parameters (1, 2 or 3).
pub fn parse_params(text: &str, dims: usize) -> Result<Vec<Vec<f64>>, IoError> {
    if !(1..=3).contains(&dims) {
        return Err(IoError::Params {
            index: None,
            message: format!("{dims} parameters per tuple requested; only 1, 2 or 3 exist"),
        });
    }
    let root = json::parse(text)?;
    let items = match &root {
        Value::Array(a) => a,
        Value::Number(_) if dims == 1 => return Ok(vec![vec![scalar(&root, None)?]]),
        other => {
            return Err(IoError::Params {
                index: None,
                message: format!(
                    "expected an array of parameter tuples {}, found {}",
                    TUPLE_NAMES[dims - 1],
                    json::describe(other)
                ),
            });
        }
    };
    items
        .iter()
        .enumerate()
        .map(|(i, t)| tuple(t, i, dims))
        .collect()
}

/// Reads a parameter file; errors name the file.
pub fn read_params(path: impl AsRef<Path>, dims: usize) -> Result<Vec<Vec<f64>>, IoError> {
    let path = path.as_ref();
    let text = std::fs::read_to_string(path).map_err(|e| IoError::file(path, e))?;
    parse_params(&text, dims).map_err(|e| e.in_file(path))
}

fn tuple(v: &Value, index: usize, dims: usize) -> Result<Vec<f64>, IoError> {
    let err = |message: String| IoError::Params {
        index: Some(index),
        message,
    };
    let what = if dims == 1 {
        "1 number [u] (or a bare number)".to_string()
    } else {
        format!("{dims} numbers {}", TUPLE_NAMES[dims - 1])
    };
    match v {
        Value::Number(_) if dims == 1 => Ok(vec![scalar(v, Some(index))?]),
        Value::Array(a) if a.len() == dims => a
            .iter()
            .map(|x| {
                x.as_f64()
                    .filter(|x| x.is_finite())
                    .ok_or_else(|| err(format!("expected {what}, found {}", json::describe(x))))
            })
            .collect(),
        other => Err(err(format!(
            "expected {what}, found {}",
            json::describe(other)
        ))),
    }
}

fn scalar(v: &Value, index: Option<usize>) -> Result<f64, IoError> {
    match v.as_f64() {
        Some(x) if x.is_finite() => Ok(x),
        _ => Err(IoError::Params {
            index,
            message: format!("expected a finite number, found {}", json::describe(v)),
        }),
    }
}
