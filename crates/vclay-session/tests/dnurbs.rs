//! D-NURBS models in a session: every command applies, undoes and redoes bit for bit, and a
//! saved model continues exactly like the uninterrupted one (`d-nurbs.txt` eqs 15-19,
//! sections 6.1-6.2).

use std::path::Path;

use crate::common;
use common::saved;
use vclay_session::models;
use vclay_session::{Command, Edit, Model, ModelKind, Session};

fn build(kind: ModelKind, model: &str, material: &str, sim: &str) -> Box<dyn Model> {
    common::build(
        kind,
        model,
        Some(material).filter(|m| !m.is_empty()),
        Some(sim),
    )
}

fn sheet() -> Box<dyn Model> {
    build(
        ModelKind::DnurbsSurface,
        "kind = \"dnurbs-surface\"\nsize = [6, 6]\ndegree = [3, 3]\nname = \"s\"",
        "",
        "dt = 0.01",
    )
}
fn frozen_sheet() -> Box<dyn Model> {
    build(
        ModelKind::DnurbsSurface,
        "kind = \"dnurbs-surface\"\nsize = [6, 6]\ndegree = [3, 3]\nengine = \"frozen\"",
        "",
        "dt = 0.01",
    )
}
fn line() -> Box<dyn Model> {
    build(
        ModelKind::DnurbsCurve,
        "kind = \"dnurbs-curve\"\nsize = [7]\ndegree = [3]\nfix = [0]",
        "mu = 1.0",
        "dt = 0.01",
    )
}
fn sphere() -> Box<dyn Model> {
    build(
        ModelKind::DnurbsSwung,
        "kind = \"dnurbs-swung\"\nprimitive = \"sphere\"",
        "",
        "dt = 0.002",
    )
}

fn kind(s: &Session) -> ModelKind {
    s.model(None).unwrap().kind()
}

/// Apply, undo (== before), redo (== after), steps then undo (== before), redo, and
/// save/load continuation.
fn check(mut s: Session, edit: Edit) {
    s.run(2).unwrap();
    common::undo_redo_and_after_steps(&mut s, &edit, 3);
    s.apply(Command::new(edit.clone())).unwrap();
    common::check_continue(&mut s, 3, edit.action());
}

fn fails(mut s: Session, edit: Edit) {
    s.run(1).unwrap();
    let before = saved(&s);
    assert!(s.apply(Command::new(edit.clone())).is_err(), "{edit:?}");
    assert_eq!(saved(&s), before);
}

fn session(m: Box<dyn Model>) -> Session {
    Session::with_model("m", m).unwrap()
}

fn rope(param: Option<[f64; 2]>, velocity: Option<[f64; 3]>, to: Option<[f64; 3]>) -> Edit {
    Edit::Rope {
        name: None,
        from: [0.2, 0.1, 0.5],
        param,
        to,
        until: to.map(|_| 0.1),
        velocity,
        release: Some(0.08),
        stiffness: None,
        length: None,
        kernel: None,
        start: None,
    }
}

