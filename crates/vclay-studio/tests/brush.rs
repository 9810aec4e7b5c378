//! Brushes on the simulation thread: a fix brush dragged across the cube fixes every control
//! point it passes and undoes as one action; a material brush paints the cells it passes.

use vclay_core::Vec3;
use vclay_session::{LineRole, Ray};
use vclay_studio::load::{builtin, builtin_named};
use vclay_studio::worker::{Grab, Request, Worker};

fn fixed_count(w: &Worker) -> usize {
    w.query(|s| {
        s.model(None)
            .unwrap()
            .display_lines()
            .into_iter()
            .find(|l| l.role == Some(LineRole::Fixed))
            .map_or(0, |l| l.points.len())
    })
    .unwrap()
}

fn down_at(x: f64, y: f64) -> Ray {
    Ray {
        origin: Vec3::new(x, y, 3.0),
        direction: Vec3::new(0.0, 0.0, -1.0),
    }
}

fn stroke(w: &Worker, grab: Grab, path: impl Iterator<Item = Vec3>) {
    w.send(Request::Grab {
        ray: down_at(0.01, 0.01),
        tolerance: 0.0,
        grab,
    });
    for to in path {
        w.send(Request::Drag { to });
        std::thread::sleep(std::time::Duration::from_millis(50));
    }
    w.send(Request::Drop);
}

#[test]
fn a_fix_brush_fixes_what_it_passes_and_undoes_as_one() {
    let session = builtin(builtin_named("cube").unwrap()).unwrap();
    let w = Worker::start(session, false);
    assert_eq!(fixed_count(&w), 0);
    // A brush of half-size 0.25 along the top edge y = 0, z = 1 of the unit cube whose control
    // points sit at thirds: it fixes (x, 0, 1) for x in {0, 1/3, 2/3, 1} and nothing else (the
    // next rows are 1/3 away).
    let path = (1..=10).map(|k| Vec3::new(0.1 * k as f64, 0.0, 1.0));
    stroke(&w, Grab::Fix { brush: 0.25 }, path);
    assert_eq!(fixed_count(&w), 4, "the top edge's points");
    let log_len = w.query(|s| s.log().len()).unwrap();
    assert!(log_len >= 2, "one command per stroke position: {log_len}");
    w.send(Request::Undo);
    assert_eq!(fixed_count(&w), 0, "one undo takes the whole stroke back");
    assert_eq!(w.query(|s| s.log().len()).unwrap(), 0);
}

#[test]
fn a_material_brush_paints_the_cells_it_passes() {
    let session = builtin(builtin_named("cube").unwrap()).unwrap();
    let w = Worker::start(session, false);
    let density = |w: &Worker| -> Vec<f64> {
        w.query(|s| {
            let v = s.model(None).unwrap().save().unwrap();
            v["material"]
                .as_array()
                .unwrap()
                .iter()
                .map(|m| m["density"].as_f64().unwrap())
                .collect()
        })
        .unwrap()
    };
    assert!(density(&w).iter().all(|&d| d == 1.0));
    // Along the top front edge: the cells whose centroids (at 1/6, 1/2, 5/6) lie within 0.2 of
    // y = 0.1, z = 0.9: the three cells of the top front row.
    let path = (0..=10).map(|k| Vec3::new(0.1 * k as f64, 0.1, 0.9));
    let grab = Grab::PaintMaterial {
        brush: 0.2,
        density: 5.0,
        damping: 2.0,
        edge_stiffness: 100.0,
    };
    stroke(&w, grab, path);
    let d = density(&w);
    assert_eq!(d.iter().filter(|&&x| x == 5.0).count(), 3, "{d:?}");
    w.send(Request::Undo);
    assert!(density(&w).iter().all(|&x| x == 1.0), "undo of the stroke");
}

/// The embedded mesh's vertex nearest `x`.
fn nearest_vertex(w: &Worker, x: Vec3) -> Vec3 {
    w.query(move |s| {
        let p = s.model(None).unwrap().data_points();
        *p.iter()
            .min_by(|a, b| (*a - x).norm().total_cmp(&(*b - x).norm()))
            .unwrap()
    })
    .unwrap()
}

