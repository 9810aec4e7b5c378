//! The `ffd` model kind in a session (`ffd-direct-manipulation.txt` eqs 7 and 12): every edit
//! applies, undoes to the same bits and redoes to the same bits; steps then undo; a saved model
//! reloads and continues bit for bit; edits that cannot apply leave the model unchanged.

use std::path::Path;

use crate::common;
use common::{positions, round_trip, saved_text as saved};
use vclay_core::Vec3;
use vclay_session::command::V3;
use vclay_session::models;
use vclay_session::{Command, Edit, Element, Model, ModelKind, PointMove, Ray, Session};

fn build(model: &str, simulation: Option<&str>) -> Box<dyn Model> {
    common::build(ModelKind::Ffd, model, None, simulation)
}

fn build_err(model: &str) -> models::SpecError {
    common::try_build(ModelKind::Ffd, model, None, None, Path::new(".")).expect_err("must fail")
}

/// A small bottle in a 4 x 4 x 5 cubic lattice.
fn session() -> Session {
    let m = build(
        "kind = \"ffd\"\nname = \"b\"\nprimitive = \"bottle\"\ncontrol = [4, 4, 5]",
        Some("dt = 0.05"),
    );
    Session::with_model("b", m).unwrap()
}

/// An FFD move of each `(from, to)` pair (eq 7: the material point under `from` goes to `to`).
fn ffd_move(pairs: &[(Vec3, Vec3)]) -> Edit {
    let a = |v: &Vec3| -> V3 { [v.x, v.y, v.z] };
    Edit::FfdMove {
        moves: pairs
            .iter()
            .map(|(f, t)| PointMove {
                from: a(f),
                to: a(t),
            })
            .collect(),
    }
}

/// Applies `edit`, checks undo restores the state before and redo the state after, bit for
/// bit; leaves the edit applied.
#[test]
fn single_point_move_is_exact_and_undoes() {
    let mut s = session();
    let k = 200;
    let p = positions(&s)[k];
    let to = p + Vec3::new(0.3, -0.1, 0.2);
    round_trip(&mut s, ffd_move(&[(p, to)]));
    // Eq 7 moves the material point under `from` (mesh vertex k) exactly onto `to`.
    let x = positions(&s)[k];
    assert!((x - to).norm() < 1e-9, "vertex {k} at {x:?}, target {to:?}");
    // A second move starts from the deformed position.
    let to2 = to + Vec3::new(0.0, 0.2, 0.0);
    round_trip(&mut s, ffd_move(&[(to, to2)]));
    assert!((positions(&s)[k] - to2).norm() < 1e-9);
}

#[test]
fn multi_point_move_meets_every_target() {
    let mut s = session();
    let pos = positions(&s);
    let (i, j) = (100, 500);
    let ti = pos[i] + Vec3::new(0.2, 0.0, 0.0);
    let tj = pos[j] + Vec3::new(0.0, 0.0, 0.3);
    round_trip(&mut s, ffd_move(&[(pos[i], ti), (pos[j], tj)]));
    let now = positions(&s);
    assert!((now[i] - ti).norm() < 1e-9);
    assert!((now[j] - tj).norm() < 1e-9);
}

#[test]
fn conflicting_moves_fail_unchanged_until_least_squares() {
    let mut s = session();
    let p = positions(&s)[300];
    let conflicting = ffd_move(&[
        (p, p + Vec3::new(0.1, 0.0, 0.0)),
        (p, p - Vec3::new(0.1, 0.0, 0.0)),
    ]);
    let before = saved(&s);
    let e = s.apply(Command::new(conflicting.clone())).unwrap_err();
    assert!(e.to_string().contains("least_squares"), "{e}");
    assert_eq!(saved(&s), before);
    assert!(!s.can_undo());
    round_trip(&mut s, common::set("least_squares", 1.0));
    round_trip(&mut s, conflicting);
    // The least-squares compromise of two opposite targets keeps the point in place.
    assert!((positions(&s)[300] - p).norm() < 1e-9);
}

#[test]
fn lattice_edits_undo_and_redo() {
    let mut s = session();
    let cp = s.model(None).unwrap().display_lines()[0].points[20];
    round_trip(
        &mut s,
        Edit::MovePoint {
            index: 20,
            to: (cp + Vec3::new(0.1, 0.2, -0.1)).into(),
        },
    );
    round_trip(
        &mut s,
        Edit::SetWeight {
            index: 21,
            weight: 3.0,
        },
    );
    // A move on the now rational lattice.
    let p = positions(&s)[250];
    round_trip(&mut s, ffd_move(&[(p, p + Vec3::new(0.0, 0.1, 0.1))]));
    round_trip(&mut s, common::set("dt", 0.01));
    assert_eq!(s.model(None).unwrap().dt(), 0.01);
}

