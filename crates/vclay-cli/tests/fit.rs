//! End-to-end tests of `vclay fit` (issue 20): a synthetic wave scan in `.xyz` and `.ply`
//! fitted to a model file read back by `vclay eval`, to STEP, the report file, and bad clouds
//! (exit code 2, the file and line named, nothing on stdout).

use serde_json::Value;
use std::fmt::Write as _;
use std::path::Path;
use std::process::{Command, Output};

fn vclay(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_vclay"))
        .args(args)
        .output()
        .expect("vclay runs")
}

fn assert_error(out: &Output, needles: &[&str]) {
    assert_eq!(out.status.code(), Some(2), "exit code");
    assert!(out.stdout.is_empty(), "stdout must be empty on error");
    let err = String::from_utf8_lossy(&out.stderr);
    for n in needles {
        assert!(err.contains(n), "stderr {err:?} lacks {n:?}");
    }
}

fn wave(x: f64, y: f64) -> f64 {
    0.15 * (2.0 * x).sin() * (1.5 * y).cos()
}

/// A jittered `m x m` grid of wave points with deterministic "noise" of amplitude `a`.
fn cloud(m: usize, a: f64) -> Vec<[f64; 3]> {
    let mut out = Vec::new();
    for i in 0..m {
        for j in 0..m {
            let k = (i * m + j) as f64;
            let x = -1.0 + 2.0 * (i as f64 + 0.5 + 0.3 * (k * 1.7).sin()) / m as f64;
            let y = -1.0 + 2.0 * (j as f64 + 0.5 + 0.3 * (k * 2.3).cos()) / m as f64;
            out.push([x, y, wave(x, y) + a * (k * 12.9898).sin()]);
        }
    }
    out
}

fn write_xyz(path: &Path, pts: &[[f64; 3]]) {
    let mut s = String::from("# synthetic wave scan\n");
    for p in pts {
        writeln!(s, "{} {} {}", p[0], p[1], p[2]).unwrap();
    }
    std::fs::write(path, s).unwrap();
}

