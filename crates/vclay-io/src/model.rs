//! The JSON model format: NURBS curves, surfaces and volumes.
//!
//! **What.** A model file holds one entity object, a JSON array of entities, or
//! `{"entities": [...]}`. Each entity is
//!
//! ```text
//! {"type": "nurbs-curve",   "degree": p,         "knots": U,         "control_points": [P_i],       "weights": [w_i]}
//! {"type": "nurbs-surface", "degree": [p, q],    "knots": [U, V],    "control_points": [[P_ij]],    "weights": [[w_ij]]}
//! {"type": "nurbs-volume",  "degree": [p, q, r], "knots": [U, V, W], "control_points": [[[P_ijk]]], "weights": [[[w_ijk]]]}
//! ```
//!
//! and `{"entities": [...], "shells": [...]}` adds the trimmed B-rep of CAD parts whose faces lie
//! on the surfaces ([`crate::trimmed`], [`parse_trimmed_model`], [`trimmed_to_json`]).
//!
//! Entities have points `[x, y, z]`, the first index running along the first parameter (`u`), optional
//! weights (all 1 when absent) of the same nesting, and an optional `"name"` string. The format is
//! documented with examples in `docs/formats.md`.
//!
//! **How.** The text is parsed into a `serde_json::Value` (syntax errors carry line and column),
//! then converted by hand while tracking the JSON path, so that a structural error reads
//! `entities[0].control_points[2][1]: expected an array of 3 numbers, found a string`. The
//! spline constructors then check the semantics (knot counts, monotone knots, positive weights,
//! rectangular nets); their errors are wrapped with the entity index and type. The writer
//! prints every `f64` in its shortest exact form and the parser rounds correctly
//! (`serde_json/float_roundtrip`), so a written model reads back bit for bit.
//!
//! **Limitations.** Paths name the i-th entity `entities[i]` whichever top-level form the file
//! uses. Unknown fields are errors (a misspelt `"weight"` would otherwise be silently ignored). A
//! model must hold at least one entity. Names are kept by the `*_named_*` functions only.

use crate::error::{IoError, quote};
use crate::json::{self, JsonPath};
use serde_json::{Map, Value};
use std::path::Path;
use vclay_core::Vec3;
use vclay_spline::{NurbsCurve, NurbsSurface, NurbsVolume, SplineError};

/// The `"type"` strings of the model format, in order of parametric dimension.
pub const ENTITY_TYPES: [&str; 3] = ["nurbs-curve", "nurbs-surface", "nurbs-volume"];

/// Fields allowed in an entity object.
const ENTITY_FIELDS: [&str; 6] = [
    "type",
    "name",
    "degree",
    "knots",
    "control_points",
    "weights",
];

/// One geometric object of a model file.
#[derive(Clone, Debug, PartialEq)]
pub enum Entity {
    /// A NURBS curve (`"nurbs-curve"`).
    Curve(NurbsCurve),
    /// A tensor-product NURBS surface (`"nurbs-surface"`).
    Surface(NurbsSurface),
    /// A trivariate NURBS volume (`"nurbs-volume"`).
    Volume(NurbsVolume),
}

impl Entity {
    /// Number of parameters: 1 for a curve, 2 for a surface, 3 for a volume.
    pub fn param_dims(&self) -> usize {
        match self {
            Entity::Curve(_) => 1,
            Entity::Surface(_) => 2,
            Entity::Volume(_) => 3,
        }
    }

    /// The `"type"` string of the model format: `nurbs-curve`, `nurbs-surface` or `nurbs-volume`.
    pub fn type_name(&self) -> &'static str {
        ENTITY_TYPES[self.param_dims() - 1]
    }
}

impl From<NurbsCurve> for Entity {
    fn from(c: NurbsCurve) -> Self {
        Entity::Curve(c)
    }
}

impl From<NurbsSurface> for Entity {
    fn from(s: NurbsSurface) -> Self {
        Entity::Surface(s)
    }
}

impl From<NurbsVolume> for Entity {
    fn from(v: NurbsVolume) -> Self {
        Entity::Volume(v)
    }
}

