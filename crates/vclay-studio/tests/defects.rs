//! The studio defects of issue 27, each driven through the UI (egui_kittest) or the simulation
//! thread: a press on a dialog over the viewport does not reach the model; redo works while
//! the simulation runs and "nothing to undo" is a status line; the PDE glass opens paused and
//! its run stops at the end of the time slider; open, the start page and quit ask about
//! unsaved changes (the quit prompt's Save saves and quits, and leaves nothing to recover); a
//! newly opened model gets a fresh log, energy plot and camera; dialogs take Enter and Esc, are
//! wide enough, suggest absolute paths and keep the last character typed before a click; log
//! lines show rounded numbers.

use std::path::{Path, PathBuf};
use std::time::{Duration, Instant};

use egui::accesskit::Role;
use egui::{Event, Key, Modifiers, PointerButton, ViewportCommand, ViewportEvent, ViewportId};
use egui_kittest::Harness;
use egui_kittest::kittest::Queryable;
use vclay_core::Vec3;
use vclay_session::{Command, Edit, Ray};
use vclay_studio::load::{builtin, builtin_named};
use vclay_studio::worker::{Frame, Grab, Notice, Request, Worker};
use vclay_studio::{Options, Studio, Tool};

use crate::common;
use common::{click, harness, paused, quiet, wait_for};

/// Steps the UI until `done` holds (at most 30 s of wall time).
fn wait(h: &mut Harness<'static, Studio>, what: &str, done: impl FnMut(&Studio) -> bool) {
    wait_for(h, 30, what, done)
}

/// File > `item`.
fn file_menu(h: &mut Harness<'static, Studio>, item: &str) {
    click(h, Role::Button, "File");
    click(h, Role::Button, item);
}

/// Types `text` into the dialog's path field and presses Enter.
fn type_and_enter(h: &mut Harness<'static, Studio>, text: &str) {
    h.get_by_role(Role::TextInput).type_text(text);
    h.step();
    h.key_press(Key::Enter);
    h.step();
}

/// Waits for the first frame of a swung surface (the [`EGG`] scenario).
fn wait_for_egg(h: &mut Harness<'static, Studio>) {
    wait(h, "the egg's frame", |s| {
        s.frame()
            .models
            .first()
            .is_some_and(|m| m.summary.starts_with("dnurbs-swung"))
    });
}

fn open_builtin(h: &mut Harness<'static, Studio>, title: &str) {
    click(h, Role::Button, title);
    wait(h, "first frame", |s| !s.frame().models.is_empty());
    h.step();
}

fn open_cube(h: &mut Harness<'static, Studio>) {
    open_builtin(h, "4^3 subdivision cube (rope, extrude, delete cell)");
    assert_eq!(h.state().tool, Tool::Rope, "the rope is the default tool");
}

fn session_log_len(s: &Studio) -> usize {
    s.worker().unwrap().query(|s| s.log().len()).unwrap()
}

fn press_and_release(h: &mut Harness<'static, Studio>, at: egui::Pos2) {
    h.hover_at(at);
    h.drag_at(at);
    h.step();
    h.drop_at(at);
    h.step();
}

/// Changes the cube's damping through its slider (an edit: the session is then modified).
fn edit_damping(h: &mut Harness<'static, Studio>) {
    h.get_by_role_and_label(Role::Slider, "damping")
        .set_value_accesskit(7.5);
    h.step();
    wait(h, "the edit makes the session modified", |s| s.dirty());
}

/// A session file of the built-in cube in `dir`.
fn cube_session(dir: &Path) -> PathBuf {
    let f = dir.join("cube.session");
    let s = builtin(builtin_named("cube").unwrap()).unwrap();
    vclay_session::file::save(&f, &s, None).unwrap();
    f
}