fn common_edits(surface: bool, frozen: bool) -> Vec<Edit> {
    use serde_json::json;
    let p = if surface { [0.4, 0.6] } else { [0.4, 0.0] };
    let mut v = vec![
        rope(Some(p), None, None),
        rope(None, Some([0.0, 0.0, 1.0]), None),
        rope(Some(p), None, Some([0.0, 0.0, 1.0])),
    ];
    v.extend(common::edits(json!([
        {"action": "force", "name": "f", "param": p, "force": [0.0, 0.0, 3.0], "until": 0.05},
        {"action": "force", "near": [0.1, 0.0, 0.0], "force": [0.0, 1.0, 0.0]},
        {"action": "gravity", "g": [0.0, 0.0, -9.8]},
        {"action": "data", "points": [[0.1, 0.1, 0.3], [-0.2, 0.0, 0.2]], "stiffness": 20.0},
        {"action": "fix", "points": [1, 2]},
        {"action": "fix", "min": [-5.0, -5.0, -5.0], "max": [0.0, 5.0, 5.0]},
        {"action": "free", "near": [-1.0, 0.0, 0.0]},
        {"action": "material", "mu": 2.0, "alpha": 3.0, "beta": 0.2},
    ])));
    v.extend(common::closing_edits(("gamma", 0.5), 0.005, "implicit"));
    if surface {
        v.extend(common::edits(
            json!([{"action": "inflate", "pressure": 0.5}]),
        ));
    }
    if !frozen {
        v.extend(common::edits(json!([
            {"action": "set-weight", "index": 2, "weight": 1.5},
            {"action": "set", "name": "weight_penalty", "value": 2.0},
            {"action": "constraint", "name": "c", "type": "point", "param": p, "target": [0.1, 0.1, 0.1]},
        ])));
        if surface {
            v.extend(common::edits(json!([
                {"action": "constraint", "type": "normal", "param": p, "normal": [0.0, 0.0, 1.0]},
            ])));
        }
    }
    v
}

fn not_applicable() -> Vec<Edit> {
    vec![
        Edit::Extrude {
            face: Some(0),
            near: None,
            factor: None,
        },
        Edit::DeleteCell {
            cell: Some(0),
            near: None,
        },
        Edit::RegionForce {
            name: None,
            center: [0.0; 3],
            radius: 1.0,
            force: [0.0, 0.0, 1.0],
            until: None,
            falloff: None,
        },
        common::pde_set("a", 1.0),
        Edit::Integrator {
            integrator: Some("explicit".into()),
            dt: None,
        },
        common::set("nope", 1.0),
        Edit::Release {
            name: "nobody".into(),
        },
        common::edit(serde_json::json!({"action": "material", "density": 1.0})),
        Edit::MovePoint {
            index: 10_000,
            to: [0.0; 3],
        },
    ]
}

#[test]
fn surface_commands() {
    for e in common_edits(true, false) {
        check(session(sheet()), e);
    }
}

#[test]
fn frozen_surface_commands() {
    for e in common_edits(true, true) {
        check(session(frozen_sheet()), e);
    }
    let mut s = session(frozen_sheet());
    fails(s, common::point_constraint([0.5, 0.5]));
    s = session(frozen_sheet());
    fails(
        s,
        Edit::SetWeight {
            index: 0,
            weight: 2.0,
        },
    );
    // The frozen engine's tools leave out what it refuses (the kind's list has them), and
    // the refusal says that the model's settings are why.
    let actions: Vec<&str> = frozen_sheet().tools().iter().map(|t| t.action).collect();
    for a in ["constraint", "set-weight"] {
        assert!(!actions.contains(&a), "{a} in {actions:?}");
        assert!(vclay_session::describe::actions(ModelKind::DnurbsSurface).contains(&a));
    }
    assert!(
        actions.contains(&"rope") && actions.contains(&"smooth"),
        "{actions:?}"
    );
    let e = session(frozen_sheet())
        .apply(Command::new(Edit::SetWeight {
            index: 0,
            weight: 2.0,
        }))
        .unwrap_err()
        .to_string();
    assert!(e.contains("set-weight") && e.contains("engine"), "{e}");
}

#[test]
fn curve_commands() {
    for e in common_edits(false, false) {
        check(session(line()), e);
    }
    fails(
        session(line()),
        Edit::Inflate {
            name: None,
            pressure: 1.0,
            until: None,
        },
    );
}