/// An entity with the optional `"name"` it carries in the file.
#[derive(Clone, Debug, PartialEq)]
pub struct NamedEntity {
    /// The `"name"` field, if any.
    pub name: Option<String>,
    /// The geometry.
    pub entity: Entity,
}

impl From<Entity> for NamedEntity {
    fn from(entity: Entity) -> Self {
        NamedEntity { name: None, entity }
    }
}

/// Parses a model from JSON text (names dropped; see [`parse_named_model`]).
pub fn parse_model(text: &str) -> Result<Vec<Entity>, IoError> {
    Ok(parse_named_model(text)?
        .into_iter()
        .map(|e| e.entity)
        .collect())
}

/// Parses a model from JSON text, keeping each entity's `"name"` (the trimmed B-rep shells of
/// `"shells"` are checked and dropped; see [`parse_trimmed_model`]).
pub fn parse_named_model(text: &str) -> Result<Vec<NamedEntity>, IoError> {
    Ok(parse_trimmed_model(text)?.0)
}

/// Parses a model from JSON text with its trimmed B-rep shells (`{"entities": [...],
/// "shells": [...]}`, [`crate::trimmed`]); each shell is validated
/// ([`crate::trimmed::validate_shell`]), errors name the shell, face, loop and use.
pub fn parse_trimmed_model(
    text: &str,
) -> Result<(Vec<NamedEntity>, Vec<crate::brep::Shell>), IoError> {
    trimmed_model_of_value(&json::parse(text)?)
}

/// [`parse_trimmed_model`] on a parsed JSON value (what [`trimmed_to_json`] gives: session
/// files keep a CAD part this way, without going through text).
pub fn trimmed_model_of_value(
    root: &Value,
) -> Result<(Vec<NamedEntity>, Vec<crate::brep::Shell>), IoError> {
    let top = JsonPath::default();
    let mut shells_json = None;
    let items: Vec<&Value> = match root {
        Value::Array(a) => a.iter().collect(),
        Value::Object(o) if o.contains_key("entities") => {
            if let Some(k) = o.keys().find(|k| *k != "entities" && *k != "shells") {
                return Err(top.error(format!(
                    "unknown field {} next to \"entities\" (allowed: \"entities\", \"shells\")",
                    quote(k)
                )));
            }
            shells_json = o.get("shells");
            let path = top.key("entities");
            json::array(&o["entities"], &path, "an array of entities")?
                .iter()
                .collect()
        }
        Value::Object(o) if o.contains_key("type") => vec![root],
        other => {
            return Err(top.expected(
                "an entity object (with \"type\"), an array of entities or {\"entities\": [...]}",
                other,
            ));
        }
    };
    if items.is_empty() {
        return Err(IoError::EmptyModel);
    }
    let entities = items
        .into_iter()
        .enumerate()
        .map(|(i, v)| parse_entity(v, i))
        .collect::<Result<Vec<_>, _>>()?;
    let shells = match shells_json {
        None => Vec::new(),
        Some(v) => crate::trimmed::shells_from_json(v, &top.key("shells"), &entities)?,
    };
    Ok((entities, shells))
}

/// Reads a model file (names dropped; see [`read_named_model`]). Errors name the file.
///
/// Like [`read_named_model`], this reads STEP and IGES files too, chosen by extension, and
/// drops their import warnings: use [`import_model`] to show them.
pub fn read_model(path: impl AsRef<Path>) -> Result<Vec<Entity>, IoError> {
    Ok(read_named_model(path)?
        .into_iter()
        .map(|e| e.entity)
        .collect())
}

/// Reads a model file keeping entity names. Errors name the file.
///
/// The extension chooses the format: `.step`, `.stp` and `.p21` are STEP
/// ([`crate::step_read`]), `.igs` and `.iges` are IGES ([`crate::iges_read`]), anything else
/// is the JSON model format. The import warnings of STEP and IGES are dropped here; use
/// [`import_model`] to show them.
pub fn read_named_model(path: impl AsRef<Path>) -> Result<Vec<NamedEntity>, IoError> {
    Ok(import_model(path)?.entities)
}

