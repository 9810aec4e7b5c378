//! Issue 30, "Sessions" and "A sculpted round trip": OpenCASCADE's plate (a 40 x 30 x 8 box
//! with a hole of radius 6 and four filleted top edges, 11 trimmed faces, written by
//! bench/gen_trimmed_parts.py) opens as a `cad-part` whose top face is a D-NURBS surface; a
//! rope pulls the face up with its boundary fixed, and the part exported as STEP and as the
//! model JSON is still one closed shell of 11 faces whose shared edges meet, whose other faces
//! are unchanged and whose volume (vclay's own measure: the closed crack-free mesh) grew.
//! OpenCASCADE's judgement of the same flow is bench/check_sculpted.py (bench/check_step.sh).
use std::path::{Path, PathBuf};

use vclay_io::brep::Shell;
use vclay_io::model::{Entity, import_model};
use vclay_io::trimmed::sculpt::mesh_volume;
use vclay_io::trimmed::{TRIM_RTOL, tessellate_shell, validate_shell};
use vclay_session::models::part::PartModel;
use vclay_session::scenario::Scenario;
use vclay_session::{Model, ModelKind};
use vclay_spline::ParametricSurface;

/// The plate's volume: the box, less the hole (radius 6, height 8) and, along the 140 units of
/// filleted top edges, the corner `r^2 - pi r^2 / 4` of each fillet of radius 2.
const PLATE_VOLUME: f64 =
    40.0 * 30.0 * 8.0 - std::f64::consts::PI * 36.0 * 8.0 - (4.0 - std::f64::consts::PI) * 140.0;

fn plate() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../vclay-io/tests/data/cad/trimmed_plate.step")
}

/// The index of the plate's top face: the face with a hole whose surface lies at z = 8.
fn top_face(shell: &Shell) -> usize {
    (0..shell.faces.len())
        .find(|&i| {
            let f = &shell.faces[i];
            let d = f.surface.domain();
            let mid = f
                .surface
                .point(0.5 * (d[0].min + d[0].max), 0.5 * (d[1].min + d[1].max))
                .unwrap();
            f.holes.len() == 1 && (mid.z - 8.0).abs() < 1e-9
        })
        .expect("the plate has a top face with a hole")
}

/// The parameters of the top face's surface nearest the point (x, y, 8) (a plane: a grid
/// search refined twice is exact enough for a rope's attachment).
fn param_near(shell: &Shell, face: usize, x: f64, y: f64) -> [f64; 2] {
    let s = &shell.faces[face].surface;
    let d = s.domain();
    let mut best = ([0.0, 0.0], f64::INFINITY);
    for i in 0..=200 {
        for j in 0..=200 {
            let (u, v) = (
                d[0].min + d[0].length() * i as f64 / 200.0,
                d[1].min + d[1].length() * j as f64 / 200.0,
            );
            let p = s.point(u, v).unwrap();
            let e = (p.x - x).powi(2) + (p.y - y).powi(2);
            if e < best.1 {
                best = ([u, v], e);
            }
        }
    }
    best.0
}

/// A scenario that opens the plate with its top face sculpted and a rope that pulls the
/// point (8, 15, 8), between the hole and the outer edge, straight up at 5 length units per s.
fn scenario(extra_model_keys: &str) -> (String, usize, [f64; 2]) {
    let imp = import_model(plate()).unwrap();
    let top = top_face(&imp.shells[0]);
    let param = param_near(&imp.shells[0], top, 8.0, 15.0);
    let text = format!(
        "[model]\nkind = \"cad-part\"\nfile = {:?}\nface = {top}\n{extra_model_keys}\n\
         [simulation]\nsteps = 30\n\n\
         [[timeline]]\nat = 0.0\naction = \"rope\"\nname = \"pull\"\nparam = [{}, {}]\n\
         from = [8.0, 15.0, 8.0]\nvelocity = [0.0, 0.0, 20.0]\nstiffness = 200.0\n",
        plate().display().to_string(),
        param[0],
        param[1]
    );
    (text, top, param)
}

