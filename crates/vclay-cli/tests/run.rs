//! `vclay run`: dispatch on `[model] kind`, a small run, and located errors.

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
    // A solid's keys under a D-NURBS kind are rejected by the D-NURBS reader, with a line.
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
