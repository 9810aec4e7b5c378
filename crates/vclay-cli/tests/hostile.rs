//! Issue 17: hostile sizes and values from arguments and files. Each input used to panic,
//! overflow the stack, abort out of memory or hang; each now gives exit code 2, one short
//! message naming the option or key, nothing on stdout, within seconds.

use std::path::{Path, PathBuf};
use std::process::{Command, Output};
use std::time::{Duration, Instant};

fn vclay_in(dir: &Path, args: &[&str]) -> (Output, Duration) {
    let t = Instant::now();
    let out = Command::new(env!("CARGO_BIN_EXE_vclay"))
        .current_dir(dir)
        .args(args)
        .output()
        .expect("vclay runs");
    (out, t.elapsed())
}

fn write(dir: &Path, name: &str, text: &str) -> PathBuf {
    let p = dir.join(name);
    std::fs::write(&p, text).unwrap();
    p
}

/// Exit 2, nothing on stdout, a single short message containing every needle, in seconds.
fn refused(dir: &Path, args: &[&str], needles: &[&str]) {
    let (out, took) = vclay_in(dir, args);
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(2), "{args:?}: {err}");
    assert!(out.stdout.is_empty(), "{args:?}: stdout must be empty");
    assert!(took < Duration::from_secs(20), "{args:?} took {took:?}");
    assert!(err.starts_with("error: "), "{err}");
    assert_eq!(err.matches("error").count(), 1, "said once: {err}");
    assert!(err.len() < 600, "short: {} bytes: {err}", err.len());
    for n in needles {
        assert!(err.contains(n), "{args:?}: {err:?} lacks {n:?}");
    }
}

const CIRCLE: &str = r#"{"type": "nurbs-curve", "degree": 2,
 "knots": [0,0,0,0.25,0.25,0.5,0.5,0.75,0.75,1,1,1],
 "control_points": [[1,0,0],[1,1,0],[0,1,0],[-1,1,0],[-1,0,0],[-1,-1,0],[0,-1,0],[1,-1,0],[1,0,0]],
 "weights": [1, 0.7071067811865476, 1, 0.7071067811865476, 1, 0.7071067811865476, 1, 0.7071067811865476, 1]}"#;

const SHEET: &str = r#"[{"type": "nurbs-surface", "degree": [1, 1], "knots": [[0,0,1,1],[0,0,2,2]],
 "control_points": [[[0,0,0],[0,1,0]],[[1,0,0],[1,1,1]]]}]"#;

const VOLUME: &str = r#"{"type":"nurbs-volume","degree":[1,1,1],"knots":[[0,0,1,1],[0,0,1,1],[0,0,1,1]],
"control_points":[[[[0,0,0],[0,0,1]],[[0,1,0],[0,1,1]]],[[[1,0,0],[1,0,1]],[[1,1,0],[1,1,1]]]]}"#;

const CUBE_OBJ: &str = "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nv 0 0 1\nv 1 0 1\nv 1 1 1\nv 0 1 1\n\
f 1 3 2\nf 1 4 3\nf 5 6 7\nf 5 7 8\nf 1 2 6\nf 1 6 5\nf 2 3 7\nf 2 7 6\nf 3 4 8\nf 3 8 7\n\
f 4 1 5\nf 4 5 8\n";

#[test]
fn eval_derivative_orders_are_bounded() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    write(d, "c.json", CIRCLE);
    write(d, "v.json", VOLUME);
    write(d, "p1.json", "[[0.5]]");
    write(d, "p3.json", "[[0.5,0.5,0.5]]");
    for k in ["18446744073709551615", "4294967296", "10000"] {
        refused(
            d,
            &["eval", "c.json", "--params", "p1.json", "--derivatives", k],
            &["--derivatives", "maximum order 64"],
        );
        refused(
            d,
            &["eval", "v.json", "--params", "p3.json", "--derivatives", k],
            &["--derivatives"],
        );
    }
    // The largest order allowed works, and --at replaces a parameter file.
    let (out, _) = vclay_in(d, &["eval", "c.json", "--at", "0.5", "--derivatives", "64"]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let v: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    assert_eq!(v["derivatives"][0].as_array().unwrap().len(), 65);
    refused(
        d,
        &["eval", "c.json", "--at", "0.5,0.5"],
        &["--at '0.5,0.5'"],
    );
}

#[test]
fn eval_of_an_overflowing_model_is_an_error_not_null() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    // Finite control points whose derivative overflows: 1e308 apart over a tiny knot span.
    write(
        d,
        "big.json",
        r#"{"type":"nurbs-curve","degree":1,"knots":[0,0,1e-10,1e-10],
            "control_points":[[-1e308,0,0],[1e308,0,0]]}"#,
    );
    refused(
        d,
        &["eval", "big.json", "--at", "5e-11", "--derivatives", "1"],
        &["not finite", "--at: parameter 0"],
    );
}