fn run(text: &str, steps: usize) -> Scenario {
    let mut sc = Scenario::parse(text, "plate.toml", "plate", Path::new(".")).unwrap();
    for _ in 0..steps {
        sc.session.step().unwrap();
    }
    sc
}

/// The volume of a closed shell by vclay's own measure (its crack-free mesh).
fn volume(shell: &Shell) -> f64 {
    mesh_volume(&tessellate_shell(shell, 48).unwrap())
}

#[test]
fn pulled_top_face_keeps_one_closed_solid() {
    let (text, top, _) = scenario("");
    let sc = run(&text, 30);
    let m = sc.session.model(None).unwrap();
    assert_eq!(m.kind(), ModelKind::CadPart);
    let part = PartModel::load(&m.save().unwrap()).unwrap();
    assert_eq!(part.face(), (0, top));
    assert!(!part.boundary().is_empty());
    // The face moved (the rope pulled it up) ...
    let before = import_model(plate()).unwrap();
    let s = part.surface().unwrap();
    let lift = s
        .control_points()
        .iter()
        .map(|p| p.z - 8.0)
        .fold(f64::NEG_INFINITY, f64::max);
    assert!(lift > 0.05, "the top face rose by {lift}");
    // ... but its edges did not: the boundary control points are fixed.
    let tol = part.tolerance();
    // The diagonal of the vertices' bounding box, 40 x 30 x 8.
    let size = (40.0f64 * 40.0 + 30.0 * 30.0 + 8.0 * 8.0).sqrt();
    assert!((tol - TRIM_RTOL * size).abs() < 1e-9 * tol, "{tol}");
    for g in part.gaps().unwrap() {
        assert!(g.moved <= tol && g.gap <= tol, "{g:?}");
    }
    let dir = tempfile::tempdir().unwrap();
    for ext in ["step", "json"] {
        let out = dir.path().join(format!("sculpted.{ext}"));
        m.export(&out).unwrap();
        let back = import_model(&out).unwrap_or_else(|e| panic!("{ext}: {e}"));
        assert_eq!(back.shells.len(), 1, "{ext}");
        let sh = &back.shells[0];
        validate_shell(sh).unwrap();
        assert!(sh.closed, "{ext}: one closed shell");
        assert_eq!(sh.faces.len(), 11, "{ext}");
        assert!(sh.edge_uses().iter().all(|&u| u == (1, 1)), "{ext}");
        // The untouched faces are the same surfaces (STEP: the written B-spline forms of
        // the same geometry, compared at points; JSON: bit for bit).
        let orig = &before.shells[0];
        let mut same = 0;
        for (i, f) in sh.faces.iter().enumerate() {
            let d = f.surface.domain();
            let o = orig.faces.iter().position(|g| {
                (0..=4).all(|a| {
                    (0..=4).all(|b| {
                        let (u, v) = (
                            d[0].min + d[0].length() * a as f64 / 4.0,
                            d[1].min + d[1].length() * b as f64 / 4.0,
                        );
                        g.surface
                            .point(u, v)
                            .is_ok_and(|q| (q - f.surface.point(u, v).unwrap()).norm() < 1e-9)
                    })
                })
            });
            if o.is_some() {
                same += 1;
            } else {
                // Only the sculpted face differs: its surface is the pulled one.
                let c = f.surface.control_points();
                assert!(
                    c.iter().any(|p| p.z > 8.0 + 0.05),
                    "{ext}: face {i} changed"
                );
            }
        }
        assert_eq!(same, 10, "{ext}: the 10 other faces are unchanged");
        if ext == "json" {
            let eb: Vec<_> = back.entities.iter().map(|e| &e.entity).collect();
            let changed = eb
                .iter()
                .zip(&before.entities)
                .filter(|(a, b)| **a != &b.entity)
                .count();
            assert_eq!(changed, 1, "only the sculpted face's entity differs");
            assert!(matches!(
                eb[sh.faces[top].entity.unwrap()],
                Entity::Surface(_)
            ));
        }
        // The solid grew: the face bulges outward.
        let (v0, v1) = (volume(&before.shells[0]), volume(sh));
        assert!((v0 - PLATE_VOLUME).abs() < 1e-2 * PLATE_VOLUME, "{v0}");
        assert!(v1 > v0 + 1e-3, "{ext}: volume {v0} -> {v1}");
    }
}

