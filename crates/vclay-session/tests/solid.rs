//! Dynamic solids in a session (`subdivision-solids-journal.txt` eqs 3-10, section 5): every
//! command applies, undoes and redoes bit for bit, undo after simulated time returns to the
//! state just before the command, and a saved model continues exactly like the uninterrupted
//! one.

use crate::common;
use common::{assert_same, saved};

use vclay_session::{Command, Edit, Element, Model, ModelKind, Ray, Session};

fn build(kind: ModelKind, model: &str, sim: &str) -> Box<dyn Model> {
    common::build(kind, model, None, Some(sim))
}

fn cube() -> Box<dyn Model> {
    build(
        ModelKind::SubdivisionSolid,
        "kind = \"subdivision-solid\"\nprimitive = \"box\"\npoints = [3, 3, 3]\nlevel = 1",
        "dt = 0.002",
    )
}

fn bspline() -> Box<dyn Model> {
    build(
        ModelKind::BsplineSolid,
        "kind = \"bspline-solid\"\ncontrol = [4, 4, 4]\nsamples = [5, 5, 5]",
        "dt = 0.002\nintegrator = \"implicit\"",
    )
}

/// The rope lines a model draws.
fn ropes_of(m: &dyn Model) -> vclay_session::LineSet {
    m.display_lines()
        .into_iter()
        .find(|l| l.role == Some(vclay_session::LineRole::Ropes))
        .unwrap()
}

/// A session of `model` with a rope `warm` pulling the corner (1, 1, 1) until t = 0.01, after
/// `steps` steps.
fn warmed(model: Box<dyn Model>, steps: u64) -> Session {
    let mut s = Session::with_model("m", model).unwrap();
    s.apply(Command::new(common::rope(
        Some("warm"),
        [1.0, 1.0, 1.0],
        Some([1.2, 1.1, 1.0]),
        Some(0.01),
    )))
    .unwrap();
    s.run(steps).unwrap();
    s
}

/// Apply, undo (== before), redo (== after), steps then undo (== before), redo again.
fn round_trip(make: fn() -> Box<dyn Model>, warmup: u64, edit: Edit) {
    let mut s = warmed(make(), warmup);
    let what = edit.action();
    let (_, after) = common::undo_redo_and_after_steps(&mut s, &edit, 5);
    s.redo().unwrap();
    assert_same(
        &saved(&s),
        &after,
        &format!("{what}: redo after undo after steps"),
    );
    common::check_continue(&mut s, 4, what);
}

fn every_edit(subdivision: bool) -> Vec<Edit> {
    use serde_json::json;
    let mut v = common::edits(json!([
        {"action": "rope", "name": "r", "from": [0.0, 0.0, 1.0], "to": [-0.2, 0.0, 1.2],
         "until": 0.02, "release": 0.05, "stiffness": 40.0, "length": 0.01},
        {"action": "move-rope", "name": "warm", "to": [1.3, 1.3, 1.3]},
        {"action": "force", "near": [0.5, 0.5, 1.0], "force": [0.0, 0.0, 3.0], "until": 0.1},
        {"action": "region-force", "name": "push", "center": [0.5, 0.5, 0.0], "radius": 0.4,
         "force": [0.0, 0.0, -2.0]},
        {"action": "gravity", "name": "g", "g": [0.0, 0.0, -9.8]},
        {"action": "inflate", "pressure": 2.0},
        {"action": "release", "name": "warm"},
        {"action": "fix", "min": [-0.1, -0.1, -0.1], "max": [1.1, 1.1, 0.1]},
        {"action": "free", "points": [0, 1]},
        {"action": "fix", "near": [1.0, 0.0, 0.0]},
        {"action": "material", "min": [0.0, 0.0, 0.0], "max": [0.6, 0.6, 0.6], "density": 2.0,
         "damping": 1.0, "edge_stiffness": 300.0, "anisotropy": [1.0, 2.0, 1.0]},
    ]));
    v.extend(common::closing_edits(
        ("edge_stiffness", 120.0),
        0.001,
        "explicit",
    ));
    if subdivision {
        v.extend(common::edits(json!([
            {"action": "extrude", "near": [1.0, 0.8, 0.8], "factor": 0.5},
            {"action": "delete-cell", "cell": 0},
        ])));
    }
    v
}

#[test]
fn every_subdivision_command_undoes_and_redoes_bit_for_bit() {
    for e in every_edit(true) {
        round_trip(cube, 3, e);
    }
}

#[test]
fn every_bspline_command_undoes_and_redoes_bit_for_bit() {
    for e in every_edit(false) {
        round_trip(bspline, 3, e);
    }
}

