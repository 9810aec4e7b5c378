//! The studio's UI logic without a display (egui_kittest: AccessKit queries and pointer
//! events; nothing is rendered): open a model from the start page, drag on it with the rope
//! (the picked point moves towards the cursor), undo (it comes back exactly), change a material
//! slider (the model's material changes), and a bad file (a located error in a dialog).

use std::time::{Duration, Instant};

use egui::{Modifiers, Pos2, Vec2};
use egui_kittest::Harness;
use egui_kittest::kittest::Queryable;
use vclay_core::Vec3;
use vclay_studio::{Options, Studio, Tool};

fn harness(opts: Options) -> Harness<'static, Studio> {
    Harness::builder()
        .with_size(Vec2::new(1280.0, 800.0))
        .with_max_steps(100) // see common::harness
        .build_ui_state(|ui, s: &mut Studio| s.show(ui), Studio::new(opts))
}

fn quiet() -> Options {
    let dir = std::env::temp_dir().join(format!("vclay-studio-test-{}", std::process::id()));
    Options {
        autosave: Some(dir.join("autosave.session")),
        no_recovery: true,
        ..Default::default()
    }
}

/// Steps the UI until `done` holds (at most 20 s of wall time).
fn wait(h: &mut Harness<'static, Studio>, what: &str, mut done: impl FnMut(&Studio) -> bool) {
    let t = Instant::now();
    while !done(h.state()) {
        assert!(t.elapsed() < Duration::from_secs(20), "timed out: {what}");
        h.step();
        std::thread::sleep(Duration::from_millis(5));
    }
}

fn mesh(s: &Studio) -> Vec<Vec3> {
    s.worker()
        .expect("a session")
        .query(|s| s.model(None).unwrap().display_mesh().unwrap().positions)
        .expect("worker answers")
}

fn open_cube(h: &mut Harness<'static, Studio>) {
    h.get_by_label("4^3 subdivision cube (rope, extrude, delete cell)")
        .click();
    h.step();
    wait(h, "first frame", |s| !s.frame().models.is_empty());
    h.step();
    assert_eq!(h.state().tool, Tool::Rope, "the rope is the default tool");
}

#[test]
fn rope_drag_pulls_the_point_and_undo_restores_it() {
    let mut h = harness(quiet());
    open_cube(&mut h);
    // Pause, so the only motion is the rope's.
    h.get_by_label("Pause").click();
    h.step();
    wait(&mut h, "paused", |s| !s.frame().running);
    let before = mesh(h.state());

    // Press at the viewport's centre (the fitted cube's centre is there, so the ray hits it).
    let rect = h.state().viewport();
    let c = rect.center();
    let (w, hh) = (rect.width() as f64, rect.height() as f64);
    let ray = h
        .state()
        .camera
        .ray((c.x - rect.min.x) as f64, (c.y - rect.min.y) as f64, w, hh);
    let hit = h
        .state()
        .worker()
        .unwrap()
        .query(move |s| s.pick(&ray, 0.0).map(|(_, hit)| hit.point))
        .unwrap()
        .expect("the ray through the centre hits the cube");
    let nearest = before
        .iter()
        .enumerate()
        .min_by(|a, b| (a.1 - hit).norm().total_cmp(&(b.1 - hit).norm()))
        .unwrap()
        .0;

    h.hover_at(c);
    h.drag_at(c);
    h.step();
    // Drag right and up in small moves.
    let target = c + Vec2::new(120.0, -80.0);
    for k in 1..=10 {
        let p = c + (target - c) * (k as f32 / 10.0);
        h.hover_at(p);
        h.step();
        std::thread::sleep(Duration::from_millis(50));
    }
    // The cursor is where the mouse is, on the plane through the hit facing the viewer.
    let cursor = {
        let s = h.state();
        let ray = s.camera.ray(
            (target.x - rect.min.x) as f64,
            (target.y - rect.min.y) as f64,
            w,
            hh,
        );
        s.camera.on_view_plane(&ray, hit)
    };
    // Let the rope pull while the button is held.
    let worker = h.state().worker().unwrap();
    worker.query(|s| s.run(100).map(|_| ()).map_err(|e| e.to_string()));
    let moved = mesh(h.state());
    let d = moved[nearest] - before[nearest];
    let towards = (cursor - before[nearest]).normalize();
    assert!(
        d.dot(&towards) > 0.02,
        "the picked point moved {d:?}, not towards the cursor {cursor:?} (direction {towards:?}); hit {hit:?}, vertex {:?}, log {:?}",
        before[nearest],
        h.state().log().collect::<Vec<_>>()
    );
    let log: Vec<String> = h
        .state()
        .worker()
        .unwrap()
        .query(|s| {
            s.log()
                .iter()
                .map(|l| l.command.edit.action().to_string())
                .collect()
        })
        .unwrap();
    // Sculpt mode (the default) anchors the free cube for the pull (a `fix` of the control
    // points far from the grab), then the rope.
    assert_eq!(
        log.iter().map(String::as_str).take(2).collect::<Vec<_>>(),
        ["fix", "rope"],
        "log: {log:?}"
    );
    assert!(log.iter().any(|a| a == "move-rope"), "log: {log:?}");

    // Release, then undo the whole drag with Ctrl+Z.
    h.drop_at(target);
    h.step();
    std::thread::sleep(Duration::from_millis(100));
    h.step();
    h.key_press_modifiers(Modifiers::COMMAND, egui::Key::Z);
    h.step();
    std::thread::sleep(Duration::from_millis(200));
    h.step();
    let after = mesh(h.state());
    assert_eq!(after, before, "undo restores the shape before the drag");
    let n = h
        .state()
        .worker()
        .unwrap()
        .query(|s| s.log().len())
        .unwrap();
    assert_eq!(n, 0, "the drag was one undo group");
}