#[test]
fn a_freed_boundary_leaves_a_gap_that_export_reports() {
    let (text, _, _) = scenario("boundary = \"free\"\n");
    let sc = run(&text, 30);
    let m = sc.session.model(None).unwrap();
    let part = PartModel::load(&m.save().unwrap()).unwrap();
    assert!(part.boundary().is_empty());
    let worst = largest_gap(&part);
    assert!(worst > part.tolerance(), "gap {worst}");
    // The face's moved edges are recomputed from its pcurves on the new surface: the part's
    // edges then follow the sculpted face (at the 65 sample parameters, exactly), and differ
    // from the ones read.
    let (_, shells) = part.part().unwrap();
    let read = import_model(plate()).unwrap();
    let (_, face) = part.face();
    let moved: Vec<usize> = part
        .gaps()
        .unwrap()
        .into_iter()
        .filter(|g| g.moved > part.tolerance())
        .map(|g| g.edge)
        .collect();
    assert!(!moved.is_empty());
    for &e in &moved {
        assert_ne!(
            shells[0].edges[e].curve, read.shells[0].edges[e].curve,
            "edge {e}"
        );
    }
    let s = part.surface().unwrap();
    for g in vclay_io::trimmed::sculpt::face_edge_gaps(&shells[0], face, &s).unwrap() {
        assert!(g.moved < 1e-9 * 51.0, "{g:?}");
    }
    let dir = tempfile::tempdir().unwrap();
    let step = dir.path().join("open.step");
    let e = m.export(&step).unwrap_err().to_string();
    assert!(
        e.contains("not written") && e.contains("boundary moved") && e.contains("open.step"),
        "{e}"
    );
    assert!(!step.exists());
    assert!(m.summary().contains("no longer closed"), "{}", m.summary());
    // A mesh is still written.
    let obj = dir.path().join("open.obj");
    m.export(&obj).unwrap();
    assert!(std::fs::metadata(&obj).unwrap().len() > 0);
}

#[test]
fn session_file_continues_bit_for_bit() {
    let (text, _, _) = scenario("");
    let sc = run(&text, 5);
    let dir = tempfile::tempdir().unwrap();
    let file = dir.path().join("plate.session");
    vclay_session::file::save(&file, &sc.session, None).unwrap();
    let (mut loaded, _) = vclay_session::file::load(&file).unwrap();
    let mut original = sc.session;
    for _ in 0..5 {
        original.step().unwrap();
        loaded.step().unwrap();
    }
    let (a, b) = (original.model(None).unwrap(), loaded.model(None).unwrap());
    assert_eq!(b.kind(), ModelKind::CadPart);
    let bits = |m: &dyn Model| -> Vec<u64> {
        m.control_points()
            .iter()
            .flat_map(|p| [p.x, p.y, p.z])
            .map(f64::to_bits)
            .collect()
    };
    assert_eq!(bits(a), bits(b));
    assert_eq!(a.time().to_bits(), b.time().to_bits());
    // The exported parts are byte for byte the same.
    let (ja, jb) = (dir.path().join("a.json"), dir.path().join("b.json"));
    a.export(&ja).unwrap();
    b.export(&jb).unwrap();
    assert_eq!(std::fs::read(&ja).unwrap(), std::fs::read(&jb).unwrap());
}