#[test]
fn commands_that_cannot_apply_name_the_reason_and_change_nothing() {
    for (make, bad) in [
        (
            cube as fn() -> Box<dyn Model>,
            Edit::Release {
                name: "nope".into(),
            },
        ),
        (
            cube,
            Edit::MoveRope {
                name: "nope".into(),
                to: [0.0; 3],
            },
        ),
        (cube, Edit::Fix(vclay_session::Selection::ids(vec![999]))),
        (
            cube,
            Edit::DeleteCell {
                cell: Some(999),
                near: None,
            },
        ),
        (
            cube,
            Edit::Extrude {
                face: Some(999_999),
                near: None,
                factor: None,
            },
        ),
        (
            cube,
            Edit::SetWeight {
                index: 0,
                weight: 2.0,
            },
        ),
        (cube, common::pde_set("a", 1.0)),
        (
            cube,
            Edit::FfdMove {
                moves: vec![vclay_session::PointMove {
                    from: [0.0; 3],
                    to: [1.0; 3],
                }],
            },
        ),
        (cube, common::set("nope", 1.0)),
        (cube, common::set("dt", -1.0)),
        (
            cube,
            Edit::Integrator {
                integrator: Some("leapfrog".into()),
                dt: None,
            },
        ),
        (
            cube,
            common::edit(serde_json::json!({"action": "material", "cells": [77], "density": 1.0})),
        ),
        (
            cube,
            Edit::Gravity {
                name: None,
                g: [f64::NAN, 0.0, 0.0],
                until: None,
            },
        ),
        (
            bspline,
            Edit::Extrude {
                face: Some(0),
                near: None,
                factor: None,
            },
        ),
        (bspline, common::point_constraint([0.0, 0.0])),
    ] {
        let mut s = Session::with_model("m", make()).unwrap();
        s.run(2).unwrap();
        let before = saved(&s);
        let what = format!("{bad:?}");
        let err = s.apply(Command::new(bad)).expect_err(&what);
        let msg = err.to_string();
        assert!(msg.starts_with("command `"), "{what}: {msg}");
        assert!(msg.contains("on model `m`"), "{what}: {msg}");
        assert_same(&saved(&s), &before, &format!("{what}: the model changed"));
        assert!(s.log().is_empty(), "{what}: logged");
    }
}

#[test]
fn scheduled_ropes_move_and_expire_and_the_display_follows() {
    let mut s = Session::with_model("m", cube()).unwrap();
    s.schedule_commands(vec![vclay_session::Timed {
        at: 0.004,
        command: Command::new(Edit::Rope {
            name: Some("r".into()),
            from: [1.0, 1.0, 1.0],
            param: None,
            to: Some([1.4, 1.0, 1.0]),
            until: Some(0.02),
            velocity: None,
            release: Some(0.03),
            stiffness: None,
            length: None,
            kernel: None,
            start: Some(0.004),
        }),
    }])
    .unwrap();
    let r0 = s.revision();
    let lines = s.run(5).unwrap();
    assert_eq!(lines.len(), 1, "{lines:?}");
    assert!(
        lines[0].starts_with("t = 0.0040: rope `r` attached"),
        "{lines:?}"
    );
    assert!(s.revision() > r0);
    let m = s.model(None).unwrap();
    let ropes = ropes_of(m);
    assert_eq!(ropes.segments.len(), 1);
    // The cursor moves towards `to` (0.4 over 0.016 s), placed before each step: the last
    // step started at t = 0.008, where it is at x = 1.1.
    let cursor = ropes.points[1];
    assert!((cursor.x - 1.1).abs() < 1e-12, "{cursor:?}");
    s.advance_to(0.04).unwrap();
    let m = s.model(None).unwrap();
    let ropes = ropes_of(m);
    assert!(ropes.segments.is_empty(), "released at 0.03");
    // The display mesh is the closed boundary with unit normals.
    let mesh = m.display_mesh().unwrap();
    assert_eq!(mesh.normals.len(), mesh.positions.len());
    assert!(mesh.triangles.len() >= 2 * 6 * 4 * 4);
}

