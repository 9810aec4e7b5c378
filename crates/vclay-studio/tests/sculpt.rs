//! The sculpting habits of issue 27 (a designer used to Blender's sculpt mode and SculptGL),
//! each driven through the UI (egui_kittest) or the simulation thread: a scenario's run stops at
//! its end step and says so; shortcuts pick tools, resize the brush, toggle symmetry, run and
//! frame, and stay out of text fields; F1 shows every shortcut; the brush circle follows the
//! mouse over the model; a force stroke acts along the drag and undoes as one; symmetry mirrors
//! a fix stroke and a rope in one undo group; control-point handles light up under the mouse.

use std::path::Path;
use std::time::Duration;

use egui::accesskit::Role;
use egui::{Key, Modifiers, Pos2, Vec2};
use egui_kittest::Harness;
use egui_kittest::kittest::Queryable;
use vclay_core::Vec3;
use vclay_session::{Edit, LineRole, Ray};
use vclay_studio::load::{builtin, builtin_named};
use vclay_studio::symmetry::Symmetry;
use vclay_studio::worker::{Flow, Grab, Request, Worker};
use vclay_studio::{Options, Studio, Tool};

use crate::common;
use common::{click, harness, paused, quiet, wait_for};

/// The paused cube from the start page.
fn paused_cube(dir: &Path) -> Harness<'static, Studio> {
    let mut h = harness(paused(dir));
    click(
        &mut h,
        Role::Button,
        "4^3 subdivision cube (rope, extrude, delete cell)",
    );
    wait_for(&mut h, 30, "first frame", |s| !s.frame().models.is_empty());
    h.step();
    h
}

fn key(h: &mut Harness<'static, Studio>, k: Key) {
    h.key_press(k);
    h.step();
}

fn edits(s: &Studio) -> Vec<Edit> {
    s.worker()
        .unwrap()
        .query(|s| s.log().iter().map(|l| l.command.edit.clone()).collect())
        .unwrap()
}

/// The viewport point `(fx, fy)` of the way across (0.5, 0.5: the centre).
fn at(s: &Studio, fx: f32, fy: f32) -> Pos2 {
    let r = s.viewport();
    r.min + Vec2::new(r.width() * fx, r.height() * fy)
}

#[test]
fn a_scenario_stops_at_its_end_step_and_says_so() {
    // fig9a's rope pulls the egg's pole up forever; the scenario ends at step 400.
    let dir = tempfile::tempdir().unwrap();
    let file =
        Path::new(env!("CARGO_MANIFEST_DIR")).join("../../examples/scenarios/fig9a_swung_egg.toml");
    let mut h = harness(Options {
        file: Some(file),
        ..quiet(dir.path())
    });
    wait_for(&mut h, 30, "first frame", |s| !s.frame().models.is_empty());
    click(&mut h, Role::Button, "max");
    wait_for(&mut h, 300, "the run stops", |s| {
        !s.frame().running && s.frame().steps > 0
    });
    assert_eq!(h.state().frame().steps, 400);
    let note = h.state().note().unwrap_or_default().to_string();
    assert!(
        note.starts_with("scenario finished at step 400 (t = ")
            && note.contains("Run continues past it"),
        "{note}"
    );
    std::thread::sleep(Duration::from_millis(200));
    h.step();
    assert_eq!(h.state().frame().steps, 400, "it stays stopped");
    // A save keeps the scenario's run (name, end step, outputs): `vclay run` and Recover go on
    // to the same end.
    let saved = dir.path().join("egg.session");
    h.state()
        .worker()
        .unwrap()
        .send(Request::Save(saved.clone()));
    wait_for(&mut h, 30, "the save", |_| saved.exists());
    let (_, run) = vclay_session::file::load(&saved).unwrap();
    let run = run.expect("the saved run information");
    assert_eq!((run.name.as_str(), run.end_step), ("fig9a_swung_egg", 400));
    // A pull after the end runs the clay again (the scenario paused it, not the designer).
    let w = h.state().worker().unwrap();
    w.send(Request::Grab {
        ray: Ray {
            origin: Vec3::new(0.0, 0.0, 10.0),
            direction: Vec3::new(0.0, 0.0, -1.0),
        },
        tolerance: 0.0,
        grab: Grab::Rope { stiffness: None },
    });
    w.send(Request::Drop);
    wait_for(&mut h, 60, "running past the end", |s| {
        s.frame().steps > 410
    });
    // Space pauses it as ever.
    key(&mut h, Key::Space);
    wait_for(&mut h, 30, "paused", |s| !s.frame().running);
}