/// The model formats [`import_model`] reads, by lower-case extension: STEP, IGES, else JSON.
fn cad_format(path: &Path) -> Option<&'static str> {
    let ext = path.extension()?.to_str()?.to_ascii_lowercase();
    match ext.as_str() {
        "step" | "stp" | "p21" => Some("step"),
        "igs" | "iges" => Some("iges"),
        _ => None,
    }
}

/// Reads a model file of any format vclay imports (JSON model, STEP, IGES; chosen by extension
/// as in [`read_named_model`]) with the warnings of the import: what a STEP or IGES file holds
/// that was not read. A JSON model has no warnings. Errors name the file.
pub fn import_model(path: impl AsRef<Path>) -> Result<crate::CadImport, IoError> {
    let path = path.as_ref();
    match cad_format(path) {
        Some("step") => crate::step_read::read_step(path),
        Some(_) => crate::iges_read::read_iges(path),
        None => {
            let text = std::fs::read_to_string(path).map_err(|e| IoError::file(path, e))?;
            let (entities, shells) = parse_trimmed_model(&text).map_err(|e| e.in_file(path))?;
            Ok(crate::CadImport {
                entities,
                warnings: Vec::new(),
                faces: Vec::new(),
                shells,
            })
        }
    }
}

/// The model as JSON: `{"entities": [...]}`. Weights are omitted when all are 1.
pub fn to_json(entities: &[Entity]) -> Value {
    let list = entities.iter().map(|e| entity_to_json(e, None)).collect();
    wrap(list)
}

/// The model as JSON, with each entity's `"name"` where it has one.
pub fn named_to_json(entities: &[NamedEntity]) -> Value {
    let list = entities
        .iter()
        .map(|e| entity_to_json(&e.entity, e.name.as_deref()))
        .collect();
    wrap(list)
}

/// The model with its trimmed B-rep shells as JSON: `{"entities": [...], "shells": [...]}`
/// (no `"shells"` when there are none).
pub fn trimmed_to_json(entities: &[NamedEntity], shells: &[crate::brep::Shell]) -> Value {
    let mut v = named_to_json(entities);
    if !shells.is_empty()
        && let Value::Object(m) = &mut v
    {
        m.insert(
            "shells".into(),
            Value::Array(shells.iter().map(crate::trimmed::shell_to_json).collect()),
        );
    }
    v
}

/// Writes a model file with its trimmed B-rep shells, atomically ([`trimmed_to_json`]).
pub fn write_trimmed_model(
    path: impl AsRef<Path>,
    entities: &[NamedEntity],
    shells: &[crate::brep::Shell],
) -> Result<(), IoError> {
    write_json(path.as_ref(), &trimmed_to_json(entities, shells))
}

/// Writes a model file (indented, one control point per line), atomically: a failed write never
/// destroys an existing file.
pub fn write_model(path: impl AsRef<Path>, entities: &[Entity]) -> Result<(), IoError> {
    write_json(path.as_ref(), &to_json(entities))
}

/// Writes a model file with entity names, atomically.
pub fn write_named_model(path: impl AsRef<Path>, entities: &[NamedEntity]) -> Result<(), IoError> {
    write_json(path.as_ref(), &named_to_json(entities))
}

/// [`write_model`] up to the rename: the model written to a temporary file beside `path`,
/// renamed over it by [`crate::Staged::commit`].
pub fn stage_model(path: impl AsRef<Path>, entities: &[Entity]) -> Result<crate::Staged, IoError> {
    let text = json::pretty(&to_json(entities));
    crate::util::stage(path.as_ref(), |w| w.write_all(text.as_bytes()))
}

/// Formats a model as the text [`write_model`] writes.
pub fn to_json_string(entities: &[Entity]) -> String {
    json::pretty(&to_json(entities))
}

fn write_json(path: &Path, v: &Value) -> Result<(), IoError> {
    let text = json::pretty(v);
    crate::util::write_atomic(path, |w| w.write_all(text.as_bytes()))
}

fn wrap(list: Vec<Value>) -> Value {
    let mut m = Map::new();
    m.insert("entities".into(), Value::Array(list));
    Value::Object(m)
}

// ---------------------------------------------------------------------------------------------
// Reading