#[test]
fn swung_commands() {
    let p = [0.4, 0.3];
    let edits = vec![
        rope(Some(p), None, None),
        rope(Some(p), Some([0.0, 0.0, 1.0]), None),
        Edit::Gravity {
            name: None,
            g: [0.0, 0.0, -1.0],
            until: None,
        },
        Edit::Inflate {
            name: None,
            pressure: 0.5,
            until: None,
        },
        Edit::Fix(vclay_session::Selection::ids(vec![0])),
        Edit::Stop,
        Edit::PlasticReset,
        Edit::SetWeight {
            index: 1,
            weight: 0.9,
        },
        {
            // A point of the sphere from a pick, moved slightly outwards.
            let m = sphere();
            let h = m
                .pick(
                    &vclay_session::Ray {
                        origin: vclay_core::Vec3::new(3.0, 0.1, 0.1),
                        direction: vclay_core::Vec3::new(-1.0, 0.0, 0.0),
                    },
                    1e-3,
                )
                .expect("the sphere is hit");
            let vclay_session::Element::SurfacePoint { param } = h.element else {
                panic!("not a surface point: {h:?}")
            };
            Edit::Constraint {
                name: None,
                kind: "point".into(),
                param,
                target: Some([h.point.x + 0.01, h.point.y, h.point.z]),
                normal: None,
            }
        },
        common::set("mu", 2.0),
    ];
    for e in edits {
        check(session(sphere()), e);
    }
}

#[test]
fn inapplicable_commands_leave_the_model_unchanged() {
    for e in not_applicable() {
        fails(session(sheet()), e.clone());
        fails(session(line()), e);
    }
}

#[test]
fn release_and_gravity_rename() {
    let mut s = session(sheet());
    s.apply(Command::new(Edit::Gravity {
        name: Some("g".into()),
        g: [0.0, 0.0, -1.0],
        until: None,
    }))
    .unwrap();
    s.apply(Command::new(Edit::Constraint {
        name: Some("c".into()),
        kind: "point".into(),
        param: [0.5, 0.5],
        target: Some([0.0, 0.0, 0.1]),
        normal: None,
    }))
    .unwrap();
    s.run(2).unwrap();
    for edit in [
        Edit::Gravity {
            name: Some("g".into()),
            g: [0.0, 0.0, -2.0],
            until: None,
        },
        Edit::Release { name: "g".into() },
        Edit::Release { name: "c".into() },
        Edit::MoveRope {
            name: "r".into(),
            to: [0.0; 3],
        },
    ] {
        let mut s2 = session(models::load(kind(&s), &saved(&s)).unwrap());
        if let Edit::MoveRope { .. } = edit {
            s2.apply(Command::new(Edit::Rope {
                name: Some("r".into()),
                from: [0.1, 0.1, 0.2],
                param: None,
                to: None,
                until: None,
                velocity: None,
                release: None,
                stiffness: Some(10.0),
                length: None,
                kernel: None,
                start: None,
            }))
            .unwrap();
        }
        check(s2, edit);
    }
}

#[test]
fn frozen_benchmark_sheet_wraps() {
    // The benchmark's spring target is a closure: the model runs but cannot be saved.
    let d = vclay_dynamics::dnurbs::benchmarks::frozen_sheet(6).unwrap();
    let m = models::dnurbs::DnurbsModel::frozen_surface(d, 0.01).unwrap();
    let mut s = session(Box::new(m));
    s.run(2).unwrap();
    assert!(s.model(None).unwrap().save().is_err());
    // The same steps as the engine alone, bit for bit.
    let mut d = vclay_dynamics::dnurbs::benchmarks::frozen_sheet(6).unwrap();
    d.run(0.01, 2).unwrap();
    let engine: Vec<f64> = d
        .geometry()
        .control_points()
        .iter()
        .flat_map(|p| [p.x, p.y, p.z])
        .collect();
    // The control net of a frozen sheet is its control points.
    let session: Vec<f64> = s.model(None).unwrap().display_lines()[0]
        .points
        .iter()
        .flat_map(|p| [p.x, p.y, p.z])
        .collect();
    assert_eq!(session, engine);
}