#[test]
fn shortcuts_pick_tools_size_the_brush_toggle_symmetry_run_and_frame() {
    let dir = tempfile::tempdir().unwrap();
    let mut h = paused_cube(dir.path());
    key(&mut h, Key::G);
    assert_eq!(h.state().tool, Tool::Force);
    let r0 = h.state().options.radius;
    key(&mut h, Key::CloseBracket);
    assert!((h.state().options.radius - r0 * 1.25).abs() < 1e-12);
    key(&mut h, Key::OpenBracket);
    assert!((h.state().options.radius - r0).abs() < 1e-12);
    key(&mut h, Key::H);
    assert_eq!(h.state().tool, Tool::Fix);
    key(&mut h, Key::R);
    assert_eq!(h.state().tool, Tool::Rope);
    // Not offered by the cube: the key does nothing.
    key(&mut h, Key::M);
    assert_eq!(h.state().tool, Tool::Rope);
    key(&mut h, Key::X);
    key(&mut h, Key::Z);
    assert_eq!(h.state().symmetry, Symmetry([true, false, true]));
    key(&mut h, Key::Z);
    assert_eq!(h.state().symmetry, Symmetry([true, false, false]));
    key(&mut h, Key::Space);
    wait_for(&mut h, 20, "running", |s| s.frame().running);
    key(&mut h, Key::Space);
    wait_for(&mut h, 20, "paused", |s| !s.frame().running);
    // F frames the model again after a zoom.
    let framed = h.state().camera.clone();
    h.state_mut().camera.distance *= 3.0;
    h.state_mut().camera.target += Vec3::new(1.0, 0.0, 0.0);
    key(&mut h, Key::F);
    let c = &h.state().camera;
    assert!((c.distance - framed.distance).abs() < 1e-3 * framed.distance);
    assert!((c.target - framed.target).norm() < 1e-3);
    // In a text field the letters are text, not tools.
    click(&mut h, Role::Button, "File");
    click(&mut h, Role::Button, "Screenshot...");
    h.get_by_role(Role::TextInput).type_text("g");
    h.step();
    key(&mut h, Key::G);
    key(&mut h, Key::X);
    assert_eq!(h.state().tool, Tool::Rope);
    assert_eq!(h.state().symmetry, Symmetry([true, false, false]));
    assert_eq!(h.state().dialog_title(), Some("Screenshot (PNG)"));
    h.key_press(Key::Escape);
    h.step();
    assert_eq!(h.state().dialog_title(), None);
}

#[test]
fn f1_shows_every_shortcut_and_esc_closes_it() {
    let dir = tempfile::tempdir().unwrap();
    let mut h = paused_cube(dir.path());
    key(&mut h, Key::F1);
    assert_eq!(h.state().dialog_title(), Some("Help"));
    h.step();
    for (_, what) in vclay_studio::keys::SHORTCUTS {
        assert!(
            h.query_by_label(what).is_some(),
            "{what} is not in the help"
        );
    }
    for t in Tool::ALL {
        let l = format!("{} tool", t.label());
        assert!(h.query_by_label(&l).is_some(), "{l} is not in the help");
    }
    // Keys are the dialog's while it is open.
    key(&mut h, Key::G);
    assert_eq!(h.state().tool, Tool::Rope);
    key(&mut h, Key::Escape);
    assert_eq!(h.state().dialog_title(), None);
    key(&mut h, Key::Questionmark);
    assert_eq!(h.state().dialog_title(), Some("Help"));
}