#[test]
fn opening_a_step_part_gives_a_cad_part_with_surface_tools() {
    let o = vclay_session::open(&plate()).unwrap();
    let m = o.session.model(None).unwrap();
    assert_eq!(m.kind(), ModelKind::CadPart);
    let tools: Vec<&str> = m.tools().iter().map(|t| t.action).collect();
    for t in ["rope", "force", "fix", "free", "move-rope", "release"] {
        assert!(tools.contains(&t), "{t}: {tools:?}");
    }
    assert!(!tools.contains(&"inflate"));
    // The largest face is sculpted: the bottom, 40 x 30 less the hole.
    let part = PartModel::load(&m.save().unwrap()).unwrap();
    let imp = import_model(plate()).unwrap();
    let f = &imp.shells[0].faces[part.face().1];
    let d = f.surface.domain();
    let mid = f.surface.point(d[0].min, d[1].min).unwrap();
    assert!(
        f.holes.len() == 1 && mid.z.abs() < 1e-9,
        "face {:?}",
        part.face()
    );
    let mesh = m.display_mesh().unwrap();
    // The whole part is shown: a closed mesh whose volume is the plate's.
    let v = mesh_volume(&mesh);
    assert!((v - PLATE_VOLUME).abs() < 1e-2 * PLATE_VOLUME, "volume {v}");
}

#[test]
fn bad_part_keys_are_located() {
    let (text, top, _) = scenario("");
    for (bad, key) in [
        ("face = 99", "face"),
        ("refine = [3]", "refine"),
        ("refine = [4, 4]", "refine"),
        ("boundary = \"loose\"", "boundary"),
        ("shell = 2", "shell"),
        ("file = \"no_such.step\"", "file"),
    ] {
        let k = bad.split(' ').next().unwrap();
        let t: String = text
            .lines()
            .filter(|l| {
                !l.starts_with(&format!("{k} = ")) || *l == format!("face = {top}") && k != "face"
            })
            .map(|l| format!("{l}\n"))
            .collect::<String>()
            .replacen("[model]\n", &format!("[model]\n{bad}\n"), 1);
        let e = match Scenario::parse(&t, "plate.toml", "plate", Path::new(".")) {
            Ok(_) => panic!("{bad}: accepted"),
            Err(e) => e.to_string(),
        };
        assert!(e.contains(key), "{bad}: {e}");
    }
}

/// A ray straight down at the top face hits it between the hole and the outer edge, but a ray
/// through the hole's middle does not attach to the untrimmed surface there (issue 30: ropes
/// must not attach inside a hole).
#[test]
fn picks_inside_the_hole_are_refused() {
    let (text, _, _) = scenario("");
    let sc = Scenario::parse(&text, "plate.toml", "plate", Path::new(".")).unwrap();
    let m = sc.session.model(None).unwrap();
    let down = |x: f64, y: f64| vclay_session::Ray {
        origin: vclay_core::Vec3::new(x, y, 20.0),
        direction: vclay_core::Vec3::new(0.0, 0.0, -1.0),
    };
    let tol = 1e-3;
    let hit = m
        .pick(&down(8.0, 15.0), tol)
        .expect("the top face is there");
    assert!((hit.point.z - 8.0).abs() < 1e-6, "{:?}", hit.point);
    match m.pick(&down(20.0, 15.0), tol) {
        None => {}
        Some(h) => assert!(
            !matches!(h.element, vclay_session::Element::SurfacePoint { .. }),
            "a surface point inside the hole: {h:?}"
        ),
    }
}

/// A horizontal ray at height `z` from far in front (y < 0) towards +y at `x`: it meets the
/// plate's front side face first.
fn from_front(x: f64, z: f64) -> vclay_session::Ray {
    vclay_session::Ray {
        origin: vclay_core::Vec3::new(x, -50.0, z),
        direction: vclay_core::Vec3::new(0.0, 1.0, 0.0),
    }
}