#[test]
fn picking_finds_control_points_and_the_surface() {
    let s = Session::with_model("m", cube()).unwrap();
    // Straight down onto the top face's centre: the control point (0.5, 0.5, 1) is there.
    let ray = Ray {
        origin: vclay_core::Vec3::new(0.5, 0.5, 3.0),
        direction: vclay_core::Vec3::new(0.0, 0.0, -1.0),
    };
    let (name, hit) = s.pick(&ray, 0.01).unwrap();
    assert_eq!(name, "m");
    match hit.element {
        Element::ControlPoint { index } => {
            let p =
                s.model(None).unwrap().save().unwrap()["state"]["control_points"][index].clone();
            assert_eq!(p, serde_json::json!([0.5, 0.5, 1.0]));
        }
        e => panic!("{e:?}"),
    }
    // Off the control points: the surface, with a data point, a face and a cell.
    let ray = Ray {
        origin: vclay_core::Vec3::new(0.3, 0.2, 3.0),
        direction: vclay_core::Vec3::new(0.0, 0.0, -2.0),
    };
    let (_, hit) = s.pick(&ray, 0.01).unwrap();
    assert!(matches!(hit.element, Element::DataPoint { .. }), "{hit:?}");
    assert!((hit.point.z - 1.0).abs() < 1e-9, "{hit:?}");
    assert!(
        (hit.distance - 1.0).abs() < 1e-9,
        "distance in units of |direction|: {hit:?}"
    );
    assert!(matches!(hit.extra[0], Some(Element::Face { .. })));
    assert!(matches!(hit.extra[1], Some(Element::Cell { .. })));
    // A miss, and a bad ray.
    let miss = Ray {
        origin: vclay_core::Vec3::new(5.0, 5.0, 3.0),
        direction: vclay_core::Vec3::new(0.0, 0.0, -1.0),
    };
    assert!(s.pick(&miss, 0.01).is_none());
    let bad = Ray {
        origin: vclay_core::Vec3::zeros(),
        direction: vclay_core::Vec3::zeros(),
    };
    assert!(s.pick(&bad, 0.01).is_none());
}

#[test]
fn exports_write_every_format_the_kind_names() {
    let dir = tempfile::tempdir().unwrap();
    for make in [cube as fn() -> Box<dyn Model>, bspline] {
        let m = make();
        for ext in m.export_formats() {
            let p = dir.path().join(format!("m.{ext}"));
            m.export(&p).unwrap_or_else(|e| panic!("{ext}: {e}"));
            assert!(std::fs::metadata(&p).unwrap().len() > 0);
        }
        let e = m.export(&dir.path().join("m.xyz")).unwrap_err().to_string();
        assert!(e.contains("cannot be written as .xyz"), "{e}");
    }
}

/// STEP and IGES exports of solids are closed B-reps (issue 20): a B-spline solid's boundary,
/// or a subdivision solid's limit patches joined, as one manifold solid.
#[test]
fn solids_export_to_step_and_iges_as_closed_breps() {
    let dir = tempfile::tempdir().unwrap();
    for make in [cube as fn() -> Box<dyn Model>, bspline] {
        let m = make();
        let p = dir.path().join("m.step");
        m.export(&p).unwrap();
        let t = std::fs::read_to_string(&p).unwrap();
        assert_eq!(t.matches("=MANIFOLD_SOLID_BREP(").count(), 1);
        assert_eq!(t.matches("=CLOSED_SHELL(").count(), 1);
        assert!(!t.contains("OPEN_SHELL"));
        let p = dir.path().join("m.igs");
        m.export(&p).unwrap();
        let t = std::fs::read_to_string(&p).unwrap();
        // Each directory entry takes two lines, both starting with the entity type.
        let solid_lines = t
            .lines()
            .filter(|l| l.len() == 80 && &l[72..73] == "D" && l[..8].trim() == "186")
            .count();
        assert_eq!(solid_lines, 2);
    }
}

#[test]
fn a_model_at_rest_and_one_with_a_moving_rope_continue_exactly() {
    let mut s = Session::with_model("m", cube()).unwrap();
    common::check_continue(&mut s, 4, "plain");
    let mut s = warmed(cube(), 3);
    common::check_continue(&mut s, 1, "rope");
}

