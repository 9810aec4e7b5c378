//! `vclay_session::open`: every file vclay reads is recognized by its content and opens as a
//! session, or is named with the commands that take it (issue 26).

use std::path::{Path, PathBuf};

use vclay_session::{FileKind, ModelKind, SessionError, open};

fn repo() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../..")
}

fn kind_of(path: &Path) -> ModelKind {
    let o = open(path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    o.session.model(None).unwrap().kind()
}

#[test]
fn shipped_files_of_every_kind_open() {
    let r = repo();
    let cases: [(&str, FileKind, ModelKind); 8] = [
        (
            "examples/scenarios/fig07_rope_cube.toml",
            FileKind::Scenario,
            ModelKind::SubdivisionSolid,
        ),
        (
            "examples/pde/aircraft.json",
            FileKind::PdeSpec,
            ModelKind::PdeSurface,
        ),
        (
            "examples/pde/fig5b.json",
            FileKind::PdeSpec,
            ModelKind::PdeSurface,
        ),
        (
            "examples/triangular/saddle_patch.json",
            FileKind::Triangular,
            ModelKind::DnurbsTriangular,
        ),
        (
            "crates/vclay-io/tests/data/cad/rational_surface.step",
            FileKind::Step,
            ModelKind::DnurbsSurface,
        ),
        (
            "crates/vclay-io/tests/data/cad/rational_surface.igs",
            FileKind::Iges,
            ModelKind::DnurbsSurface,
        ),
        (
            "crates/vclay-session/tests/data/before/plastic_reset/final.ovm",
            FileKind::Lattice,
            ModelKind::SubdivisionSolid,
        ),
        ("fuzz/seeds/obj/cube.obj", FileKind::Mesh, ModelKind::Ffd),
    ];
    for (f, file_kind, model_kind) in cases {
        let p = r.join(f);
        let o = open(&p).unwrap_or_else(|e| panic!("{f}: {e}"));
        assert_eq!(o.kind, file_kind, "{f}");
        assert_eq!(o.session.model(None).unwrap().kind(), model_kind, "{f}");
        let mesh = o.session.model(None).unwrap().display_mesh().unwrap();
        assert!(!mesh.triangles.is_empty(), "{f}: nothing to show");
    }
    // A scenario keeps its run length and outputs; a model file has none.
    let o = open(&r.join("examples/scenarios/fig9a_swung_egg.toml")).unwrap();
    assert_eq!(o.run.as_ref().unwrap().end_step, 400);
    assert!(
        open(&r.join("examples/pde/fig5b.json"))
            .unwrap()
            .run
            .is_none()
    );
}

#[test]
fn content_decides_not_the_extension() {
    let dir = tempfile::tempdir().unwrap();
    // A model file of each entity type, recognized as JSON model files.
    let sheet = dir.path().join("sheet.json");
    std::fs::write(
        &sheet,
        r#"{"entities": [{"type": "nurbs-curve", "degree": 1, "knots": [0, 0, 1, 1],
            "control_points": [[0, 0, 0], [1, 0, 0]]},
           {"type": "nurbs-surface", "degree": [1, 2],
            "knots": [[0, 0, 1, 1], [0, 0, 0, 1, 1, 1]],
            "control_points": [[[0, 0, 0], [0, 1, 0.5], [0, 2, 0]],
                               [[1, 0, 0], [1, 1, 0.5], [1, 2, 0]]]}]}"#,
    )
    .unwrap();
    // The first surface wins over a curve before it.
    assert_eq!(kind_of(&sheet), ModelKind::DnurbsSurface);
    let curve = dir.path().join("curve.json");
    std::fs::write(
        &curve,
        r#"{"entities": [{"type": "nurbs-curve", "degree": 1, "knots": [0, 0, 1, 1],
            "control_points": [[0, 0, 0], [1, 0, 0]]}]}"#,
    )
    .unwrap();
    assert_eq!(kind_of(&curve), ModelKind::DnurbsCurve);
    // The model format's other two shapes: a list of entities, and one entity.
    let one = r#"{"type": "nurbs-curve", "degree": 1, "knots": [0, 0, 1, 1],
            "control_points": [[0, 0, 0], [1, 0, 0]]}"#;
    std::fs::write(&curve, one).unwrap();
    assert_eq!(kind_of(&curve), ModelKind::DnurbsCurve);
    std::fs::write(&curve, format!("[{one}]")).unwrap();
    assert_eq!(kind_of(&curve), ModelKind::DnurbsCurve);
    // A scenario in a file without the .toml extension.
    let sc = dir.path().join("scenario.txt");
    std::fs::write(
        &sc,
        "[model]\nkind = \"dnurbs-surface\"\nsize = [5, 5]\n[simulation]\ndt = 0.01\n",
    )
    .unwrap();
    assert_eq!(kind_of(&sc), ModelKind::DnurbsSurface);
    // A saved session named .json opens as the session, not as a model file.
    let s = vclay_session::open(&sc).unwrap().session;
    let saved = dir.path().join("saved.json");
    vclay_session::file::save(&saved, &s, None).unwrap();
    assert_eq!(open(&saved).unwrap().kind, FileKind::Session);
}

