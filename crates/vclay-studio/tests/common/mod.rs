//! Helpers shared by the studio's egui_kittest tests.
#![allow(dead_code)]

use std::path::Path;
use std::time::{Duration, Instant};

use egui::Vec2;
use egui::accesskit::Role;
use egui_kittest::Harness;
use egui_kittest::kittest::Queryable;
use vclay_studio::{Options, Studio};

/// The studio in a 1280 x 800 harness.
pub fn harness(opts: Options) -> Harness<'static, Studio> {
    Harness::builder()
        .with_size(Vec2::new(1280.0, 800.0))
        // The builder runs frames until the UI settles, at most this many: a running
        // simulation never settles, and 100,000 frames of a debug UI with a full energy plot
        // took minutes. Tests wait for what they need with `wait_for`.
        .with_max_steps(100)
        .build_ui_state(|ui, s: &mut Studio| s.show(ui), Studio::new(opts))
}

/// Options with the autosave in `dir` and no recovery prompt.
pub fn quiet(dir: &Path) -> Options {
    Options {
        autosave: Some(dir.join("autosave.session")),
        no_recovery: true,
        ..Default::default()
    }
}

/// [`quiet`] with the simulation paused at the start.
pub fn paused(dir: &Path) -> Options {
    Options {
        paused: true,
        ..quiet(dir)
    }
}

/// Steps the UI until `done` holds (at most `secs` of wall time).
pub fn wait_for(
    h: &mut Harness<'static, Studio>,
    secs: u64,
    what: &str,
    mut done: impl FnMut(&Studio) -> bool,
) {
    let t = Instant::now();
    while !done(h.state()) {
        assert!(
            t.elapsed() < Duration::from_secs(secs),
            "timed out: {what}; note {:?}, log {:?}",
            h.state().note(),
            h.state().log().collect::<Vec<_>>()
        );
        h.step();
        std::thread::sleep(Duration::from_millis(5));
    }
}

/// Steps until a node labelled `label` with `role` shows, then clicks it.
pub fn click(h: &mut Harness<'static, Studio>, role: Role, label: &str) {
    for _ in 0..50 {
        if h.query_by_role_and_label(role, label).is_some() {
            break;
        }
        h.step();
    }
    h.get_by_role_and_label(role, label).click();
    h.step();
    h.step();
}