#[test]
fn fits_a_scan_to_model_step_and_report() {
    let dir = tempfile::tempdir().unwrap();
    let scan = dir.path().join("wave.xyz");
    write_xyz(&scan, &cloud(60, 0.002));
    let model = dir.path().join("wave.json");
    let report = dir.path().join("r.json");
    let out = vclay(&[
        "fit",
        scan.to_str().unwrap(),
        "--grid",
        "12x10",
        "--fairness",
        "0,1e-8",
        "--out",
        model.to_str().unwrap(),
        "--report",
        report.to_str().unwrap(),
    ]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let printed: Value = serde_json::from_slice(&out.stdout).unwrap();
    let saved: Value = serde_json::from_str(&std::fs::read_to_string(&report).unwrap()).unwrap();
    assert_eq!(printed, saved);
    assert_eq!(saved["points"], 3600);
    assert_eq!(saved["grid"], serde_json::json!([12, 10]));
    let rms = saved["rms"].as_f64().unwrap();
    // The "noise" is a sine of amplitude 0.002: RMS 0.0014 (less its part the surface absorbs).
    assert!(rms > 0.0008 && rms < 0.0016, "rms {rms}");
    assert!(saved["max"].as_f64().unwrap() < 0.004);
    assert!(saved["fairness_energy"].as_f64().unwrap() > 0.0);
    for k in [
        "read",
        "assemble",
        "solve",
        "correct",
        "distances",
        "total",
        "write",
    ] {
        assert!(saved["timings"][k].as_f64().unwrap() >= 0.0, "timing {k}");
    }
    // The model reads back: a surface point near the middle lies on the wave.
    let ev = vclay(&[
        "eval",
        model.to_str().unwrap(),
        "--at",
        "0.5,0.5",
        "--at",
        "0.3,0.8",
    ]);
    assert!(
        ev.status.success(),
        "{}",
        String::from_utf8_lossy(&ev.stderr)
    );
    let ev: Value = serde_json::from_slice(&ev.stdout).unwrap();
    for p in ev["points"].as_array().unwrap() {
        let p: Vec<f64> = p
            .as_array()
            .unwrap()
            .iter()
            .map(|c| c.as_f64().unwrap())
            .collect();
        assert!(
            (p[2] - wave(p[0], p[1])).abs() < 0.004,
            "{p:?} off the wave"
        );
    }
    // STEP.
    let step = dir.path().join("wave.step");
    let out = vclay(&[
        "fit",
        scan.to_str().unwrap(),
        "--grid",
        "8",
        "--out",
        step.to_str().unwrap(),
    ]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let text = std::fs::read_to_string(&step).unwrap();
    assert!(text.starts_with("ISO-10303-21;") && text.contains("B_SPLINE_SURFACE_WITH_KNOTS"));
}

#[test]
fn robust_and_weights_options_reach_the_report() {
    let dir = tempfile::tempdir().unwrap();
    let mut pts = cloud(40, 0.001);
    for k in (0..pts.len()).step_by(25) {
        pts[k][2] += 0.4;
    }
    // A vertex-only PLY.
    let ply = dir.path().join("wave.ply");
    let mut s = format!(
        "ply\nformat ascii 1.0\nelement vertex {}\nproperty double x\nproperty double y\nproperty double z\nend_header\n",
        pts.len()
    );
    for p in &pts {
        writeln!(s, "{} {} {}", p[0], p[1], p[2]).unwrap();
    }
    std::fs::write(&ply, s).unwrap();
    let model = dir.path().join("w.json");
    let out = vclay(&[
        "fit",
        ply.to_str().unwrap(),
        "--grid",
        "8",
        "--robust",
        "--weights",
        "--out",
        model.to_str().unwrap(),
    ]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let r: Value = serde_json::from_slice(&out.stdout).unwrap();
    assert_eq!(r["robust"], "tukey");
    assert_eq!(r["rational"], true);
    assert_eq!(r["outliers"], 64);
    assert!(r["rms_inliers"].as_f64().unwrap() < 0.002, "{r}");
    let out = vclay(&[
        "fit",
        ply.to_str().unwrap(),
        "--grid",
        "8",
        "--robust",
        "huber",
        "--out",
        model.to_str().unwrap(),
    ]);
    assert!(out.status.success());
    let r: Value = serde_json::from_slice(&out.stdout).unwrap();
    assert_eq!(r["robust"], "huber");
}

#[test]
fn bad_clouds_and_options_are_located_errors() {
    let dir = tempfile::tempdir().unwrap();
    let d = |name: &str| dir.path().join(name).to_str().unwrap().to_string();
    std::fs::write(d("nan.xyz"), "0 0 0\n1 0 0\n\n0 1 nan\n").unwrap();
    assert_error(
        &vclay(&["fit", &d("nan.xyz"), "--out", &d("o.json")]),
        &["nan.xyz:4: column 5", "not a finite number"],
    );
    std::fs::write(d("short.xyz"), "0 0 0\n1 0\n").unwrap();
    assert_error(
        &vclay(&["fit", &d("short.xyz"), "--out", &d("o.json")]),
        &["short.xyz:2", "expected 3 coordinates"],
    );
    std::fs::write(d("line.xyz"), "0 0 0\n1 1 1\n2 2 2\n3 3 3\n").unwrap();
    assert_error(
        &vclay(&["fit", &d("line.xyz"), "--grid", "4", "--out", &d("o.json")]),
        &["line.xyz", "on a line"],
    );
    std::fs::write(d("two.xyz"), "0 0 0\n1 1 1\n").unwrap();
    assert_error(
        &vclay(&["fit", &d("two.xyz"), "--out", &d("o.json")]),
        &["2 points are too few"],
    );
    write_xyz(&dir.path().join("few.xyz"), &cloud(10, 0.0));
    assert_error(
        &vclay(&[
            "fit",
            &d("few.xyz"),
            "--grid",
            "32x32",
            "--fairness",
            "0,0",
            "--out",
            &d("o.json"),
        ]),
        &["100 points are too few", "1024 control points"],
    );
    // Issue 29 item 1: a net the points cannot determine is fitted with a warning that says
    // how many points it needs (the fairness term shapes the rest), and -q silences it.
    let out = vclay(&["fit", &d("few.xyz"), "--out", &d("few.json")]);
    assert!(out.status.success());
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(
        err.contains("warning") && err.contains("100 points") && err.contains("1024 points"),
        "{err}"
    );
    let r: Value = serde_json::from_slice(&out.stdout).unwrap();
    assert_eq!(r["warnings"].as_array().unwrap().len(), 1);
    assert!(r["worst_region"]["rms"].as_f64().is_some(), "{r}");
    let out = vclay(&["-q", "fit", &d("few.xyz"), "--out", &d("few.json")]);
    assert!(out.status.success() && out.stderr.is_empty());
    std::fs::remove_file(d("few.json")).unwrap();
    assert_error(
        &vclay(&["fit", &d("few.xyz"), "--grid", "3x8", "--out", &d("o.json")]),
        &["grid = 3x8"],
    );
    assert_error(
        &vclay(&[
            "fit",
            &d("few.xyz"),
            "--grid",
            "9x9x9",
            "--out",
            &d("o.json"),
        ]),
        &["--grid 9x9x9"],
    );
    assert_error(
        &vclay(&[
            "fit",
            &d("few.xyz"),
            "--fairness",
            "1",
            "--out",
            &d("o.json"),
        ]),
        &["--fairness 1", "ALPHA,BETA"],
    );
    assert_error(
        &vclay(&[
            "fit",
            &d("few.xyz"),
            "--fairness",
            "0,-1",
            "--out",
            &d("o.json"),
        ]),
        &["non-negative"],
    );
    assert_error(
        &vclay(&["fit", &d("few.xyz"), "--out", &d("o.obj")]),
        &["o.obj", "unknown output format"],
    );
    assert_error(
        &vclay(&["fit", &d("missing.xyz"), "--out", &d("o.json")]),
        &["missing.xyz"],
    );
    assert_error(
        &vclay(&[
            "--max-memory",
            "1K",
            "fit",
            &d("few.xyz"),
            "--out",
            &d("o.json"),
        ]),
        &["more than the limit", "--max-memory"],
    );
    assert!(!dir.path().join("o.json").exists());
}