/// Issue 30, "the designer picks one and sculpts it": a click on another face of the part
/// names that face (the pick), `sculpt-face` makes it the sculpted one while the face pulled
/// before keeps its new shape, the clock and the revision run on, a rope aimed at a face that
/// is not sculpted is refused, the part stays one closed solid, and undo brings the first face
/// back.
#[test]
fn a_clicked_face_becomes_the_sculpted_one_and_the_first_keeps_its_shape() {
    let (text, top, _) = scenario("");
    let mut sc = run(&text, 30);
    let (pulled, t0, steps0, rev0) = {
        let m = sc.session.model(None).unwrap();
        let part = PartModel::load(&m.save().unwrap()).unwrap();
        (part.surface().unwrap(), m.time(), m.steps(), m.revision())
    };
    // The pick from the front hits the front side face, not the top face.
    let side = {
        let m = sc.session.model(None).unwrap();
        let hit = m
            .pick(&from_front(20.0, 4.0), 1e-3)
            .expect("the front face");
        match hit.element {
            vclay_session::Element::Face { index } => index,
            e => panic!("expected a part face, got {e:?}"),
        }
    };
    assert_ne!(side, top);
    // A rope at the front face, given by position, is refused while the top face is sculpted.
    let rope = |from: [f64; 3]| vclay_session::Edit::Rope {
        name: Some("side".into()),
        from,
        param: None,
        to: None,
        until: None,
        velocity: Some([0.0, -10.0, 0.0]),
        release: None,
        stiffness: Some(200.0),
        length: None,
        kernel: None,
        start: None,
    };
    let err = sc
        .session
        .apply(vclay_session::Command::new(rope([20.0, 0.0, 4.0])))
        .unwrap_err()
        .to_string();
    assert!(err.contains(&format!("face {side}")), "{err}");
    // Choose the front face; the top face keeps its pulled surface exactly.
    sc.session
        .apply(vclay_session::Command::new(
            vclay_session::Edit::SculptFace {
                face: Some(side),
                near: None,
            },
        ))
        .unwrap();
    {
        let m = sc.session.model(None).unwrap();
        let part = PartModel::load(&m.save().unwrap()).unwrap();
        assert_eq!(part.face(), (0, side));
        let (entities, shells) = part.part().unwrap();
        let e = shells[0].faces[top].entity.unwrap();
        let Entity::Surface(s) = &entities[e].entity else {
            panic!("the top face's entity is a surface")
        };
        assert_eq!(s.control_points(), pulled.control_points());
        assert_eq!(m.time(), t0);
        assert_eq!(m.steps(), steps0);
        assert!(m.revision() > rev0);
    }
    // Now the rope at the front face attaches, and the front face moves out.
    sc.session
        .apply(vclay_session::Command::new(rope([20.0, 0.0, 4.0])))
        .unwrap();
    for _ in 0..20 {
        sc.session.step().unwrap();
    }
    {
        let m = sc.session.model(None).unwrap();
        let part = PartModel::load(&m.save().unwrap()).unwrap();
        assert!(m.time() > t0);
        let (_, shells) = part.part().unwrap();
        validate_shell(&shells[0]).unwrap();
        let gap = largest_gap(&part);
        assert!(gap <= part.tolerance(), "gap {gap}");
        let min_y = tessellate_shell(&shells[0], 32)
            .unwrap()
            .positions
            .iter()
            .map(|p| p.y)
            .fold(f64::INFINITY, f64::min);
        assert!(min_y < -1e-3, "the front face did not move out: {min_y}");
    }
    // Undo the rope, then the change of face: the top face is sculpted again, as it was.
    sc.session.undo().unwrap();
    sc.session.undo().unwrap();
    let m = sc.session.model(None).unwrap();
    let part = PartModel::load(&m.save().unwrap()).unwrap();
    assert_eq!(part.face(), (0, top));
    assert_eq!(
        part.surface().unwrap().control_points(),
        pulled.control_points()
    );
}

