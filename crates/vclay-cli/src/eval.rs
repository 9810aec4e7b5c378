//! `vclay eval MODEL.json (--params PARAMS.json | --at U[,V[,W]]...) [--derivatives K]
//! [--entity I]`; `vclay eval LATTICE.ovm (--params P.json | --at CELL,U,V,W...)
//! [--derivatives 1]`: the limit of the subdivision solid (issue 19; smooth boundary rule).
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
use vclay::lattice::{
    BoundaryRule, Features, LimitEvaluator, LimitParams, LimitQuery, SubdivisionRules,
};
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

// Bytes of the JSON tree per printed point and of a lattice's limit evaluation: the session
// layer's estimates, shared with Python.
use vclay::session::limits::{BYTES_PER_JSON_POINT, limit_eval_bytes};

/// Evaluates the entity and returns the JSON document; all errors carry the file and place.
/// A lattice (`.ovm`) goes to [`evaluate_lattice`] with boundary rule `rule`.
pub fn evaluate(
    model: &Path,
    params: &Params,
    order: Option<usize>,
    entity: usize,
    rule: BoundaryRule,
) -> Result<Value> {
    if is_lattice(model) {
        return evaluate_lattice(model, params, order, rule);
    }
    if let Some(text) = triangular_text(model) {
        return evaluate_triangular(model, &text, params, order);
    }
    if let Some(k) = order
        && k > MAX_DERIVATIVE_ORDER
    {
        bail!("--derivatives {k}: more than the supported maximum order {MAX_DERIVATIVE_ORDER}");
    }
    let entities = read_model(model).map_err(|e| not_a_model(model, e.into()))?;
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

/// Whether `path` names a subdivision-solid lattice (`.ovm`).
pub fn is_lattice(path: &Path) -> bool {
    path.extension()
        .is_some_and(|e| e.eq_ignore_ascii_case("ovm"))
}

/// Tuples in a parameter file of lattice queries, counted before it is parsed: one `[` each
/// (and one for the list), read in blocks without holding the file.
fn count_tuples(path: &Path) -> Result<usize> {
    use std::io::Read as _;
    let cannot = || format!("cannot read parameter file {}", path.display());
    let mut f = std::fs::File::open(path).with_context(cannot)?;
    let mut buf = vec![0u8; 1 << 16];
    let mut open = 0usize;
    loop {
        let n = f.read(&mut buf).with_context(cannot)?;
        if n == 0 {
            break;
        }
        open += buf[..n].iter().filter(|&&b| b == b'[').count();
    }
    Ok(open.saturating_sub(1))
}

/// Parses `[[cell, u, v, w], ...]` (a file) or `CELL,U,V,W` items (`--at`); errors name the
/// tuple. Range checks (cell, `[0, 1]`) are the evaluator's, also by tuple index. Returns the
/// queries, their source and the parameter file's size (0 for `--at`).
fn lattice_queries(params: &Params) -> Result<(Vec<LimitQuery>, String, u64)> {
    let parse_tuple = |nums: &[Value], place: &dyn Fn() -> String| -> Result<LimitQuery> {
        if nums.len() != 4 {
            bail!(
                "{}: expected 4 numbers [cell, u, v, w], found {}",
                place(),
                nums.len()
            );
        }
        let cell = nums[0]
            .as_u64()
            .filter(|&c| c <= u32::MAX as u64)
            .ok_or_else(|| {
                anyhow::anyhow!(
                    "{}: the cell index {} is not a non-negative integer",
                    place(),
                    nums[0]
                )
            })?;
        let mut uvw = [0.0; 3];
        for (a, x) in nums[1..].iter().enumerate() {
            uvw[a] = x.as_f64().filter(|x| x.is_finite()).ok_or_else(|| {
                anyhow::anyhow!(
                    "{}: {} = {x} is not a finite number",
                    place(),
                    ["u", "v", "w"][a]
                )
            })?;
        }
        Ok(LimitQuery {
            cell: cell as usize,
            uvw,
        })
    };
    match params {
        Params::File(path) => {
            let bytes = std::fs::metadata(path)
                .with_context(|| format!("cannot read parameter file {}", path.display()))?
                .len();
            // The file's text and its tuples (counted in a first pass), before parsing.
            let tuples = count_tuples(path)?;
            crate::limits::check_memory(
                &format!("parameter file {} ({tuples} tuples)", path.display()),
                limit_eval_bytes(0, tuples, bytes),
            )?;
            let text = std::fs::read_to_string(path)
                .with_context(|| format!("cannot read parameter file {}", path.display()))?;
            let root: Value = serde_json::from_str(&text)
                .map_err(|e| anyhow::anyhow!("{}: {e}", path.display()))?;
            let Value::Array(items) = root else {
                bail!(
                    "{}: expected an array of [cell, u, v, w] tuples",
                    path.display()
                );
            };
            let qs = items
                .iter()
                .enumerate()
                .map(|(i, t)| {
                    let place = || format!("{}: parameter tuple {i}", path.display());
                    match t {
                        Value::Array(nums) => parse_tuple(nums, &place),
                        other => bail!("{}: expected [cell, u, v, w], found {other}", place()),
                    }
                })
                .collect::<Result<Vec<_>>>()?;
            Ok((qs, path.display().to_string(), bytes))
        }
        Params::Inline(items) => {
            let qs = items
                .iter()
                .enumerate()
                .map(|(i, item)| {
                    let place = || format!("--at '{}' (tuple {i})", crate::limits::quote(item));
                    let nums: Vec<Value> = item
                        .split(',')
                        .map(|x| {
                            serde_json::from_str::<Value>(x.trim())
                                .unwrap_or_else(|_| Value::String(x.trim().to_string()))
                        })
                        .collect();
                    parse_tuple(&nums, &place)
                })
                .collect::<Result<Vec<_>>>()?;
            Ok((qs, "--at".to_string(), 0))
        }
    }
}

/// `vclay eval LATTICE.ovm`: the limit of the subdivision solid with control lattice `path` at
/// `(cell, u, v, w)` tuples (docs/formats.md, "Limit parameters"); `order` at most 1
/// (first derivatives `[x_u, x_v, x_w]`).
pub fn evaluate_lattice(
    path: &Path,
    params: &Params,
    order: Option<usize>,
    rule: BoundaryRule,
) -> Result<Value> {
    if let Some(k) = order
        && k > 1
    {
        bail!(
            "--derivatives {k}: the limit of a subdivision solid gives first derivatives only (--derivatives 1)"
        );
    }
    let (queries, source, text_bytes) = lattice_queries(params)?;
    let lattice = vclay::lattice::formats::ovm::read(path)?;
    crate::limits::check_memory(
        &format!(
            "the limit of {} ({} cells) at {} quer{}",
            path.display(),
            lattice.num_cells(),
            queries.len(),
            if queries.len() == 1 { "y" } else { "ies" }
        ),
        limit_eval_bytes(lattice.num_cells(), queries.len(), text_bytes),
    )?;
    let features = Features::none(&lattice);
    let ev = LimitEvaluator::new(
        &lattice,
        &features,
        SubdivisionRules::new(rule),
        LimitParams::default(),
    )?;
    let pts = ev
        .evaluate_many(&queries)
        .map_err(|e| anyhow::anyhow!("{source}: {e} (lattice {})", path.display()))?;
    for (i, p) in pts.iter().enumerate() {
        let all = std::iter::once(&p.position).chain(p.derivatives.iter());
        if !all.flat_map(|v| v.iter()).all(|x| x.is_finite()) {
            bail!(
                "{source}: parameter tuple {i}: the limit is not finite (overflow); nothing written"
            );
        }
    }
    let mut out = json!({
        "points": pts.iter().map(|p| point(&p.position)).collect::<Vec<_>>(),
        "exact": pts.iter().map(|p| p.exact).collect::<Vec<_>>(),
        "error_estimate": pts.iter().map(|p| p.error).collect::<Vec<_>>(),
        "tolerance": ev.absolute_tolerance(),
    });
    if order == Some(1) {
        out["derivatives"] = Value::Array(
            pts.iter()
                .map(|p| Value::Array(p.derivatives.iter().map(point).collect()))
                .collect(),
        );
    }
    Ok(out)
}

/// Runs the subcommand: prints the document only when everything succeeded.
pub fn run(
    model: &Path,
    params: &Params,
    order: Option<usize>,
    entity: usize,
    rule: BoundaryRule,
) -> Result<()> {
    let doc = evaluate(model, params, order, entity, rule)?;
    println!("{}", serde_json::to_string(&doc)?);
    Ok(())
}

/// The text of `model` when it is a triangular NURBS file (`"type": "triangular-nurbs"`).
fn triangular_text(model: &Path) -> Option<String> {
    let ext = model.extension()?.to_string_lossy().to_ascii_lowercase();
    if ext != "json" {
        return None;
    }
    let text = std::fs::read_to_string(model).ok()?;
    vclay::io::triangular::is_triangular(&text).then_some(text)
}

/// `vclay eval` of a triangular NURBS: points at `(u, v)` domain parameters and, with
/// `--derivatives K` (K <= 2), the table `d[a][b] = d^(a+b) s / du^a dv^b` for `a + b <= K`
/// (as for tensor-product surfaces).
fn evaluate_triangular(
    model: &Path,
    text: &str,
    params: &Params,
    order: Option<usize>,
) -> Result<Value> {
    let k = order.unwrap_or(0);
    if k > 2 {
        bail!("--derivatives {k}: triangular NURBS are evaluated up to second derivatives");
    }
    let t = vclay::io::triangular::parse_triangular(text)
        .map_err(|e| anyhow::anyhow!("{}: {e}", model.display()))?;
    let (tuples, source) = match params {
        Params::File(path) => {
            let text = std::fs::read_to_string(path)
                .with_context(|| format!("cannot read parameter file {}", path.display()))?;
            let tuples = parse_params(&text, 2)
                .map_err(|err| anyhow::anyhow!("{}: {err}", path.display()))?;
            (tuples, path.display().to_string())
        }
        Params::Inline(items) => (inline(items, 2)?, "--at".to_string()),
    };
    crate::limits::check_memory(
        &format!("--derivatives {k} at {} parameter tuples", tuples.len()),
        tuples.len() as f64 * ((k + 1) * (k + 1)) as f64 * BYTES_PER_JSON_POINT,
    )?;
    let mut points = Vec::with_capacity(tuples.len());
    let mut derivs = Vec::with_capacity(tuples.len());
    for (n, tu) in tuples.iter().enumerate() {
        let d = t
            .surface
            .derivatives([tu[0], tu[1]])
            .with_context(|| format!("{source}: parameter {n} {tu:?}"))?;
        if !d.iter().all(|p| p.iter().all(|x| x.is_finite())) {
            bail!("{source}: parameter {n} {tu:?}: the point or a derivative is not finite");
        }
        points.push(point(&d[0]));
        // d = (s, s_u, s_v, s_uu, s_uv, s_vv) -> table [a][b].
        let at = |a: usize, b: usize| match (a, b) {
            (0, 0) => Some(d[0]),
            (1, 0) => Some(d[1]),
            (0, 1) => Some(d[2]),
            (2, 0) => Some(d[3]),
            (1, 1) => Some(d[4]),
            (0, 2) => Some(d[5]),
            _ => None,
        };
        let table: Vec<Value> = (0..=k)
            .map(|a| {
                Value::Array(
                    (0..=k)
                        .map(|b| {
                            if a + b <= k {
                                at(a, b).map_or(Value::Null, |p| point(&p))
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
    let mut doc = json!({ "points": points });
    if order.is_some() {
        doc["derivatives"] = Value::Array(derivs);
    }
    Ok(doc)
}

/// A model file that does not read: where the file is something else vclay reads (a mesh, a
/// point cloud, a scenario), says what it is and which commands take it (issue 26), else the
/// reader's own error.
pub fn not_a_model(path: &Path, err: anyhow::Error) -> anyhow::Error {
    use vclay::session::FileKind;
    match vclay::session::open::identify(path) {
        Ok(k) if !matches!(k, FileKind::ModelJson | FileKind::Step | FileKind::Iges) => {
            anyhow::anyhow!(
                "{}: {}, not a model file; use {}",
                path.display(),
                k.describe(),
                k.commands()
            )
        }
        _ => err,
    }
}