#[test]
fn a_click_on_a_dialog_over_the_viewport_does_not_reach_the_model() {
    let dir = tempfile::tempdir().unwrap();
    let mut h = harness(paused(dir.path()));
    open_cube(&mut h);
    let centre = h.state().viewport().center();
    file_menu(&mut h, "Open...");
    assert_eq!(h.state().dialog_title(), Some("Open"));
    // The path field lies over the viewport, above the cube.
    let field = h.get_by_role(Role::TextInput).rect().center();
    assert!(h.state().viewport().contains(field));
    for at in [field, centre] {
        press_and_release(&mut h, at);
        std::thread::sleep(Duration::from_millis(100));
        h.step();
    }
    assert_eq!(session_log_len(h.state()), 0, "no rope was attached");
    assert!(
        !h.state().log().any(|l| l.contains("rope")),
        "{:?}",
        h.state().log().collect::<Vec<_>>()
    );
    assert_eq!(h.state().dialog_title(), Some("Open"), "the dialog stays");
    // Closed, the same press attaches the rope.
    h.key_press(Key::Escape);
    h.step();
    assert_eq!(h.state().dialog_title(), None, "Esc closes the dialog");
    press_and_release(&mut h, centre);
    wait(&mut h, "the rope drag is logged", |s| {
        session_log_len(s) > 0
    });
}

fn down_at(x: f64, y: f64) -> Ray {
    Ray {
        origin: Vec3::new(x, y, 3.0),
        direction: Vec3::new(0.0, 0.0, -1.0),
    }
}

/// Notices until one matches `done` (at most 20 s); panics on an error notice.
fn notices_until(w: &Worker, mut done: impl FnMut(&Notice) -> bool) -> Vec<Notice> {
    let t = Instant::now();
    let mut seen = Vec::new();
    loop {
        for n in w.notices() {
            assert!(!matches!(n, Notice::Error { .. }), "{n:?} after {seen:?}");
            let stop = done(&n);
            seen.push(n);
            if stop {
                return seen;
            }
        }
        assert!(t.elapsed() < Duration::from_secs(20), "timed out: {seen:?}");
        std::thread::sleep(Duration::from_millis(5));
    }
}

/// The next frame the worker publishes.
fn next_frame(w: &Worker) -> Frame {
    let t = Instant::now();
    loop {
        if let Some(f) = w.take_frame() {
            return f;
        }
        assert!(t.elapsed() < Duration::from_secs(20), "no frame");
        std::thread::sleep(Duration::from_millis(5));
    }
}

fn is_status(n: &Notice, prefix: &str) -> bool {
    matches!(n, Notice::Status(l) if l.starts_with(prefix))
}

/// A paused model has no step time: the status bar must not print "step -0.00 ms" (a float
/// sum of no steps is -0).
#[test]
fn a_paused_model_reports_a_step_time_of_plus_zero() {
    let session = builtin(builtin_named("cube").unwrap()).unwrap();
    let w = Worker::start(session, false);
    let f = next_frame(&w);
    assert!(!f.running);
    assert_eq!(
        f.step_seconds.to_bits(),
        0.0f64.to_bits(),
        "{}",
        f.step_seconds
    );
    assert_eq!(format!("{:.2}", f.step_seconds * 1e3), "0.00");
}

#[test]
fn redo_works_while_the_simulation_runs() {
    let session = builtin(builtin_named("cube").unwrap()).unwrap();
    let w = Worker::start(session, true);
    w.send(Request::Grab {
        ray: down_at(0.5, 0.5),
        tolerance: 0.0,
        grab: Grab::Rope { stiffness: None },
    });
    for k in 1..=5 {
        w.send(Request::Drag {
            to: Vec3::new(0.5, 0.5, 1.0 + 0.1 * k as f64),
        });
        std::thread::sleep(Duration::from_millis(50));
    }
    w.send(Request::Drop);
    let dragged = w.query(|s| s.log().len()).unwrap();
    assert!(dragged >= 2, "attach, moves, release: {dragged}");
    w.send(Request::Undo);
    notices_until(&w, |n| is_status(n, "undone"));
    assert_eq!(w.query(|s| s.log().len()).unwrap(), 0);
    // The simulation would have stepped many times by now.
    std::thread::sleep(Duration::from_millis(300));
    let _ = w.take_frame();
    // Held by the undo, so that redo gives the drag back exactly.
    let held = next_frame(&w);
    assert!(!held.running && held.can_redo, "{held:?}");
    w.send(Request::Redo);
    notices_until(&w, |n| is_status(n, "redone"));
    assert_eq!(w.query(|s| s.log().len()).unwrap(), dragged);
    let _ = w.take_frame();
    let after = next_frame(&w);
    assert!(after.running, "redo done, the run goes on: {after:?}");
    let t0 = after.time;
    std::thread::sleep(Duration::from_millis(200));
    assert!(w.query(|s| s.time()).unwrap() > t0, "time goes on");
}