fn parse_entity(v: &Value, index: usize) -> Result<NamedEntity, IoError> {
    let path = JsonPath::entity(index);
    let Value::Object(obj) = v else {
        return Err(path.expected("an entity object", v));
    };
    for k in obj.keys() {
        if !ENTITY_FIELDS.contains(&k.as_str()) {
            return Err(path.error(format!(
                "unknown field {} (allowed: {})",
                quote(k),
                ENTITY_FIELDS.join(", ")
            )));
        }
    }
    let field = |k: &str| -> Result<&Value, IoError> {
        obj.get(k)
            .ok_or_else(|| path.error(format!("missing field \"{k}\"")))
    };
    let tpath = path.key("type");
    let kind = match obj.get("type") {
        None => {
            return Err(path.error(format!(
                "missing field \"type\" (one of {})",
                ENTITY_TYPES.map(|t| format!("\"{t}\"")).join(", ")
            )));
        }
        Some(Value::String(s)) => match ENTITY_TYPES.iter().position(|t| t == s) {
            Some(k) => k,
            None => {
                return Err(IoError::UnknownType {
                    path: tpath.to_string(),
                    found: s.clone(),
                    allowed: &ENTITY_TYPES,
                });
            }
        },
        Some(other) => return Err(tpath.expected("a string", other)),
    };
    let name = match obj.get("name") {
        None => None,
        Some(Value::String(s)) => Some(s.clone()),
        Some(other) => return Err(path.key("name").expected("a string", other)),
    };
    let (dp, kp, cp, wp) = (
        path.key("degree"),
        path.key("knots"),
        path.key("control_points"),
        path.key("weights"),
    );
    let (degree, knots, points) = (field("degree")?, field("knots")?, field("control_points")?);
    let weights = obj.get("weights");
    let wrap_err = |source: SplineError| IoError::Entity {
        index,
        kind: ENTITY_TYPES[kind],
        source,
    };
    let entity = match kind {
        0 => {
            let degree = json::integer(degree, &dp)?;
            let knots = numbers(knots, &kp)?;
            let pts = points1(points, &cp)?;
            let w = weights.map(|w| numbers(w, &wp)).transpose()?;
            Entity::Curve(NurbsCurve::new(degree, knots, pts, w).map_err(wrap_err)?)
        }
        1 => {
            let [p, q] = integers::<2>(degree, &dp)?;
            let [u, v] = knot_vectors::<2>(knots, &kp)?;
            let pts = nested(points, &cp, points1)?;
            let w = weights.map(|w| nested(w, &wp, numbers)).transpose()?;
            Entity::Surface(NurbsSurface::new([p, q], [u, v], pts, w).map_err(wrap_err)?)
        }
        _ => {
            let deg = integers::<3>(degree, &dp)?;
            let kv = knot_vectors::<3>(knots, &kp)?;
            let pts = nested(points, &cp, |v, p| nested(v, p, points1))?;
            let w = weights
                .map(|w| nested(w, &wp, |v, p| nested(v, p, numbers)))
                .transpose()?;
            Entity::Volume(NurbsVolume::new(deg, kv, pts, w).map_err(wrap_err)?)
        }
    };
    Ok(NamedEntity { name, entity })
}

/// `[n, n, ...]` of exactly `N` non-negative integers.
fn integers<const N: usize>(v: &Value, path: &JsonPath) -> Result<[usize; N], IoError> {
    let what = format!("an array of {N} non-negative integers");
    let a = json::array(v, path, &what)?;
    if a.len() != N {
        return Err(path.expected(&what, v));
    }
    let mut out = [0; N];
    for (i, x) in a.iter().enumerate() {
        out[i] = json::integer(x, &path.index(i))?;
    }
    Ok(out)
}

/// `[U, V, ...]`: exactly `N` arrays of numbers.
fn knot_vectors<const N: usize>(v: &Value, path: &JsonPath) -> Result<[Vec<f64>; N], IoError> {
    let what = format!("an array of {N} knot vectors");
    let a = json::array(v, path, &what)?;
    if a.len() != N {
        return Err(path.expected(&what, v));
    }
    let mut out: [Vec<f64>; N] = std::array::from_fn(|_| Vec::new());
    for (i, x) in a.iter().enumerate() {
        out[i] = numbers(x, &path.index(i))?;
    }
    Ok(out)
}

