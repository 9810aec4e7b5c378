//! The `pde-surface` model kind in a session (`dynamic-pde-surfaces.txt` eqs 1-12): setting a
//! named constant, the time or `dt` applies, undoes to the same bits and redoes to the same
//! bits; steps advance the PDE's t; a saved model reloads and continues bit for bit; edits that
//! cannot apply leave the model unchanged.

use std::path::Path;

use crate::common;
use common::{positions, round_trip, saved_text as saved};
use vclay_core::Vec3;
use vclay_session::models;
use vclay_session::{Command, Edit, Element, Model, ModelKind, Session};

fn build_at(
    model: &str,
    simulation: Option<&str>,
    base: &Path,
) -> Result<Box<dyn Model>, models::SpecError> {
    common::try_build(ModelKind::PdeSurface, model, None, simulation, base)
}

fn build(model: &str) -> Box<dyn Model> {
    build_at(model, Some("dt = 0.1"), Path::new(".")).expect("builds")
}

/// The glass of Fig 2 on a coarse grid.
fn session() -> Session {
    let m = build("kind = \"pde-surface\"\nname = \"g\"\nbuiltin = \"glass\"\ngrid = [8, 12]");
    Session::with_model("g", m).unwrap()
}

fn param(s: &Session, name: &str) -> f64 {
    s.model(None)
        .unwrap()
        .params()
        .iter()
        .find(|p| p.name == name)
        .unwrap_or_else(|| panic!("no param {name}"))
        .value
}

#[test]
fn setting_a_constant_reshapes_and_undoes() {
    let mut s = session();
    let before = positions(&s);
    round_trip(&mut s, common::pde_set("a", 1.5));
    assert_eq!(param(&s, "a"), 1.5);
    // The rim (u = 0 of the bowl) is x = a cos v at t = 0: its first vertex (v = 0) moved.
    let now = positions(&s);
    assert!((now[0].x - 1.5).abs() < 1e-9, "{:?}", now[0]);
    assert!((before[0].x - 1.0).abs() < 1e-9, "{:?}", before[0]);
    // `set` reaches the same constants.
    round_trip(&mut s, common::set("h0", 3.5));
    assert!((positions(&s)[0].z - 3.5).abs() < 1e-9);
    round_trip(&mut s, common::set("dt", 0.25));
    assert_eq!(s.model(None).unwrap().dt(), 0.25);
}

#[test]
fn setting_the_time_reshapes_and_undoes() {
    let mut s = session();
    round_trip(&mut s, common::pde_set("t", 1.0));
    let m = s.model(None).unwrap();
    assert_eq!(m.time(), 1.0);
    // At t = 1 the rim carries the petals: x(0, 0) = a cos 0 + b sin 0 = 1, but z = h0 + h01 sin(5v).
    let p = positions(&s);
    let nv = 12;
    let v = std::f64::consts::TAU / (nv - 1) as f64;
    assert!(
        (p[1].z - (3.0 + 0.25 * (5.0 * v).sin())).abs() < 1e-9,
        "{:?}",
        p[1]
    );
}

#[test]
fn steps_advance_t_and_undo_restores_the_state_before_the_edit() {
    let mut s = session();
    let edit = common::pde_set("b", 0.3);
    let (at_edit, stepped) = common::steps_then_undo(&mut s, edit, 3, 0.1);
    assert_ne!(stepped, at_edit, "the petals grow with t");
}

#[test]
fn saved_model_continues_bit_for_bit() {
    let mut s = session();
    s.apply(Command::new(common::pde_set("h01", 0.4))).unwrap();
    s.run(2).unwrap();
    let mut t = common::reloaded(&s, "g");
    s.run(3).unwrap();
    t.run(3).unwrap();
    assert_eq!(saved(&t), saved(&s));
    assert_eq!(positions(&t), positions(&s));
    assert_eq!(t.model(None).unwrap().time(), s.model(None).unwrap().time());
}

