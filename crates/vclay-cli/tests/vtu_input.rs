//! `vclay convert` and `vclay render` take `.vtu` lattices (issue 20): the boundary of the
//! lattice `vclay subdivide` wrote, as a mesh; a damaged file is a located error.

use std::process::{Command, Output};

fn vclay(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_vclay"))
        .args(args)
        .output()
        .expect("vclay runs")
}

#[test]
fn vtu_lattices_convert_and_render() {
    let dir = tempfile::tempdir().unwrap();
    let p = |f: &str| dir.path().join(f).to_str().unwrap().to_string();
    let r = vclay(&[
        "subdivide",
        "--primitive",
        "box:2x2x2",
        "--levels",
        "1",
        "--out",
        &p("box.vtu"),
        "-q",
    ]);
    assert!(r.status.success(), "{}", String::from_utf8_lossy(&r.stderr));
    let r = vclay(&["convert", &p("box.vtu"), &p("box.stl")]);
    assert!(r.status.success(), "{}", String::from_utf8_lossy(&r.stderr));
    // The one-cell box (2x2x2 points) subdivided once: 2x2 quads per side, two triangles each.
    let stl = std::fs::read(p("box.stl")).unwrap();
    let facets = u32::from_le_bytes(stl[80..84].try_into().unwrap());
    assert_eq!(facets, 6 * 4 * 2);
    let r = vclay(&[
        "render",
        &p("box.vtu"),
        "--out",
        &p("box.png"),
        "--size",
        "64x48",
    ]);
    assert!(r.status.success(), "{}", String::from_utf8_lossy(&r.stderr));
    assert!(std::fs::metadata(p("box.png")).unwrap().len() > 100);
    // A damaged file: exit code 2, the file and line named.
    let text = std::fs::read_to_string(p("box.vtu")).unwrap();
    std::fs::write(
        p("bad.vtu"),
        text.replacen("format=\"ascii\">", "format=\"ascii\">\n x", 1),
    )
    .unwrap();
    let r = vclay(&["convert", &p("bad.vtu"), &p("bad.stl")]);
    assert_eq!(r.status.code(), Some(2));
    let err = String::from_utf8_lossy(&r.stderr);
    assert!(
        err.contains("bad.vtu:7: expected a number in data array"),
        "{err}"
    );
}