#[test]
fn mesh_and_sample_sizes_are_checked_before_allocating() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    write(d, "s.json", SHEET);
    write(d, "cube.obj", CUBE_OBJ);
    for n in ["18446744073709551615", "20000"] {
        refused(
            d,
            &["convert", "s.json", "o.stl", "--samples", n],
            &["--samples", "--max-memory", "limit of 4G"],
        );
    }
    // The same command within a raised limit is a plain success, and a small --max-memory
    // refuses the default.
    refused(
        d,
        &["--max-memory", "100K", "convert", "s.json", "o.obj"],
        &["--samples 48", "limit of 100K"],
    );
    refused(
        d,
        &[
            "ffd",
            "cube.obj",
            "--out",
            "o.obj",
            "--move",
            "0.5,0.5,0.5:1,1,1",
            "--lattice",
            "1000x1000x1000",
        ],
        &["--lattice 1000x1000x1000", "GB"],
    );
    refused(
        d,
        &["render", "s.json", "--out", "r.png", "--size", "8192x8192"],
        &["--size 8192x8192", "--max-memory"],
    );
    refused(
        d,
        &[
            "render",
            "s.json",
            "--out",
            "r.gif",
            "--frames",
            "1000000000",
        ],
        &["--frames", "10000"],
    );
    refused(
        d,
        &["subdivide", "--primitive", "box", "--levels", "6"],
        &["--levels 6", "7077888 cells", "--max-memory"],
    );
    assert!(
        std::fs::read_dir(d).unwrap().count() == 2,
        "nothing written"
    );
}

#[test]
fn degenerate_primitives_and_overflowing_moves_are_errors_not_panics() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    write(d, "cube.obj", CUBE_OBJ);
    refused(
        d,
        &[
            "subdivide",
            "--primitive",
            "tetrahedron-with-holes:1e-300",
            "--levels",
            "2",
        ],
        &["tetrahedron-with-holes:1e-300", "degenerate"],
    );
    refused(
        d,
        &[
            "ffd",
            "cube.obj",
            "--out",
            "o.obj",
            "--move",
            "0.5,0.5,0.5:1e308,1e308,1e308",
        ],
        &["--move", "finite"],
    );
    assert!(!d.join("o.obj").exists());
}

const SPEC_HEAD: &str = r#"{"trial_terms": 7, "patches": [{
  "x": {"u0": "cos(v)", "du0": 0, "u1": "0.5*cos(v)", "du1": 0},
  "y": {"u0": "sin(v)", "du0": 0, "u1": "0.5*sin(v)", "du1": 0},
  "z": {"u0": "#;

fn spec(dir: &Path, name: &str, z_u0: &str, extra: &str) {
    write(
        dir,
        name,
        &format!(
            "{SPEC_HEAD}{}, \"du0\": 0, \"u1\": 1, \"du1\": 0}}{extra}}}]}}",
            serde_json::to_string(z_u0).unwrap()
        ),
    );
}

#[test]
fn pde_expressions_frames_and_grids_are_bounded() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    spec(d, "ok.json", "0", "");
    let (out, _) = vclay_in(d, &["pde", "ok.json", "--t", "0", "--out", "ok.obj"]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    for frames in ["0:1:18446744073709551615", "0:1:1000000000", "0:1:100000"] {
        refused(
            d,
            &[
                "pde",
                "ok.json",
                "--frames",
                frames,
                "--out-dir",
                "f",
                "--grid",
                "2x2",
            ],
            &["--frames", "10000"],
        );
    }
    let chain = |op: &str, n: usize| vec!["v"; n].join(op);
    let cases = [
        ("plus.json", chain("+", 30_000), "tokens"),
        ("minus.json", format!("{}v", "-".repeat(30_000)), "tokens"),
        ("times.json", chain("*", 100_000), "tokens"),
        ("pow.json", chain("^", 100_000), "tokens"),
        ("tower.json", chain("^", 200), "derivative"),
        ("div0.json", "0/0".to_string(), "division by zero"),
        ("mul0.json", "0*(1/0)".to_string(), "division by zero"),
    ];
    for (name, text, needle) in &cases {
        spec(d, name, text, "");
        refused(
            d,
            &["pde", name, "--t", "0", "--out", "o.obj"],
            &["patches[0].z", needle],
        );
    }
    let sines: Vec<String> = (1..=2000).map(|k| format!("sin({k}*v)")).collect();
    spec(d, "sines.json", &sines.join("+"), "");
    refused(
        d,
        &["pde", "sines.json", "--t", "0", "--out", "o.obj"],
        &["tokens"],
    );
    let sines: Vec<String> = (1..=300).map(|k| format!("sin({k}*v)")).collect();
    spec(d, "sines300.json", &sines.join("+"), "");
    refused(
        d,
        &["pde", "sines300.json", "--t", "0", "--out", "o.obj"],
        &["deep"],
    );
    spec(
        d,
        "colloc.json",
        "0",
        r#", "collocation": [100000, 100000]"#,
    );
    refused(
        d,
        &["pde", "colloc.json", "--t", "0", "--out", "o.obj"],
        &["patches[0].collocation", "limits"],
    );
    assert!(!d.join("o.obj").exists());
}

#[test]
fn glb_counts_are_checked_against_the_buffer() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let json = r#"{"asset":{"version":"2.0"},"buffers":[{"byteLength":36}],
      "bufferViews":[{"buffer":0,"byteOffset":0,"byteLength":36}],
      "accessors":[{"bufferView":0,"componentType":5126,"count":4000000000,"type":"VEC3"}],
      "meshes":[{"primitives":[{"attributes":{"POSITION":0}}]}]}"#;
    let mut j = json.as_bytes().to_vec();
    while !j.len().is_multiple_of(4) {
        j.push(b' ');
    }
    let bin = vec![0u8; 36];
    let mut glb = Vec::new();
    glb.extend_from_slice(b"glTF");
    glb.extend_from_slice(&2u32.to_le_bytes());
    glb.extend_from_slice(&((12 + 8 + j.len() + 8 + bin.len()) as u32).to_le_bytes());
    glb.extend_from_slice(&(j.len() as u32).to_le_bytes());
    glb.extend_from_slice(b"JSON");
    glb.extend_from_slice(&j);
    glb.extend_from_slice(&(bin.len() as u32).to_le_bytes());
    glb.extend_from_slice(b"BIN\0");
    glb.extend_from_slice(&bin);
    std::fs::write(d.join("big.glb"), glb).unwrap();
    refused(
        d,
        &["convert", "big.glb", "o.obj"],
        &["big.glb", "count 4000000000", "36 bytes"],
    );
}

