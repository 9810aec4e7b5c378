//! D-NURBS scenario files (`vclay run`): a small run end to end, and errors that name the file,
//! line and key.
use std::path::Path;
use vclay_dynamics::scenario::DnurbsScenario;

const SMALL: &str = r#"
[model]
kind = "dnurbs-surface"
primitive = "sheet"
size = [5, 5]
degree = [2, 2]
fix = [0, 4]

[material]
mu = 1.0
gamma = 2.0
alpha = 1.0
beta = 0.1

[simulation]
dt = 0.05
steps = 20

[[force]]
type = "spring"
param = [0.5, 0.5]
target = [0.0, 0.0, 0.5]
stiffness = 50.0

[[constraint]]
type = "normal"
param = [0.5, 0.5]
normal = [0.0, 0.0, 1.0]
"#;

#[test]
fn a_small_scenario_runs_and_writes_its_files() {
    let dir = tempfile::tempdir().unwrap();
    let mut s = DnurbsScenario::parse(SMALL, "small.toml", dir.path()).unwrap();
    let mut calls = 0;
    let r = s.run(&mut |_, _, _| calls += 1).unwrap();
    assert_eq!((r.steps, calls), (20, 20));
    assert!(r.constraint_violation < 1e-9, "{}", r.constraint_violation);
    for f in ["energy.csv", "final.obj", "final.json"] {
        let p = dir.path().join("vclay-run").join(f);
        assert!(p.metadata().unwrap().len() > 0, "{f}");
    }
    let model = vclay_io::model::read_model(dir.path().join("vclay-run/final.json")).unwrap();
    let vclay_io::model::Entity::Surface(surface) = &model[0] else {
        panic!("expected a surface")
    };
    let mid = vclay_spline::ParametricSurface::point(surface, 0.5, 0.5).unwrap();
    assert!(mid.z > 0.05, "the spring should lift the middle: {mid:?}");
}

fn error_of(text: &str) -> String {
    DnurbsScenario::parse(text, "bad.toml", Path::new("."))
        .unwrap_err()
        .to_string()
}

#[test]
fn bad_scenarios_name_file_line_and_key() {
    let e = error_of(&SMALL.replace("stiffness = 50.0", "stiffness = -5.0"));
    assert!(
        e.starts_with("bad.toml:23:") && e.contains("stiffness"),
        "{e}"
    );
    let e = error_of(&SMALL.replace("dt = 0.05", "dt = \"fast\""));
    assert!(e.starts_with("bad.toml:16:"), "{e}");
    let e = error_of(&SMALL.replace("kind = \"dnurbs-surface\"", "kind = \"dnurbs-blob\""));
    assert!(e.contains("kind") && e.contains("dnurbs-blob"), "{e}");
    let e = error_of(&SMALL.replace("primitive = \"sheet\"", "primitive = \"teapot\""));
    assert!(e.contains("primitive") && e.contains("teapot"), "{e}");
    let e = error_of(&SMALL.replace("param = [0.5, 0.5]\nnormal", "param = [3.0, 0.5]\nnormal"));
    assert!(
        e.starts_with("bad.toml:25:") && e.contains("constraint"),
        "{e}"
    );
    let e = error_of(&SMALL.replace("fix = [0, 4]", "fix = [0, 99]"));
    assert!(e.contains("fix") && e.contains("99"), "{e}");
    let e = error_of(&SMALL.replace("[simulation]", "[simulation]\nspeed = 3"));
    assert!(e.contains("speed"), "{e}");
    let e = error_of("[model\nkind = 1");
    assert!(e.starts_with("bad.toml:1:"), "{e}");
}
