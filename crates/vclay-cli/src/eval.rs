//! `vclay eval MODEL.json --params PARAMS.json [--derivatives K] [--entity I]`.

use anyhow::{Context, Result, bail};
use serde_json::{Value, json};
use std::path::Path;
use vclay::Vec3;
use vclay::io::model::{Entity, read_model};
use vclay::io::params::parse_params;
use vclay::spline::{ParametricCurve, ParametricSurface, ParametricVolume};

fn point(p: &Vec3) -> Value {
    json!([p.x, p.y, p.z])
}

/// Evaluates the entity and returns the JSON document; all errors carry the file and place.
pub fn evaluate(model: &Path, params: &Path, order: Option<usize>, entity: usize) -> Result<Value> {
    let entities = read_model(model)?;
    let Some(e) = entities.get(entity) else {
        bail!(
            "{}: entity {entity} requested, but the file holds {} entit{}",
            model.display(),
            entities.len(),
            if entities.len() == 1 { "y" } else { "ies" }
        );
    };
    let text = std::fs::read_to_string(params)
        .with_context(|| format!("cannot read parameter file {}", params.display()))?;
    let tuples = parse_params(&text, e.param_dims())
        .map_err(|err| anyhow::anyhow!("{}: {err}", params.display()))?;
    let mut points = Vec::with_capacity(tuples.len());
    let mut derivs = Vec::with_capacity(tuples.len());
    let k = order.unwrap_or(0);
    for (n, t) in tuples.iter().enumerate() {
        let place = || format!("{}: parameter {n} {t:?}", params.display());
        match e {
            Entity::Curve(c) => {
                let d = c.derivatives(t[0], k).with_context(place)?;
                points.push(point(&d[0]));
                derivs.push(Value::Array(d.iter().map(point).collect()));
            }
            Entity::Surface(s) => {
                let d = s.derivatives(t[0], t[1], k).with_context(place)?;
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

/// Runs the subcommand: prints the document only when everything succeeded.
pub fn run(model: &Path, params: &Path, order: Option<usize>, entity: usize) -> Result<()> {
    let doc = evaluate(model, params, order, entity)?;
    println!("{}", serde_json::to_string(&doc)?);
    Ok(())
}
