//! The desktop's file chooser (`vclay_studio::native`): File > Open asks the chooser program,
//! opens what it answers, and falls back to the typed-path dialog when the program fails. The
//! chooser here is a stand-in script that answers like `zenity --file-selection`.
use crate::common;

use std::os::unix::fs::PermissionsExt;
use std::path::{Path, PathBuf};

use egui::accesskit::Role;
use egui_kittest::kittest::Queryable;
use vclay_studio::Options;
use vclay_studio::native::{Chooser, Flavor};

use common::{click, harness, quiet, wait_for};

const EGG: &str = "[model]\nkind = \"dnurbs-swung\"\nprimitive = \"sphere\"\n\n[material]\n\
                   preset = \"Egg sculpting\"\n\n[simulation]\ndt = 0.01\n";

/// A zenity stand-in: logs its arguments to `args.txt` beside it, prints `answer` and exits
/// with `code`.
fn fake_zenity(dir: &Path, answer: &str, code: i32) -> PathBuf {
    let p = dir.join("zenity");
    let log = dir.join("args.txt");
    std::fs::write(
        &p,
        format!(
            "#!/bin/sh\necho \"$@\" > '{}'\nprintf '%s\\n' '{answer}'\nexit {code}\n",
            log.display()
        ),
    )
    .unwrap();
    std::fs::set_permissions(&p, std::fs::Permissions::from_mode(0o755)).unwrap();
    p
}

fn with_chooser(dir: &Path, program: PathBuf) -> Options {
    Options {
        chooser: Some(Chooser {
            program,
            flavor: Flavor::Zenity,
        }),
        ..quiet(dir)
    }
}

#[test]
fn open_asks_the_desktop_chooser_and_opens_its_answer() {
    let dir = tempfile::tempdir().unwrap();
    let egg = dir.path().join("egg.toml");
    std::fs::write(&egg, EGG).unwrap();
    let zenity = fake_zenity(dir.path(), &egg.display().to_string(), 0);
    let mut h = harness(with_chooser(dir.path(), zenity));
    click(&mut h, Role::Button, "File");
    click(&mut h, Role::Button, "Open...");
    wait_for(&mut h, 30, "the chosen file to open", |s| {
        !s.frame().models.is_empty()
    });
    assert_eq!(h.state().dialog_title(), None);
    let args = std::fs::read_to_string(dir.path().join("args.txt")).unwrap();
    assert!(
        args.contains("--file-selection") && !args.contains("--save"),
        "{args}"
    );
}

#[test]
fn a_cancelled_chooser_closes_and_a_broken_one_falls_back_to_typing() {
    let dir = tempfile::tempdir().unwrap();
    let cancel = fake_zenity(dir.path(), "", 1);
    let mut h = harness(with_chooser(dir.path(), cancel));
    click(&mut h, Role::Button, "File");
    click(&mut h, Role::Button, "Open...");
    wait_for(&mut h, 30, "the cancelled dialog to close", |s| {
        s.dialog_title().is_none()
    });
    assert!(h.state().frame().models.is_empty());

    let broken = dir.path().join("broken");
    std::fs::create_dir(&broken).unwrap();
    let program = fake_zenity(&broken, "", 255);
    let mut h = harness(with_chooser(dir.path(), program));
    click(&mut h, Role::Button, "File");
    click(&mut h, Role::Button, "Open...");
    wait_for(&mut h, 30, "the typed-path dialog", |s| {
        s.log().any(|l| l.contains("type the path instead"))
    });
    assert_eq!(h.state().dialog_title(), Some("Open"));
    // The typed dialog is really there (drawn by the next frames): its path field.
    for _ in 0..20 {
        if h.query_by_role(Role::TextInput).is_some() {
            break;
        }
        h.step();
    }
    assert!(h.query_by_role(Role::TextInput).is_some());
}