#[test]
fn nothing_to_undo_is_a_status_line_not_an_error() {
    let dir = tempfile::tempdir().unwrap();
    let mut h = harness(quiet(dir.path()));
    open_cube(&mut h);
    h.key_press_modifiers(Modifiers::COMMAND, Key::Z);
    h.step();
    wait(&mut h, "the status line", |s| s.note().is_some());
    assert_eq!(h.state().note(), Some("nothing to undo"));
    assert_eq!(h.state().error(), None, "no error box");
    assert!(h.state().log().any(|l| l == "nothing to undo"));
    h.key_press_modifiers(Modifiers::COMMAND | Modifiers::SHIFT, Key::Z);
    h.step();
    wait(&mut h, "redo's status line", |s| {
        s.note() == Some("nothing to redo")
    });
    assert_eq!(h.state().error(), None);
}

#[test]
fn the_pde_glass_opens_paused_and_its_run_stops_at_the_end_of_the_time_slider() {
    let dir = tempfile::tempdir().unwrap();
    let mut h = harness(quiet(dir.path()));
    open_builtin(&mut h, "PDE glass (boundary constants, time)");
    for _ in 0..10 {
        std::thread::sleep(Duration::from_millis(20));
        h.step();
    }
    let f = h.state().frame();
    assert!(!f.running, "the glass waits for Run");
    assert_eq!(f.time, 0.0);
    h.get_by_label_contains("stops there");
    click(&mut h, Role::Button, "max");
    click(&mut h, Role::Button, "Run");
    wait(&mut h, "running", |s| s.frame().running);
    // t = 10 at full speed: about 15 s of a loaded 2-core machine (the other tests run too).
    wait_for(&mut h, 120, "the run stops at the end", |s| {
        !s.frame().running && s.frame().time > 1.0
    });
    let t = h.state().frame().time;
    let dt = h.state().frame().models[0].dt;
    let end = vclay_studio::app::PDE_T_MAX;
    assert!(t <= end + 1e-9 && t > end - dt - 1e-9, "t = {t}");
    assert!(
        h.state()
            .note()
            .is_some_and(|n| n.contains("end of the time range")),
        "{:?}",
        h.state().note()
    );
    std::thread::sleep(Duration::from_millis(200));
    h.step();
    assert_eq!(h.state().frame().time, t, "time stays at the end");
    // Run again starts over from 0.
    click(&mut h, Role::Button, "Run");
    wait(&mut h, "started over", |s| s.frame().time < 1.0);
}

#[test]
fn open_and_the_start_page_ask_about_unsaved_changes() {
    let dir = tempfile::tempdir().unwrap();
    let mut h = harness(paused(dir.path()));
    open_cube(&mut h);
    edit_damping(&mut h);
    file_menu(&mut h, "Open...");
    assert_eq!(h.state().dialog_title(), Some("Unsaved changes"));
    click(&mut h, Role::Button, "Cancel");
    assert_eq!(h.state().dialog_title(), None);
    file_menu(&mut h, "Open...");
    click(&mut h, Role::Button, "Discard");
    assert_eq!(h.state().dialog_title(), Some("Open"));
    h.key_press(Key::Escape);
    h.step();
    assert_eq!(h.state().dialog_title(), None);

    file_menu(&mut h, "Start page");
    assert_eq!(h.state().dialog_title(), Some("Unsaved changes"));
    h.key_press(Key::Escape);
    h.step();
    assert!(h.state().worker().is_some(), "Esc cancels");
    file_menu(&mut h, "Start page");
    click(&mut h, Role::Button, "Discard");
    assert!(h.state().worker().is_none(), "the start page");
    h.get_by_label("4^3 subdivision cube (rope, extrude, delete cell)");
}

/// A scenario file of the egg of the start page.
const EGG: &str = "[model]\nkind = \"dnurbs-swung\"\nprimitive = \"sphere\"\n\n[material]\n\
                   preset = \"Egg sculpting\"\n\n[simulation]\ndt = 0.01\n";
