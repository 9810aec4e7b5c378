//! End-to-end tests of `vclay clay` (issue 19): a closed mesh gives an `.ovm` lattice that
//! `vclay subdivide` reads back and a JSON report within the goal; an open mesh is refused with
//! exit code 2 and the faulty edges named.

use serde_json::Value;
use std::path::Path;
use std::process::{Command, Output};

use vclay::TriMesh;

fn vclay(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_vclay"))
        .args(args)
        .output()
        .expect("vclay runs")
}

/// A UV sphere of radius 1 (poles closed by fans).
fn sphere() -> TriMesh {
    let rings = 24;
    let profile: Vec<(f64, f64)> = (0..=rings)
        .map(|i| {
            let t = std::f64::consts::PI * i as f64 / rings as f64;
            let r = if i == 0 || i == rings { 0.0 } else { t.sin() };
            (r, -t.cos())
        })
        .collect();
    TriMesh::revolution(&profile, 48)
}

fn s(p: &Path) -> &str {
    p.to_str().unwrap()
}

#[test]
fn sphere_to_lattice_with_report() {
    let dir = tempfile::tempdir().unwrap();
    let (mesh, out, surface, report) = (
        dir.path().join("sphere.obj"),
        dir.path().join("sphere.ovm"),
        dir.path().join("fit.stl"),
        dir.path().join("r.json"),
    );
    vclay::io::write_mesh(&mesh, &sphere()).unwrap();
    let run = vclay(&[
        "clay",
        s(&mesh),
        "--cells",
        "300",
        "--levels",
        "1",
        "--out",
        s(&out),
        "--surface",
        s(&surface),
        "--report",
        s(&report),
    ]);
    assert!(
        run.status.success(),
        "{}",
        String::from_utf8_lossy(&run.stderr)
    );
    let r: Value = serde_json::from_str(&std::fs::read_to_string(&report).unwrap()).unwrap();
    let cells = r["cells"].as_u64().unwrap();
    assert!((270..=330).contains(&cells), "{r}");
    assert!(r["min_cell_volume"].as_f64().unwrap() > 0.0, "{r}");
    assert_eq!(r["folded_cells_finest"].as_u64(), Some(0), "{r}");
    assert!(r["distance"]["mean"].as_f64().unwrap() < 0.002, "{r}");
    assert!(r["distance"]["max"].as_f64().unwrap() < 0.01, "{r}");
    assert!(surface.exists());
    // The lattice reads back with the control cell count.
    let back = vclay(&["subdivide", s(&out), "--levels", "0", "--stats"]);
    assert!(
        back.status.success(),
        "{}",
        String::from_utf8_lossy(&back.stderr)
    );
    let st: Value = serde_json::from_slice(&back.stdout).unwrap();
    assert_eq!(st["cells"].as_u64(), Some(cells));
    assert_eq!(st["inverted_cells"].as_u64(), Some(0));
}

#[test]
fn open_mesh_and_bad_sizes_are_refused() {
    let dir = tempfile::tempdir().unwrap();
    let (mesh, out) = (dir.path().join("open.obj"), dir.path().join("o.ovm"));
    let mut m = sphere();
    m.triangles.truncate(m.triangles.len() - 1);
    vclay::io::write_mesh(&mesh, &m).unwrap();
    for (args, needles) in [
        (
            vec!["--cells", "100"],
            vec!["open.obj", "open", "one triangle", "in triangles"],
        ),
        (vec!["--cells", "0"], vec!["--cells 0"]),
        (vec!["--cells", "200001"], vec!["--cells 200001"]),
        (vec!["--levels", "9"], vec!["--levels 9"]),
    ] {
        let mut all = vec!["clay", s(&mesh), "--out", s(&out)];
        all.extend(args);
        let run = vclay(&all);
        assert_eq!(run.status.code(), Some(2));
        assert!(run.stdout.is_empty());
        let err = String::from_utf8_lossy(&run.stderr);
        for n in needles {
            assert!(err.contains(n), "{err:?} lacks {n:?}");
        }
        assert!(!out.exists());
    }
}