#[test]
fn edits_that_cannot_apply_leave_the_model_unchanged() {
    let mut s = session();
    let before = (saved(&s), positions(&s));
    let bad = [
        common::pde_set("nope", 1.0),
        common::set("stiffness", 1.0),
        Edit::MovePoint {
            index: 0,
            to: [0.0; 3],
        },
        Edit::Stop,
        Edit::FfdMove {
            moves: vec![vclay_session::PointMove {
                from: [0.0; 3],
                to: [1.0; 3],
            }],
        },
    ];
    for edit in bad {
        let e = s.apply(Command::new(edit.clone())).unwrap_err();
        let msg = e.to_string();
        assert!(msg.contains(edit.action()), "{msg}");
        if !matches!(edit, Edit::PdeSet { .. } | Edit::Set { .. }) {
            assert!(msg.contains("pde-surface"), "{msg}");
        }
        assert_eq!((saved(&s), positions(&s)), before, "{edit:?}");
    }
    assert!(!s.can_undo());
}

#[test]
fn pick_reports_surface_parameters() {
    let s = session();
    let m = s.model(None).unwrap();
    let hit = common::pick_along_minus_x(&s, [5.0, 0.01, 2.8]);
    let Element::SurfacePoint { param } = hit.element else {
        panic!("{hit:?}")
    };
    assert!(param[0] > 0.0 && param[0] < 0.5, "{param:?}");
    assert!((0.0..0.6).contains(&param[1]), "{param:?}");
    assert!(hit.point.x > 0.5, "{hit:?}");
    let lines = m.display_lines();
    assert_eq!(
        lines[0].points.len(),
        3 * 2 * 12,
        "two boundary curves per patch"
    );
}

#[test]
fn spec_files_constants_and_keys() {
    let dir = tempfile::tempdir().unwrap();
    std::fs::write(dir.path().join("vase.json"), vclay_pde::builtin::VASE).unwrap();
    let spec: vclay_pde::SpecFile = serde_json::from_str(vclay_pde::builtin::VASE).unwrap();
    let (name, value) = spec.params.iter().next().expect("the vase has constants");
    let m = build_at(
        &format!(
            "spec = \"vase.json\"\ngrid = [6, 6]\nparams = {{ {name} = {} }}",
            value + 0.01
        ),
        None,
        dir.path(),
    )
    .unwrap();
    let p = m.params();
    assert_eq!(
        p.iter().find(|p| &p.name == name).unwrap().value,
        value + 0.01
    );
    assert_eq!(m.dt(), 1.0 / 30.0);
    let dir_path = dir.path();
    for (text, key) in [
        ("builtin = \"teapot\"", "builtin"),
        ("builtin = \"glass\"\ngrid = [1, 8]", "grid"),
        ("builtin = \"glass\"\ngrid = [8, 2000]", "grid"),
        ("builtin = \"glass\"\nparams = { zz = 1.0 }", "params"),
        ("spec = \"missing.json\"", "spec"),
        ("grid = [8, 8]", "spec"),
        ("builtin = \"glass\"\ncolour = 1", "colour"),
    ] {
        let e = build_at(text, None, dir_path).expect_err(text);
        assert_eq!(e.key, key, "{text}: {e:?}");
    }
    let e = build_at("builtin = \"glass\"", Some("dt = -1"), dir_path).expect_err("dt");
    assert_eq!((e.table.as_str(), e.key.as_str()), ("simulation", "dt"));
}

#[test]
fn exports_the_surface_and_the_spec() {
    let s = session();
    let m = s.model(None).unwrap();
    let dir = tempfile::tempdir().unwrap();
    common::export_each(&s, dir.path(), "g", &["obj", "ply", "stl", "glb", "json"]);
    // The exported spec compiles.
    vclay_pde::PdeModel::read(dir.path().join("g.json")).unwrap();
    assert!(m.export(&dir.path().join("g.vtu")).is_err());
}