#[test]
fn edits_that_cannot_apply_leave_the_model_unchanged() {
    let mut s = session();
    let before = (saved(&s), positions(&s));
    let bad = [
        Edit::Fix(vclay_session::Selection::ids(vec![0])),
        common::rope(None, [0.0; 3], None, None),
        common::pde_set("a", 1.0),
        Edit::MovePoint {
            index: 10_000,
            to: [0.0; 3],
        },
        Edit::SetWeight {
            index: 10_000,
            weight: 1.0,
        },
        common::set("stiffness", 1.0),
        common::set("least_squares", 0.5),
        // Far outside the lattice.
        ffd_move(&[(Vec3::new(50.0, 0.0, 0.0), Vec3::new(51.0, 0.0, 0.0))]),
    ];
    for edit in bad {
        let e = s.apply(Command::new(edit.clone())).unwrap_err();
        let msg = e.to_string();
        assert!(msg.contains(edit.action()), "{msg}");
        if matches!(edit, Edit::Rope { .. } | Edit::PdeSet { .. }) {
            assert!(msg.contains("ffd"), "{msg}");
        }
        assert_eq!((saved(&s), positions(&s)), before, "{edit:?}");
    }
    assert!(!s.can_undo());
}

#[test]
fn steps_advance_the_clock_only_and_undo_restores_it() {
    let mut s = session();
    let p = positions(&s)[50];
    let edit = ffd_move(&[(p, p + Vec3::new(0.0, 0.0, 0.25))]);
    let (at_edit, stepped) = common::steps_then_undo(&mut s, edit, 5, 0.05);
    assert_eq!(stepped, at_edit, "steps change nothing but the clock");
}

#[test]
fn saved_model_continues_bit_for_bit() {
    let mut s = session();
    let p = positions(&s)[120];
    s.apply(Command::new(Edit::SetWeight {
        index: 30,
        weight: 0.5,
    }))
    .unwrap();
    s.apply(Command::new(ffd_move(&[(
        p,
        p + Vec3::new(0.15, 0.1, 0.0),
    )])))
    .unwrap();
    s.run(3).unwrap();
    let mut t = common::reloaded(&s, "b");
    s.run(4).unwrap();
    t.run(4).unwrap();
    let q = positions(&s)[400];
    for x in [&mut s, &mut t] {
        x.apply(Command::new(ffd_move(&[(q, q - Vec3::new(0.1, 0.0, 0.1))])))
            .unwrap();
    }
    assert_eq!(saved(&t), saved(&s));
    assert_eq!(positions(&t), positions(&s));
}

#[test]
fn pick_finds_mesh_vertices_and_control_points() {
    let s = session();
    let m = s.model(None).unwrap();
    // The bottle's axis is z; a ray along -x at mid-body height hits the body at x = 1.
    let hit = common::pick_along_minus_x(&s, [5.0, 0.0, 1.0]);
    let Element::MeshVertex { index } = hit.element else {
        panic!("{hit:?}")
    };
    assert!((positions(&s)[index] - hit.point).norm() < 0.3);
    assert!((hit.point.x - 1.0).abs() < 0.05, "{hit:?}");
    // A ray through a lattice corner.
    let corner = m.display_lines()[0].points[0];
    let ray = Ray {
        origin: corner + Vec3::new(0.0, 0.0, -5.0),
        direction: Vec3::new(0.0, 0.0, 1.0),
    };
    let hit = m.pick(&ray, 1e-6).expect("hits the corner");
    assert_eq!(hit.element, Element::ControlPoint { index: 0 });
}

#[test]
fn spec_keys_are_validated() {
    for prim in ["bottle", "sphere", "box"] {
        let m = build(
            &format!("primitive = \"{prim}\"\ndegree = 2\ncontrol = 3\nmode = \"least-squares\""),
            None,
        );
        assert!(m.summary().contains(prim), "{}", m.summary());
        assert_eq!(m.params()[1].value, 1.0);
        assert_eq!(m.dt(), 1.0 / 30.0);
    }
    let m = build(
        "primitive = \"box\"\nmin = [-2, -2, -2]\nmax = [2, 2, 2]",
        None,
    );
    assert!((m.size() - 4.0 * 3f64.sqrt()).abs() < 1e-12);
    for (text, key) in [
        ("control = 65", "control"),
        ("control = [60, 60, 60]", "control"),
        ("control = 3", "control"),
        ("degree = 0", "degree"),
        ("primitive = \"teapot\"", "primitive"),
        ("mode = \"fast\"", "mode"),
        ("margin = -1.0", "margin"),
        ("min = [0, 0, 0]", "min"),
        ("mesh = \"nowhere.obj\"", "mesh"),
        ("colour = 3", "colour"),
    ] {
        let e = build_err(text);
        assert_eq!(e.key, key, "{text}: {e:?}");
    }
}

#[test]
fn exports_meshes_and_the_lattice() {
    let s = session();
    let m = s.model(None).unwrap();
    let dir = tempfile::tempdir().unwrap();
    common::export_each(&s, dir.path(), "b", &["obj", "ply", "stl", "glb", "json"]);
    let lattice = vclay_io::read_model(dir.path().join("b.json")).unwrap();
    assert_eq!(lattice.len(), 1);
    let e = m.export(&dir.path().join("b.vtu")).unwrap_err();
    assert!(e.to_string().contains(".obj"), "{e}");
}
