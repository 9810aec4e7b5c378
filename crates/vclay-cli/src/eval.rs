//! `vclay eval MODEL.json (--params PARAMS.json | --at U[,V[,W]]...) [--derivatives K]
//! [--entity I]`.
//!
//! Limits (issue 17): `K` at most `vclay_spline::MAX_DERIVATIVE_ORDER`; the output's estimated
//! size checked against `--max-memory`; a non-finite point or derivative (overflow) is an error
//! naming the tuple, never printed as `null`.

use anyhow::{Context, Result, bail};
use serde_json::{Value, json};
use std::path::{Path, PathBuf};
use vclay::Vec3;
use vclay::io::model::{Entity, read_model};
use vclay::io::params::parse_params;
use vclay::spline::{MAX_DERIVATIVE_ORDER, ParametricCurve, ParametricSurface, ParametricVolume};

fn point(p: &Vec3) -> Value {
    json!([p.x, p.y, p.z])
}

/// Where the parameters come from.
#[derive(Debug)]
pub enum Params {
    /// A parameter file (`--params`).
    File(PathBuf),
    /// Inline tuples (`--at 0.5,0.25`, repeatable).
    Inline(Vec<String>),
}

/// Bytes of the JSON tree per printed point (a `Value::Array` of three numbers and its text).
const BYTES_PER_JSON_POINT: f64 = 200.0;

/// Evaluates the entity and returns the JSON document; all errors carry the file and place.
pub fn evaluate(
    model: &Path,
    params: &Params,
    order: Option<usize>,
    entity: usize,
) -> Result<Value> {
    if let Some(k) = order
        && k > MAX_DERIVATIVE_ORDER
    {
        bail!("--derivatives {k}: more than the supported maximum order {MAX_DERIVATIVE_ORDER}");
    }
    let entities = read_model(model)?;
    let Some(e) = entities.get(entity) else {
        bail!(
            "{}: entity {entity} requested, but the file holds {} entit{}",
            model.display(),
            entities.len(),
            if entities.len() == 1 { "y" } else { "ies" }
        );
    };
    let (tuples, source) = match params {
        Params::File(path) => {
            let text = std::fs::read_to_string(path)
                .with_context(|| format!("cannot read parameter file {}", path.display()))?;
            let tuples = parse_params(&text, e.param_dims())
                .map_err(|err| anyhow::anyhow!("{}: {err}", path.display()))?;
            (tuples, path.display().to_string())
        }
        Params::Inline(items) => (inline(items, e.param_dims())?, "--at".to_string()),
    };
    let k = order.unwrap_or(0);
    let per_tuple = (k as f64 + 1.0).powi(e.param_dims() as i32);
    crate::limits::check_memory(
        &format!("--derivatives {k} at {} parameter tuples", tuples.len()),
        tuples.len() as f64 * per_tuple * BYTES_PER_JSON_POINT,
    )?;
    let params = Path::new(&source);
    let mut points = Vec::with_capacity(tuples.len());
    let mut derivs = Vec::with_capacity(tuples.len());
    for (n, t) in tuples.iter().enumerate() {
        let place = || format!("{}: parameter {n} {t:?}", params.display());
        let finite = |d: &[&Vec3]| -> Result<()> {
            if d.iter().all(|p| p.iter().all(|x| x.is_finite())) {
                Ok(())
            } else {
                bail!(
                    "{}: the point or a derivative is not finite (overflow); nothing written",
                    place()
                )
            }
        };
        match e {
            Entity::Curve(c) => {
                let d = c.derivatives(t[0], k).with_context(place)?;
                finite(&d.iter().collect::<Vec<_>>())?;
                points.push(point(&d[0]));
                derivs.push(Value::Array(d.iter().map(point).collect()));
            }
            Entity::Surface(s) => {
                let d = s.derivatives(t[0], t[1], k).with_context(place)?;
                finite(&d.iter().flatten().collect::<Vec<_>>())?;
                points.push(point(&d[0][0]));
                let table: Vec<Value> = (0..=k)
                    .map(|a| {
                        Value::Array(
                            (0..=k)
                                .map(|b| {
                                    if a + b <= k {
                                        point(&d[a][b])
                                    } else {
                                        Value::Null
                                    }
                                })
                                .collect(),
                        )
                    })
                    .collect();
                derivs.push(Value::Array(table));
            }
            Entity::Volume(v) => {
                let d = v.derivatives(t[0], t[1], t[2], k).with_context(place)?;
                finite(&d.iter().flatten().flatten().collect::<Vec<_>>())?;
                points.push(point(&d[0][0][0]));
                let table: Vec<Value> = (0..=k)
                    .map(|a| {
                        Value::Array(
                            (0..=k)
                                .map(|b| {
                                    Value::Array(
                                        (0..=k)
                                            .map(|c| {
                                                if a + b + c <= k {
                                                    point(&d[a][b][c])
                                                } else {
                                                    Value::Null
                                                }
                                            })
                                            .collect(),
                                    )
                                })
                                .collect(),
                        )
                    })
                    .collect();
                derivs.push(Value::Array(table));
            }
        }
    }
    let mut out = json!({ "points": points });
    if order.is_some() {
        out["derivatives"] = Value::Array(derivs);
    }
    Ok(out)
}

/// Parses `--at` values: each `U`, `U,V` or `U,V,W` with the entity's number of parameters.
fn inline(items: &[String], dims: usize) -> Result<Vec<Vec<f64>>> {
    items
        .iter()
        .map(|item| {
            let nums: Vec<Option<f64>> = item
                .split(',')
                .map(|x| x.trim().parse::<f64>().ok().filter(|x| x.is_finite()))
                .collect();
            match nums.iter().copied().collect::<Option<Vec<f64>>>() {
                Some(t) if t.len() == dims => Ok(t),
                _ => bail!(
                    "--at '{}': expected {dims} finite comma-separated number(s) ({})",
                    crate::limits::quote(item),
                    ["u", "u,v", "u,v,w"][dims - 1]
                ),
            }
        })
        .collect()
}

/// Runs the subcommand: prints the document only when everything succeeded.
pub fn run(model: &Path, params: &Params, order: Option<usize>, entity: usize) -> Result<()> {
    let doc = evaluate(model, params, order, entity)?;
    println!("{}", serde_json::to_string(&doc)?);
    Ok(())
}
