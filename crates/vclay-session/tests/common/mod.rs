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

/// Applies `edit`, checks that it changed the saved model, that undo gives back the state
/// before (saved model and display mesh, bit for bit) and redo the state after; returns both.
#[track_caller]
#[allow(clippy::type_complexity)]
pub fn round_trip(
    s: &mut vclay_session::Session,
    edit: vclay_session::Edit,
) -> (
    (String, Vec<vclay_core::Vec3>),
    (String, Vec<vclay_core::Vec3>),
) {
    let before = (saved_text(s), positions(s));
    s.apply(vclay_session::Command::new(edit.clone()))
        .unwrap_or_else(|e| panic!("{edit:?}: {e}"));
    let after = (saved_text(s), positions(s));
    assert_ne!(before.0, after.0, "{edit:?} changed nothing");
    s.undo().unwrap();
    assert_eq!((saved_text(s), positions(s)), before, "undo of {edit:?}");
    s.redo().unwrap();
    assert_eq!((saved_text(s), positions(s)), after, "redo of {edit:?}");
    (before, after)
}

/// Applies `edit` to a model whose steps only advance its clock (FFD, PDE surfaces), runs `n`
/// steps of `dt` (no energy), undoes: the state before the edit comes back with time 0.
/// Returns the display mesh just after the edit and after the steps.
#[track_caller]
pub fn steps_then_undo(
    s: &mut vclay_session::Session,
    edit: vclay_session::Edit,
    n: u64,
    dt: f64,
) -> (Vec<vclay_core::Vec3>, Vec<vclay_core::Vec3>) {
    let before = (saved_text(s), positions(s));
    s.apply(vclay_session::Command::new(edit)).unwrap();
    let at_edit = positions(s);
    s.run(n).unwrap();
    let m = s.model(None).unwrap();
    assert_eq!(m.steps(), n);
    assert!((m.time() - n as f64 * dt).abs() < 1e-12);
    assert_eq!(m.energy().total(), 0.0);
    let stepped = positions(s);
    s.undo().unwrap();
    assert_eq!((saved_text(s), positions(s)), before);
    assert_eq!(s.model(None).unwrap().time(), 0.0);
    (at_edit, stepped)
}

/// The session's (first) model saved as text, loaded again into a new session under `name`:
/// the same saved text and display mesh.
#[track_caller]
pub fn reloaded(s: &vclay_session::Session, name: &str) -> vclay_session::Session {
    let text = saved_text(s);
    let value: serde_json::Value = serde_json::from_str(&text).unwrap();
    let kind = s.model(None).unwrap().kind();
    let loaded = vclay_session::models::load(kind, &value).unwrap();
    let t = vclay_session::Session::with_model(name, loaded).unwrap();
    assert_eq!(saved_text(&t), text);
    assert_eq!(positions(&t), positions(s));
    t
}

/// A `rope` edit (named `name`, else numbered) from `from`, its cursor moving to `to` by
/// `until`; every other key absent.
pub fn rope(
    name: Option<&str>,
    from: [f64; 3],
    to: Option<[f64; 3]>,
    until: Option<f64>,
) -> vclay_session::Edit {
    vclay_session::Edit::Rope {
        name: name.map(str::to_string),
        from,
        param: None,
        to,
        until,
        velocity: None,
        release: None,
        stiffness: None,
        length: None,
        kernel: None,
        start: None,
    }
}

/// Save -> text -> load, then `n` steps of both: identical saves (every f64 bit); `what`
/// names the case in a failure.
#[track_caller]
pub fn check_continue(s: &mut vclay_session::Session, n: u64, what: &str) {
    let text = serde_json::to_string(&saved(s)).unwrap();
    let v: serde_json::Value = serde_json::from_str(&text).unwrap();
    let kind = s.model(None).unwrap().kind();
    let mut s2 =
        vclay_session::Session::with_model("m", vclay_session::models::load(kind, &v).unwrap())
            .unwrap();
    assert_same(
        &saved(&s2),
        &v,
        &format!("{what}: load did not reproduce the saved state"),
    );
    s.run(n).unwrap();
    s2.run(n).unwrap();
    assert_same(
        &saved(s),
        &saved(&s2),
        &format!("{what}: continued runs differ"),
    );
}

/// Applies `edit`: undo gives back the saved model before it, redo the one after, and after
/// `steps` steps undo gives back the one before again (bit for bit). Returns the saved model
/// before and after the edit.
#[track_caller]
pub fn undo_redo_and_after_steps(
    s: &mut vclay_session::Session,
    edit: &vclay_session::Edit,
    steps: u64,
) -> (serde_json::Value, serde_json::Value) {
    let what = edit.action();
    let before = saved(s);
    s.apply(vclay_session::Command::new(edit.clone()))
        .unwrap_or_else(|e| panic!("{what}: {e}"));
    let after = saved(s);
    s.undo().unwrap();
    assert_same(&saved(s), &before, &format!("{what}: undo"));
    s.redo().unwrap();
    assert_same(&saved(s), &after, &format!("{what}: redo"));
    s.run(steps).unwrap_or_else(|e| panic!("{what}: {e}"));
    assert!(
        saved(s) != after || steps == 0,
        "{what}: steps changed nothing"
    );
    s.undo().unwrap();
    assert_same(&saved(s), &before, &format!("{what}: undo after steps"));
    (before, after)
}

/// The text of the shipped scenario `examples/scenarios/<name>`.
pub fn example(name: &str) -> String {
    let p = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../../examples/scenarios")
        .join(name);
    std::fs::read_to_string(p).unwrap()
}

/// The error of a scenario that must not parse, as a user reads it.
#[track_caller]
pub fn scenario_error(text: &str) -> String {
    vclay_session::scenario::Scenario::parse(text, "bad.toml", "bad", std::path::Path::new("."))
        .unwrap_err()
        .to_string()
}