#[test]
fn display_pick_export() {
    let dir = tempfile::tempdir().unwrap();
    for m in [sheet(), line(), sphere(), frozen_sheet()] {
        let mesh = m.display_mesh().unwrap();
        let lines = m.display_lines();
        assert!(!lines.is_empty());
        let ray = vclay_session::Ray {
            origin: vclay_core::Vec3::new(0.05, 0.03, 5.0),
            direction: vclay_core::Vec3::new(0.0, 0.0, -1.0),
        };
        if m.kind() == ModelKind::DnurbsSurface {
            assert!(!mesh.triangles.is_empty());
            let h = m.pick(&ray, 1e-3).expect("hit");
            assert!(matches!(
                h.element,
                vclay_session::Element::SurfacePoint { .. }
            ));
        }
        for ext in ["json", "obj"] {
            m.export(&dir.path().join(format!("x.{ext}"))).unwrap();
        }
        assert!(m.export(&dir.path().join("x.vtu")).is_err());
    }
}

#[test]
fn spec_errors() {
    let err = |kind, model| {
        common::try_build(kind, model, None, Some("dt = 0.01"), Path::new(".")).unwrap_err()
    };
    let e = err(
        ModelKind::DnurbsSurface,
        "kind = \"dnurbs-surface\"\nsize = [600, 6]",
    );
    assert_eq!(e.key, "size");
    let e = err(
        ModelKind::DnurbsSwung,
        "kind = \"dnurbs-swung\"\nprimitive = \"sphere\"\nengine = \"frozen\"",
    );
    assert_eq!(e.key, "engine");
}

/// The model counts steps of `dt`, whatever adaptive sub-steps the engine takes inside them
/// (so frames every k steps and `--until` are right): a fit with dynamic weights, whose engine
/// may halve steps, still counts exactly the steps asked for.
#[test]
fn steps_count_steps_of_dt_not_engine_substeps() {
    let m = build(
        ModelKind::DnurbsSurface,
        "kind = \"dnurbs-surface\"\nprimitive = \"sheet\"\nsize = [7, 7]\ndegree = [2, 2]\nextent = 2.4",
        "preset = \"Hemisphere fitting\"",
        "reference = \"absolute\"",
    );
    let mut s = Session::with_model("m", m).unwrap();
    s.apply(Command::new(Edit::Data {
        name: None,
        points: vclay_dynamics::dnurbs::figures::hemisphere_points()
            .iter()
            .map(|p| [p.x, p.y, p.z])
            .collect(),
        stiffness: None,
    }))
    .unwrap();
    s.run(40).unwrap();
    let m = s.model(None).unwrap();
    assert_eq!(m.steps(), 40);
    assert!((m.time() - 40.0 * m.dt()).abs() < 1e-9 * m.time().max(1.0));
}

/// Issue 26: every D-NURBS kind is the one model (`GeneralizedModel` over a `DnurbsEngine`):
/// curves, surfaces on either engine, swung, triangular and joined patches take `set dt`
/// through the same path (the same refusal, the step and the parameter follow), and undo puts
/// the step back.
#[test]
fn every_dnurbs_kind_takes_set_dt_through_the_one_model() {
    let triangular = common::build(
        ModelKind::DnurbsTriangular,
        "kind = \"dnurbs-triangular\"\nrounding = \"edge\"\nquadrature = \"whole\"",
        None,
        None,
    );
    let patches = vclay_session::scenario::Scenario::parse(
        &common::example("fig_patches_g1.toml"),
        "p.toml",
        "p",
        Path::new("."),
    )
    .unwrap()
    .session
    .model(None)
    .unwrap()
    .clone_model();
    let models = [
        sheet(),
        frozen_sheet(),
        line(),
        sphere(),
        triangular,
        patches,
    ];
    for m in models {
        let kind = m.kind();
        let dt0 = m.dt();
        let mut s = session(m);
        let set = |v: f64| Command::new(common::set("dt", v));
        let e = s.apply(set(-1.0)).unwrap_err().to_string();
        assert!(e.contains("dt = -1: must be positive"), "{kind}: {e}");
        s.apply(set(0.004)).unwrap();
        let m = s.model(None).unwrap();
        assert_eq!(m.dt(), 0.004, "{kind}");
        let p = m.params().into_iter().find(|p| p.name == "dt").unwrap();
        assert_eq!(p.value, 0.004, "{kind}");
        s.step().unwrap();
        assert!(
            (s.model(None).unwrap().time() - 0.004).abs() < 1e-12,
            "{kind}"
        );
        s.undo().unwrap();
        assert_eq!(s.model(None).unwrap().dt(), dt0, "{kind}");
    }
}

