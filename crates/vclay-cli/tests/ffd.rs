//! End-to-end tests of `vclay ffd` (`ffd-direct-manipulation.txt`): targets met, the report, the
//! lattice file read back by `vclay eval`, partial embedding (Fig. 6: vertices outside the box
//! stay put), conflicting constraints, and bad input (exit code 2, the place named, nothing on
//! stdout).

use serde_json::Value;
use std::fmt::Write as _;
use std::path::{Path, PathBuf};
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

/// A UV sphere of radius 1 at the origin (`n` rings of `n` vertices plus two poles) as OBJ text.
fn sphere_obj(n: usize) -> String {
    let mut s = String::new();
    writeln!(s, "v 0 0 -1").unwrap();
    for i in 1..=n {
        let th = std::f64::consts::PI * i as f64 / (n + 1) as f64;
        for j in 0..n {
            let ph = std::f64::consts::TAU * j as f64 / n as f64;
            let (x, y, z) = (th.sin() * ph.cos(), th.sin() * ph.sin(), -th.cos());
            writeln!(s, "v {x} {y} {z}").unwrap();
        }
    }
    writeln!(s, "v 0 0 1").unwrap();
    let top = n * n + 2;
    let id = |i: usize, j: usize| 2 + (i - 1) * n + j % n;
    for j in 0..n {
        writeln!(s, "f 1 {} {}", id(1, j + 1), id(1, j)).unwrap();
        writeln!(s, "f {top} {} {}", id(n, j), id(n, j + 1)).unwrap();
    }
    for i in 1..n {
        for j in 0..n {
            let (a, b, c, d) = (id(i, j), id(i, j + 1), id(i + 1, j + 1), id(i + 1, j));
            writeln!(s, "f {a} {b} {c}\nf {a} {c} {d}").unwrap();
        }
    }
    s
}

fn obj_positions(path: &Path) -> Vec<[f64; 3]> {
    std::fs::read_to_string(path)
        .unwrap()
        .lines()
        .filter_map(|l| l.strip_prefix("v "))
        .map(|l| {
            let v: Vec<f64> = l.split_whitespace().map(|t| t.parse().unwrap()).collect();
            [v[0], v[1], v[2]]
        })
        .collect()
}

struct Setup {
    _dir: tempfile::TempDir,
    input: PathBuf,
    root: PathBuf,
}

fn setup() -> Setup {
    let dir = tempfile::tempdir().unwrap();
    let root = dir.path().to_path_buf();
    let input = root.join("sphere.obj");
    std::fs::write(&input, sphere_obj(16)).unwrap();
    Setup {
        _dir: dir,
        input,
        root,
    }
}

fn run_ffd(input: &Path, out: &Path, extra: &[&str]) -> Output {
    let mut args = vec![
        "ffd",
        input.to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
    ];
    args.extend_from_slice(extra);
    vclay(&args)
}

fn report(out: &Output) -> Value {
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    serde_json::from_slice(&out.stdout).expect("report is JSON")
}

#[test]
fn single_move_meets_its_target_and_the_lattice_file_evaluates_there() {
    let s = setup();
    let out = s.root.join("moved.obj");
    let lat = s.root.join("lattice.json");
    let r = report(&run_ffd(
        &s.input,
        &out,
        &[
            "--move",
            "0,0,1:0.2,0.1,1.5",
            "--lattice",
            "5x5x6",
            "--lattice-out",
            lat.to_str().unwrap(),
        ],
    ));
    assert!(r["max_target_distance_relative"].as_f64().unwrap() < 1e-12);
    assert_eq!(r["constraints"], 1);
    // Cubic, 5 x 5 x 6: the 4 x 4 x 4 support of the source moves.
    assert_eq!(r["control_points_moved"], 64);
    assert_eq!(r["lattice"]["control_points"], serde_json::json!([5, 5, 6]));
    let n = r["vertices"].as_u64().unwrap();
    let changed = r["vertices_changed"].as_u64().unwrap();
    assert_eq!(n, 16 * 16 + 2);
    assert!(changed > 0 && changed <= n, "{changed}");
    assert!(r["milliseconds"]["total"].as_f64().unwrap() >= 0.0);
    // The north pole is the source: in the output it sits on the target.
    let pos = obj_positions(&out);
    let pole = pos[pos.len() - 1];
    let d = ((pole[0] - 0.2).powi(2) + (pole[1] - 0.1).powi(2) + (pole[2] - 1.5).powi(2)).sqrt();
    assert!(d < 1e-9, "{d}");
    // The lattice file: `vclay eval` at the source's parameters gives the target.
    let bx = &r["lattice"]["box"];
    let t: Vec<f64> = (0..3)
        .map(|a| {
            let (lo, hi) = (bx[0][a].as_f64().unwrap(), bx[1][a].as_f64().unwrap());
            ([0.0, 0.0, 1.0][a] - lo) / (hi - lo)
        })
        .collect();
    let params = s.root.join("params.json");
    std::fs::write(&params, format!("[[{}, {}, {}]]", t[0], t[1], t[2])).unwrap();
    let e = vclay(&[
        "eval",
        lat.to_str().unwrap(),
        "--params",
        params.to_str().unwrap(),
    ]);
    let v: Value = serde_json::from_slice(&e.stdout).unwrap_or_else(|_| {
        panic!("eval failed: {}", String::from_utf8_lossy(&e.stderr));
    });
    let p = &v["points"][0];
    let target = [0.2, 0.1, 1.5];
    for a in 0..3 {
        assert!((p[a].as_f64().unwrap() - target[a]).abs() < 1e-12, "{p}");
    }
}

