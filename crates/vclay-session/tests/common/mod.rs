//! Shared test helpers.

/// The first place where two JSON values differ (`None` if equal), with both values
/// shortened: keeps failure messages readable when saved models are large.
pub fn first_difference(a: &serde_json::Value, b: &serde_json::Value) -> Option<String> {
    use serde_json::Value;
    fn go(a: &Value, b: &Value, path: &str) -> Option<String> {
        match (a, b) {
            (Value::Object(x), Value::Object(y)) => {
                for (k, v) in x {
                    match y.get(k) {
                        Some(w) => {
                            if let Some(d) = go(v, w, &format!("{path}.{k}")) {
                                return Some(d);
                            }
                        }
                        None => return Some(format!("{path}.{k}: missing on the right")),
                    }
                }
                y.keys()
                    .find(|k| !x.contains_key(*k))
                    .map(|k| format!("{path}.{k}: missing on the left"))
            }
            (Value::Array(x), Value::Array(y)) => {
                if x.len() != y.len() {
                    return Some(format!("{path}: lengths {} and {}", x.len(), y.len()));
                }
                x.iter()
                    .zip(y)
                    .enumerate()
                    .find_map(|(i, (v, w))| go(v, w, &format!("{path}[{i}]")))
            }
            _ if a == b => None,
            _ => {
                let s = |v: &Value| v.to_string().chars().take(80).collect::<String>();
                Some(format!("{path}: {} != {}", s(a), s(b)))
            }
        }
    }
    go(a, b, "")
}

/// Asserts equality of two JSON values, naming the first difference.
#[track_caller]
pub fn assert_same(a: &serde_json::Value, b: &serde_json::Value, what: &str) {
    if let Some(d) = first_difference(a, b) {
        panic!("{what}: {d}");
    }
}

/// A scenario's two models of two kinds: a subdivision solid `cube` (`points` control points
/// per direction, level 1, dt 0.002) and a 5 x 5 `dnurbs-surface` `sheet` (dt 0.01).
pub fn cube_and_sheet(points: usize) -> String {
    format!(
        r#"
[[model]]
name = "cube"
kind = "subdivision-solid"
points = [{points}, {points}, {points}]
level = 1
[model.simulation]
dt = 0.002

[[model]]
name = "sheet"
kind = "dnurbs-surface"
size = [5, 5]
[model.simulation]
dt = 0.01
"#
    )
}

/// [`cube_and_sheet`] (2 points) run for 30 steps with a timeline: a rope on the cube from
/// t = 0 to 0.02, gravity on the sheet from t = 0.1.
pub fn two_kinds() -> String {
    cube_and_sheet(2)
        + r#"
[simulation]
steps = 30

[[timeline]]
at = 0.0
model = "cube"
action = "rope"
from = [1.0, 1.0, 1.0]
to = [1.2, 1.0, 1.0]
until = 0.02

[[timeline]]
at = 0.1
model = "sheet"
action = "gravity"
g = [0.0, 0.0, -1.0]
"#
}

/// Builds a model of `kind` from the TOML text of its tables (`material` and `simulation`:
/// `None` when absent), file names relative to `base`.
pub fn try_build(
    kind: vclay_session::ModelKind,
    model: &str,
    material: Option<&str>,
    simulation: Option<&str>,
    base: &std::path::Path,
) -> Result<Box<dyn vclay_session::Model>, vclay_session::models::SpecError> {
    let table = |t: &str| toml::from_str::<toml::Table>(t).expect("valid toml");
    let (m, mat, sim) = (table(model), material.map(table), simulation.map(table));
    vclay_session::models::build(
        kind,
        &vclay_session::models::Spec {
            model: &m,
            material: mat.as_ref(),
            simulation: sim.as_ref(),
            base,
        },
    )
}

/// [`try_build`] in the current folder; panics with the error.
#[track_caller]
pub fn build(
    kind: vclay_session::ModelKind,
    model: &str,
    material: Option<&str>,
    simulation: Option<&str>,
) -> Box<dyn vclay_session::Model> {
    try_build(kind, model, material, simulation, std::path::Path::new("."))
        .unwrap_or_else(|e| panic!("{e:?}"))
}

/// The session's (first) model as its session file saves it.
pub fn saved(s: &vclay_session::Session) -> serde_json::Value {
    s.model(None).unwrap().save().unwrap()
}

/// [`saved`] as text (exact floats: equal texts are equal bits).
pub fn saved_text(s: &vclay_session::Session) -> String {
    serde_json::to_string(&saved(s)).unwrap()
}

/// The vertices of the (first) model's display mesh.
pub fn positions(s: &vclay_session::Session) -> Vec<vclay_core::Vec3> {
    s.model(None).unwrap().display_mesh().unwrap().positions
}