#[test]
fn files_that_are_not_sessions_say_what_takes_them() {
    let dir = tempfile::tempdir().unwrap();
    let cloud = dir.path().join("scan.xyz");
    std::fs::write(&cloud, "0 0 0\n1 0 0.5\n0 1 0.25\n1 1 0\n").unwrap();
    let e = open(&cloud).unwrap_err();
    assert!(matches!(e, SessionError::NotASession { .. }), "{e}");
    let m = e.to_string();
    assert!(m.contains("point cloud") && m.contains("vclay fit"), "{m}");
    assert_eq!(m.lines().count(), 1, "{m}");
    let geomdl = dir.path().join("g.json");
    std::fs::write(
        &geomdl,
        r#"{"shape": {"type": "curve", "count": 0, "data": []}}"#,
    )
    .unwrap();
    let m = open(&geomdl).unwrap_err().to_string();
    assert!(m.contains("geomdl") && m.contains("vclay convert"), "{m}");
    // JSON of another format, and JSON that is nothing vclay reads.
    let other = dir.path().join("o.json");
    std::fs::write(&other, r#"{"format": "blender"}"#).unwrap();
    let m = open(&other).unwrap_err().to_string();
    assert!(m.contains("\"blender\"") && m.contains("o.json"), "{m}");
    std::fs::write(&other, r#"{"answer": 42}"#).unwrap();
    let m = open(&other).unwrap_err().to_string();
    assert!(m.contains("not a vclay session"), "{m}");
    // Broken JSON names the line.
    std::fs::write(&other, "{\n\"entities\": [\n,]}").unwrap();
    let m = open(&other).unwrap_err().to_string();
    assert!(m.contains("line 3"), "{m}");
    // A mesh under another extension: recognized, and told to rename.
    let obj = dir.path().join("cube.txt");
    std::fs::copy(repo().join("fuzz/seeds/obj/cube.obj"), &obj).unwrap();
    let m = open(&obj).unwrap_err().to_string();
    assert!(m.contains("surface mesh") && m.contains("rename"), "{m}");
    // Missing and unknown files.
    let m = open(&dir.path().join("none.toml")).unwrap_err().to_string();
    assert!(m.contains("no such file"), "{m}");
    let bin = dir.path().join("x.bin");
    std::fs::write(&bin, [0u8, 159, 146, 150, 1, 2, 3]).unwrap();
    let m = open(&bin).unwrap_err().to_string();
    assert!(m.contains("not a file vclay reads"), "{m}");
}

#[test]
fn openable_lists_every_kind_that_opens_with_the_extensions_its_files_have() {
    let o = vclay_session::open::openable();
    for k in FileKind::ALL {
        assert_eq!(o.contains(k.describe()), k.opens(), "{k:?} in {o}");
        if k.opens() {
            for e in k.extensions() {
                assert!(o.contains(&format!(".{e}")), ".{e} of {k:?} in {o}");
            }
        }
    }
    assert!(o.contains("a STEP file (.step, .stp, .p21)"), "{o}");
    // The repository's example and seed files: each one recognized has an extension its kind
    // lists (so the start page and the Open dialog name what the files are called).
    let mut seen = std::collections::BTreeSet::new();
    let mut dirs = vec![
        repo().join("examples"),
        repo().join("crates/vclay-io/tests/data/cad"),
    ];
    for d in [
        "geomdl",
        "glb",
        "iges",
        "model_json",
        "obj",
        "ovm",
        "pde_spec",
        "ply",
        "scenario",
        "session",
        "step",
        "stl",
    ] {
        dirs.push(repo().join("fuzz/seeds").join(d));
    }
    while let Some(d) = dirs.pop() {
        for entry in std::fs::read_dir(&d).unwrap() {
            let p = entry.unwrap().path();
            if p.is_dir() {
                dirs.push(p);
                continue;
            }
            let Ok(kind) = vclay_session::open::identify(&p) else {
                continue;
            };
            let ext = p
                .extension()
                .map_or(String::new(), |e| e.to_string_lossy().to_lowercase());
            assert!(
                kind.extensions().contains(&ext.as_str()),
                "{} is {kind:?}, whose extensions are {:?}",
                p.display(),
                kind.extensions()
            );
            seen.insert(format!("{kind:?}"));
        }
    }
    assert!(seen.len() >= 9, "kinds seen: {seen:?}");
}