/// Any closed mesh opens as clay (issue 19): a `subdivision-solid` whose `file` is a mesh gets
/// a hexahedral lattice of about `cells` cells fitted to it, and sculpts like any solid.
#[test]
fn a_closed_mesh_opens_as_a_sculptable_solid() {
    let dir = tempfile::tempdir().unwrap();
    // A closed sphere mesh (a surface of revolution with its poles on the axis).
    let profile: Vec<(f64, f64)> = (0..=24)
        .map(|k| {
            let a = std::f64::consts::PI * k as f64 / 24.0;
            // Exact zeros at the poles, so the revolution closes them.
            (if k % 24 == 0 { 0.0 } else { a.sin() }, -a.cos())
        })
        .collect();
    let mesh = vclay_core::TriMesh::revolution(&profile, 32);
    let path = dir.path().join("ball.obj");
    vclay_io::mesh::write_mesh(&path, &mesh).unwrap();
    let model = solid_from_file(
        "kind = \"subdivision-solid\"\nfile = \"ball.obj\"\ncells = 300\nlevel = 1",
        dir.path(),
    )
    .unwrap_or_else(|e| panic!("{e:?}"));
    let cells = model.save().unwrap()["material"].as_array().unwrap().len();
    // Coarse voxel grids lose cells to the one-voxel-thick cleanup: between a third and all.
    assert!((100..=450).contains(&cells), "about 300 cells: {cells}");
    let mut s = Session::with_model("ball", model).unwrap();
    s.apply(Command::new(common::rope(
        None,
        [0.0, 0.0, 1.0],
        Some([0.0, 0.0, 1.5]),
        Some(0.05),
    )))
    .unwrap();
    let top = |s: &Session| common::top_z(&s.model(None).unwrap().data_points());
    let z0 = top(&s);
    s.run(60).unwrap();
    assert!(
        top(&s) > z0 + 0.01,
        "the rope pulled the top up: {z0} -> {}",
        top(&s)
    );
    // `cells` belongs to meshes only; an open mesh is a located error.
    let e = solid_from_file("kind = \"subdivision-solid\"\ncells = 60", dir.path()).unwrap_err();
    assert_eq!(e.key, "cells");
    let mut open = mesh.clone();
    open.triangles.truncate(open.triangles.len() - 3);
    vclay_io::mesh::write_mesh(&path, &open).unwrap();
    let e = solid_from_file(
        "kind = \"subdivision-solid\"\nfile = \"ball.obj\"",
        dir.path(),
    )
    .unwrap_err();
    assert_eq!(e.key, "file");
    assert!(e.what.contains("open"), "{}", e.what);
}

/// A subdivision solid built from `keys` (its `[model]` table) with files read beside `dir`.
fn solid_from_file(
    keys: &str,
    dir: &std::path::Path,
) -> Result<Box<dyn Model>, vclay_session::models::SpecError> {
    common::try_build(ModelKind::SubdivisionSolid, keys, None, None, dir)
}

/// Issue 31's grid numbering: a subdivided box of at least
/// `vclay_solids::model::GRID_NUMBERING_POINTS` data points (here level 4 of the 4^3 box) is
/// saved with `"numbering": "grid"`; the same model saved by an older build (no `numbering`,
/// data points and the rope's data point in the Cuthill-McKee numbering) loads into the grid
/// numbering and saves back as exactly the new file, so it continues as the new one does.
#[test]
fn a_large_box_saved_in_the_old_numbering_loads_into_the_grid_numbering() {
    use serde_json::Value;
    use vclay_solids::DataNumbering;
    let model = build(
        ModelKind::SubdivisionSolid,
        "kind = \"subdivision-solid\"\nprimitive = \"box\"\npoints = [4, 4, 4]\nlevel = 4",
        "dt = 0.001",
    );
    let mut s = warmed(model, 2);
    let new = saved(&s);
    assert_eq!(new["numbering"], "grid");
    // The file of an older build: the orders of both numberings from the same topology.
    let (source, p) = vclay_solids::benchmarks::subdivision_box(4, 4);
    let old_order = source
        .discretize_numbered(&p, Some(DataNumbering::Locality))
        .unwrap()
        .order;
    let grid_order = source.discretize(&p).unwrap().order;
    let mut grid_index = vec![0usize; grid_order.len()];
    for (i, &g) in grid_order.iter().enumerate() {
        grid_index[g as usize] = i;
    }
    // Old data point i is grid data point `to_grid[i]`.
    let to_grid: Vec<usize> = old_order.iter().map(|&g| grid_index[g as usize]).collect();
    let mut to_old = vec![0usize; to_grid.len()];
    for (i, &j) in to_grid.iter().enumerate() {
        to_old[j] = i;
    }
    let mut old = new.clone();
    old.as_object_mut().unwrap().remove("numbering");
    for (part, key) in [
        ("rest", "data_points"),
        ("rest", "physics_data_points"),
        ("state", "data_points"),
    ] {
        let a = new[part][key].as_array().unwrap();
        old[part][key] = Value::Array(to_grid.iter().map(|&j| a[j].clone()).collect());
    }
    let rope = &mut old["state"]["tools"][0];
    let j = rope["point"].as_u64().unwrap() as usize;
    rope["point"] = Value::from(to_old[j]);
    assert_ne!(old, new, "the old file differs");
    let kind = ModelKind::SubdivisionSolid;
    let loaded = vclay_session::models::load(kind, &old).unwrap();
    let mut s2 = Session::with_model("m", loaded).unwrap();
    assert_same(&saved(&s2), &new, "the old file loaded and saved again");
    s.run(2).unwrap();
    s2.run(2).unwrap();
    assert_same(&saved(&s2), &saved(&s), "continued");
    // An unknown numbering is an error that names it.
    let mut bad = new.clone();
    bad["numbering"] = Value::from("spiral");
    let e = vclay_session::models::load(kind, &bad)
        .unwrap_err()
        .to_string();
    assert!(e.contains("spiral"), "{e}");
}