/// A scenario file of the cube of the start page.
const CUBE: &str = "[model]\nkind = \"subdivision-solid\"\nprimitive = \"box\"\npoints = [4, 4, 4]\n\
                    level = 2\nboundary = \"sharp\"\n\n[simulation]\ndt = 0.002\n";

#[test]
fn a_newly_opened_model_has_a_fresh_log_plot_and_camera() {
    let dir = tempfile::tempdir().unwrap();
    let egg = dir.path().join("egg.toml");
    std::fs::write(&egg, EGG).unwrap();
    let mut h = harness(quiet(dir.path()));
    open_cube(&mut h);
    edit_damping(&mut h);
    wait(&mut h, "a second of simulation", |s| {
        s.energy_samples().last().is_some_and(|e| e[0] > 0.5)
    });
    assert!(h.state().log().any(|l| l.contains("damping")));
    h.state_mut().camera.distance *= 3.0;
    h.state_mut().camera.yaw += 1.0;

    file_menu(&mut h, "Open...");
    click(&mut h, Role::Button, "Discard");
    assert_eq!(h.state().dialog_title(), Some("Open"));
    type_and_enter(&mut h, &egg.display().to_string());
    assert_eq!(h.state().dialog_title(), None, "Enter opens");
    wait_for_egg(&mut h);
    // Let frames and notices that the cube's session still had in flight arrive.
    for _ in 0..20 {
        std::thread::sleep(Duration::from_millis(10));
        h.step();
    }
    let s = h.state();
    let log: Vec<&String> = s.log().collect();
    assert!(!log.iter().any(|l| l.contains("damping")), "{log:?}");
    let t = s.frame().time;
    let first = s.energy_samples().first().map_or(0.0, |e| e[0]);
    assert!(
        s.energy_samples().iter().all(|e| e[0] <= t + 1e-9) && first < 0.25,
        "samples {first} .. of the cube's run, the egg is at t = {t}"
    );
    let shown = s.camera.clone();
    h.state_mut().fit();
    // The fit of the egg as it is now (it moves a little while it runs).
    let fit = &h.state().camera;
    assert!(
        (fit.target - shown.target).norm() < 1e-3 * fit.distance
            && (fit.distance - shown.distance).abs() < 1e-3 * fit.distance
            && (fit.yaw, fit.pitch) == (shown.yaw, shown.pitch),
        "the egg is framed: {shown:?}, its fit {fit:?}"
    );
}

/// Whether the last frame asked to close the window.
fn asked_to_close(h: &Harness<'static, Studio>) -> bool {
    h.output()
        .viewport_output
        .get(&ViewportId::ROOT)
        .is_some_and(|v| {
            v.commands
                .iter()
                .any(|c| matches!(c, ViewportCommand::Close))
        })
}

fn request_close(h: &mut Harness<'static, Studio>) {
    h.input_mut()
        .viewports
        .entry(ViewportId::ROOT)
        .or_default()
        .events
        .push(ViewportEvent::Close);
    h.step();
}

#[test]
fn save_in_the_quit_prompt_saves_and_quits_and_leaves_nothing_to_recover() {
    let dir = tempfile::tempdir().unwrap();
    let file = cube_session(dir.path());
    let auto = dir.path().join("autosave.session");
    let opts = Options {
        file: Some(file.clone()),
        autosave: Some(auto.clone()),
        ..Default::default()
    };
    let mut h = harness(opts.clone());
    assert_eq!(h.state().dialog_title(), None);
    wait(&mut h, "first frame", |s| !s.frame().models.is_empty());
    edit_damping(&mut h);
    // Saved, then autosaved again while the simulation runs on.
    h.key_press_modifiers(Modifiers::COMMAND, Key::S);
    h.step();
    wait(&mut h, "saved", |s| s.log().any(|l| l.starts_with("saved")));
    let saved = std::fs::metadata(&file).unwrap().modified().unwrap();
    wait(&mut h, "an autosave after the save", |_| {
        std::fs::metadata(&auto)
            .and_then(|m| m.modified())
            .is_ok_and(|t| t > saved)
    });
    assert!(h.state().dirty(), "the run moved on");

    request_close(&mut h);
    assert!(!asked_to_close(&h));
    assert_eq!(h.state().dialog_title(), Some("Unsaved changes"));
    click(&mut h, Role::Button, "Save");
    let t = Instant::now();
    while !asked_to_close(&h) {
        assert!(t.elapsed() < Duration::from_secs(20), "Save did not quit");
        h.step();
        std::thread::sleep(Duration::from_millis(5));
    }
    let now = std::fs::metadata(&file).unwrap().modified().unwrap();
    assert!(now > saved, "saved again on quit");
    drop(h);
    assert!(!auto.exists(), "a clean exit leaves no autosave");

    // The next start offers no recovery.
    let h = harness(opts);
    assert_eq!(h.state().dialog_title(), None);
}