#[test]
fn material_slider_changes_the_material() {
    let mut h = harness(quiet());
    open_cube(&mut h);
    h.get_by_label("Pause").click();
    h.step();
    let damping = |s: &Studio| {
        s.worker()
            .unwrap()
            .query(|s| {
                s.model(None)
                    .unwrap()
                    .params()
                    .into_iter()
                    .find(|p| p.name == "damping")
                    .map(|p| p.value)
            })
            .unwrap()
    };
    assert_eq!(damping(h.state()), Some(2.0));
    h.get_by_role_and_label(egui::accesskit::Role::Slider, "damping")
        .set_value_accesskit(7.5);
    h.step();
    wait(&mut h, "damping applied", |s| damping(s) == Some(7.5));
    // Undo puts it back.
    h.key_press_modifiers(Modifiers::COMMAND, egui::Key::Z);
    h.step();
    wait(&mut h, "damping undone", |s| damping(s) == Some(2.0));
}

#[test]
fn bad_file_shows_the_located_error() {
    let dir = tempfile::tempdir().unwrap();
    let f = dir.path().join("bad.toml");
    std::fs::write(&f, "[model]\nkind = \"subdivision-solid\"\nlevel = 99\n").unwrap();
    let mut h = harness(Options {
        file: Some(f.clone()),
        ..quiet()
    });
    h.step();
    let err = h.state().error().expect("an error dialog").to_string();
    assert!(err.contains("bad.toml"), "{err}");
    assert!(err.contains("level"), "{err}");
    assert!(h.state().worker().is_none(), "nothing opened");
    // The dialog shows it.
    h.get_by_label(err.as_str());
    let _ = Pos2::ZERO;
}

#[test]
fn the_integrator_box_switches_the_solid_integrator() {
    let mut h = harness(quiet());
    open_cube(&mut h);
    h.get_by_label("integrator").click();
    for _ in 0..20 {
        h.step();
        if h.query_by_label("implicit").is_some() {
            break;
        }
    }
    h.get_by_label("implicit").click();
    h.step();
    let mut integrator = String::new();
    for _ in 0..200 {
        integrator = h
            .state()
            .worker()
            .unwrap()
            .query(|s| {
                s.model(None).unwrap().save().unwrap()["params"]["integrator"]
                    .as_str()
                    .unwrap_or("")
                    .to_string()
            })
            .unwrap();
        if integrator == "implicit" {
            break;
        }
        h.step();
        std::thread::sleep(Duration::from_millis(5));
    }
    assert_eq!(integrator, "implicit");
}
