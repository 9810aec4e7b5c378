//! End-to-end tests of `vclay render` and `vclay convert`: pictures of models and meshes, format
//! round trips through every readable format, and refused conversions (exit code 2, a message,
//! nothing on stdout).

use serde_json::Value;
use std::path::Path;
use std::process::{Command, Output};

fn vclay(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_vclay"))
        .args(args)
        .output()
        .expect("vclay runs")
}

fn ok(args: &[&str]) {
    let out = vclay(args);
    assert!(
        out.status.success(),
        "{args:?}: {}",
        String::from_utf8_lossy(&out.stderr)
    );
}

fn assert_error(out: &Output, needles: &[&str]) {
    assert_eq!(out.status.code(), Some(2), "exit code");
    assert!(out.stdout.is_empty(), "stdout must be empty on error");
    let err = String::from_utf8_lossy(&out.stderr);
    for n in needles {
        assert!(err.contains(n), "stderr {err:?} lacks {n:?}");
    }
}

/// A rational biquadratic patch (a quarter cylinder, bent) with a repeated interior knot.
const MODEL: &str = r#"{"entities": [{"type": "nurbs-surface", "name": "patch", "degree": [2, 2],
  "knots": [[0, 0, 0, 1, 1, 1], [0, 0, 0, 0.5, 0.5, 1, 1, 1]],
  "control_points": [
    [[1, 0, 0], [1, 0, 0.5], [1, 0, 1], [1, 0, 1.5], [1.2, 0, 2]],
    [[1, 1, 0], [1, 1, 0.5], [1, 1, 1], [1, 1, 1.5], [1.2, 1.2, 2]],
    [[0, 1, 0], [0, 1, 0.5], [0, 1, 1], [0, 1, 1.5], [0, 1.2, 2]]],
  "weights": [[1, 1, 1, 1, 1], [0.7071067811865476, 0.7071067811865476, 0.7071067811865476, 0.7071067811865476, 0.7071067811865476], [1, 1, 1, 1, 1]]}]}"#;

fn png_size(path: &Path) -> (u32, u32) {
    let b = std::fs::read(path).unwrap();
    assert_eq!(&b[..8], b"\x89PNG\r\n\x1a\n", "PNG signature");
    let w = u32::from_be_bytes(b[16..20].try_into().unwrap());
    let h = u32::from_be_bytes(b[20..24].try_into().unwrap());
    (w, h)
}

fn s(p: &Path) -> &str {
    p.to_str().unwrap()
}

#[test]
fn render_model_and_mesh_to_png_and_gif() {
    let dir = tempfile::tempdir().unwrap();
    let model = dir.path().join("patch.json");
    std::fs::write(&model, MODEL).unwrap();
    let png = dir.path().join("patch.png");
    ok(&[
        "render",
        s(&model),
        "--out",
        s(&png),
        "--size",
        "64x48",
        "--wireframe",
    ]);
    assert_eq!(png_size(&png), (64, 48));
    let obj = dir.path().join("patch.obj");
    ok(&["convert", s(&model), s(&obj), "--samples", "8"]);
    let png2 = dir.path().join("mesh.png");
    ok(&[
        "render",
        s(&obj),
        "--out",
        s(&png2),
        "--size",
        "40x30",
        "--view",
        "top",
        "--ortho",
    ]);
    assert_eq!(png_size(&png2), (40, 30));
    let gif = dir.path().join("turn.gif");
    ok(&[
        "render",
        s(&obj),
        "--out",
        s(&gif),
        "--size",
        "32x24",
        "--frames",
        "3",
    ]);
    let b = std::fs::read(&gif).unwrap();
    assert_eq!(&b[..6], b"GIF89a");
    // Three image descriptors (0x2C after a graphic control extension block).
    assert_eq!(b.windows(2).filter(|w| w == &[0x00, 0x2C]).count(), 3);
}

#[test]
fn render_rejects_bad_arguments() {
    let dir = tempfile::tempdir().unwrap();
    let model = dir.path().join("patch.json");
    std::fs::write(&model, MODEL).unwrap();
    let out = dir.path().join("x.png");
    assert_error(
        &vclay(&["render", s(&model), "--out", s(&out), "--size", "0x5"]),
        &["--size '0x5'"],
    );
    assert_error(
        &vclay(&["render", s(&model), "--out", s(&out), "--view", "back"]),
        &["--view 'back'"],
    );
    let bmp = dir.path().join("x.bmp");
    assert_error(
        &vclay(&["render", s(&model), "--out", s(&bmp)]),
        &["x.bmp", "expected .png or .gif"],
    );
    let bad = dir.path().join("bad.json");
    std::fs::write(&bad, MODEL.replace("[1, 0, 0.5]", "[1, 0]")).unwrap();
    assert_error(
        &vclay(&["render", s(&bad), "--out", s(&out)]),
        &["bad.json", "control_points[0][1]"],
    );
    assert!(!out.exists(), "no picture written on error");
}