#[test]
fn a_clean_quit_does_not_prompt_and_removes_the_autosave() {
    let dir = tempfile::tempdir().unwrap();
    let file = cube_session(dir.path());
    let auto = dir.path().join("autosave.session");
    let mut h = harness(Options {
        file: Some(file),
        autosave: Some(auto.clone()),
        paused: true,
        ..Default::default()
    });
    wait(&mut h, "first frame", |s| !s.frame().models.is_empty());
    std::fs::write(&auto, "stale").unwrap();
    request_close(&mut h);
    assert_eq!(h.state().dialog_title(), None, "nothing to save");
    drop(h);
    assert!(!auto.exists());
}

#[test]
fn save_as_suggests_an_absolute_path_beside_the_file_and_enter_saves() {
    let dir = tempfile::tempdir().unwrap();
    let scenario = dir.path().join("cube.toml");
    std::fs::write(&scenario, CUBE).unwrap();
    let mut h = harness(Options {
        file: Some(scenario),
        paused: true,
        ..quiet(dir.path())
    });
    wait(&mut h, "first frame", |s| !s.frame().models.is_empty());
    h.key_press_modifiers(Modifiers::COMMAND, Key::S);
    h.step();
    h.step();
    assert_eq!(h.state().dialog_title(), Some("Save session as"));
    let value = h.get_by_role(Role::TextInput).value().unwrap();
    let expected = std::path::absolute(dir.path().join("cube.session")).unwrap();
    assert_eq!(PathBuf::from(&value), expected);
    h.key_press(Key::Enter);
    h.step();
    assert_eq!(h.state().dialog_title(), None);
    wait(&mut h, "saved", |_| expected.exists());

    // Without a file: absolute, named after the model.
    let mut h = harness(paused(dir.path()));
    open_cube(&mut h);
    file_menu(&mut h, "Save as...");
    let value = PathBuf::from(h.get_by_role(Role::TextInput).value().unwrap());
    assert!(value.is_absolute(), "{value:?}");
    assert_eq!(value.extension().unwrap(), "session");
}

#[test]
fn an_error_box_is_wide_enough_to_read() {
    let dir = tempfile::tempdir().unwrap();
    let mut h = harness(quiet(dir.path()));
    // The error follows the open dialog in the same modal area (which kept that dialog's
    // narrow size before).
    file_menu(&mut h, "Open...");
    let missing = dir
        .path()
        .join("a/folder/that/does/not/exist/with/a/rather/long/name/model.toml");
    h.get_by_role(Role::TextInput).click();
    h.step();
    h.get_by_role(Role::TextInput)
        .type_text(&missing.display().to_string());
    h.step();
    h.key_press(Key::Enter);
    for _ in 0..5 {
        h.step();
    }
    let err = h.state().error().expect("no such file").to_string();
    let w = h.get_by_label(err.as_str()).rect().width();
    assert!(
        w >= vclay_studio::app::DIALOG_MIN_WIDTH - 30.0,
        "the message is {w} points wide"
    );
    h.key_press(Key::Enter);
    h.step();
    assert_eq!(h.state().error(), None, "Enter closes it");
}