#[test]
fn writes_create_folders_and_clean_stale_temporaries() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    write(d, "s.json", SHEET);
    let (out, _) = vclay_in(d, &["convert", "s.json", "new/deeper/s.obj"]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    assert!(d.join("new/deeper/s.obj").is_file());
    // A leftover of a killed write (a process that no longer runs) is removed by the next
    // write into the folder; another file is left alone.
    let stale = d.join("new/.vclay-tmp-999999999-abcdef");
    std::fs::write(&stale, "partial").unwrap();
    std::fs::write(d.join("new/keep.txt"), "mine").unwrap();
    let (out, _) = vclay_in(d, &["convert", "s.json", "new/s.stl"]);
    assert!(out.status.success());
    assert!(!stale.exists(), "stale temporary removed");
    assert!(d.join("new/keep.txt").exists());
}

#[test]
fn ffd_writes_both_files_or_neither() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    write(d, "cube.obj", CUBE_OBJ);
    // The lattice file's folder is a file: the lattice cannot be written, so the mesh is not.
    write(d, "blocker", "a file, not a folder");
    let (out, _) = vclay_in(
        d,
        &[
            "ffd",
            "cube.obj",
            "--out",
            "o.obj",
            "--move",
            "0.5,0.5,0.5:0.5,0.5,0.6",
            "--lattice-out",
            "blocker/l.json",
        ],
    );
    assert_eq!(out.status.code(), Some(2));
    assert!(
        !d.join("o.obj").exists(),
        "mesh not written without its lattice"
    );
    let (out, _) = vclay_in(
        d,
        &[
            "ffd",
            "cube.obj",
            "--out",
            "o.obj",
            "--move",
            "0.5,0.5,0.5:0.5,0.5,0.6",
            "--lattice-out",
            "l.json",
        ],
    );
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    assert!(d.join("o.obj").is_file() && d.join("l.json").is_file());
}

#[test]
fn subdivide_without_output_says_what_it_did() {
    let dir = tempfile::tempdir().unwrap();
    let (out, _) = vclay_in(
        dir.path(),
        &["subdivide", "--primitive", "box", "--levels", "1"],
    );
    assert!(out.status.success());
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(
        err.contains("216 cells") && err.contains("give --out FILE or --stats"),
        "{err}"
    );
    let (out, _) = vclay_in(
        dir.path(),
        &[
            "--quiet",
            "subdivide",
            "--primitive",
            "box",
            "--levels",
            "1",
        ],
    );
    assert!(out.status.success() && out.stderr.is_empty());
}
