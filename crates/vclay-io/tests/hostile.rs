//! Hostile input (issue 17): random byte mutations of valid files given to every reader of
//! vclay-io (model JSON, geomdl JSON, parameter lists, OBJ, STL and PLY in text and binary,
//! binary glTF, STEP, IGES) give an `Ok` or an `Err`, never a panic, and each within a bounded
//! time. Seeded (the same cases every run); each reader's cases take well under a second in a
//! debug build. Longer, coverage-guided runs: `fuzz/` (docs/limits.md).

use proptest::prelude::*;
use proptest::test_runner::{Config, RngAlgorithm, TestRng, TestRunner};
use std::time::{Duration, Instant};
use vclay_core::{TriMesh, Vec3};
use vclay_io::MeshFormat;
use vclay_io::mesh::{Encoding, decode_mesh, encode_mesh};

/// Cases per reader.
const CASES: u32 = 4000;
/// Longest time one case may take (a reader that trusts a mutated count would take far
/// longer, or abort).
const CASE_LIMIT: Duration = Duration::from_secs(2);

/// One edit: (kind, position, byte).
type Edit = (u8, usize, u8);

/// Bytes worth inserting: JSON and number syntax, separators, and any byte.
fn byte() -> impl Strategy<Value = u8> {
    prop_oneof![
        3 => prop::sample::select(b"0123456789-+.eE[]{}\",: \n\t/x".to_vec()),
        1 => any::<u8>(),
    ]
}

fn edits() -> impl Strategy<Value = Vec<Edit>> {
    prop::collection::vec((0u8..5, any::<usize>(), byte()), 1..6)
}

/// Applies `edits` to `seed`: replace, insert or delete a byte, truncate, or repeat a slice
/// (which makes keys, lines and elements appear twice).
fn mutate(seed: &[u8], edits: &[Edit]) -> Vec<u8> {
    let mut b = seed.to_vec();
    for &(kind, pos, x) in edits {
        let n = b.len();
        match kind {
            0 if n > 0 => b[pos % n] = x,
            1 => b.insert(pos % (n + 1), x),
            2 if n > 0 => {
                b.remove(pos % n);
            }
            3 => b.truncate(pos % (n + 1)),
            4 if n > 0 => {
                let start = pos % n;
                let end = (start + 1 + x as usize).min(n);
                let slice = b[start..end].to_vec();
                b.splice(end..end, slice);
            }
            _ => {}
        }
    }
    b
}

/// Runs `read` on mutations of every seed (it says whether the input was accepted); fails on a
/// panic or a slow case.
fn hostile(name: &str, seeds: &[Vec<u8>], read: impl Fn(&[u8]) -> bool) {
    let config = Config {
        cases: CASES,
        failure_persistence: None,
        ..Config::default()
    };
    let rng = TestRng::deterministic_rng(RngAlgorithm::ChaCha);
    let mut runner = TestRunner::new_with_rng(config, rng);
    let strategy = (0..seeds.len(), edits());
    let started = Instant::now();
    let accepted = std::cell::Cell::new(0);
    let result = runner.run(&strategy, |(s, e)| {
        let bytes = mutate(&seeds[s], &e);
        let t = Instant::now();
        if read(&bytes) {
            accepted.set(accepted.get() + 1);
        }
        prop_assert!(
            t.elapsed() < CASE_LIMIT,
            "{name}: {:?} for {:?}",
            t.elapsed(),
            String::from_utf8_lossy(&bytes)
        );
        Ok(())
    });
    if let Err(e) = result {
        panic!("{name}: {e}");
    }
    eprintln!(
        "{name}: {CASES} cases ({} accepted) in {:.2?}",
        accepted.get(),
        started.elapsed()
    );
}

fn text(b: &[u8]) -> std::borrow::Cow<'_, str> {
    String::from_utf8_lossy(b)
}

const MODEL: &str = r#"{"entities": [
{"type": "nurbs-curve", "name": "arc", "degree": 2, "knots": [0, 0, 0, 1, 1, 1],
 "control_points": [[1, 0, 0], [1, 1, 0], [0, 1, 0]], "weights": [1, 0.7071067811865476, 1]},
{"type": "nurbs-surface", "degree": [1, 2], "knots": [[0, 0, 1, 1], [0, 0, 0, 1, 1, 1]],
 "control_points": [[[0, 0, 0], [0, 1, 0.5], [0, 2, 0]], [[1, 0, 0], [1, 1, 0.5], [1, 2, 0]]],
 "weights": [[1, 2, 1], [1, 2, 1]]},
{"type": "nurbs-volume", "degree": [1, 1, 1], "knots": [[0, 0, 1, 1], [0, 0, 1, 1], [0, 0, 1, 1]],
 "control_points": [[[[0, 0, 0], [0, 0, 1]], [[0, 1, 0], [0, 1, 1]]],
                    [[[1, 0, 0], [1, 0, 1]], [[1, 1, 0], [1, 1, 1]]]]}
]}"#;