#[test]
fn text_typed_in_the_frame_of_a_click_is_not_lost() {
    let dir = tempfile::tempdir().unwrap();
    let file = cube_session(dir.path());
    let path = file.display().to_string();
    let (head, last) = path.split_at(path.len() - 1);
    let mut h = harness(quiet(dir.path()));
    file_menu(&mut h, "Open...");
    h.get_by_role(Role::TextInput).click();
    h.step();
    h.get_by_role(Role::TextInput).type_text(head);
    h.step();
    // Press on Open, then the last key and the release arrive in one frame.
    let button = h
        .get_by_role_and_label(Role::Button, "Open")
        .rect()
        .center();
    h.hover_at(button);
    h.step();
    h.input_mut().events.push(Event::PointerButton {
        pos: button,
        button: PointerButton::Primary,
        pressed: true,
        modifiers: Modifiers::NONE,
    });
    h.step();
    h.input_mut().events.extend([
        Event::Text(last.to_string()),
        Event::PointerButton {
            pos: button,
            button: PointerButton::Primary,
            pressed: false,
            modifiers: Modifiers::NONE,
        },
    ]);
    h.step();
    h.step();
    assert_eq!(h.state().error(), None);
    wait(&mut h, "the file opened", |s| !s.frame().models.is_empty());
}

#[test]
fn log_lines_show_rounded_numbers() {
    let dir = tempfile::tempdir().unwrap();
    let mut h = harness(paused(dir.path()));
    open_cube(&mut h);
    let w = h.state().worker().unwrap();
    let model = h.state().frame().models[0].name.clone();
    let rope = Edit::Rope {
        name: Some("r".into()),
        from: [0.5, 0.5, 1.0],
        param: None,
        to: None,
        until: None,
        velocity: None,
        release: None,
        stiffness: None,
        length: None,
        kernel: None,
        start: None,
    };
    w.send(Request::Apply(Command::to(&model, rope)));
    w.send(Request::Apply(Command::to(
        &model,
        Edit::MoveRope {
            name: "r".into(),
            to: [0.1234567890123456, -2.0000000000000004, 1.5],
        },
    )));
    wait(&mut h, "the cursor line", |s| {
        s.log().any(|l| l.contains("cursor at"))
    });
    let line = h.state().log().find(|l| l.contains("cursor at")).unwrap();
    assert!(line.ends_with("cursor at [0.123, -2, 1.5]"), "{line}");
}

#[test]
fn a_recovered_session_counts_as_modified() {
    let dir = tempfile::tempdir().unwrap();
    let file = cube_session(dir.path());
    let auto = dir.path().join("autosave.session");
    std::thread::sleep(Duration::from_millis(20));
    std::fs::copy(&file, &auto).unwrap();
    let mut h = harness(Options {
        file: Some(file),
        autosave: Some(auto),
        paused: true,
        ..Default::default()
    });
    assert_eq!(h.state().dialog_title(), Some("Recover?"));
    click(&mut h, Role::Button, "Recover");
    wait(&mut h, "recovered and modified", |s| {
        !s.frame().models.is_empty() && s.dirty()
    });
    // So quitting asks (and a clean quit would not throw the recovered changes away).
    request_close(&mut h);
    assert_eq!(h.state().dialog_title(), Some("Unsaved changes"));
}

#[test]
fn the_status_line_rounds_numbers_as_the_log_does() {
    // Undoing a rope on the egg names the material point it held, which the session writes
    // with every digit ([0.590938872494213, ...]); the status line shows it rounded.
    let dir = tempfile::tempdir().unwrap();
    let mut h = harness(paused(dir.path()));
    open_builtin(&mut h, "Swung D-NURBS egg (Egg sculpting material)");
    let w = h.state().worker().unwrap();
    w.send(Request::Grab {
        ray: Ray {
            origin: Vec3::new(0.3, 0.2, 10.0),
            direction: Vec3::new(0.0, 0.0, -1.0),
        },
        tolerance: 0.0,
        grab: Grab::Rope { stiffness: None },
    });
    w.send(Request::Drag {
        to: Vec3::new(0.3, 0.2, 1.3),
    });
    w.send(Request::Drop);
    let long = |s: &str| {
        s.split(|c: char| !(c.is_ascii_digit() || c == '.'))
            .any(|t| t.split_once('.').is_some_and(|(_, f)| f.len() > 3))
    };
    let attached = w.query(|s| s.log()[0].message.clone()).unwrap();
    assert!(
        long(&attached),
        "the session's own message keeps every digit: {attached}"
    );
    h.key_press_modifiers(Modifiers::COMMAND, Key::Z);
    h.step();
    wait(&mut h, "the undo's status line", |s| {
        s.note().is_some_and(|n| n.starts_with("undone: "))
    });
    let note = h.state().note().unwrap().to_string();
    assert!(note.contains("material point [") && !long(&note), "{note}");
}