/// `sculpt-face` by `near` takes the nearest face; the part saved after a change of face
/// continues bit for bit, and the sculpted face is the one chosen.
#[test]
fn sculpt_face_near_a_point_and_the_session_file_continues() {
    let (text, top, _) = scenario("");
    let mut sc = run(&text, 5);
    sc.session
        .apply(vclay_session::Command::new(
            vclay_session::Edit::SculptFace {
                face: None,
                near: Some([20.0, -0.1, 4.0]),
            },
        ))
        .unwrap();
    let side = {
        let m = sc.session.model(None).unwrap();
        PartModel::load(&m.save().unwrap()).unwrap().face().1
    };
    assert_ne!(side, top);
    let again = sc
        .session
        .apply(vclay_session::Command::new(
            vclay_session::Edit::SculptFace {
                face: Some(side),
                near: None,
            },
        ))
        .unwrap_err()
        .to_string();
    assert!(again.contains("already"), "{again}");
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("part.session");
    vclay_session::file::save(&path, &sc.session, None).unwrap();
    let (mut back, _) = vclay_session::file::load(&path).unwrap();
    for _ in 0..3 {
        sc.session.step().unwrap();
        back.step().unwrap();
    }
    let a = sc.session.model(None).unwrap();
    let b = back.model(None).unwrap();
    assert_eq!(a.time(), b.time());
    assert_eq!(a.control_points(), b.control_points());
    assert_eq!(
        PartModel::load(&b.save().unwrap()).unwrap().face(),
        (0, side)
    );
}

/// The largest gap between the part's edges and its faces' pcurves on the surfaces now.
fn largest_gap(part: &PartModel) -> f64 {
    part.gaps()
        .unwrap()
        .iter()
        .map(|g| g.gap)
        .fold(0.0, f64::max)
}

/// Without `refine`, the holed top face is refined until at least half of its control points
/// are free with the boundary fixed (`part::AUTO_REFINE`); at the first density, 24 x 24, most
/// of them touch the outer edges or the hole. An explicit `refine` is taken as given.
#[test]
fn the_default_density_leaves_half_of_a_holed_face_free() {
    use vclay_session::models::part::{AUTO_REFINE, MIN_FREE_SHARE};
    let counts = |keys: &str| {
        let (text, _, _) = scenario(keys);
        let sc = run(&text, 0);
        let m = sc.session.model(None).unwrap();
        let part = PartModel::load(&m.save().unwrap()).unwrap();
        (m.control_points().len(), part.boundary().len())
    };
    let (n, fixed) = counts("");
    assert!(
        (n - fixed) as f64 >= MIN_FREE_SHARE * n as f64,
        "{fixed} of {n} fixed"
    );
    let (n24, fixed24) = counts("refine = [24, 24]");
    assert_eq!(n24, 24 * 24);
    assert!(
        ((n24 - fixed24) as f64) < MIN_FREE_SHARE * n24 as f64,
        "the first density would have done: {fixed24} of {n24} fixed"
    );
    assert!(
        n > n24 && n <= AUTO_REFINE[AUTO_REFINE.len() - 1].pow(2),
        "{n}"
    );
    eprintln!("default: {fixed} of {n} fixed; refine = [24, 24]: {fixed24} of {n24}");
}

/// The cut sphere (its body: quarter arcs joined at triple knots, the seam at u = 0 = 2 pi):
/// a rope at the front of the equator (u = 3 pi / 2, y = -10) pulls the clay out with the
/// boundary fixed, as one at the back (u = pi / 2) does. Before, the refinement for sculpting
/// filled its knot grid from u = 0 and left the last quarter one span wide, all of whose
/// control points touch the seam and were held: the front did not move at all.
#[test]
fn a_rope_pulls_the_sphere_wherever_it_grabs() {
    let file = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../vclay-io/tests/data/cad/trimmed_cut_sphere.step");
    let pull = |y: f64| {
        let text = format!(
            "[model]\nkind = \"cad-part\"\nfile = {:?}\n\n[simulation]\nsteps = 40\n\n\
             [[timeline]]\nat = 0.0\naction = \"rope\"\nname = \"pull\"\n\
             from = [0.0, {y}, 0.0]\nto = [0.0, {}, 0.0]\n",
            file.display().to_string(),
            1.3 * y
        );
        let mut sc = Scenario::parse(&text, "sphere.toml", "sphere", Path::new(".")).unwrap();
        let p0 = sc.session.model(None).unwrap().control_points();
        for _ in 0..40 {
            sc.session.step().unwrap();
        }
        let m = sc.session.model(None).unwrap();
        assert!(
            m.summary().contains("boundary control points fixed"),
            "{}",
            m.summary()
        );
        // How far the clay moved out along the pull (radius 10).
        m.control_points()
            .iter()
            .zip(&p0)
            .map(|(p, q)| (p.y - q.y) * y.signum())
            .fold(0.0, f64::max)
    };
    let (front, back) = (pull(-10.0), pull(10.0));
    eprintln!("the rope moved the front out by {front:.3}, the back by {back:.3}");
    assert!(front > 0.2, "the front moved by {front}");
    assert!(back > 0.2, "the back moved by {back}");
    assert!(
        (front - back).abs() < 0.5 * front.max(back),
        "front {front} and back {back} differ"
    );
}

