//! Sessions: several models, history rules, and session files (versioned, located errors,
//! atomic save, bitwise continuation with a pending timeline).

use crate::common;
use common::assert_same;

use std::path::Path;

use vclay_session::scenario::Scenario;
use vclay_session::{Command, Edit, Session, SessionError, file};

/// [`common::two_kinds`] and the rope's release at t = 0.04.
fn two() -> String {
    common::two_kinds()
        + r#"
[[timeline]]
at = 0.04
model = "cube"
action = "release"
name = "rope0"
"#
}

fn saved_all(s: &Session) -> serde_json::Value {
    file::to_value(s, None).unwrap()
}

#[test]
fn a_session_holds_models_of_several_kinds_with_their_own_clocks() {
    let mut sc = Scenario::parse(&two(), "two.toml", "two", Path::new(".")).unwrap();
    assert_eq!(sc.session.model_names(), ["cube", "sheet"]);
    let lines = sc.session.run(30).unwrap();
    // The cube's rope at 0, its release at 0.04 (step 20); the sheet's gravity at 0.1 (step 10).
    assert_eq!(lines.len(), 3, "{lines:?}");
    let cube = sc.session.model(Some("cube")).unwrap();
    let sheet = sc.session.model(Some("sheet")).unwrap();
    assert!((cube.time() - 0.06).abs() < 1e-12 && (sheet.time() - 0.3).abs() < 1e-12);
    assert_eq!(sc.session.log().len(), 3);
    assert_eq!(sc.session.log()[1].model, "sheet");
    assert_eq!(sc.session.log()[1].step, 10);
    // Time of the session: the earliest clock.
    assert!((sc.session.time() - 0.06).abs() < 1e-12);
    // Commands go to the named model; an unknown name is an error naming the known ones.
    let e = sc
        .session
        .apply(Command::to("blob", Edit::Stop))
        .unwrap_err()
        .to_string();
    assert!(e.contains("blob") && e.contains("cube, sheet"), "{e}");
}

#[test]
fn undo_and_redo_follow_the_history_rules() {
    let mut sc = Scenario::parse(&two(), "two.toml", "two", Path::new(".")).unwrap();
    let s = &mut sc.session;
    assert!(matches!(s.undo(), Err(SessionError::History("undo"))));
    assert!(matches!(s.redo(), Err(SessionError::History("redo"))));
    s.run(5).unwrap();
    let before = saved_all(s);
    s.apply(Command::to(
        "sheet",
        Edit::Gravity {
            name: Some("g".into()),
            g: [0.0, 0.0, 2.0],
            until: None,
        },
    ))
    .unwrap();
    s.apply(Command::to("cube", Edit::Stop)).unwrap();
    s.run(3).unwrap();
    let log_len = s.log().len();
    s.undo().unwrap();
    s.undo().unwrap();
    assert_eq!(s.log().len(), log_len - 2);
    // Both models back where they were before the two commands: clocks included. The models'
    // saved states must match; the history differs (the undone entries left the log).
    let now = saved_all(s);
    assert_same(&now["models"], &before["models"], "undo of two commands");
    assert!(s.can_redo());
    s.redo().unwrap();
    // A step keeps the redo list (the studio's simulation runs while the designer undoes and
    // redoes, issue 27); redo applies the command at the current time. A new command clears it.
    s.undo().unwrap();
    s.run(1).unwrap();
    assert!(s.can_redo());
    s.redo().unwrap();
    s.undo().unwrap();
    s.apply(Command::to("cube", Edit::Stop)).unwrap();
    assert!(!s.can_redo());
}

#[test]
fn session_files_continue_exactly_with_the_pending_timeline() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("two.session");
    let mut a = common::scenario(&two());
    a.run(12).unwrap();
    file::save(&path, &a, None).unwrap();
    // The save left no temporary file behind.
    assert_eq!(std::fs::read_dir(dir.path()).unwrap().count(), 1);
    let (mut b, run) = file::load(&path).unwrap();
    assert!(run.is_none());
    assert_eq!(
        b.schedule().len(),
        1,
        "the release at 0.04 is still pending"
    );
    assert_eq!(b.log().len(), 2);
    a.run(18).unwrap();
    b.run(18).unwrap();
    assert_same(&saved_all(&a), &saved_all(&b), "continued sessions");
}

#[test]
fn bad_session_files_are_located_errors() {
    let a = common::scenario(&two());
    let good = serde_json::to_string(&file::to_value(&a, None).unwrap()).unwrap();
    let check = |text: &str, key: &str, words: &[&str]| match file::parse(text, "x.session") {
        Err(SessionError::File {
            file, key: k, what, ..
        }) => {
            assert_eq!(file, "x.session");
            assert!(k.contains(key), "key {k}, wanted {key}: {what}");
            for w in words {
                assert!(what.contains(w), "{what} lacks {w}");
            }
        }
        other => panic!("{key}: {other:?}"),
    };
    check(
        &good.replace("\"version\":1", "\"version\":7"),
        "version",
        &["version 7", "update vclay"],
    );
    check(
        &good.replace("\"format\":\"vclay-session\"", "\"format\":\"zip\""),
        "format",
        &["zip"],
    );
    check(
        &good.replace("\"kind\":\"dnurbs-surface\"", "\"kind\":\"clay\""),
        "models[1].kind",
        &["clay"],
    );
    check(
        &good.replace("\"model\":\"sheet\"", "\"model\":\"ghost\""),
        "schedule[2].model",
        &["ghost"],
    );
    check(&good[..good.len() / 2], "syntax", &[]);
    match file::parse(
        "{\n\"format\": \"vclay-session\",\n\"version\": 1,\n\"models\": [\n}",
        "y.session",
    ) {
        Err(SessionError::File { line, .. }) => assert_eq!(line, 5),
        other => panic!("{other:?}"),
    }
    // A model whose parts do not fit (a tool handle the kernel does not have).
    let v: serde_json::Value = serde_json::from_str(&good).unwrap();
    let mut w = v.clone();
    w["models"][0]["state"]["state"]["velocities"] = serde_json::json!([[0.0, 0.0, 0.0]]);
    check(&w.to_string(), "models[0] (cube)", &["velocities"]);
}

