//! Issue 29, items 3-6: memory estimates that are right, quiet is quiet, output is short,
//! messages point the right way, and reading our own STEP files is silent.

use std::path::Path;
use std::process::{Command, Output};

fn vclay(dir: &Path, args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_vclay"))
        .current_dir(dir)
        .args(args)
        .output()
        .expect("vclay runs")
}

fn text(b: &[u8]) -> String {
    String::from_utf8_lossy(b).into_owned()
}

fn scenario(name: &str) -> String {
    format!(
        "{}/../../examples/scenarios/{name}",
        env!("CARGO_MANIFEST_DIR")
    )
}

#[test]
fn run_quiet_prints_no_notes_and_a_long_run_lists_its_frames_as_a_range() {
    let dir = tempfile::tempdir().unwrap();
    let out = vclay(
        dir.path(),
        &[
            "run",
            &scenario("fig07_rope_cube.toml"),
            "--steps",
            "600",
            "-q",
            "--out",
            "o",
        ],
    );
    assert!(out.status.success(), "{}", text(&out.stderr));
    assert_eq!(text(&out.stderr), "", "-q: nothing on stderr");
    let stdout = text(&out.stdout);
    // The timeline's event (the rope attached at 0), once.
    assert_eq!(
        stdout.matches("attached to data point").count(),
        1,
        "{stdout}"
    );
    // 9 frames: listed as a range, not one line each.
    assert!(
        stdout.contains("-> frames frame_000000.obj .. frame_000600.obj"),
        "{stdout}"
    );
    assert!(stdout.lines().count() < 12, "short: {stdout}");
    let verbose = vclay(
        dir.path(),
        &[
            "run",
            &scenario("fig07_rope_cube.toml"),
            "--steps",
            "600",
            "-v",
            "--out",
            "v",
        ],
    );
    assert!(text(&verbose.stdout).contains("frame_000075.obj"));
}

#[test]
fn messages_point_the_right_way() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let err = |args: &[&str]| {
        let out = vclay(d, args);
        assert_eq!(out.status.code(), Some(2), "{args:?}");
        text(&out.stderr)
    };
    let e = err(&["run", &scenario("fig07_rope_cube.toml"), "--steps=-5"]);
    assert!(
        e.contains("negative") && !e.contains("invalid digit"),
        "{e}"
    );
    let e = err(&["run", &scenario("fig07_rope_cube.toml"), "--steps", "-5"]);
    assert!(e.contains("negative") && !e.contains("tip"), "{e}");
    let e = err(&["subdivide", "--primitive", "cube", "--levels", "two"]);
    assert!(e.contains("not a whole number"), "{e}");
    let e = err(&["eval", "model.json"]);
    assert!(e.contains("--params") && e.contains("--at"), "{e}");
    std::fs::write(d.join("s.xyz"), "0 0 0\n1 0 0\n0 1 0\n1 1 1\n").unwrap();
    let e = err(&["fit", "s.xyz", "--grid", "-4x4", "--out", "f.json"]);
    assert!(e.contains("--grid -4x4") && !e.contains("tip"), "{e}");
    std::fs::write(
        d.join("lv.toml"),
        "[model]\nkind = \"subdivision-solid\"\nlevel = \"two\"\n",
    )
    .unwrap();
    let e = err(&["run", "lv.toml"]);
    assert!(
        e.contains("expected a whole number") && !e.contains("usize"),
        "{e}"
    );
    std::fs::write(d.join("bad.session"), "garbage").unwrap();
    let e = err(&["run", "bad.session"]);
    assert!(e.contains("damaged") && e.contains("line 1"), "{e}");
    // `vclay help` is a command of its own: with --help, and for a subcommand.
    let h = vclay(d, &["help", "--help"]);
    assert!(h.status.success(), "{}", text(&h.stderr));
    let h = vclay(d, &["help", "run"]);
    assert!(
        text(&h.stdout).contains("Usage: vclay run"),
        "{}",
        text(&h.stdout)
    );
    let e = err(&["help", "nope"]);
    assert!(e.contains("no command `nope`"), "{e}");
}

#[test]
fn reading_our_own_step_file_warns_only_about_what_is_dropped() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    std::fs::write(
        d.join("c.json"),
        r#"{"type": "nurbs-curve", "degree": 1, "knots": [0, 0, 1, 1],
            "control_points": [[0, 0, 0], [1, 0, 0]]}"#,
    )
    .unwrap();
    let out = vclay(d, &["convert", "c.json", "c.step"]);
    assert!(out.status.success(), "{}", text(&out.stderr));
    let back = vclay(d, &["convert", "c.step", "back.json"]);
    assert!(back.status.success(), "{}", text(&back.stderr));
    let e = text(&back.stderr);
    for noise in [
        "not read",
        "PRODUCT",
        "_CONTEXT",
        "UNIT",
        "not imported as separate",
    ] {
        assert!(!e.contains(noise), "{noise}: {e}");
    }
}

/// Issue 29 item 3: `vclay convert LATTICE.ovm` estimated its limit patches one level too deep
/// (8x too much: a level-3 torus asked for 11.2 GB and ran in 2.07 GB); the estimate now
/// follows the sample level (`docs/limits.md`: within 1.5x of the measured peaks). The
/// 128-cell torus samples 65,536 cells: 79 MB now, 398 MB before, so a 200M limit takes it.
/// Limits read as given (50M, 4G).
#[test]
fn lattice_patch_estimate_follows_the_sample_level() {
    let dir = tempfile::tempdir().unwrap();
    let made = vclay(
        dir.path(),
        &[
            "subdivide",
            "--primitive",
            "torus",
            "--levels",
            "0",
            "--out",
            "t.ovm",
        ],
    );
    assert!(made.status.success(), "{}", text(&made.stderr));
    let ok = vclay(
        dir.path(),
        &["--max-memory", "200M", "convert", "t.ovm", "t.step"],
    );
    assert!(ok.status.success(), "{}", text(&ok.stderr));
    let refused = vclay(
        dir.path(),
        &["--max-memory", "50M", "convert", "t.ovm", "u.step"],
    );
    assert_eq!(refused.status.code(), Some(2));
    let err = text(&refused.stderr);
    assert!(
        err.contains("128 cells") && err.contains("79 MB") && err.contains("limit of 50M"),
        "{err}"
    );
    assert!(!dir.path().join("u.step").exists());
}