#[test]
fn every_builtin_opens() {
    for name in vclay_session::models::pde::BUILTINS {
        let m: toml::Table = toml::from_str(&format!(
            "kind = \"pde-surface\"\nbuiltin = \"{name}\"\ngrid = [8, 8]"
        ))
        .unwrap();
        let model = vclay_session::models::build(
            vclay_session::ModelKind::PdeSurface,
            &vclay_session::models::Spec {
                model: &m,
                material: None,
                simulation: None,
                base: std::path::Path::new("."),
            },
        )
        .unwrap_or_else(|e| panic!("{name}: {e:?}"));
        assert!(
            !model.display_mesh().unwrap().triangles.is_empty(),
            "{name}"
        );
    }
}

#[test]
fn a_local_deformation_moves_its_region_only_and_undoes_saves_and_releases() {
    let mut s = session();
    let before = positions(&s);
    // A G0 bump over the middle of the glass's first patch, pushed out along x by
    // p = (1.6, 0, 0): at the region's centre the surface moves by p / 16 = 0.1.
    let bump = |patch: usize, u: [f64; 2], p: [f64; 3]| Edit::PdeLocal {
        name: "bump".into(),
        patch,
        u,
        v: [1.0, 2.0],
        continuity: Some("G0".into()),
        p,
    };
    let local = bump(0, [0.25, 0.75], [1.6, 0.0, 0.0]);
    round_trip(&mut s, local.clone());
    // The region is sampled more finely (its borders become grid lines), and the surface
    // moved there: the deformed mesh is not the undeformed one.
    let after = positions(&s);
    assert!(
        after.len() > before.len(),
        "{} -> {}",
        before.len(),
        after.len()
    );
    // Every vertex lies within the bump's peak (p / 16 = 0.1) of the undeformed surface's
    // sample nearest to it, up to the grid's spacing (the new samples fall between old ones).
    let spacing = 0.5;
    for q in &after {
        let d = before
            .iter()
            .map(|b| (b - q).norm())
            .fold(f64::INFINITY, f64::min);
        assert!(d <= 0.1 + spacing, "a vertex moved {d}");
    }
    // The same name replaces it; release removes it; unknown names are errors.
    s.apply(Command::new(bump(0, [0.25, 0.75], [0.0, 0.0, 1.6])))
        .unwrap();
    let log_saved = saved(&s);
    assert!(log_saved.contains("\"locals\""), "saved with the model");
    let v: serde_json::Value = serde_json::from_str(&log_saved).unwrap();
    let mut loaded = Session::with_model(
        "g",
        vclay_session::models::load(ModelKind::PdeSurface, &v).unwrap(),
    )
    .unwrap();
    assert_eq!(
        positions(&loaded),
        positions(&s),
        "reloaded with its deformation"
    );
    loaded
        .apply(Command::new(Edit::Release {
            name: "bump".into(),
        }))
        .unwrap();
    assert_eq!(positions(&loaded), before, "released");
    let e = loaded
        .apply(Command::new(Edit::Release {
            name: "bump".into(),
        }))
        .unwrap_err()
        .to_string();
    assert!(e.contains("no local deformation named `bump`"), "{e}");
    // A patch that does not exist, a u range outside [0, 1].
    let e = s
        .apply(Command::new(bump(9, [0.25, 0.75], [1.6, 0.0, 0.0])))
        .unwrap_err()
        .to_string();
    assert!(e.contains("patch 9 does not exist"), "{e}");
    assert!(
        s.apply(Command::new(bump(0, [0.5, 1.5], [1.6, 0.0, 0.0])))
            .is_err()
    );
    // A pick on the glass names its patch.
    let m = s.model(None).unwrap();
    let c = m.display_mesh().unwrap().positions[0];
    let ray = vclay_session::Ray {
        origin: c * 3.0 + Vec3::new(0.0, 0.0, 0.01),
        direction: -c * 2.0,
    };
    if let Some(hit) = m.pick(&ray, 0.0) {
        assert!(
            matches!(
                hit.extra[0],
                Some(vclay_session::Element::Patch { index: 0 })
            ),
            "{hit:?}"
        );
    }
}
