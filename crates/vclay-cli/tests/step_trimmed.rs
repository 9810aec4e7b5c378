//! `vclay convert` of a STEP B-rep to a mesh applies the faces' trimming loops (issue 20): an
//! OpenCASCADE cylinder's caps become discs, so the mesh's area is the cylinder's.

use std::process::Command;

#[test]
fn step_brep_to_mesh_is_trimmed() {
    let dir = tempfile::tempdir().unwrap();
    let step = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../vclay-io/tests/data/cad/brep_cylinder.step"
    );
    let stl = dir.path().join("c.stl");
    let out = Command::new(env!("CARGO_BIN_EXE_vclay"))
        .args([
            "-q",
            "convert",
            step,
            stl.to_str().unwrap(),
            "--samples",
            "64",
        ])
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let b = std::fs::read(&stl).unwrap();
    let n = u32::from_le_bytes(b[80..84].try_into().unwrap()) as usize;
    let mut area = 0.0;
    for k in 0..n {
        let f = |i: usize| {
            let o = 84 + 50 * k + 12 + 4 * i;
            f32::from_le_bytes(b[o..o + 4].try_into().unwrap()) as f64
        };
        let p = |j: usize| [f(3 * j), f(3 * j + 1), f(3 * j + 2)];
        let (a, bb, c) = (p(0), p(1), p(2));
        let u = [bb[0] - a[0], bb[1] - a[1], bb[2] - a[2]];
        let v = [c[0] - a[0], c[1] - a[1], c[2] - a[2]];
        let x = [
            u[1] * v[2] - u[2] * v[1],
            u[2] * v[0] - u[0] * v[2],
            u[0] * v[1] - u[1] * v[0],
        ];
        area += (x[0] * x[0] + x[1] * x[1] + x[2] * x[2]).sqrt() / 2.0;
    }
    let (r, h) = (0.8f64, 1.7f64);
    let pi = std::f64::consts::PI;
    let want = 2.0 * pi * r * h + 2.0 * pi * r * r;
    let untrimmed = 2.0 * pi * r * h + 2.0 * 4.0 * r * r;
    assert!(
        (area - want).abs() < 0.03 * want,
        "{area} vs {want} (untrimmed {untrimmed})"
    );
}
