//! End-to-end tests of `vclay subdivide`: `--stats` against `subdivision-solids-conference.txt`
//! Table 1, every output format, `.ovm` round trips, and bad input (exit code 2, a message naming
//! the file and line, nothing on stdout).

use serde_json::Value;
use std::path::Path;
use std::process::{Command, Output};

fn vclay(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_vclay"))
        .args(args)
        .output()
        .expect("vclay runs")
}

fn stats(args: &[&str]) -> [u64; 4] {
    let mut all = vec!["subdivide"];
    all.extend_from_slice(args);
    all.push("--stats");
    let out = vclay(&all);
    assert!(
        out.status.success(),
        "{args:?}: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    let v: Value = serde_json::from_slice(&out.stdout).expect("stats are JSON");
    ["points", "edges", "faces", "cells"].map(|k| v[k].as_u64().expect(k))
}

fn assert_error(out: &Output, needles: &[&str]) {
    assert_eq!(out.status.code(), Some(2), "exit code");
    assert!(out.stdout.is_empty(), "stdout must be empty on error");
    let err = String::from_utf8_lossy(&out.stderr);
    for n in needles {
        assert!(err.contains(n), "stderr {err:?} lacks {n:?}");
    }
}

#[test]
fn stats_equal_table1_for_the_cubes() {
    // Table 1: Cube (3^3) levels 2 and 3, Cube (4^3) levels 1 and 2.
    assert_eq!(
        stats(&["--primitive", "box:3", "--levels", "2"]),
        [729, 1944, 1728, 512]
    );
    assert_eq!(
        stats(&["--primitive", "box:3x3x3", "--levels", "3"]),
        [4913, 13872, 13056, 4096]
    );
    assert_eq!(
        stats(&["--primitive", "box", "--levels", "1"]),
        [343, 882, 756, 216]
    );
    assert_eq!(
        stats(&[
            "--primitive",
            "box:4x4x4",
            "--levels",
            "2",
            "--boundary",
            "sharp"
        ]),
        [2197, 6084, 5616, 1728]
    );
    // Level 0 is the control lattice itself.
    assert_eq!(
        stats(&["--primitive", "box:4", "--levels", "0"]),
        [64, 144, 108, 27]
    );
}

#[test]
fn stats_equal_table1_for_the_other_models() {
    assert_eq!(
        stats(&[
            "--primitive",
            "tetrahedron-with-holes-paper",
            "--levels",
            "3"
        ]),
        [2505, 6808, 6048, 1744]
    );
    assert_eq!(
        stats(&["--primitive", "gear", "--levels", "2"]),
        [1480, 3864, 3344, 960]
    );
    assert_eq!(
        stats(&[
            "--primitive",
            "cylinder",
            "--levels",
            "3",
            "--boundary",
            "interior"
        ]),
        [3553, 10144, 9664, 3072]
    );
}

/// Issue 19: the galleries' soccer player and cactus have Table 1's counts, and `--stats` reports
/// no folded cell for them or for the default (split) tetrahedron with holes; the paper's
/// single cell folds and the command warns.
#[test]
fn gallery_stats_equal_table1_and_nothing_folds() {
    assert_eq!(
        stats(&["--primitive", "soccer-player", "--levels", "2"]),
        [2450, 6320, 5408, 1536]
    );
    assert_eq!(
        stats(&["--primitive", "cactus", "--levels", "2"]),
        [2625, 6800, 5840, 1664]
    );
    for name in ["soccer-player", "tetrahedron-with-holes", "spiked-object"] {
        let out = vclay(&["subdivide", "--primitive", name, "--levels", "2", "--stats"]);
        let v: Value = serde_json::from_slice(&out.stdout).expect("stats are JSON");
        assert_eq!(v["inverted_cells"], 0, "{name}");
        assert!(
            !String::from_utf8_lossy(&out.stderr).contains("warning"),
            "{name}"
        );
    }
    let out = vclay(&[
        "subdivide",
        "--primitive",
        "tetrahedron-with-holes-paper",
        "--levels",
        "1",
        "--stats",
    ]);
    let v: Value = serde_json::from_slice(&out.stdout).expect("stats are JSON");
    assert_eq!(v["inverted_cells"], 12);
    assert!(String::from_utf8_lossy(&out.stderr).contains("non-positive volume"));
}

#[test]
fn every_output_format_is_written_and_ovm_reads_back() {
    let dir = tempfile::tempdir().unwrap();
    let p = |name: &str| dir.path().join(name).to_str().unwrap().to_string();
    for ext in ["ovm", "vtu", "obj", "ply", "stl"] {
        let file = p(&format!("t.{ext}"));
        let out = vclay(&[
            "subdivide",
            "--primitive",
            "t",
            "--levels",
            "1",
            "--out",
            &file,
        ]);
        assert!(
            out.status.success(),
            "{}",
            String::from_utf8_lossy(&out.stderr)
        );
        assert!(out.stdout.is_empty(), "no --stats, no stdout");
        assert!(std::fs::metadata(&file).unwrap().len() > 100, "{ext}");
    }
    let vtu = std::fs::read_to_string(p("t.vtu")).unwrap();
    assert!(vtu.contains("UnstructuredGrid"));
    // The subdivided T (4 hexahedra -> 32) read back from .ovm and subdivided once more.
    assert_eq!(
        stats(&[&p("t.ovm"), "--levels", "0"]),
        stats(&["--primitive", "t", "--levels", "1"])
    );
    assert_eq!(
        stats(&[&p("t.ovm"), "--levels", "1"]),
        stats(&["--primitive", "t", "--levels", "2"])
    );
    // OBJ: a closed boundary surface, every vertex used.
    let obj = std::fs::read_to_string(p("t.obj")).unwrap();
    let v = obj.lines().filter(|l| l.starts_with("v ")).count();
    let f = obj.lines().filter(|l| l.starts_with("f ")).count();
    assert!(v > 0 && f > 0);
    // Closed triangulated surface of genus 0: V - E + F = 2 with E = 3F/2.
    assert_eq!(2 * v as i64 - f as i64, 4, "V - F/2 = 2");
}

#[test]
fn bad_files_name_the_file_and_line() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("bad.ovm");
    std::fs::write(
        &path,
        "OVM ASCII\nVertices\n2\n0 0 0\n1 zero 0\nEdges\n0\nFaces\n0\nPolyhedra\n0\n",
    )
    .unwrap();
    let file = path.to_str().unwrap();
    let out = vclay(&["subdivide", file, "--levels", "1", "--stats"]);
    assert_error(&out, &["bad.ovm", ":5"]);

    // A face referencing a missing edge.
    std::fs::write(
        &path,
        "OVM ASCII\nVertices\n3\n0 0 0\n1 0 0\n0 1 0\nEdges\n2\n0 1\n1 2\nFaces\n1\n3 0 2 9\nPolyhedra\n0\n",
    )
    .unwrap();
    let out = vclay(&["subdivide", file, "--levels", "1"]);
    assert_error(&out, &["bad.ovm", ":13"]);

    let missing = dir.path().join("missing.ovm");
    let out = vclay(&["subdivide", missing.to_str().unwrap(), "--levels", "1"]);
    assert_error(&out, &["missing.ovm"]);
}

#[test]
fn bad_arguments_are_reported() {
    let out = vclay(&["subdivide", "--primitive", "dodecahedron", "--levels", "1"]);
    assert_error(&out, &["dodecahedron", "unknown name"]);
    let out = vclay(&["subdivide", "--primitive", "box:1", "--levels", "1"]);
    assert_error(&out, &["box:1"]);
    let out = vclay(&[
        "subdivide",
        "--primitive",
        "tetrahedron-with-holes:1.5",
        "--levels",
        "1",
    ]);
    assert_error(&out, &["between 0 and 1"]);
    let out = vclay(&[
        "subdivide",
        "--primitive",
        "box",
        "--levels",
        "1",
        "--out",
        Path::new("x.dat").to_str().unwrap(),
    ]);
    assert_error(&out, &["x.dat", "unknown output format"]);
    let out = vclay(&["subdivide", "--primitive", "box", "--levels", "9"]);
    assert_error(&out, &["levels"]);
    // Neither or both sources: clap rejects (exit code 2).
    let out = vclay(&["subdivide", "--levels", "1"]);
    assert_eq!(out.status.code(), Some(2));
}