/// The sculpted face runs on the frozen-weight engine unless the part asks for the generalized
/// one (a part's weights are held, so its matrices are constant and factored once): the two
/// give the same pull to 1e-3 of it, the frozen part offers no `constraint` (the generalized
/// one does, and takes one), and both take the studio's plastic flow and the smooth brush.
#[test]
fn the_face_runs_on_the_frozen_engine_unless_asked_and_both_sculpt_alike() {
    use vclay_session::{Command, Edit, Plasticity};
    let file = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../vclay-io/tests/data/cad/trimmed_cut_sphere.step");
    let part = |engine: &str| {
        let text = format!(
            "[model]\nkind = \"cad-part\"\nfile = {:?}\n{engine}\n[simulation]\nsteps = 30\n\n\
             [[timeline]]\nat = 0.0\naction = \"rope\"\nname = \"pull\"\n\
             from = [0.0, -10.0, 0.0]\nto = [0.0, -12.0, 0.0]\n",
            file.display().to_string()
        );
        Scenario::parse(&text, "sphere.toml", "sphere", Path::new(".")).unwrap()
    };
    let mut frozen = part("");
    let mut general = part("engine = \"generalized\"");
    let p0 = frozen.session.model(None).unwrap().control_points();
    for _ in 0..30 {
        frozen.session.step().unwrap();
        general.session.step().unwrap();
    }
    let (a, b) = (
        frozen.session.model(None).unwrap().control_points(),
        general.session.model(None).unwrap().control_points(),
    );
    let moved = a
        .iter()
        .zip(&p0)
        .map(|(p, q)| (p - q).norm())
        .fold(0.0, f64::max);
    let differ = a
        .iter()
        .zip(&b)
        .map(|(p, q)| (p - q).norm())
        .fold(0.0, f64::max);
    eprintln!("pulled by {moved:.4}; the engines differ by {differ:.2e}");
    assert!(moved > 0.5, "the pull moved the face by {moved}");
    assert!(
        differ < 1e-3 * moved.max(1.0),
        "the engines differ by {differ}"
    );
    let actions = |sc: &Scenario| -> Vec<&'static str> {
        let m = sc.session.model(None).unwrap();
        m.tools().iter().map(|t| t.action).collect()
    };
    assert!(
        !actions(&frozen).contains(&"constraint"),
        "{:?}",
        actions(&frozen)
    );
    assert!(actions(&general).contains(&"constraint"));
    for sc in [&mut frozen, &mut general] {
        assert!(actions(sc).contains(&"smooth"));
        // The studio's plastic flow: rest positions follow what the pull displaced.
        sc.session
            .set_plasticity(None, Some(Plasticity::new(20.0, 0.0).unwrap()))
            .unwrap();
        let rest0 = sc.session.model(None).unwrap().save().unwrap();
        sc.session.run(5).unwrap();
        let rest1 = sc.session.model(None).unwrap().save().unwrap();
        assert_ne!(rest0["dnurbs"], rest1["dnurbs"], "the flow changed nothing");
        sc.session
            .apply(Command::new(Edit::Smooth {
                near: [0.0, -10.5, 0.0],
                radius: 3.0,
                strength: Some(0.5),
            }))
            .unwrap();
    }
    let e = frozen
        .session
        .apply(Command::new(Edit::Constraint {
            name: None,
            kind: "point".into(),
            param: [4.0, 0.0],
            target: Some([0.0, -10.0, 0.0]),
            normal: None,
        }))
        .unwrap_err()
        .to_string();
    assert!(e.contains("constraint"), "{e}");
}
