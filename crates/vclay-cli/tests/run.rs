//! `vclay run`: a small run, located errors, sessions continued exactly, the output rule.

use std::path::Path;
use std::process::Command;

const SMALL: &str = r#"
[model]
kind = "subdivision-solid"
points = [2, 2, 2]
level = 1

[simulation]
steps = 10

[[timeline]]
action = "rope"
at = 0.0
from = [1.0, 1.0, 1.0]
to = [1.2, 1.0, 1.0]
until = 0.005

[output]
frames = ["obj"]
every = 5
csv = "energy.csv"
final = "final.ovm"
"#;

fn vclay(args: &[&str]) -> std::process::Output {
    Command::new(env!("CARGO_BIN_EXE_vclay"))
        .args(args)
        .output()
        .unwrap()
}

#[test]
fn runs_a_scenario_and_prints_a_summary() {
    let dir = tempfile::tempdir().unwrap();
    let sc = dir.path().join("s.toml");
    std::fs::write(&sc, SMALL).unwrap();
    let out = dir.path().join("out");
    let o = vclay(&["run", sc.to_str().unwrap(), "--out", out.to_str().unwrap()]);
    let stdout = String::from_utf8_lossy(&o.stdout);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    assert!(
        stdout.contains("10 steps") && stdout.contains("final energy"),
        "{stdout}"
    );
    for f in ["frame_000010.obj", "energy.csv", "final.ovm"] {
        assert!(out.join(f).exists(), "{f}");
    }
}

#[test]
fn unknown_kind_and_bad_keys_fail_with_location() {
    let dir = tempfile::tempdir().unwrap();
    let sc = dir.path().join("bad.toml");
    std::fs::write(&sc, SMALL.replace("subdivision-solid", "clay-blob")).unwrap();
    let o = vclay(&["run", sc.to_str().unwrap()]);
    assert_eq!(o.status.code(), Some(2));
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(
        err.contains("clay-blob") && err.contains("known kinds") && err.contains("dnurbs-swung"),
        "{err}"
    );
    // A solid's keys under a D-NURBS kind are rejected by the D-NURBS builder, with a line.
    std::fs::write(&sc, SMALL.replace("subdivision-solid", "dnurbs-curve")).unwrap();
    let o = vclay(&["run", sc.to_str().unwrap()]);
    assert_eq!(o.status.code(), Some(2));
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(err.contains("bad.toml:"), "{err}");
    std::fs::write(&sc, SMALL.replace("steps = 10", "stepz = 10")).unwrap();
    let o = vclay(&["run", sc.to_str().unwrap()]);
    assert_eq!(o.status.code(), Some(2));
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(err.contains("bad.toml:") && err.contains("stepz"), "{err}");
}

/// `vclay run s.toml --steps N --save a.session` then `vclay run a.session --steps N` ends in
/// the same state as `vclay run s.toml --steps 2N` (the final model files compare equal), for
/// a solid with a timeline that spans the cut, and for a D-NURBS swung surface with a moving
/// spring and a constraint.
#[test]
fn a_saved_session_continues_like_the_uninterrupted_run() {
    let dir = tempfile::tempdir().unwrap();
    let solid = SMALL
        .replace("steps = 10", "steps = 40\ndt = 0.002")
        .replace(
            "[output]",
            "[[timeline]]\naction = \"fix\"\nat = 0.03\npoints = [0]\n\n[[timeline]]\naction = \"release\"\nat = 0.05\nname = \"rope0\"\n\n[output]",
        );
    let swung = std::fs::read_to_string(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../../examples/scenarios/fig9a_swung_egg.toml"
    ))
    .unwrap()
    .replace("steps = 400", "steps = 40");
    for (name, text, n, fin) in [
        ("solid", solid, "20", "final.ovm"),
        ("swung", swung, "20", "final.json"),
    ] {
        let sc = dir.path().join(format!("{name}.toml"));
        std::fs::write(&sc, text).unwrap();
        let d = |s: &str| dir.path().join(format!("{name}-{s}"));
        let session = dir.path().join(format!("{name}.session"));
        let run = |args: &[&str]| {
            let o = vclay(args);
            assert!(
                o.status.success(),
                "{args:?}: {}",
                String::from_utf8_lossy(&o.stderr)
            );
            String::from_utf8_lossy(&o.stdout).to_string()
        };
        let s = sc.to_str().unwrap();
        run(&[
            "run",
            s,
            "--steps",
            n,
            "--save",
            session.to_str().unwrap(),
            "--out",
            d("a").to_str().unwrap(),
            "--quiet",
        ]);
        let out = run(&[
            "run",
            session.to_str().unwrap(),
            "--out",
            d("b").to_str().unwrap(),
            "--quiet",
        ]);
        assert!(
            out.contains(&format!("{n} steps")),
            "continues to the scenario's end: {out}"
        );
        run(&["run", s, "--out", d("c").to_str().unwrap(), "--quiet"]);
        let b = std::fs::read(d("b").join(fin)).unwrap();
        let c = std::fs::read(d("c").join(fin)).unwrap();
        assert!(
            b == c,
            "{name}: the continued run differs from the uninterrupted one"
        );
        let a = std::fs::read(d("a").join(fin)).unwrap();
        assert!(a != c, "{name}: the second half changed nothing");
        // The summary lists every file written.
        assert!(out.contains("files written") && out.contains(fin), "{out}");
    }
}