fn entity(path: &Path) -> Value {
    let v: Value = serde_json::from_str(&std::fs::read_to_string(path).unwrap()).unwrap();
    v["entities"][0].clone()
}

#[test]
fn convert_round_trips_model_geomdl_and_meshes() {
    let dir = tempfile::tempdir().unwrap();
    let p = |f: &str| dir.path().join(f);
    std::fs::write(p("m.json"), MODEL).unwrap();
    // Model -> geomdl -> model: exact.
    ok(&["convert", s(&p("m.json")), s(&p("m.geomdl.json"))]);
    let g: Value =
        serde_json::from_str(&std::fs::read_to_string(p("m.geomdl.json")).unwrap()).unwrap();
    assert_eq!(g["shape"]["type"], "surface");
    assert_eq!(g["shape"]["data"][0]["size_v"], 5);
    ok(&["convert", s(&p("m.geomdl.json")), s(&p("back.json"))]);
    let (a, b) = (entity(&p("m.json")), entity(&p("back.json")));
    for k in ["degree", "knots", "control_points", "weights", "name"] {
        let (x, y) = (&a[k], &b[k]);
        let num = |v: &Value| v.to_string().replace(".0", "");
        assert_eq!(num(x), num(y), "field {k}");
    }
    // Model -> STEP: exact B-spline entities.
    ok(&["convert", s(&p("m.json")), s(&p("m.step"))]);
    let step = std::fs::read_to_string(p("m.step")).unwrap();
    assert!(step.contains("RATIONAL_B_SPLINE_SURFACE"));
    assert!(step.contains("B_SPLINE_SURFACE_WITH_KNOTS((3,3),(3,2,3),(0.,1.),(0.,0.5,1.)"));
    ok(&["convert", s(&p("m.json")), s(&p("m.igs"))]);
    let iges = std::fs::read_to_string(p("m.igs")).unwrap();
    assert!(iges.lines().all(|l| l.len() == 80));
    let pdata: String = iges
        .lines()
        .filter(|l| &l[72..73] == "P")
        .map(|l| l[..64].trim_end())
        .collect();
    assert!(
        pdata.starts_with("128,2,4,2,2,0,0,0,0,0,0.,0.,0.,1.,1.,1.,0.,0.,0.,0.5,0.5,1.,1.,1.,")
    );
    // Model -> OBJ -> GLB -> STL -> PLY: the triangle count survives every hop.
    ok(&["convert", s(&p("m.json")), s(&p("m.obj")), "--samples", "6"]);
    ok(&["convert", s(&p("m.obj")), s(&p("m.glb"))]);
    ok(&["convert", s(&p("m.glb")), s(&p("m.stl"))]);
    ok(&["convert", s(&p("m.stl")), s(&p("m.ply"))]);
    let stl = std::fs::read(p("m.stl")).unwrap();
    let facets = u32::from_le_bytes(stl[80..84].try_into().unwrap());
    let obj_faces = std::fs::read_to_string(p("m.obj"))
        .unwrap()
        .lines()
        .filter(|l| l.starts_with("f "))
        .count() as u32;
    assert_eq!(facets, obj_faces);
    // 6 x 6 samples: 5 x 5 quads, but the double knot v = 0.5 (a C0 line) gets a sample line
    // of its own on each side, so v has 2 + 2 intervals (issue 28: sharp creases).
    assert_eq!(facets, 2 * 5 * 4);
}

#[test]
fn convert_refuses_what_cannot_be_done() {
    let dir = tempfile::tempdir().unwrap();
    let p = |f: &str| dir.path().join(f);
    std::fs::write(p("m.json"), MODEL).unwrap();
    ok(&["convert", s(&p("m.json")), s(&p("m.obj")), "--samples", "4"]);
    assert_error(
        &vclay(&["convert", s(&p("m.obj")), s(&p("m.step"))]),
        &["is a mesh", "exact NURBS"],
    );
    assert_error(
        &vclay(&["convert", s(&p("m.json")), s(&p("m.xyz"))]),
        &["m.xyz", "unknown output format"],
    );
    assert_error(
        &vclay(&["convert", s(&p("nothere.json")), s(&p("m.obj"))]),
        &["nothere.json"],
    );
    assert_error(
        &vclay(&["convert", s(&p("m.obj")), s(&p("m.igs"))]),
        &["is a mesh"],
    );
    assert!(!p("m.step").exists() && !p("m.igs").exists());
}