fn cube() -> TriMesh {
    let mut m = TriMesh::new();
    for i in 0..8 {
        m.positions.push(Vec3::new(
            (i & 1) as f64,
            ((i >> 1) & 1) as f64,
            ((i >> 2) & 1) as f64,
        ));
    }
    for [a, b, c, d] in [
        [0, 2, 3, 1],
        [4, 5, 7, 6],
        [0, 1, 5, 4],
        [2, 6, 7, 3],
        [0, 4, 6, 2],
        [1, 3, 7, 5],
    ] {
        m.triangles.push([a, b, c]);
        m.triangles.push([a, c, d]);
    }
    m.compute_normals();
    m
}

#[test]
fn model_json() {
    hostile("model JSON", &[MODEL.into()], |b| {
        vclay_io::parse_model(&text(b)).is_ok()
    });
}

#[test]
fn geomdl_json() {
    let model = vclay_io::parse_named_model(MODEL).unwrap();
    let seeds: Vec<Vec<u8>> = model
        .into_iter()
        .map(|e| {
            let v = vclay_io::geomdl::to_geomdl_json(&[e]).unwrap();
            serde_json::to_vec(&v).unwrap()
        })
        .collect();
    hostile("geomdl JSON", &seeds, |b| {
        vclay_io::geomdl::parse_geomdl(&text(b)).is_ok()
    });
}

#[test]
fn parameter_lists() {
    let seeds = [b"[[0.1, 0.2], [0.3, 0.4], [1, 0]]".to_vec()];
    hostile("params", &seeds, |b| {
        (1..=3)
            .filter(|&dims| vclay_io::parse_params(&text(b), dims).is_ok())
            .count()
            > 0
    });
}

#[test]
fn meshes() {
    let m = cube();
    for format in [MeshFormat::Obj, MeshFormat::Stl, MeshFormat::Ply] {
        let seeds: Vec<Vec<u8>> = [Encoding::Ascii, Encoding::Binary]
            .into_iter()
            .map(|e| encode_mesh(&m, format, e).unwrap())
            .collect();
        hostile(&format!("{format:?}"), &seeds, |b| {
            decode_mesh(b, format, "hostile").is_ok()
        });
    }
}

#[test]
fn glb() {
    let seed = vclay_io::gltf::to_glb(&[vclay_io::gltf::GlbMesh::new("cube", cube())]).unwrap();
    hostile("glb", &[seed], |b| vclay_io::gltf::decode_glb(b).is_ok());
}

#[test]
fn step_and_iges() {
    let dir = concat!(env!("CARGO_MANIFEST_DIR"), "/tests/data/cad");
    let read = |f: &str| std::fs::read(format!("{dir}/{f}")).unwrap();
    hostile(
        "STEP",
        &[
            read("curve.step"),
            read("rational_surface.step"),
            read("brep_cone.step"),
            read("brep_revolution.step"),
        ],
        |b| vclay_io::step_read::parse_step(&text(b)).is_ok(),
    );
    hostile(
        "IGES",
        &[
            read("curve.igs"),
            read("rational_surface.igs"),
            // Planes through trimmed surfaces, revolutions of arcs, chained transformations.
            read("iges_cylinder_moved.igs"),
            read("iges_sphere.igs"),
            read("iges_extruded_bspline.igs"),
            // Trimmed surfaces (144/142/102) and a B-rep (186, 502-514, 190-196), issue 30.
            read("trimmed_cut_sphere_faces.igs"),
            read("trimmed_cut_sphere_brep.igs"),
        ],
        |b| vclay_io::iges_read::parse_iges(&text(b)).is_ok(),
    );
}

/// Inputs that made a reader panic under `fuzz/run.sh`, kept as regression tests (issue 17).
#[test]
fn fuzz_findings() {
    let dir = concat!(env!("CARGO_MANIFEST_DIR"), "/tests/data/fuzz");
    // An IGES directory entry whose status field holds a multi-byte character: the reader
    // sliced it at a byte that is not a character boundary.
    let iges = std::fs::read(format!("{dir}/iges_status_multibyte.igs")).unwrap();
    let _ = vclay_io::iges_read::parse_iges(&text(&iges));
}