/// Without `--out`, a run writes to `./vclay-run/<scenario name>/` in the current folder,
/// never beside the scenario file.
#[test]
fn the_default_output_folder_is_under_the_current_folder() {
    let src = tempfile::tempdir().unwrap();
    let cwd = tempfile::tempdir().unwrap();
    let sc = src.path().join("tiny.toml");
    std::fs::write(&sc, SMALL).unwrap();
    let o = Command::new(env!("CARGO_BIN_EXE_vclay"))
        .args(["run", sc.to_str().unwrap(), "--quiet"])
        .current_dir(cwd.path())
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    assert!(cwd.path().join("vclay-run/tiny/final.ovm").exists());
    let beside: Vec<_> = std::fs::read_dir(src.path()).unwrap().collect();
    assert_eq!(beside.len(), 1, "nothing written beside the scenario");
}

/// Issue 29 item 2: a run checks its output before the first step: an unwritable folder, more
/// output than `--max-output`, an energy table over `--max-memory` are errors at once (a run of
/// 10^8 steps would take hours), and never name an internal temporary file.
#[test]
fn a_run_checks_its_output_before_the_first_step() {
    let dir = tempfile::tempdir().unwrap();
    let sc = dir.path().join("s.toml");
    std::fs::write(&sc, SMALL).unwrap();
    let sc = sc.to_str().unwrap();
    let out = dir.path().join("out");
    let o = out.to_str().unwrap();
    let fails = |args: &[&str], needles: &[&str]| {
        let t = std::time::Instant::now();
        let r = vclay(args);
        let err = String::from_utf8_lossy(&r.stderr);
        assert_eq!(r.status.code(), Some(2), "{args:?}: {err}");
        for n in needles {
            assert!(err.contains(n), "{args:?}: {err:?} lacks {n:?}");
        }
        assert!(!err.contains(".vclay-"), "{err}");
        assert!(t.elapsed().as_secs_f64() < 20.0, "{args:?} ran");
    };
    // 201 frames of some kB each: more than 100 kB.
    fails(
        &[
            "run",
            sc,
            "--steps",
            "1000",
            "--max-output",
            "100K",
            "--out",
            o,
        ],
        &["1000 steps would write about", "201 frames", "output limit"],
    );
    assert_eq!(std::fs::read_dir(&out).unwrap().count(), 0, "nothing left");
    // The energy table of 10^6 steps is held in memory: 160 MB.
    fails(
        &[
            "--max-memory",
            "10M",
            "run",
            sc,
            "--steps",
            "1000000",
            "--out",
            o,
        ],
        &[
            "1000000 steps",
            "energy table",
            "limit of 10M",
            "raise --max-memory",
        ],
    );
    // An existing folder the process cannot write to (Linux's /sys, even as root).
    if std::fs::write("/sys/vclay-probe", "").is_err() && Path::new("/sys").is_dir() {
        fails(
            &["run", sc, "--steps", "100000000", "--out", "/sys"],
            &["/sys", "not writable"],
        );
    }
    // Within the limits it runs.
    let r = vclay(&["run", sc, "--max-output", "10M", "--out", o]);
    assert!(r.status.success(), "{}", String::from_utf8_lossy(&r.stderr));
}