/// An array of finite numbers.
pub(crate) fn numbers(v: &Value, path: &JsonPath) -> Result<Vec<f64>, IoError> {
    json::array(v, path, "an array of numbers")?
        .iter()
        .enumerate()
        .map(|(i, x)| json::number(x, &path.index(i)))
        .collect()
}

/// A point `[x, y, z]`.
pub(crate) fn point(v: &Value, path: &JsonPath) -> Result<Vec3, IoError> {
    const WHAT: &str = "an array of 3 numbers";
    match v.as_array() {
        Some(a) if a.len() == 3 => Ok(Vec3::new(
            json::number(&a[0], &path.index(0))?,
            json::number(&a[1], &path.index(1))?,
            json::number(&a[2], &path.index(2))?,
        )),
        _ => Err(path.expected(WHAT, v)),
    }
}

/// An array of points.
pub(crate) fn points1(v: &Value, path: &JsonPath) -> Result<Vec<Vec3>, IoError> {
    json::array(v, path, "an array of points [x, y, z]")?
        .iter()
        .enumerate()
        .map(|(i, x)| point(x, &path.index(i)))
        .collect()
}

/// An array of `inner` items.
fn nested<T>(
    v: &Value,
    path: &JsonPath,
    inner: impl Fn(&Value, &JsonPath) -> Result<T, IoError>,
) -> Result<Vec<T>, IoError> {
    json::array(v, path, "an array")?
        .iter()
        .enumerate()
        .map(|(i, x)| inner(x, &path.index(i)))
        .collect()
}

// ---------------------------------------------------------------------------------------------
// Writing

pub(crate) fn num(x: f64) -> Value {
    // Entities are validated, so every number is finite and `from_f64` succeeds.
    serde_json::Number::from_f64(x).map_or(Value::Null, Value::Number)
}

pub(crate) fn nums(xs: &[f64]) -> Value {
    Value::Array(xs.iter().map(|&x| num(x)).collect())
}

fn pt(p: &Vec3) -> Value {
    Value::Array(vec![num(p.x), num(p.y), num(p.z)])
}

/// Nests a flat array (last index fastest) to the shape `dims`.
fn nest<T>(flat: &[T], dims: &[usize], leaf: &impl Fn(&T) -> Value) -> Value {
    match dims {
        [] | [_] => Value::Array(flat.iter().map(leaf).collect()),
        [_, rest @ ..] => {
            let stride: usize = rest.iter().product();
            if stride == 0 {
                return Value::Array(Vec::new());
            }
            Value::Array(flat.chunks(stride).map(|c| nest(c, rest, leaf)).collect())
        }
    }
}

pub(crate) fn entity_to_json(e: &Entity, name: Option<&str>) -> Value {
    let mut m = Map::new();
    m.insert("type".into(), Value::String(e.type_name().into()));
    if let Some(n) = name {
        m.insert("name".into(), Value::String(n.into()));
    }
    let (degree, knots, dims, points, weights): (Value, Value, Vec<usize>, &[Vec3], &[f64]) =
        match e {
            Entity::Curve(c) => (
                Value::from(c.degree()),
                nums(c.knots().as_slice()),
                vec![c.control_points().len()],
                c.control_points(),
                c.weights(),
            ),
            Entity::Surface(s) => (
                Value::from(s.degree().to_vec()),
                Value::Array(s.knots().iter().map(|k| nums(k.as_slice())).collect()),
                s.dims().to_vec(),
                s.control_points(),
                s.weights(),
            ),
            Entity::Volume(v) => (
                Value::from(v.degree().to_vec()),
                Value::Array(v.knots().iter().map(|k| nums(k.as_slice())).collect()),
                v.dims().to_vec(),
                v.control_points(),
                v.weights(),
            ),
        };
    m.insert("degree".into(), degree);
    m.insert("knots".into(), knots);
    m.insert("control_points".into(), nest(points, &dims, &pt));
    if weights.iter().any(|&w| w != 1.0) {
        m.insert("weights".into(), nest(weights, &dims, &|&w| num(w)));
    }
    Value::Object(m)
}
