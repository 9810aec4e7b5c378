//! `vclay convert` to STEP and IGES writes B-reps (issue 20): a closed surface becomes a solid,
//! an open one an open shell, and `--loose` keeps the loose-surface layout.

use std::path::Path;
use std::process::{Command, Output};

fn vclay(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_vclay"))
        .args(args)
        .output()
        .expect("vclay runs")
}

/// The exact torus (major radius 2, minor 0.5) of `NurbsSurface::torus`, as model JSON, and an
/// open bilinear sheet.
fn model() -> String {
    let h = std::f64::consts::FRAC_1_SQRT_2;
    let circ = [
        (1., 0.),
        (1., 1.),
        (0., 1.),
        (-1., 1.),
        (-1., 0.),
        (-1., -1.),
        (0., -1.),
        (1., -1.),
        (1., 0.),
    ];
    let cw = [1., h, 1., h, 1., h, 1., h, 1.];
    let (mut rows, mut wrows) = (Vec::new(), Vec::new());
    for (&(a, b), &w) in circ.iter().zip(&cw) {
        let (x, z) = (2.0 + 0.5 * a, -0.5 * b);
        let row: Vec<String> = circ
            .iter()
            .map(|&(c, d)| format!("[{}, {}, {}]", x * c, x * d, z))
            .collect();
        rows.push(format!("[{}]", row.join(", ")));
        let wr: Vec<String> = cw.iter().map(|c| (w * c).to_string()).collect();
        wrows.push(format!("[{}]", wr.join(", ")));
    }
    let k = "[0, 0, 0, 0.25, 0.25, 0.5, 0.5, 0.75, 0.75, 1, 1, 1]";
    format!(
        r#"{{"entities": [
        {{"type": "nurbs-surface", "name": "torus", "degree": [2, 2], "knots": [{k}, {k}],
          "control_points": [{}], "weights": [{}]}},
        {{"type": "nurbs-surface", "degree": [1, 1], "knots": [[0, 0, 1, 1], [0, 0, 1, 1]],
          "control_points": [[[0, 0, 3], [0, 1, 3]], [[1, 0, 3], [1, 1, 3.5]]]}}]}}"#,
        rows.join(", "),
        wrows.join(", ")
    )
}

fn convert(dir: &Path, out: &str, extra: &[&str]) -> (String, String) {
    let input = dir.join("m.json");
    std::fs::write(&input, model()).unwrap();
    let o = dir.join(out);
    let mut args = vec!["convert", input.to_str().unwrap(), o.to_str().unwrap()];
    args.extend(extra);
    let r = vclay(&args);
    assert!(r.status.success(), "{}", String::from_utf8_lossy(&r.stderr));
    (
        std::fs::read_to_string(o).unwrap(),
        String::from_utf8_lossy(&r.stderr).into_owned(),
    )
}

#[test]
fn closed_surfaces_become_solids_and_open_ones_shells() {
    let dir = tempfile::tempdir().unwrap();
    let (step, err) = convert(dir.path(), "m.step", &[]);
    assert!(
        err.contains("1 solid(s), 1 open shell(s), 0 curve(s)"),
        "{err}"
    );
    assert_eq!(step.matches("MANIFOLD_SOLID_BREP(").count(), 1);
    assert_eq!(step.matches("CLOSED_SHELL(").count(), 1);
    assert_eq!(step.matches("OPEN_SHELL(").count(), 1);
    assert_eq!(step.matches("ADVANCED_FACE(").count(), 2);
    // Torus: 1 vertex, 2 seams; sheet: 4 vertices, 4 edges.
    assert_eq!(step.matches("=VERTEX_POINT(").count(), 5);
    assert_eq!(step.matches("=EDGE_CURVE(").count(), 6);
    assert!(!step.contains("GEOMETRIC_SET"));
    let (iges, _) = convert(dir.path(), "m.igs", &[]);
    let types: Vec<&str> = iges
        .lines()
        .filter(|l| &l[72..73] == "D")
        .step_by(2)
        .map(|l| l[..8].trim())
        .collect();
    assert_eq!(types.iter().filter(|t| **t == "186").count(), 1);
    assert_eq!(types.iter().filter(|t| **t == "514").count(), 2);
    assert_eq!(types.iter().filter(|t| **t == "510").count(), 2);
    // --loose: the geometric set and independent 128 surfaces, no topology.
    let (step, err) = convert(dir.path(), "l.step", &["--loose"]);
    assert!(step.contains("GEOMETRIC_SET") && !step.contains("SHELL"));
    assert!(!err.contains("solid(s)"), "{err}");
    let (iges, _) = convert(dir.path(), "l.igs", &["--loose"]);
    let types: Vec<&str> = iges
        .lines()
        .filter(|l| &l[72..73] == "D")
        .step_by(2)
        .map(|l| l[..8].trim())
        .collect();
    assert_eq!(types, ["128", "128"]);
}

#[test]
fn subdivision_solid_limit_patches_join_into_a_solid() {
    let dir = tempfile::tempdir().unwrap();
    let ovm = dir.path().join("box.ovm");
    let r = vclay(&[
        "subdivide",
        "--primitive",
        "box:3x3x3",
        "--levels",
        "0",
        "--out",
        ovm.to_str().unwrap(),
        "-q",
    ]);
    assert!(r.status.success(), "{}", String::from_utf8_lossy(&r.stderr));
    let step = dir.path().join("box.step");
    let r = vclay(&["convert", ovm.to_str().unwrap(), step.to_str().unwrap()]);
    let err = String::from_utf8_lossy(&r.stderr);
    assert!(r.status.success(), "{err}");
    assert!(err.contains("1 solid(s), 0 open shell(s)"), "{err}");
    let text = std::fs::read_to_string(&step).unwrap();
    let faces = text.matches("=ADVANCED_FACE(").count();
    assert!(faces >= 24, "{faces} faces");
    assert_eq!(text.matches("=MANIFOLD_SOLID_BREP(").count(), 1);
    // Quad patches on a closed surface: every edge is shared by two faces (E = 2F), and
    // Euler's formula for a sphere-like surface V - E + F = 2.
    let e = text.matches("=EDGE_CURVE(").count();
    let v = text.matches("=VERTEX_POINT(").count();
    assert_eq!(e, 2 * faces);
    assert_eq!(v as i64 - e as i64 + faces as i64, 2);
}
