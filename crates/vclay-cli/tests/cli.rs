//! End-to-end tests of the `vclay` binary: `eval` output shapes and values, every bad-input path
//! (exit code 2, message naming the place, nothing on stdout), and `demo`.

use serde_json::Value;
use std::path::{Path, PathBuf};
use std::process::{Command, Output};

fn vclay(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_vclay"))
        .args(args)
        .output()
        .expect("vclay runs")
}

/// Runs `vclay` in the folder `dir`.
fn vclay_in(dir: &Path, args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_vclay"))
        .current_dir(dir)
        .args(args)
        .output()
        .expect("vclay runs")
}

fn write(dir: &Path, name: &str, text: &str) -> PathBuf {
    let p = dir.join(name);
    std::fs::write(&p, text).unwrap();
    p
}

fn eval(model: &Path, params: &Path, extra: &[&str]) -> Output {
    let mut args = vec![
        "eval",
        model.to_str().unwrap(),
        "--params",
        params.to_str().unwrap(),
    ];
    args.extend_from_slice(extra);
    vclay(&args)
}

const CIRCLE: &str = r#"{"type": "nurbs-curve", "degree": 2,
 "knots": [0,0,0,0.25,0.25,0.5,0.5,0.75,0.75,1,1,1],
 "control_points": [[1,0,0],[1,1,0],[0,1,0],[-1,1,0],[-1,0,0],[-1,-1,0],[0,-1,0],[1,-1,0],[1,0,0]],
 "weights": [1, 0.7071067811865476, 1, 0.7071067811865476, 1, 0.7071067811865476, 1, 0.7071067811865476, 1]}"#;

const BILINEAR: &str = r#"[{"type": "nurbs-surface", "degree": [1, 1], "knots": [[0,0,1,1],[0,0,2,2]],
 "control_points": [[[0,0,0],[0,1,0]],[[1,0,0],[1,1,1]]]}]"#;