#[test]
fn a_rope_stroke_logs_one_cursor_line_per_rope() {
    // Twelve cursor moves of a rope and its mirror image (symmetry X) on the paused cube: the
    // log says each rope was attached, where its cursor is now (one line each) and that it
    // was released, not one line per mouse move.
    let dir = tempfile::tempdir().unwrap();
    let mut h = harness(paused(dir.path()));
    open_cube(&mut h);
    let w = h.state().worker().unwrap();
    w.send(Request::Symmetry(vclay_studio::symmetry::Symmetry([
        true, false, false,
    ])));
    w.send(Request::Grab {
        ray: down_at(0.9, 0.5),
        tolerance: 0.0,
        grab: Grab::Rope { stiffness: None },
    });
    for k in 1..=12 {
        w.send(Request::Drag {
            to: Vec3::new(0.9, 0.5, 1.0 + 0.05 * k as f64),
        });
        std::thread::sleep(Duration::from_millis(60));
    }
    w.send(Request::Drop);
    wait(&mut h, "the release in the log", |s| {
        s.log().filter(|l| l.starts_with("released")).count() == 2
    });
    let moves = h
        .state()
        .worker()
        .unwrap()
        .query(|s| {
            s.log()
                .iter()
                .filter(|l| l.message.contains("cursor at"))
                .count()
        })
        .unwrap();
    assert!(moves >= 8, "the session logs every move: {moves}");
    let log: Vec<String> = h.state().log().cloned().collect();
    let cursor: Vec<&String> = log.iter().filter(|l| l.contains("cursor at")).collect();
    assert_eq!(cursor.len(), 2, "one line per rope: {log:#?}");
    assert!(
        cursor.iter().all(|l| l.ends_with(", 1.6]")),
        "the last position: {log:#?}"
    );
    assert_ne!(cursor[0], cursor[1], "the rope and its mirror image");
}

#[test]
fn the_open_dialog_reads_a_relative_path_from_the_opened_files_folder() {
    let dir = tempfile::tempdir().unwrap();
    let scenario = dir.path().join("cube.toml");
    std::fs::write(&scenario, CUBE).unwrap();
    std::fs::write(dir.path().join("egg.toml"), EGG).unwrap();
    // The studio runs from another folder than the files'.
    let mut h = harness(Options {
        file: Some(scenario),
        paused: true,
        ..quiet(dir.path())
    });
    wait(&mut h, "first frame", |s| !s.frame().models.is_empty());
    file_menu(&mut h, "Open...");
    assert_eq!(h.state().dialog_title(), Some("Open"));
    let folder = std::path::absolute(dir.path()).unwrap();
    assert_eq!(h.state().open_folder(), folder);
    let says = format!("A relative path is read from {}", folder.display());
    h.get_by_label(says.as_str());
    type_and_enter(&mut h, "egg.toml");
    assert_eq!(h.state().error(), None, "egg.toml beside cube.toml opens");
    wait_for_egg(&mut h);
    assert_eq!(h.state().recent()[0], folder.join("egg.toml"));
}

#[test]
fn the_energy_plot_of_a_model_at_rest_shows_no_rounding_spikes() {
    let dir = tempfile::tempdir().unwrap();
    let mut h = harness(quiet(dir.path()));
    open_builtin(&mut h, "Swung D-NURBS egg (Egg sculpting material)");
    // Running, with no tool: the energies are rounding noise (6e-28 when this was written).
    wait(&mut h, "a few energy samples", |s| {
        s.energy_samples().len() > 20
    });
    h.step();
    let noise = h
        .state()
        .energy_samples()
        .iter()
        .fold(0.0_f64, |m, e| m.max(e[1].abs()).max(e[2].abs()));
    let size = h.state().frame().models[0].size;
    let floor = vclay_studio::app::ENERGY_PLOT_FLOOR * size * size;
    assert!(
        noise > 0.0 && noise < 1e-3 * floor,
        "the egg at rest has energy {noise}"
    );
    let [lo, hi] = h.state().energy_y_range().expect("the plot was drawn");
    assert!(lo <= 0.0 && hi >= floor, "the axis spans [{lo}, {hi}]");
}