#[test]
fn an_ffd_drag_with_a_pin_is_a_multi_point_move_that_keeps_the_pin() {
    let session = builtin(builtin_named("bottle").unwrap()).unwrap();
    let w = Worker::start(session, false);
    let pts = w.query(|s| s.model(None).unwrap().data_points()).unwrap();
    // A vertex of the bottle to drag (through a ray from outside towards the axis) and the
    // vertex farthest from it to pin.
    let a = pts[pts.len() / 3];
    let b = *pts
        .iter()
        .max_by(|p, q| (*p - a).norm().total_cmp(&(*q - a).norm()))
        .unwrap();
    let ray = Ray {
        origin: Vec3::new(a.x * 3.0, a.y * 3.0, a.z),
        direction: Vec3::new(-a.x, -a.y, 0.0),
    };
    let hit = w
        .query(move |s| s.pick(&ray, 0.0).map(|h| h.1.point))
        .unwrap()
        .expect("the ray hits the bottle");
    w.send(Request::Grab {
        ray,
        tolerance: 0.0,
        grab: Grab::FfdPoint { pins: vec![b] },
    });
    w.send(Request::Drag {
        to: hit + Vec3::new(0.0, 0.0, 0.2),
    });
    w.send(Request::Drop);
    let log = w
        .query(|s| {
            s.log()
                .iter()
                .map(|l| l.command.edit.clone())
                .collect::<Vec<_>>()
        })
        .unwrap();
    let moves = log
        .iter()
        .find_map(|e| match e {
            vclay_session::Edit::FfdMove { moves } => Some(moves.clone()),
            _ => None,
        })
        .unwrap_or_else(|| panic!("no ffd-move applied: {log:?}"));
    assert_eq!(moves.len(), 2, "the dragged point and the pin");
    assert_eq!(moves[1].from, moves[1].to, "the pin stays");
    // The pinned vertex did not move (eq 12 holds it exactly).
    let b_now = nearest_vertex(&w, b);
    assert!((b_now - b).norm() < 1e-9, "pin moved: {b:?} -> {b_now:?}");
    // Something did move.
    let moved = w.query(|s| s.model(None).unwrap().data_points()).unwrap();
    assert!(moved.iter().zip(&pts).any(|(p, q)| (p - q).norm() > 0.05));
}

#[test]
fn ctrl_click_sets_a_control_point_weight() {
    let session = builtin(builtin_named("bottle").unwrap()).unwrap();
    let w = Worker::start(session, false);
    let cp = w
        .query(|s| s.model(None).unwrap().control_points()[0])
        .unwrap();
    w.send(Request::Grab {
        ray: Ray {
            origin: cp + Vec3::new(0.0, 0.0, -5.0),
            direction: Vec3::new(0.0, 0.0, 1.0),
        },
        tolerance: 1e-3,
        grab: Grab::Weight { weight: 3.0 },
    });
    let log = w
        .query(|s| {
            s.log()
                .iter()
                .map(|l| l.command.edit.clone())
                .collect::<Vec<_>>()
        })
        .unwrap();
    assert!(
        matches!(
            log.as_slice(),
            [vclay_session::Edit::SetWeight { weight, .. }] if *weight == 3.0
        ),
        "{log:?}"
    );
}

#[test]
fn a_drag_on_a_pde_surface_adds_a_local_deformation_that_undo_removes() {
    let session = builtin(builtin_named("glass").unwrap()).unwrap();
    let w = Worker::start(session, false);
    let mesh = |w: &Worker| {
        w.query(|s| s.model(None).unwrap().display_mesh().unwrap().positions)
            .unwrap()
    };
    let before = mesh(&w);
    // A ray at a vertex of the glass along its normal, from outside.
    let (q, n) = w
        .query(|s| {
            let m = s.model(None).unwrap().display_mesh().unwrap();
            let k = m.positions.len() / 2 + 3;
            (m.positions[k], m.normals[k])
        })
        .unwrap();
    let ray = Ray {
        origin: q + n * 5.0,
        direction: -n,
    };
    let hit = w
        .query(move |s| s.pick(&ray, 0.0).map(|h| h.1.point))
        .unwrap()
        .expect("the ray hits the glass");
    w.send(Request::Grab {
        ray,
        tolerance: 0.0,
        grab: Grab::PdeLocal { half: [0.2, 0.6] },
    });
    w.send(Request::Drag { to: hit + n * 0.3 });
    w.send(Request::Drop);
    let log = w
        .query(|s| {
            s.log()
                .iter()
                .map(|l| l.command.edit.action())
                .collect::<Vec<_>>()
        })
        .unwrap();
    assert_eq!(log, ["pde-local"], "{:?}", w.notices());
    let after = mesh(&w);
    assert_ne!(after, before, "the surface moved");
    // The surface near the grabbed point moved along the drag (G1 bump peak = p / 256 at the
    // region's centre, the point grabbed).
    let target = hit + n * 0.3;
    let gap = |m: &[Vec3]| {
        m.iter()
            .map(|p| (p - target).norm())
            .fold(f64::INFINITY, f64::min)
    };
    assert!(
        gap(&after) < gap(&before) - 0.15,
        "the surface reached towards the cursor: {} -> {}",
        gap(&before),
        gap(&after)
    );
    w.send(Request::Undo);
    assert_eq!(mesh(&w), before, "undo removes it exactly");
}