#[test]
fn an_undo_group_is_undone_whole_and_keeps_one_snapshot_for_a_drag() {
    let mut sc = Scenario::parse(&two(), "two.toml", "two", Path::new(".")).unwrap();
    let s = &mut sc.session;
    s.run(3).unwrap();
    s.apply(Command::to("cube", Edit::Stop)).unwrap();
    let before = saved_all(s);
    let log_before = s.log().len();
    // A drag: attach, cursor moves with steps in between, release.
    s.begin_group();
    s.apply(Command::to(
        "cube",
        common::rope(Some("drag"), [1.0, 1.0, 1.0], None, None),
    ))
    .unwrap();
    for k in 0..20 {
        s.apply(Command::to(
            "cube",
            Edit::MoveRope {
                name: "drag".into(),
                to: [1.0 + 0.01 * k as f64, 1.0, 1.0],
            },
        ))
        .unwrap();
        s.step().unwrap();
    }
    s.apply(Command::to(
        "cube",
        Edit::Release {
            name: "drag".into(),
        },
    ))
    .unwrap();
    s.end_group();
    // Every command is logged, the scheduled ones that fired during the drag too (the cube's
    // release of `rope0` at 0.04 s and the sheet's gravity at 0.1 s).
    let n = s.log().len() - log_before;
    assert_eq!(n, 22 + 2, "{:?}", &s.log()[log_before..]);
    let after = saved_all(s);
    // One undo takes the whole drag back, the cube's clock included; the command before it
    // stays. (The sheet goes back to just before its own command in the group, the gravity
    // that fired at its step 10: each command is undone to the state just before it.)
    let first = s.undo().unwrap();
    assert!(matches!(first.command.edit, Edit::Rope { .. }), "{first:?}");
    assert_same(
        &saved_all(s)["models"][0],
        &before["models"][0],
        "undo of the group",
    );
    assert_eq!(saved_all(s)["models"][1]["state"]["state"]["steps"], 10);
    assert_eq!(s.log().len(), log_before);
    assert!(s.can_undo(), "the stop before the group is its own step");
    // Redo applies the group's commands again (without the steps between them).
    let m = s.redo().unwrap();
    assert_eq!(m.lines().count(), n, "{m}");
    assert_eq!(s.log().len(), log_before + n);
    assert!(
        saved_all(s)["models"][0] != after["models"][0],
        "the steps are not replayed"
    );
    s.undo().unwrap();
    assert_same(
        &saved_all(s)["models"][0],
        &before["models"][0],
        "undo of the redone group",
    );
    // Nested groups count as the outermost.
    s.begin_group();
    s.begin_group();
    s.apply(Command::to("cube", Edit::Stop)).unwrap();
    s.end_group();
    s.apply(Command::to("cube", Edit::Stop)).unwrap();
    s.end_group();
    s.undo().unwrap();
    assert_eq!(s.log().len(), log_before);
}

#[test]
fn a_bad_value_in_a_session_file_names_its_path() {
    let a = common::scenario(&two());
    let mut v = file::to_value(&a, None).unwrap();
    v["log"] = serde_json::json!([{"step": "three"}]);
    match file::parse(&v.to_string(), "x.session") {
        Err(SessionError::File { key, what, .. }) => {
            assert!(key.starts_with("log[0]"), "{key}: {what}");
        }
        other => panic!("{other:?}"),
    }
}

#[test]
fn redo_right_after_undo_gives_back_a_drag_exactly() {
    // A drag is commands with steps between them; applying them again at once would not deform
    // the model. Redo with nothing in between puts back the model as it was before the undo.
    let text = "[model]\nkind = \"subdivision-solid\"\nprimitive = \"box\"\npoints = [3, 3, 3]\nlevel = 1\n";
    let mut s = common::scenario(text);
    s.begin_group();
    s.apply(Command::new(common::rope(
        Some("drag"),
        [1.0, 1.0, 1.0],
        None,
        None,
    )))
    .unwrap();
    s.apply(Command::new(Edit::MoveRope {
        name: "drag".into(),
        to: [1.5, 1.5, 1.5],
    }))
    .unwrap();
    s.run(50).unwrap();
    s.apply(Command::new(Edit::Release {
        name: "drag".into(),
    }))
    .unwrap();
    s.apply(Command::new(Edit::PlasticReset)).unwrap();
    s.end_group();
    let dragged = saved_all(&s);
    s.undo().unwrap();
    s.redo().unwrap();
    assert_same(&saved_all(&s)["models"], &dragged["models"], "exact redo");
    // Undo and redo again: the same.
    s.undo().unwrap();
    s.redo().unwrap();
    assert_same(
        &saved_all(&s)["models"],
        &dragged["models"],
        "second exact redo",
    );
    // After a step in between, redo applies the commands again (no exact copy).
    s.undo().unwrap();
    s.run(1).unwrap();
    s.redo().unwrap();
    assert_ne!(saved_all(&s)["models"], dragged["models"]);
}