fn assert_error(out: &Output, needles: &[&str]) {
    assert_eq!(
        out.status.code(),
        Some(2),
        "stderr: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    assert!(out.stdout.is_empty(), "stdout must be empty on error");
    let err = String::from_utf8_lossy(&out.stderr);
    for n in needles {
        assert!(err.contains(n), "stderr {err:?} lacks {n:?}");
    }
}

#[test]
fn eval_circle_points_and_derivatives() {
    let dir = tempfile::tempdir().unwrap();
    let m = write(dir.path(), "circle.json", CIRCLE);
    let p = write(dir.path(), "p.json", "[[0], [0.125], [0.3], [1]]");
    let out = eval(&m, &p, &["--derivatives", "2"]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let v: Value = serde_json::from_slice(&out.stdout).unwrap();
    let pts = v["points"].as_array().unwrap();
    assert_eq!(pts.len(), 4);
    for pt in pts {
        let (x, y) = (pt[0].as_f64().unwrap(), pt[1].as_f64().unwrap());
        assert!(((x * x + y * y).sqrt() - 1.0).abs() < 1e-14);
    }
    let d = v["derivatives"].as_array().unwrap();
    assert_eq!(d[0].as_array().unwrap().len(), 3);
    // First derivative at u = 0 points along +y.
    assert!(d[0][1][1].as_f64().unwrap() > 0.0 && d[0][1][0].as_f64().unwrap().abs() < 1e-12);
    // Without --derivatives there is no derivatives key.
    let out = eval(&m, &p, &[]);
    let v: Value = serde_json::from_slice(&out.stdout).unwrap();
    assert!(v.get("derivatives").is_none());
}

#[test]
fn eval_surface_derivative_table_has_nulls_above_order() {
    let dir = tempfile::tempdir().unwrap();
    let m = write(dir.path(), "s.json", BILINEAR);
    let p = write(dir.path(), "p.json", "[[0.5, 1.0]]");
    let out = eval(&m, &p, &["--derivatives", "2"]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let v: Value = serde_json::from_slice(&out.stdout).unwrap();
    // s(u, v) = (u, v/2, u v/2): s_uv = (0, 0, 1/2).
    let d = &v["derivatives"][0];
    assert_eq!(v["points"][0], serde_json::json!([0.5, 0.5, 0.25]));
    assert_eq!(d[1][1], serde_json::json!([0.0, 0.0, 0.5]));
    assert_eq!(d[0][1], serde_json::json!([0.0, 0.5, 0.25]));
    assert!(d[2][1].is_null() && d[1][2].is_null() && d[2][2].is_null());
    assert_eq!(d[2][0], serde_json::json!([0.0, 0.0, 0.0]));
}

#[test]
fn eval_volume() {
    let dir = tempfile::tempdir().unwrap();
    let m = write(
        dir.path(),
        "v.json",
        r#"{"type": "nurbs-volume", "degree": [1,1,1], "knots": [[0,0,1,1],[0,0,1,1],[0,0,1,1]],
        "control_points": [[[[0,0,0],[0,0,3]],[[0,2,0],[0,2,3]]],[[[1,0,0],[1,0,3]],[[1,2,0],[1,2,3]]]]}"#,
    );
    let p = write(dir.path(), "p.json", "[[0.5, 0.25, 1.0]]");
    let out = eval(&m, &p, &["--derivatives", "1"]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let v: Value = serde_json::from_slice(&out.stdout).unwrap();
    assert_eq!(v["points"][0], serde_json::json!([0.5, 0.5, 3.0]));
    assert_eq!(
        v["derivatives"][0][0][0][1],
        serde_json::json!([0.0, 0.0, 3.0])
    );
    assert!(v["derivatives"][0][1][1][1].is_null());
}

#[test]
fn bad_inputs_exit_2_and_name_the_place() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let good = write(d, "good.json", CIRCLE);
    let params = write(d, "p.json", "[[0.5]]");
    // Parameter outside the domain names the parameter index.
    let outside = write(d, "outside.json", "[[0.5], [1.5]]");
    assert_error(
        &eval(&good, &outside, &[]),
        &["parameter 1", "outside the domain"],
    );
    // Wrong arity.
    let arity = write(d, "arity.json", "[[0.5, 0.1]]");
    assert_error(&eval(&good, &arity, &[]), &["arity.json"]);
    // Knot count.
    let m = write(
        d,
        "knots.json",
        &CIRCLE.replace("[0,0,0,0.25,", "[0,0,0.25,"),
    );
    assert_error(
        &eval(&m, &params, &[]),
        &["knots.json", "entity 0", "knots given, expected 12"],
    );
    // Decreasing knots.
    let m = write(
        d,
        "dec.json",
        &CIRCLE.replace("0.5,0.5,0.75", "0.5,0.4,0.75"),
    );
    assert_error(&eval(&m, &params, &[]), &["dec.json", "decrease"]);
    // Non-positive weight.
    let m = write(
        d,
        "w.json",
        &CIRCLE.replace("[1, 0.7071067811865476, 1,", "[1, 0.7071067811865476, -1,"),
    );
    assert_error(&eval(&m, &params, &[]), &["w.json", "weight [2]"]);
    // Ragged control net.
    let m = write(
        d,
        "ragged.json",
        &BILINEAR.replace("[[1,0,0],[1,1,1]]", "[[1,0,0]]"),
    );
    let p2 = write(d, "p2.json", "[[0.5, 0.5]]");
    assert_error(&eval(&m, &p2, &[]), &["ragged.json", "control_points[1]"]);
    // Unreadable JSON: line and column.
    let m = write(
        d,
        "syntax.json",
        "{\"type\": \"nurbs-curve\",\n \"degree\": 2,\n \"knots\": [0, 0,, 1]}",
    );
    assert_error(&eval(&m, &params, &[]), &["syntax.json", "line 3"]);
    // Missing file.
    let missing = d.join("nope.json");
    assert_error(&eval(&missing, &params, &[]), &["nope.json"]);
    // Entity index out of range.
    assert_error(
        &eval(&good, &params, &["--entity", "3"]),
        &["entity 3", "holds 1"],
    );
}

#[test]
fn demo_writes_its_files() {
    // Run as the README says: `demo` in the current folder writes ./vclay-demo. The whole demo
    // takes a minute and a half in a debug build; the spline steps show the folder, the files
    // and the summary, and CI runs the whole demo in release and checks every file its summary
    // lists (.ci/run).
    let dir = tempfile::tempdir().unwrap();
    let out_dir = dir.path().join("vclay-demo");
    let out = vclay_in(dir.path(), &["demo", "--only", "torus,sheet,volume"]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    for f in [
        "torus.obj",
        "torus.json",
        "sheet.obj",
        "twisted_volume.obj",
        "twisted_volume.json",
        "summary.json",
    ] {
        let meta = std::fs::metadata(out_dir.join(f)).unwrap_or_else(|_| panic!("{f} missing"));
        assert!(meta.len() > 100, "{f} is nearly empty");
    }
    // The demo's model files evaluate with `vclay eval`.
    let p = write(dir.path(), "p.json", "[[0.1, 0.2, 0.3]]");
    let out = eval(&out_dir.join("twisted_volume.json"), &p, &[]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );

    // Issue 17: the README's `eval` example works as written (it named a params.json that
    // nothing wrote). The command is taken from the README itself.
    let readme = include_str!("../../../README.md");
    let line = readme
        .lines()
        .find(|l| l.starts_with("cargo run --release -- eval "))
        .expect("the README shows an eval example");
    let args: Vec<&str> = line["cargo run --release -- ".len()..]
        .split_whitespace()
        .collect();
    let out = vclay_in(dir.path(), &args);
    assert!(
        out.status.success(),
        "{line}: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    let v: Value = serde_json::from_slice(&out.stdout).unwrap();
    assert_eq!(v["points"].as_array().unwrap().len(), 1, "{v}");
    assert!(v["derivatives"].is_array(), "{v}");

    // The summary says which steps ran and that the demo was partial.
    let summary: Value =
        serde_json::from_slice(&std::fs::read(out_dir.join("summary.json")).unwrap()).unwrap();
    assert_eq!(summary["complete"], false);
    let names: Vec<&str> = summary["steps"]
        .as_array()
        .unwrap()
        .iter()
        .map(|s| s["name"].as_str().unwrap())
        .collect();
    assert_eq!(names, ["exact torus", "refined sheet", "twisted volume"]);
    // An unknown step is named, with the list of steps, before anything is written.
    let other = dir.path().join("other");
    let out = vclay_in(
        dir.path(),
        &["demo", "--only", "torus,teapot", "--out", "other"],
    );
    assert!(!out.status.success());
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(err.contains("`teapot`") && err.contains("rope"), "{err}");
    assert!(!other.exists());
}

/// Issue 28: `vclay pde` warns when the residual is large compared with the surface (fig6a at
/// t = 1, a disc on a pinched spindle), on stderr and in its JSON, and not where the PDE is
/// solved (t = 0.5); frames name the frames over the threshold.
#[test]
fn pde_warns_when_the_residual_is_large_for_the_surface() {
    let dir = tempfile::tempdir().unwrap();
    let spec = format!(
        "{}/../../examples/pde/fig6a.json",
        env!("CARGO_MANIFEST_DIR")
    );
    let at = |t: &str| {
        let out = vclay_in(dir.path(), &["pde", &spec, "--t", t, "--out", "s.obj"]);
        assert!(
            out.status.success(),
            "{}",
            String::from_utf8_lossy(&out.stderr)
        );
        let v: Value = serde_json::from_slice(&out.stdout).unwrap();
        (v, String::from_utf8_lossy(&out.stderr).into_owned())
    };
    let (bad, err) = at("1");
    assert!(bad["residual_to_size"].as_f64().unwrap() > 0.01, "{bad}");
    assert!(bad["warning"].as_str().unwrap().contains("residual RMS"));
    assert!(err.contains("warning: t = 1"), "{err}");
    let (good, err) = at("0.5");
    assert!(good["residual_to_size"].as_f64().unwrap() < 1e-10, "{good}");
    assert!(
        good["warning"].is_null() && !err.contains("warning"),
        "{err}"
    );
    let out = vclay_in(
        dir.path(),
        &["pde", &spec, "--frames", "0:1:3", "--out-dir", "f"],
    );
    assert!(out.status.success());
    let v: Value = serde_json::from_slice(&out.stdout).unwrap();
    let w = v["warning"].as_str().unwrap();
    assert!(w.contains("in 1 of 3 frames: frame 2 (t = 1"), "{w}");
}
