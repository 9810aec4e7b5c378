//! Shared test helpers.

/// An edit from its session-file form: the `action` tag and its keys (docs/formats.md
/// section 9).
pub fn edit(v: serde_json::Value) -> vclay_session::Edit {
    serde_json::from_value(v.clone()).unwrap_or_else(|e| panic!("{v}: {e}"))
}

/// Applies the edit of session-file form `v` to the session's first model.
#[track_caller]
pub fn apply_json(s: &mut vclay_session::Session, v: serde_json::Value) {
    s.apply(vclay_session::Command::new(edit(v))).unwrap();
}

/// The highest `z` of `points`.
pub fn top_z(points: &[vclay_core::Vec3]) -> f64 {
    points.iter().map(|p| p.z).fold(f64::NEG_INFINITY, f64::max)
}

/// The whole session file of `s` as text (`vclay_session::file`'s form).
pub fn session_text(s: &vclay_session::Session) -> String {
    serde_json::to_string(&vclay_session::file::to_value(s, None).unwrap()).unwrap()
}

/// `s` and `back` (loaded from `s`'s session file) run on `steps` steps each and must end
/// with the same models, bit for bit.
#[track_caller]
pub fn continue_alike(
    s: &mut vclay_session::Session,
    back: &mut vclay_session::Session,
    steps: u64,
    what: &str,
) {
    s.run(steps).unwrap();
    back.run(steps).unwrap();
    let models = |s: &vclay_session::Session| {
        vclay_session::file::to_value(s, None).unwrap()["models"].clone()
    };
    assert_same(&models(back), &models(s), what);
}

/// The first model's hit of a ray from `origin` along -x (pick tolerance 1e-3).
#[track_caller]
pub fn pick_along_minus_x(s: &vclay_session::Session, origin: [f64; 3]) -> vclay_session::Hit {
    let ray = vclay_session::Ray {
        origin: origin.into(),
        direction: vclay_core::Vec3::new(-1.0, 0.0, 0.0),
    };
    let m = s.model(None).unwrap();
    m.pick(&ray, 1e-3)
        .unwrap_or_else(|| panic!("nothing hit from {origin:?}"))
}

/// `set name = value` (a parameter of [`vclay_session::Model::params`]).
pub fn set(name: &str, value: f64) -> vclay_session::Edit {
    vclay_session::Edit::Set {
        name: name.into(),
        value,
    }
}

/// `pde-set name = value` (a PDE parameter).
pub fn pde_set(name: &str, value: f64) -> vclay_session::Edit {
    vclay_session::Edit::PdeSet {
        name: name.into(),
        value,
    }
}

/// A point constraint (an unnamed `constraint` of kind `point`) holding the surface point at
/// `param` at the origin.
pub fn point_constraint(param: [f64; 2]) -> vclay_session::Edit {
    vclay_session::Edit::Constraint {
        name: None,
        kind: "point".into(),
        param,
        target: Some([0.0; 3]),
        normal: None,
    }
}

/// Exports the session's first model as `dir/stem.ext` for each of `exts`; each file is written
/// and not empty.
#[track_caller]
pub fn export_each(s: &vclay_session::Session, dir: &std::path::Path, stem: &str, exts: &[&str]) {
    let m = s.model(None).unwrap();
    for ext in exts {
        let path = dir.join(format!("{stem}.{ext}"));
        m.export(&path).unwrap_or_else(|e| panic!("{ext}: {e}"));
        assert!(std::fs::metadata(&path).unwrap().len() > 0, "{ext}: empty");
    }
}

/// Edits from an array of their session-file forms.
pub fn edits(v: serde_json::Value) -> Vec<vclay_session::Edit> {
    let serde_json::Value::Array(a) = v else {
        panic!("not an array: {v}")
    };
    a.into_iter().map(edit).collect()
}

/// The edits every control-net kind takes, in their session-file form: plastic reset, stop,
/// moving point 3, setting the material key `key`, `set dt` and a change to `integrator` at
/// half that step.
pub fn closing_edits(
    (key, value): (&str, f64),
    dt: f64,
    integrator: &str,
) -> Vec<vclay_session::Edit> {
    edits(serde_json::json!([
        {"action": "plastic-reset"},
        {"action": "stop"},
        {"action": "move-point", "index": 3, "to": [0.1, 0.2, 0.3]},
        {"action": "set", "name": key, "value": value},
        {"action": "set", "name": "dt", "value": dt},
        {"action": "integrator", "integrator": integrator, "dt": dt / 2.0},
    ]))
}

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

/// For each `(from, to, says)`: the example scenario `name` with its first `from` replaced by
/// `to` is refused with a message containing `says`.
#[track_caller]
pub fn refused_variants(name: &str, cases: &[(&str, &str, &str)]) {
    let base = example(name);
    for (from, to, says) in cases {
        assert!(base.contains(from), "{name} has no `{from}`");
        let e = scenario_error(&base.replacen(from, to, 1));
        assert!(e.contains(says), "{from} -> {to}: {e}");
    }
}

/// Parses the scenario `text` (errors panic) into its session.
#[track_caller]
pub fn scenario(text: &str) -> vclay_session::Session {
    vclay_session::scenario::Scenario::parse(text, "t.toml", "t", std::path::Path::new("."))
        .unwrap_or_else(|e| panic!("{e}"))
        .session
}