#[test]
fn the_brush_circle_follows_the_mouse_over_the_model() {
    let dir = tempfile::tempdir().unwrap();
    let mut h = paused_cube(dir.path());
    key(&mut h, Key::G);
    let c = at(h.state(), 0.5, 0.5);
    h.hover_at(c);
    h.step();
    let b = h
        .state()
        .brush_cursor()
        .expect("a brush circle over the cube");
    let s = h.state();
    let r = s.viewport();
    let ray = s.camera.ray(
        (c.x - r.min.x) as f64,
        (c.y - r.min.y) as f64,
        r.width() as f64,
        r.height() as f64,
    );
    let hit = s
        .worker()
        .unwrap()
        .query(move |s| s.pick(&ray, 0.0).map(|h| h.1.point))
        .unwrap()
        .unwrap();
    assert!((b.centre - hit).norm() < 1e-2, "{b:?} vs {hit:?}");
    let size = s.frame().models[0].size;
    assert!((b.radius - s.options.radius * size).abs() < 1e-12);
    assert!((b.normal.norm() - 1.0).abs() < 1e-9);
    // It moves with the mouse, and it is gone off the model.
    h.hover_at(c + Vec2::new(20.0, 10.0));
    h.step();
    let moved = h.state().brush_cursor().unwrap();
    assert!((moved.centre - b.centre).norm() > 1e-3);
    h.hover_at(at(h.state(), 0.02, 0.05));
    h.step();
    assert_eq!(h.state().brush_cursor(), None);
    // ] grows it.
    h.hover_at(c);
    h.step();
    key(&mut h, Key::CloseBracket);
    let grown = h.state().brush_cursor().unwrap();
    assert!((grown.radius - 1.25 * b.radius).abs() < 1e-9);
}

#[test]
fn a_force_stroke_acts_along_the_drag_and_undoes_as_one() {
    let dir = tempfile::tempdir().unwrap();
    let mut h = paused_cube(dir.path());
    key(&mut h, Key::G);
    let (a, b) = (at(h.state(), 0.42, 0.5), at(h.state(), 0.58, 0.5));
    h.hover_at(a);
    h.drag_at(a);
    h.step();
    for k in 1..=16 {
        h.hover_at(a + (b - a) * (k as f32 / 16.0));
        h.step();
        std::thread::sleep(Duration::from_millis(50));
    }
    h.drop_at(b);
    h.step();
    std::thread::sleep(Duration::from_millis(100));
    let log = edits(h.state());
    let centres: Vec<[f64; 3]> = log
        .iter()
        .filter_map(|e| match e {
            Edit::RegionForce { center, .. } => Some(*center),
            _ => None,
        })
        .collect();
    // The brush's default profile (smooth, from the model's tool description).
    assert!(
        log.iter()
            .all(|e| !matches!(e, Edit::RegionForce { falloff, .. }
            if falloff.as_deref() != Some("smooth"))),
        "{log:?}"
    );
    // The forces, then (sculpt mode, the default) the stop and plastic reset that keep the
    // shape the stroke made.
    assert_eq!(centres.len() + 2, log.len(), "only forces: {log:?}");
    assert!(
        matches!(log[log.len() - 2..], [Edit::Stop, Edit::PlasticReset]),
        "{log:?}"
    );
    assert!(
        centres.len() >= 3,
        "the brush acts along the stroke: {log:?}"
    );
    // Spaced by half the radius at least, so a stroke of a few radii is a few commands.
    let r = h.state().options.radius * h.state().frame().models[0].size;
    for w in centres.windows(2) {
        let d = Vec3::from(w[1]) - Vec3::from(w[0]);
        assert!(d.norm() >= 0.5 * r - 1e-9, "{centres:?}");
    }
    h.key_press_modifiers(Modifiers::COMMAND, Key::Z);
    h.step();
    wait_for(&mut h, 20, "one undo", |s| edits(s).is_empty());
}