/// `[simulation] solver = "block-schur"` (issues 27/31): the split solve follows the direct
/// factorization within its stated tolerance (1e-12 relative residual per solve; here 1e-10 of
/// the model size after 60 steps with a rope pulling), is saved with the model and continues
/// bit for bit after a load; the frozen engine and unknown names are refused with the key.
#[test]
fn the_block_schur_solver_follows_the_direct_one_and_is_saved() {
    let model = "kind = \"dnurbs-surface\"\nsize = [10, 10]\ndegree = [3, 3]";
    let run = |sim: &str| {
        let mut s = session(build(ModelKind::DnurbsSurface, model, "", sim));
        s.apply(Command::new(rope(
            Some([0.4, 0.6]),
            None,
            Some([0.3, 0.2, 0.8]),
        )))
        .unwrap();
        s.run(60).unwrap();
        s
    };
    let direct = run("dt = 0.01");
    let mut split = run("dt = 0.01\nsolver = \"block-schur\"");
    let size = direct.model(None).unwrap().size();
    let (a, b) = (
        direct.model(None).unwrap().control_points(),
        split.model(None).unwrap().control_points(),
    );
    let gap = a
        .iter()
        .zip(&b)
        .map(|(p, q)| (*p - *q).norm())
        .fold(0.0, f64::max);
    assert!(gap < 1e-10 * size, "block-schur is {gap} from direct");
    assert_ne!(saved(&direct), saved(&split), "the split path was taken");
    assert_eq!(saved(&split)["solver"], "block-schur");
    assert!(saved(&direct).get("solver").is_none());
    common::check_continue(&mut split, 3, "block-schur");

    // The build's error for `model` with `sim`, as text.
    let refused = |model: &str, sim: &str, why: &str| {
        let Err(e) = common::try_build(
            ModelKind::DnurbsSurface,
            model,
            None,
            Some(sim),
            Path::new("."),
        ) else {
            panic!("{why}")
        };
        format!("{e:?}")
    };
    let e = refused(
        "kind = \"dnurbs-surface\"\nsize = [6, 6]\ndegree = [3, 3]\nengine = \"frozen\"",
        "dt = 0.01\nsolver = \"block-schur\"",
        "the frozen engine refuses it",
    );
    assert!(e.contains("solver") && e.contains("generalized"), "{e}");
    let e = refused(model, "dt = 0.01\nsolver = \"lu\"", "an unknown solver");
    assert!(e.contains("solver") && e.contains("lu"), "{e}");

    // "auto" (the default) takes it from 20 x 20 control points with dynamic weights.
    let takes = |size: usize, sim: &str, weights: &str| {
        let m = build(
            ModelKind::DnurbsSurface,
            &format!(
                "kind = \"dnurbs-surface\"\nsize = [{size}, {size}]\ndegree = [3, 3]\nweights = \"{weights}\""
            ),
            "",
            sim,
        );
        m.save().unwrap().get("solver").is_some()
    };
    let n = (vclay_session::models::dnurbs::AUTO_BLOCK_SCHUR_POINTS as f64).sqrt() as usize;
    assert!(takes(n, "dt = 0.01", "dynamic"));
    assert!(takes(n, "dt = 0.01\nsolver = \"auto\"", "dynamic"));
    assert!(!takes(n - 1, "dt = 0.01", "dynamic"));
    assert!(!takes(n, "dt = 0.01\nsolver = \"direct\"", "dynamic"));
    assert!(!takes(n, "dt = 0.01", "frozen"));
}