#[test]
fn several_moves_are_met_together_and_conflicts_are_named() {
    let s = setup();
    let out = s.root.join("moved.ply");
    let r = report(&run_ffd(
        &s.input,
        &out,
        &[
            "--move",
            "1,0,0:1.3,0,0",
            "--move",
            "-1,0,0:-1.3,0,0",
            "--move",
            "0,0,-1:0,0,-0.8",
            "--degree",
            "2",
        ],
    ));
    assert!(r["max_target_distance_relative"].as_f64().unwrap() < 1e-12);
    assert_eq!(r["constraints"], 3);
    assert!(std::fs::metadata(&out).unwrap().len() > 0);

    // The same source sent to two places: refused, naming both; least squares meets neither
    // exactly but lands halfway.
    let twice = ["--move", "1,0,0:1.3,0,0", "--move", "1,0,0:1.5,0,0"];
    let e = run_ffd(&s.input, &out, &twice);
    assert_error(&e, &["least-squares", "0", "1"]);
    let mut ls = twice.to_vec();
    ls.push("--least-squares");
    let r = report(&run_ffd(&s.input, &out, &ls));
    let miss = r["max_target_distance"].as_f64().unwrap();
    assert!((miss - 0.1).abs() < 1e-9, "{miss}");
}

#[test]
fn vertices_outside_the_box_stay_put() {
    // Fig. 6: only the upper part of the sphere is embedded.
    let s = setup();
    let out = s.root.join("local.obj");
    let r = report(&run_ffd(
        &s.input,
        &out,
        &[
            "--box",
            "-1.2,-1.2,0.3,1.2,1.2,1.2",
            "--move",
            "0,0,1:0,0,1.4",
        ],
    ));
    let before = obj_positions(&s.input);
    let after = obj_positions(&out);
    assert_eq!(before.len(), after.len());
    let embedded = r["vertices_embedded"].as_u64().unwrap() as usize;
    let inside = before.iter().filter(|p| p[2] >= 0.3).count();
    assert_eq!(embedded, inside);
    for (b, a) in before.iter().zip(&after) {
        if b[2] < 0.3 {
            assert_eq!(a, b, "a vertex outside the box moved");
        }
    }
    assert!(r["vertices_changed"].as_u64().unwrap() as usize <= inside);
}

#[test]
fn bad_input_is_reported() {
    let s = setup();
    let out = s.root.join("o.obj");
    let mv = ["--move", "0,0,1:0,0,2"];
    // A source outside the lattice.
    let e = run_ffd(
        &s.input,
        &out,
        &["--move", "0,0,1:0,0,2", "--move", "5,0,0:5,1,0"],
    );
    assert_error(&e, &["--move 2", "outside the lattice box"]);
    // A face referencing a missing vertex.
    let bad = s.root.join("bad.obj");
    std::fs::write(&bad, "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 9\n").unwrap();
    assert_error(&run_ffd(&bad, &out, &mv), &["bad.obj", "4"]);
    // A non-finite coordinate.
    std::fs::write(&bad, "v 0 0 0\nv 1 nan 0\nv 0 1 0\nf 1 2 3\n").unwrap();
    assert_error(&run_ffd(&bad, &out, &mv), &["bad.obj", "2"]);
    // An empty file.
    std::fs::write(&bad, "").unwrap();
    assert_error(&run_ffd(&bad, &out, &mv), &["bad.obj"]);
    // A missing file, an unknown output format, a degree the lattice cannot carry, bad boxes.
    assert_error(&run_ffd(&s.root.join("none.obj"), &out, &mv), &["none.obj"]);
    assert_error(&run_ffd(&s.input, &s.root.join("o.xyz"), &mv), &["o.xyz"]);
    let mut a = mv.to_vec();
    a.extend(["--lattice", "3x3x3", "--degree", "3"]);
    assert_error(&run_ffd(&s.input, &out, &a), &["--lattice"]);
    let mut a = mv.to_vec();
    a.extend(["--box", "0,0,0,1,1"]);
    assert_error(&run_ffd(&s.input, &out, &a), &["--box"]);
    assert_error(
        &run_ffd(&s.input, &out, &["--move", "0,0,1"]),
        &["--move", "SOURCE:TARGET"],
    );
    assert!(!out.exists(), "no output written on error");
}
