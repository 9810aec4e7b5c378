//! End-to-end tests of `vclay eval LATTICE.ovm` (limit of a subdivision solid at `(cell, u, v,
//! w)`, issue 19) and `vclay convert LATTICE.ovm OUT.step` (limit patches, issue 20): values,
//! located errors (exit code 2, nothing on stdout).

use serde_json::Value;
use std::path::{Path, PathBuf};
use std::process::{Command, Output};

fn vclay(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_vclay"))
        .args(args)
        .output()
        .expect("vclay runs")
}

fn tmp(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("vclay-eval-lattice-{}", std::process::id()));
    std::fs::create_dir_all(&d).unwrap();
    d.join(name)
}

fn box_ovm() -> PathBuf {
    let p = tmp("box.ovm");
    let out = vclay(&[
        "subdivide",
        "--primitive",
        "box",
        "--levels",
        "0",
        "--out",
        p.to_str().unwrap(),
        "-q",
    ]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    p
}

fn assert_error(out: &Output, needles: &[&str]) {
    assert_eq!(out.status.code(), Some(2), "exit code");
    assert!(out.stdout.is_empty(), "stdout must be empty on error");
    let err = String::from_utf8_lossy(&out.stderr);
    for n in needles {
        assert!(err.contains(n), "stderr {err:?} lacks {n:?}");
    }
}

fn write(path: &Path, text: &str) -> String {
    std::fs::write(path, text).unwrap();
    path.to_str().unwrap().to_string()
}

#[test]
fn eval_lattice_gives_limit_points_and_derivatives() {
    let ovm = box_ovm();
    let params = write(
        &tmp("p.json"),
        "[[13, 0.5, 0.5, 0.5], [13, 0.25, 0.5, 0.75], [0, 0.0, 0.0, 0.0]]",
    );
    let out = vclay(&[
        "eval",
        ovm.to_str().unwrap(),
        "--params",
        &params,
        "--derivatives",
        "1",
    ]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let v: Value = serde_json::from_slice(&out.stdout).unwrap();
    let pts = v["points"].as_array().unwrap();
    assert_eq!(pts.len(), 3);
    // The 4x4x4-point unit-spaced box: its centre cell is regular and symmetric, so the limit
    // at its centre is the box centre and x_u = (1, 0, 0).
    let p0: Vec<f64> = pts[0]
        .as_array()
        .unwrap()
        .iter()
        .map(|x| x.as_f64().unwrap())
        .collect();
    for c in p0 {
        assert!((c - 1.5).abs() < 1e-12);
    }
    assert_eq!(v["exact"][0], Value::Bool(true));
    assert!((v["derivatives"][0][0][0].as_f64().unwrap() - 1.0).abs() < 1e-12);
    // The box corner is on the boundary: stopped at the tolerance, with an error estimate.
    assert_eq!(v["exact"][2], Value::Bool(false));
    assert!(v["error_estimate"][2].as_f64().unwrap() <= v["tolerance"].as_f64().unwrap());
    // Sharp boundary: the box corner stays.
    let out = vclay(&[
        "eval",
        ovm.to_str().unwrap(),
        "--at",
        "0,0,0,0",
        "--boundary",
        "sharp",
    ]);
    assert!(out.status.success());
    let v: Value = serde_json::from_slice(&out.stdout).unwrap();
    for c in v["points"][0].as_array().unwrap() {
        assert!(c.as_f64().unwrap().abs() < 1e-9, "{v}");
    }
}

#[test]
fn eval_lattice_errors_are_located() {
    let ovm = box_ovm();
    let o = ovm.to_str().unwrap();
    let p = write(&tmp("b1.json"), "[[1, 0.5, 0.5, 0.5], [99, 0.5, 0.5, 0.5]]");
    assert_error(
        &vclay(&["eval", o, "--params", &p]),
        &[
            "b1.json",
            "limit query 1",
            "cell 99 is out of range (27 cells)",
        ],
    );
    let p = write(&tmp("b2.json"), "[[1, 0.5, -0.25, 0.5]]");
    assert_error(
        &vclay(&["eval", o, "--params", &p]),
        &["limit query 0", "v = -0.25 is outside [0, 1]"],
    );
    let p = write(&tmp("b3.json"), "[[1, 0.5, 0.5]]");
    assert_error(
        &vclay(&["eval", o, "--params", &p]),
        &["parameter tuple 0", "expected 4 numbers [cell, u, v, w]"],
    );
    let p = write(&tmp("b4.json"), "[[1.5, 0.5, 0.5, 0.5]]");
    assert_error(
        &vclay(&["eval", o, "--params", &p]),
        &["not a non-negative integer"],
    );
    let p = write(&tmp("b5.json"), "[[1, 0.5,\n 0.5 0.5]]");
    assert_error(&vclay(&["eval", o, "--params", &p]), &["b5.json", "line 2"]);
    assert_error(
        &vclay(&["eval", o, "--at", "1,nan,0,0"]),
        &["u = \"nan\" is not a finite number"],
    );
    assert_error(
        &vclay(&["eval", o, "--at", "1,0,0,0", "--derivatives", "2"]),
        &["first derivatives only"],
    );
    // A prism of the cylinder is not a hexahedron.
    let cyl = tmp("cyl.ovm");
    let c = cyl.to_str().unwrap();
    assert!(
        vclay(&[
            "subdivide",
            "--primitive",
            "cylinder",
            "--levels",
            "0",
            "--out",
            c,
            "-q"
        ])
        .status
        .success()
    );
    assert_error(
        &vclay(&["eval", c, "--at", "0,0.5,0.5,0.5"]),
        &["is not a hexahedron"],
    );
}

#[test]
fn convert_lattice_writes_limit_patches_to_step() {
    let ovm = box_ovm();
    let step = tmp("box.step");
    let out = vclay(&["convert", ovm.to_str().unwrap(), step.to_str().unwrap()]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(
        err.contains("54 bicubic patches") && err.contains("30 exact, 24 fitted"),
        "{err}"
    );
    let text = std::fs::read_to_string(&step).unwrap();
    assert_eq!(text.matches("B_SPLINE_SURFACE_WITH_KNOTS").count(), 54);
    // Read back: 54 surfaces.
    let back = tmp("back.json");
    let out = vclay(&[
        "convert",
        step.to_str().unwrap(),
        back.to_str().unwrap(),
        "-q",
    ]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let v: Value = serde_json::from_str(&std::fs::read_to_string(&back).unwrap()).unwrap();
    let n = v
        .get("entities")
        .and_then(Value::as_array)
        .map_or_else(|| v.as_array().map_or(1, Vec::len), Vec::len);
    assert_eq!(n, 54, "{v}");
}

#[test]
fn subdivide_limit_writes_the_limit_surface() {
    let obj = tmp("limit.obj");
    let o = obj.to_str().unwrap();
    let out = vclay(&[
        "subdivide",
        "--primitive",
        "box",
        "--levels",
        "1",
        "--limit",
        "--out",
        o,
    ]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let text = std::fs::read_to_string(&obj).unwrap();
    let verts: Vec<Vec<f64>> = text
        .lines()
        .filter_map(|l| l.strip_prefix("v "))
        .map(|l| l.split_whitespace().map(|x| x.parse().unwrap()).collect())
        .collect();
    // Level 1 of the 4^3-point box: 6 sides of 6 x 6 quads, 7^2 x 6 - 12 x 7 + 8 points.
    assert_eq!(verts.len(), 6 * 49 - 12 * 7 + 8);
    // The limit surface lies strictly inside the control box [0, 3]^3 at its corners.
    assert!(
        verts
            .iter()
            .all(|v| v.iter().all(|&c| (0.0..=3.0).contains(&c)))
    );
    assert!(!verts.iter().any(|v| v.iter().all(|&c| c == 0.0)));
    assert_error(
        &vclay(&[
            "subdivide",
            "--primitive",
            "box",
            "--levels",
            "1",
            "--limit",
            "--out",
            "x.ovm",
        ]),
        &["x.ovm: the limit surface is written to .obj, .ply or .stl only"],
    );
    assert_error(
        &vclay(&[
            "subdivide",
            "--primitive",
            "box",
            "--levels",
            "1",
            "--limit",
            "--boundary",
            "interior",
            "--out",
            o,
        ]),
        &["needs the Smooth or Sharp boundary rule"],
    );
}