fn fixed(w: &Worker) -> Vec<Vec3> {
    w.query(|s| {
        s.model(None)
            .unwrap()
            .display_lines()
            .into_iter()
            .find(|l| l.role == Some(LineRole::Fixed))
            .map_or(Vec::new(), |l| l.points)
    })
    .unwrap()
}

fn down_at(x: f64, y: f64) -> Ray {
    Ray {
        origin: Vec3::new(x, y, 3.0),
        direction: Vec3::new(0.0, 0.0, -1.0),
    }
}

#[test]
fn symmetry_mirrors_a_fix_stroke_and_a_rope_in_one_undo_group() {
    let session = builtin(builtin_named("cube").unwrap()).unwrap();
    let w = Worker::start(session, false);
    w.send(Request::Symmetry(Symmetry([true, false, false])));
    // A fix brush at the top face's corner (0, 0, 1): the mirror across x = 1/2 fixes (1, 0, 1).
    w.send(Request::Grab {
        ray: down_at(0.05, 0.05),
        tolerance: 0.0,
        grab: Grab::Fix { brush: 0.1 },
    });
    w.send(Request::Drop);
    let f = fixed(&w);
    assert_eq!(f.len(), 2, "{f:?}");
    for want in [Vec3::new(0.0, 0.0, 1.0), Vec3::new(1.0, 0.0, 1.0)] {
        assert!(
            f.iter().any(|p| (p - want).norm() < 1e-6),
            "{want:?} in {f:?}"
        );
    }
    w.send(Request::Undo);
    assert!(fixed(&w).is_empty(), "one undo takes both back");
    // A rope: two ropes, the mirror's cursor mirrored, released together.
    w.send(Request::Grab {
        ray: down_at(0.2, 0.5),
        tolerance: 0.0,
        grab: Grab::Rope { stiffness: None },
    });
    w.send(Request::Drag {
        to: Vec3::new(0.1, 0.5, 1.5),
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
    let ropes: Vec<(String, [f64; 3])> = log
        .iter()
        .filter_map(|e| match e {
            Edit::MoveRope { name, to } => Some((name.clone(), *to)),
            _ => None,
        })
        .collect();
    assert_eq!(ropes.len(), 2, "{log:?}");
    assert!(
        (ropes[0].1[0] - 0.1).abs() < 1e-9 && (ropes[1].1[0] - 0.9).abs() < 1e-9,
        "{ropes:?}"
    );
    assert_ne!(ropes[0].0, ropes[1].0);
    let releases = log
        .iter()
        .filter(|e| matches!(e, Edit::Release { .. }))
        .count();
    assert_eq!(releases, 2, "{log:?}");
    w.send(Request::Undo);
    assert_eq!(w.query(|s| s.log().len()).unwrap(), 0);
}

#[test]
fn a_control_point_handle_lights_up_under_the_mouse() {
    let dir = tempfile::tempdir().unwrap();
    let mut h = harness(paused(dir.path()));
    click(
        &mut h,
        Role::Button,
        "Swung D-NURBS egg (Egg sculpting material)",
    );
    wait_for(&mut h, 30, "first frame", |s| !s.frame().models.is_empty());
    h.step();
    assert_eq!(h.state().hovered_handle(), None);
    key(&mut h, Key::N); // the control net (and its handles)
    wait_for(&mut h, 20, "the control net", |s| {
        s.frame().models[0]
            .lines
            .iter()
            .any(|l| l.role == Some(LineRole::ControlNet))
    });
    let s = h.state();
    let r = s.viewport();
    // The control point nearest the viewer, where the mouse goes.
    let cp = s.frame().models[0]
        .lines
        .iter()
        .filter(|l| l.role == Some(LineRole::ControlNet))
        .flat_map(|l| l.points.clone())
        .max_by(|a, b| a.dot(&s.camera.back()).total_cmp(&b.dot(&s.camera.back())))
        .unwrap();
    let (x, y) = s
        .camera
        .project(cp, r.width() as f64, r.height() as f64)
        .unwrap();
    h.hover_at(r.min + Vec2::new(x as f32, y as f32 + 2.0));
    h.step();
    let got = h
        .state()
        .hovered_handle()
        .expect("a handle under the mouse");
    assert!((got - cp).norm() < 0.2, "{got:?} vs {cp:?}");
    h.hover_at(at(h.state(), 0.02, 0.05));
    h.step();
    assert_eq!(h.state().hovered_handle(), None);
}

/// The top of the 4^3 cube after a rope pull with the bottom fixed, `settle` steps after the
/// release, in sculpt mode or not.
fn top_after_pull(sculpt: bool, settle: u64) -> f64 {
    top_after_flow_pull(sculpt, None, settle)
}

/// [`top_after_pull`] with sculpt mode's plastic flow.
fn top_after_flow_pull(sculpt: bool, flow: Option<Flow>, settle: u64) -> f64 {
    let session = builtin(builtin_named("cube").unwrap()).unwrap();
    let w = Worker::start(session, false);
    w.send(Request::Apply(vclay_session::Command::new(Edit::Fix(
        vclay_session::Selection::rest_box([-0.1, -0.1, -0.1], [1.1, 1.1, 0.01]),
    ))));
    w.send(Request::Sculpt(sculpt));
    w.send(Request::Flow(flow));
    w.send(Request::Grab {
        ray: down_at(0.5, 0.5),
        tolerance: 0.0,
        grab: Grab::Rope { stiffness: None },
    });
    w.send(Request::Drag {
        to: Vec3::new(0.5, 0.5, 1.8),
    });
    // The worker applies a drag's cursor at most every DRAG_INTERVAL.
    std::thread::sleep(Duration::from_millis(150));
    w.send(Request::Step(400));
    w.send(Request::Drop);
    w.send(Request::Step(settle));
    w.query(|s| {
        s.model(None)
            .unwrap()
            .data_points()
            .iter()
            .map(|p| p.z)
            .fold(f64::MIN, f64::max)
    })
    .unwrap()
}

#[test]
fn in_sculpt_mode_what_is_pulled_stays() {
    // Pulled up from z = 1 and released: sculpted clay keeps its height, elastic clay (the
    // papers' mode) springs back down.
    let kept = top_after_pull(true, 600);
    let elastic = top_after_pull(false, 600);
    let at_release = top_after_pull(true, 0);
    assert!(at_release > 1.05, "the pull raised the top: {at_release}");
    assert!(
        (kept - at_release).abs() < 0.1 * (at_release - 1.0),
        "sculpt keeps the shape: {kept} after, {at_release} at the release"
    );
    assert!(
        elastic - 1.0 < 0.5 * (kept - 1.0),
        "elastic springs back: {elastic} (sculpt {kept})"
    );
}

#[test]
fn plastic_flow_keeps_what_yields_and_springs_back_the_elastic_part() {
    // Sculpt mode with plastic flow: the rest shape follows the pull while it lasts, so after
    // the release the top stays up by what yielded; a slow flow keeps less than a fast one, and
    // both keep more than elastic clay. A large yield distance keeps nothing.
    let fast = top_after_flow_pull(
        true,
        Some(Flow {
            rate: 50.0,
            yield_fraction: 0.0,
        }),
        600,
    );
    let slow = top_after_flow_pull(
        true,
        Some(Flow {
            rate: 0.5,
            yield_fraction: 0.0,
        }),
        600,
    );
    let stiff = top_after_flow_pull(
        true,
        Some(Flow {
            rate: 50.0,
            yield_fraction: 1.0,
        }),
        600,
    );
    let elastic = top_after_pull(false, 600);
    assert!(fast > 1.1, "a fast flow keeps the pull: {fast}");
    assert!(
        slow - 1.0 < 0.8 * (fast - 1.0) && slow > elastic,
        "a slow flow keeps less: slow {slow}, fast {fast}, elastic {elastic}"
    );
    assert!(
        (stiff - elastic).abs() < 0.02,
        "below the yield the clay is elastic: {stiff} vs {elastic}"
    );
}

/// Lowest and highest data point of the free 4^3 cube (nothing fixed) after a rope pull up from
/// its top, at the release.
fn free_cube_pull(sculpt: bool) -> (f64, f64) {
    let session = builtin(builtin_named("cube").unwrap()).unwrap();
    let w = Worker::start(session, false);
    w.send(Request::Sculpt(sculpt));
    w.send(Request::Grab {
        ray: down_at(0.5, 0.5),
        tolerance: 0.0,
        grab: Grab::Rope { stiffness: None },
    });
    w.send(Request::Drag {
        to: Vec3::new(0.5, 0.5, 1.8),
    });
    std::thread::sleep(Duration::from_millis(150));
    w.send(Request::Step(400));
    w.send(Request::Drop);
    let z = w
        .query(|s| {
            s.model(None)
                .unwrap()
                .data_points()
                .iter()
                .map(|p| p.z)
                .collect::<Vec<_>>()
        })
        .unwrap();
    let fixed_after = fixed(&w).len();
    assert_eq!(fixed_after, 0, "the anchor is freed at the release");
    (
        z.iter().copied().fold(f64::MAX, f64::min),
        z.iter().copied().fold(f64::MIN, f64::max),
    )
}

#[test]
fn sculpt_mode_anchors_a_free_solid_so_a_pull_deforms_it() {
    // The elastic clay of the papers: a rope on a free cube lifts it whole. Sculpt mode holds
    // the control points far from the grab for the pull, so the top rises and the bottom stays.
    let (low, high) = free_cube_pull(true);
    let (low_free, high_free) = free_cube_pull(false);
    assert!(high > 1.05, "the top rose: {high}");
    assert!(low.abs() < 0.02, "the bottom stayed: {low}");
    assert!(
        low_free > 0.05,
        "a free cube moves as a whole: {low_free} (top {high_free})"
    );
}

#[test]
fn files_opened_come_back_under_open_recent() {
    let dir = tempfile::tempdir().unwrap();
    let list = dir.path().join("config/recent.json");
    let egg = dir.path().join("egg.toml");
    std::fs::write(
        &egg,
        "[model]\nkind = \"dnurbs-swung\"\nprimitive = \"sphere\"\n[simulation]\ndt = 0.01\n",
    )
    .unwrap();
    let cube = dir.path().join("cube.toml");
    std::fs::write(
        &cube,
        "[model]\nkind = \"subdivision-solid\"\nprimitive = \"box\"\nlevel = 1\n",
    )
    .unwrap();
    // Opening the egg at start-up puts it in the list.
    let mut h = harness(Options {
        file: Some(egg.clone()),
        recent: Some(list.clone()),
        paused: true,
        ..quiet(dir.path())
    });
    wait_for(&mut h, 30, "the egg", |s| !s.frame().models.is_empty());
    let egg_abs = std::fs::canonicalize(&egg).unwrap();
    assert_eq!(h.state().recent(), std::slice::from_ref(&egg_abs));
    drop(h);
    // A later start with the cube: both listed, newest first; File > Open recent > egg opens it.
    let mut h = harness(Options {
        file: Some(cube.clone()),
        recent: Some(list.clone()),
        paused: true,
        ..quiet(dir.path())
    });
    wait_for(&mut h, 30, "the cube", |s| {
        s.frame()
            .models
            .first()
            .is_some_and(|m| m.summary.contains("springs"))
    });
    let cube_abs = std::fs::canonicalize(&cube).unwrap();
    assert_eq!(h.state().recent(), [cube_abs, egg_abs.clone()]);
    click(&mut h, Role::Button, "File");
    click(&mut h, Role::Button, "Open recent");
    click(&mut h, Role::Button, &egg_abs.display().to_string());
    // The cube was not modified (paused, untouched): no prompt, the egg opens.
    wait_for(&mut h, 30, "the egg again", |s| {
        s.frame()
            .models
            .first()
            .is_some_and(|m| m.summary.starts_with("dnurbs-swung"))
    });
    assert_eq!(h.state().recent()[0], egg_abs);
}

#[test]
fn the_smooth_brush_strokes_smooth_edits_along_the_drag_in_one_undo_step() {
    let session = builtin(builtin_named("cube").unwrap()).unwrap();
    let w = Worker::start(session, false);
    w.send(Request::Grab {
        ray: down_at(0.3, 0.5),
        tolerance: 0.0,
        grab: Grab::Smooth {
            brush: 0.2,
            strength: 0.5,
        },
    });
    for k in 1..=6 {
        w.send(Request::Stroke {
            ray: down_at(0.3 + 0.07 * k as f64, 0.5),
            tolerance: 0.0,
        });
        std::thread::sleep(Duration::from_millis(60));
    }
    w.send(Request::Drop);
    let log: Vec<Edit> = w
        .query(|s| s.log().iter().map(|l| l.command.edit.clone()).collect())
        .unwrap();
    let dabs: Vec<[f64; 3]> = log
        .iter()
        .filter_map(|e| match e {
            Edit::Smooth {
                near,
                radius,
                strength,
            } => {
                assert_eq!((*radius, *strength), (0.2, Some(0.5)));
                Some(*near)
            }
            _ => None,
        })
        .collect();
    assert!(dabs.len() >= 2, "the brush acts along the stroke: {log:?}");
    assert!(
        dabs.iter().all(|p| (p[2] - 1.0).abs() < 0.1),
        "on the top: {dabs:?}"
    );
    assert!(dabs.last().unwrap()[0] > dabs[0][0] + 0.1, "{dabs:?}");
    // No plastic reset: smoothing is not a pull (the clay settles to the faired rest shape).
    assert!(
        !log.iter().any(|e| matches!(e, Edit::PlasticReset)),
        "{log:?}"
    );
    w.send(Request::Undo);
    let left = w.query(|s| s.log().len()).unwrap();
    assert_eq!(left, 0, "one undo step");
}

#[test]
fn a_key_pressed_in_the_frame_after_a_dialog_closes_is_a_shortcut() {
    // The path field had the keyboard focus; the dialog that held it is gone, so the next
    // frame's keys are the designer's shortcuts (a stale focus used to swallow them for a frame).
    let dir = tempfile::tempdir().unwrap();
    let mut h = paused_cube(dir.path());
    key(&mut h, Key::R);
    assert_eq!(h.state().tool, Tool::Rope);
    h.key_press_modifiers(Modifiers::COMMAND | Modifiers::SHIFT, Key::S);
    h.step();
    assert_eq!(h.state().dialog_title(), Some("Save session as"));
    let path = dir.path().join("cube.session");
    h.key_press_modifiers(Modifiers::COMMAND, Key::A);
    h.step();
    h.get_by_role(Role::TextInput)
        .type_text(&format!("{}", path.display()));
    h.step();
    key(&mut h, Key::Enter);
    assert_eq!(h.state().dialog_title(), None);
    key(&mut h, Key::H);
    assert_eq!(h.state().tool, Tool::Fix, "the key after the dialog");
    wait_for(&mut h, 30, "the save", |_| path.exists());
}
