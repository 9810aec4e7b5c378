//! Mesh files: round trips through OBJ, STL (ASCII, binary) and PLY (ASCII, binary), reader
//! features of each format, and every error path with its location.

use std::path::Path;
use vclay_core::{TriMesh, Vec3};
use vclay_io::mesh::{
    Encoding, MeshFormat, decode_mesh, encode_mesh, read_mesh, write_mesh, write_mesh_with,
};

/// A unit cube, 8 shared vertices, 12 triangles, with normals; coordinates that are not exact
/// in binary (0.1) test bit-exact text output.
fn cube() -> TriMesh {
    let mut m = TriMesh::new();
    for i in 0..8 {
        m.positions.push(Vec3::new(
            (i & 1) as f64 * 0.1,
            ((i >> 1) & 1) as f64 / 3.0,
            ((i >> 2) & 1) as f64 - 0.5,
        ));
    }
    let quads = [
        [0, 2, 3, 1],
        [4, 5, 7, 6],
        [0, 1, 5, 4],
        [2, 6, 7, 3],
        [0, 4, 6, 2],
        [1, 3, 7, 5],
    ];
    for [a, b, c, d] in quads {
        m.triangles.push([a, b, c]);
        m.triangles.push([a, c, d]);
    }
    m.compute_normals();
    m
}

fn without_normals(mut m: TriMesh) -> TriMesh {
    m.normals.clear();
    m
}

fn decode(text: &str, format: MeshFormat, name: &str) -> Result<TriMesh, String> {
    decode_mesh(text.as_bytes(), format, name).map_err(|e| e.to_string())
}

fn assert_err(result: Result<TriMesh, String>, pieces: &[&str]) {
    let msg = result.expect_err("expected an error");
    for p in pieces {
        assert!(msg.contains(p), "message {msg:?} lacks {p:?}");
    }
}

/// Asserts that two meshes have the same triangles as coordinate triples (STL numbers vertices
/// in order of first use) up to `tol`.
fn assert_same_triangles(a: &TriMesh, b: &TriMesh, tol: f64) {
    assert_eq!(a.triangles.len(), b.triangles.len());
    for (s, t) in a.triangles.iter().zip(&b.triangles) {
        for k in 0..3 {
            let d = a.positions[s[k] as usize] - b.positions[t[k] as usize];
            assert!(d.norm() <= tol, "{s:?} vs {t:?}");
        }
    }
}

fn round_trip(path: &Path, mesh: &TriMesh, encoding: Encoding) -> TriMesh {
    write_mesh_with(path, mesh, encoding).unwrap();
    read_mesh(path).unwrap()
}

// ---------------------------------------------------------------------------------------------
// Round trips

#[test]
fn obj_round_trip_is_exact_with_and_without_normals() {
    let dir = tempfile::tempdir().unwrap();
    let p = dir.path().join("cube.obj");
    let m = cube();
    assert_eq!(round_trip(&p, &m, Encoding::Ascii), m);
    let text = std::fs::read_to_string(&p).unwrap();
    assert!(
        text.contains("\nvn ") && text.contains("\nf 1//1 3//3 4//4\n"),
        "{text}"
    );
    let bare = without_normals(cube());
    write_mesh(&p, &bare).unwrap();
    assert!(std::fs::read_to_string(&p).unwrap().contains("\nf 1 3 4\n"));
    assert_eq!(read_mesh(&p).unwrap(), bare);
}

#[test]
fn stl_round_trips() {
    let dir = tempfile::tempdir().unwrap();
    let m = cube();
    // ASCII keeps full f64 precision; vertices are merged back to the 8 corners.
    let p = dir.path().join("cube.stl");
    let back = round_trip(&p, &m, Encoding::Ascii);
    assert!(
        std::fs::read_to_string(&p)
            .unwrap()
            .starts_with("solid vclay")
    );
    assert_eq!(back.positions.len(), 8);
    assert!(back.normals.is_empty());
    assert_same_triangles(&back, &m, 0.0);
    // Binary is f32.
    let back = round_trip(&p, &m, Encoding::Binary);
    let bytes = std::fs::read(&p).unwrap();
    assert_eq!(bytes.len(), 84 + 50 * 12);
    assert!(!bytes.starts_with(b"solid"));
    assert_eq!(back.positions.len(), 8);
    assert!(back.normals.is_empty());
    assert_same_triangles(&back, &m, 1e-7);
    // write_mesh defaults to binary.
    write_mesh(&p, &m).unwrap();
    assert_eq!(std::fs::read(&p).unwrap(), bytes);
}

#[test]
fn ply_round_trips_are_exact() {
    let dir = tempfile::tempdir().unwrap();
    let p = dir.path().join("cube.ply");
    for m in [cube(), without_normals(cube())] {
        assert_eq!(round_trip(&p, &m, Encoding::Ascii), m);
        assert!(
            std::fs::read_to_string(&p)
                .unwrap()
                .contains("format ascii 1.0")
        );
        assert_eq!(round_trip(&p, &m, Encoding::Binary), m);
        let bytes = std::fs::read(&p).unwrap();
        assert!(bytes.windows(20).any(|w| w == b"binary_little_endian"));
    }
}

#[test]
fn in_memory_encode_decode() {
    let m = cube();
    for (f, e) in [
        (MeshFormat::Obj, Encoding::Ascii),
        (MeshFormat::Ply, Encoding::Ascii),
        (MeshFormat::Ply, Encoding::Binary),
    ] {
        let bytes = encode_mesh(&m, f, e).unwrap();
        assert_eq!(decode_mesh(&bytes, f, "mem").unwrap(), m, "{f:?} {e:?}");
    }
    let mut bad = cube();
    bad.triangles.push([0, 1, 99]);
    assert!(encode_mesh(&bad, MeshFormat::Obj, Encoding::Ascii).is_err());
}

#[test]
fn format_by_extension() {
    assert_eq!(MeshFormat::from_path("a/b.OBJ").unwrap(), MeshFormat::Obj);
    assert_eq!(MeshFormat::from_path("x.stl").unwrap(), MeshFormat::Stl);
    assert_eq!(MeshFormat::from_path("x.Ply").unwrap(), MeshFormat::Ply);
    assert_eq!(MeshFormat::Ply.extension(), "ply");
    let msg = read_mesh("model.off").unwrap_err().to_string();
    assert!(
        msg.contains("model.off: unknown mesh format \".off\"; expected .obj, .stl or .ply"),
        "{msg}"
    );
    let msg = write_mesh("noext", &cube()).unwrap_err().to_string();
    assert!(
        msg.contains("noext: unknown mesh format (no extension)"),
        "{msg}"
    );
}

#[test]
fn failed_write_keeps_existing_file() {
    let dir = tempfile::tempdir().unwrap();
    let p = dir.path().join("keep.obj");
    write_mesh(&p, &cube()).unwrap();
    let before = std::fs::read(&p).unwrap();
    let mut bad = cube();
    bad.positions[2].x = f64::NAN;
    let msg = write_mesh(&p, &bad).unwrap_err().to_string();
    assert!(
        msg.contains("keep.obj") && msg.contains("vertex 2"),
        "{msg}"
    );
    assert_eq!(std::fs::read(&p).unwrap(), before);
    // No temporary file is left behind.
    assert_eq!(std::fs::read_dir(dir.path()).unwrap().count(), 1);
    // Missing folder: created (issue 17; it was an error naming a temporary file).
    write_mesh(dir.path().join("nope/x.ply"), &cube()).unwrap();
    assert!(dir.path().join("nope/x.ply").is_file());
    // A folder that cannot be created (a file is in the way): the error names the target.
    let msg = write_mesh(dir.path().join("keep.obj/x.ply"), &cube())
        .unwrap_err()
        .to_string();
    assert!(msg.contains("x.ply"), "{msg}");
}

/// Issue 17: what a format would write as `inf` is refused, nothing written.
#[test]
fn values_beyond_the_format_are_refused() {
    let dir = tempfile::tempdir().unwrap();
    let mut big = cube();
    big.positions[3].y = 1e300;
    let p = dir.path().join("big.stl");
    let msg = write_mesh(&p, &big).unwrap_err().to_string();
    assert!(msg.contains("big.stl") && msg.contains("vertex 3"), "{msg}");
    assert!(!p.exists());
    // OBJ and PLY store f64: written.
    write_mesh(dir.path().join("big.obj"), &big).unwrap();
    let mut nan_normal = cube();
    nan_normal.compute_normals();
    nan_normal.normals[1].x = f64::NAN;
    let msg = write_mesh(dir.path().join("n.obj"), &nan_normal)
        .unwrap_err()
        .to_string();
    assert!(msg.contains("normal 1"), "{msg}");
}

#[cfg(unix)]
#[test]
fn written_files_are_not_private() {
    use std::os::unix::fs::PermissionsExt;
    let dir = tempfile::tempdir().unwrap();
    let p = dir.path().join("m.obj");
    write_mesh(&p, &cube()).unwrap();
    let mode = std::fs::metadata(&p).unwrap().permissions().mode();
    assert_ne!(mode & 0o600, 0);
    // Some group or other bit is set under any usual umask (022, 002, 027).
    assert_ne!(mode & 0o070, 0, "mode {mode:o}");
}

// ---------------------------------------------------------------------------------------------
// OBJ reader

#[test]
fn obj_corner_forms_negative_indices_polygons_and_comments() {
    let text = "# a quad and a triangle\n\
                mtllib x.mtl\no thing\n\
                v 0 0 0\nv 1 0 0 1.0\nv 1 1 0 0.5 0.5 0.5\nv 0 1 0\n\
                vt 0 0\nvt 1 0\nvt 1 1\n\
                g group\ns off\nusemtl m\n\
                f 1/1 2/2 3/3 4  # quad, fan-triangulated\n\
                f -4 -3 -1\n";
    let m = decode(text, MeshFormat::Obj, "q.obj").unwrap();
    assert_eq!(m.positions.len(), 4);
    assert_eq!(m.triangles, [[0, 1, 2], [0, 2, 3], [0, 1, 3]]);
    assert!(m.normals.is_empty());

    let text = "v 0 0 0\nv 1 0 0\nv 0 1 0\nvn 0 0 1\nvt 0 0\nf 1//1 2/1/1 -1//-1\n";
    let m = decode(text, MeshFormat::Obj, "n.obj").unwrap();
    assert_eq!(m.normals, vec![Vec3::z(); 3]);
}

#[test]
fn obj_vertex_with_two_normals_is_split() {
    let text = "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\nvn 0 0 1\nvn 1 0 0\n\
                f 1//1 2//1 3//1\nf 1//2 4//2 2//2\n";
    let m = decode(text, MeshFormat::Obj, "s.obj").unwrap();
    // Vertices 1 and 2 are used with both normals: each is duplicated once.
    assert_eq!(m.positions.len(), 6);
    assert_eq!(m.triangles, [[0, 1, 2], [4, 3, 5]]);
    assert_eq!(m.positions[4], m.positions[0]);
    assert_eq!(m.normals[4], Vec3::x());
    assert_eq!(m.normals[0], Vec3::z());
    m.validate().unwrap();
    // A corner without a normal drops normals for the whole mesh.
    let text = "v 0 0 0\nv 1 0 0\nv 0 1 0\nvn 0 0 1\nf 1//1 2//1 3\n";
    assert!(
        decode(text, MeshFormat::Obj, "p.obj")
            .unwrap()
            .normals
            .is_empty()
    );
}

#[test]
fn obj_errors_give_file_and_line() {
    let mut text = String::new();
    for i in 0..200 {
        text.push_str(&format!("v {i} 0 0\n"));
    }
    let bad = format!("{text}# c\n\nf 1 2 203\n");
    assert_err(
        decode(&bad, MeshFormat::Obj, "mesh.obj"),
        &["mesh.obj:203: face references vertex 203 but only 200 vertices are defined"],
    );
    let o = MeshFormat::Obj;
    assert_err(
        decode("v 0 0 0\nv 1 nan 0\n", o, "m.obj"),
        &["m.obj:2: vertex has a non-finite coordinate (nan)"],
    );
    assert_err(
        decode("v 0 0 0\nv 1 0 inf\n", o, "m.obj"),
        &["m.obj:2:", "non-finite"],
    );
    assert_err(
        decode("v 0 0 0\nv 1 x 0\n", o, "m.obj"),
        &["m.obj:2: vertex coordinate \"x\" is not a number"],
    );
    assert_err(
        decode("v 0 0\n", o, "m.obj"),
        &["m.obj:1: vertex needs 3 coordinates, found 2"],
    );
    assert_err(
        decode("v 0 0 0\nv 1 0 0\nf 1 2\n", o, "m.obj"),
        &["m.obj:3: face has 2 corners"],
    );
    assert_err(
        decode("v 0 0 0\nv 1 0 0\nv 1 1 0\nf 1 2 0\n", o, "m.obj"),
        &["m.obj:4: face references vertex 0; OBJ indices start at 1"],
    );
    assert_err(
        decode("v 0 0 0\nv 1 0 0\nv 1 1 0\nf 1 2 -4\n", o, "m.obj"),
        &[
            "m.obj:4: face references vertex -4 (relative) but only 3 vertices are defined before it",
        ],
    );
    assert_err(
        decode("v 0 0 0\nv 1 0 0\nv 1 1 0\nf 1 2 three\n", o, "m.obj"),
        &["m.obj:4: face vertex index \"three\" is not an integer"],
    );
    assert_err(
        decode(
            "v 0 0 0\nv 1 0 0\nv 1 1 0\nvn 0 0 1\nf 1//1 2//1 3//2\n",
            o,
            "m.obj",
        ),
        &["m.obj:5: face references normal 2 but only 1 normals are defined"],
    );
    assert_err(
        decode("v 0 0 0\nv 1 0 0\nv 1 1 0\nf 1/1 2/1 3/1\n", o, "m.obj"),
        &["m.obj:4: face references texture coordinate 1 but only 0"],
    );
    assert_err(
        decode("v 0 0 0\nv 1 0 0\nv 1 1 0\nf 1/1/1/1 2 3\n", o, "m.obj"),
        &["m.obj:4:", "more than 3 parts"],
    );
    assert_err(
        decode("v 0 0 0\nvn 0 1\n", o, "m.obj"),
        &["m.obj:2: normal needs 3 coordinates"],
    );
    assert_err(
        decode("# nothing here\n", o, "empty.obj"),
        &["empty.obj: no vertices"],
    );
    assert_err(decode("", o, "empty.obj"), &["empty.obj: no vertices"]);
}

#[test]
fn read_errors_name_the_file() {
    let dir = tempfile::tempdir().unwrap();
    let p = dir.path().join("mesh.obj");
    std::fs::write(&p, "v 0 0 0\nf 1 1 2\n").unwrap();
    let msg = read_mesh(&p).unwrap_err().to_string();
    assert!(
        msg.ends_with("mesh.obj:2: face references vertex 2 but only 1 vertices are defined"),
        "{msg}"
    );
    let msg = read_mesh(dir.path().join("gone.stl"))
        .unwrap_err()
        .to_string();
    assert!(msg.contains("gone.stl"), "{msg}");
}

// ---------------------------------------------------------------------------------------------
// STL reader

fn binary_stl(header: &[u8], tris: &[[[f32; 3]; 3]]) -> Vec<u8> {
    let mut b = vec![b' '; 80];
    b[..header.len()].copy_from_slice(header);
    b.extend_from_slice(&(tris.len() as u32).to_le_bytes());
    for t in tris {
        b.extend_from_slice(&[0u8; 12]);
        for v in t {
            for c in v {
                b.extend_from_slice(&c.to_le_bytes());
            }
        }
        b.extend_from_slice(&[0, 0]);
    }
    b
}

#[test]
fn stl_binary_detected_by_content_even_with_solid_header() {
    let tris = [
        [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]],
        [[1.0, 0.0, 0.0], [1.0, 1.0, 0.0], [0.0, 1.0, 0.0]],
    ];
    let bytes = binary_stl(b"solid but actually binary", &tris);
    let m = decode_mesh(&bytes, MeshFormat::Stl, "b.stl").unwrap();
    assert_eq!(m.positions.len(), 4, "shared vertices are merged");
    assert_eq!(m.triangles, [[0, 1, 2], [1, 3, 2]]);
}

#[test]
fn stl_ascii_merges_and_fans() {
    let text = "solid x\n facet normal 0 0 1\n  outer loop\n   vertex 0 0 0\n   vertex 1 0 0\n   \
                vertex 1 1 0\n   vertex 0 1 0\n  endloop\n endfacet\n facet normal 0 0 1\n outer loop\n\
                vertex -0.0 0 0\n vertex 1 1 0\n vertex 0.5 2 0\n endloop\n endfacet\nendsolid x\n\
                solid second\nendsolid\n";
    let m = decode(text, MeshFormat::Stl, "a.stl").unwrap();
    assert_eq!(m.positions.len(), 5, "-0.0 merges with 0.0");
    assert_eq!(m.triangles, [[0, 1, 2], [0, 2, 3], [0, 2, 4]]);
    // A missing final endsolid is accepted.
    let text = "solid x\nfacet normal 0 0 1\nouter loop\nvertex 0 0 0\nvertex 1 0 0\nvertex 1 1 0\nendloop\nendfacet\n";
    assert_eq!(
        decode(text, MeshFormat::Stl, "a.stl")
            .unwrap()
            .triangles
            .len(),
        1
    );
}

#[test]
fn stl_errors() {
    let s = MeshFormat::Stl;
    let head = "solid x\nfacet normal 0 0 1\nouter loop\nvertex 0 0 0\n";
    assert_err(
        decode(&format!("{head}vertex 1 0 nan\n"), s, "a.stl"),
        &["a.stl:5: vertex has a non-finite coordinate"],
    );
    assert_err(
        decode(&format!("{head}vertex 1 0\n"), s, "a.stl"),
        &["a.stl:5: vertex needs 3 coordinates, found 2"],
    );
    assert_err(
        decode(&format!("{head}vertex 1 0 0\nendloop\n"), s, "a.stl"),
        &["a.stl:6: facet has 2 vertices"],
    );
    assert_err(
        decode(
            &format!("{head}vertex 1 0 0\nvertex 1 1 0\nendfacet\n"),
            s,
            "a.stl",
        ),
        &["a.stl:7: expected \"vertex\" or \"endloop\", found \"endfacet\""],
    );
    assert_err(
        decode(&format!("{head}vertex 1 0 0\n"), s, "a.stl"),
        &["a.stl:5: file ends inside a facet"],
    );
    assert_err(
        decode("solid x\nfacet normal 0 0 1\nvertex 0 0 0\n", s, "a.stl"),
        &["a.stl:3: expected \"outer loop\""],
    );
    assert_err(
        decode("solid x\nendsolid x\n", s, "a.stl"),
        &["a.stl: no vertices"],
    );
    assert_err(decode("", s, "a.stl"), &["a.stl: no vertices"]);
    assert_err(
        decode("hello", s, "a.stl"),
        &["a.stl: not ASCII STL", "too short"],
    );

    let tri = [[[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]]];
    let mut bytes = binary_stl(b"bin", &[tri[0], tri[0], tri[0]]);
    bytes.truncate(bytes.len() - 7);
    let msg = decode_mesh(&bytes, s, "t.stl").unwrap_err().to_string();
    assert!(msg.contains("t.stl: not ASCII STL and not binary STL: the binary header declares 3 triangles, which take 234 bytes, but the file has 227 bytes"), "{msg}");
    let bad = [
        tri[0],
        [[0.0, 0.0, 0.0], [f32::INFINITY, 0.0, 0.0], [0.0, 1.0, 0.0]],
    ];
    let msg = decode_mesh(&binary_stl(b"bin", &bad), s, "t.stl")
        .unwrap_err()
        .to_string();
    assert!(
        msg.contains("t.stl: facet 1: vertex 1 has a non-finite coordinate"),
        "{msg}"
    );
    let msg = decode_mesh(&binary_stl(b"bin", &[]), s, "t.stl")
        .unwrap_err()
        .to_string();
    assert!(msg.contains("t.stl: no vertices"), "{msg}");
}

// ---------------------------------------------------------------------------------------------
// PLY reader

const PLY_HEAD: &str = "ply\nformat ascii 1.0\ncomment hi\nobj_info x\nelement vertex 4\n\
                        property float x\nproperty float y\nproperty float z\nproperty uchar red\n\
                        element face 2\nproperty list uchar int vertex_indices\n\
                        element edge 1\nproperty int vertex1\nproperty int vertex2\nend_header\n";

#[test]
fn ply_ascii_with_extra_properties_quads_and_other_elements() {
    let text =
        format!("{PLY_HEAD}0 0 0 255\n1 0 0 255\n1 1 0 255\n0 1 0 255\n4 0 1 2 3\n3 0 2 3\n0 1\n");
    let m = decode(&text, MeshFormat::Ply, "a.ply").unwrap();
    assert_eq!(m.positions.len(), 4);
    assert_eq!(m.triangles, [[0, 1, 2], [0, 2, 3], [0, 2, 3]]);
    assert!(m.normals.is_empty());
}

#[test]
fn ply_big_endian_with_mixed_types() {
    let mut b = b"ply\nformat binary_big_endian 1.0\nelement vertex 3\nproperty double x\n\
                  property float y\nproperty short z\nproperty float nx\nproperty float ny\n\
                  property float nz\nelement face 1\nproperty list ushort uint vertex_index\nend_header\n"
        .to_vec();
    for (x, y, z) in [(0.0f64, 0.0f32, 0i16), (1.5, 0.0, 2), (0.0, -1.25, -3)] {
        b.extend_from_slice(&x.to_be_bytes());
        b.extend_from_slice(&y.to_be_bytes());
        b.extend_from_slice(&z.to_be_bytes());
        for n in [0.0f32, 0.0, 1.0] {
            b.extend_from_slice(&n.to_be_bytes());
        }
    }
    b.extend_from_slice(&3u16.to_be_bytes());
    for i in [0u32, 1, 2] {
        b.extend_from_slice(&i.to_be_bytes());
    }
    let m = decode_mesh(&b, MeshFormat::Ply, "be.ply").unwrap();
    assert_eq!(m.positions[1], Vec3::new(1.5, 0.0, 2.0));
    assert_eq!(m.positions[2], Vec3::new(0.0, -1.25, -3.0));
    assert_eq!(m.normals, vec![Vec3::z(); 3]);
    assert_eq!(m.triangles, [[0, 1, 2]]);
}

#[test]
fn ply_errors_give_line_or_element() {
    let p = MeshFormat::Ply;
    let verts = "0 0 0 1\n1 0 0 1\n1 1 0 1\n0 1 0 1\n";
    // Header is 15 lines; vertices on 16-19, faces on 20-21.
    assert_err(
        decode(
            &format!("{PLY_HEAD}{verts}3 0 1 2\n3 0 2 203\n0 1\n"),
            p,
            "mesh.ply",
        ),
        &["mesh.ply:21: face 1: references vertex 203 but only 4 vertices are defined"],
    );
    assert_err(
        decode(
            &format!("{PLY_HEAD}{verts}3 0 1 2\n2 0 2\n0 1\n"),
            p,
            "m.ply",
        ),
        &["m.ply:21: face 1: has 2 vertices"],
    );
    assert_err(
        decode(&format!("{PLY_HEAD}0 0 0 1\n1 nan 0 1\n"), p, "m.ply"),
        &["m.ply:17: vertex 1: non-finite coordinate"],
    );
    assert_err(
        decode(&format!("{PLY_HEAD}0 0 0 1\n1 x 0 1\n"), p, "m.ply"),
        &["m.ply:17: vertex 1: \"x\" is not a valid value"],
    );
    assert_err(
        decode(&format!("{PLY_HEAD}{verts}3 0 1 2.5\n"), p, "m.ply"),
        &["m.ply:20: face 0:"],
    );
    assert_err(
        decode(&format!("{PLY_HEAD}{verts}3 0 1 2\n"), p, "m.ply"),
        &[
            "m.ply:20: face 1: the file ends inside this element (the header declares 2 face elements)",
        ],
    );
    assert_err(
        decode(
            "ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\nproperty float y\nend_header\n0 0\n",
            p,
            "m.ply",
        ),
        &["m.ply:3: element vertex lacks one of the scalar properties x, y, z"],
    );
    assert_err(
        decode(
            "ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\nproperty float y\nproperty float z\nelement face 0\nproperty int a\nend_header\n0 0 0\n",
            p,
            "m.ply",
        ),
        &["m.ply:7: element face lacks a list property vertex_indices"],
    );
    assert_err(
        decode(
            "ply\nformat ascii 1.0\nelement vertex 1\nproperty flot x\nend_header\n",
            p,
            "m.ply",
        ),
        &["m.ply:4: unknown property type \"flot\""],
    );
    assert_err(
        decode(
            "ply\nformat ascii 1.0\nproperty float x\nend_header\n",
            p,
            "m.ply",
        ),
        &["m.ply:3: property before any element"],
    );
    assert_err(
        decode(
            "ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\n",
            p,
            "m.ply",
        ),
        &["m.ply:4: the header has no \"end_header\" line"],
    );
    assert_err(
        decode("ply\nformat utf8 1.0\nend_header\n", p, "m.ply"),
        &["m.ply:2: unknown PLY format \"utf8\""],
    );
    assert_err(
        decode("ply\nelement vertex 0\nend_header\n", p, "m.ply"),
        &["m.ply:3: the header has no \"format\" line"],
    );
    assert_err(
        decode("ply\nformat ascii 1.0\nwhatever\nend_header\n", p, "m.ply"),
        &["m.ply:3: unrecognized header line \"whatever\""],
    );
    assert_err(
        decode(
            "ply\nformat ascii 1.0\nelement vertex -1\nend_header\n",
            p,
            "m.ply",
        ),
        &["m.ply:3: element count \"-1\""],
    );
    assert_err(
        decode("PLY file\n", p, "m.ply"),
        &["m.ply:1: not a PLY file"],
    );
    assert_err(
        decode(
            "ply\nformat ascii 1.0\nelement vertex 0\nproperty float x\nproperty float y\nproperty float z\nend_header\n",
            p,
            "m.ply",
        ),
        &["m.ply: no vertices"],
    );
    assert_err(decode("", p, "m.ply"), &["m.ply: no vertices"]);
}

#[test]
fn ply_binary_errors_give_element_index() {
    let m = cube();
    let bytes = encode_mesh(&m, MeshFormat::Ply, Encoding::Binary).unwrap();
    // Cut inside the last face.
    let msg = decode_mesh(&bytes[..bytes.len() - 3], MeshFormat::Ply, "c.ply")
        .unwrap_err()
        .to_string();
    assert!(msg.contains("c.ply: face 11: the file ends inside this element (the header declares 12 face elements)"), "{msg}");
    // Corrupt the last index of face 5 to 99.
    let end = bytes.len() - 6 * 13;
    let mut bad = bytes.clone();
    bad[end - 4..end].copy_from_slice(&99i32.to_le_bytes());
    let msg = decode_mesh(&bad, MeshFormat::Ply, "c.ply")
        .unwrap_err()
        .to_string();
    assert!(
        msg.contains("c.ply: face 5: references vertex 99 but only 8 vertices are defined"),
        "{msg}"
    );
    // A NaN in vertex 3's y.
    let header_len = bytes
        .windows(11)
        .position(|w| w == b"end_header\n")
        .unwrap()
        + 11;
    let mut bad = bytes.clone();
    let off = header_len + 3 * 48 + 8;
    bad[off..off + 8].copy_from_slice(&f64::NAN.to_le_bytes());
    let msg = decode_mesh(&bad, MeshFormat::Ply, "c.ply")
        .unwrap_err()
        .to_string();
    assert!(
        msg.contains("c.ply: vertex 3: non-finite coordinate"),
        "{msg}"
    );
    // A huge declared count does not allocate or panic.
    let text = String::from_utf8_lossy(&bytes[..header_len])
        .replace("element vertex 8", "element vertex 99999999999");
    let mut huge = text.into_bytes();
    huge.extend_from_slice(&bytes[header_len..]);
    assert!(decode_mesh(&huge, MeshFormat::Ply, "c.ply").is_err());
}

#[test]
fn readers_never_panic_on_garbage() {
    let m = cube();
    let mut inputs: Vec<Vec<u8>> = Vec::new();
    for (f, e) in [
        (MeshFormat::Obj, Encoding::Ascii),
        (MeshFormat::Stl, Encoding::Ascii),
        (MeshFormat::Stl, Encoding::Binary),
        (MeshFormat::Ply, Encoding::Ascii),
        (MeshFormat::Ply, Encoding::Binary),
    ] {
        let bytes = encode_mesh(&m, f, e).unwrap();
        // Every prefix and a few byte flips.
        for cut in (0..bytes.len()).step_by(7) {
            inputs.push(bytes[..cut].to_vec());
        }
        for k in (0..bytes.len()).step_by(5) {
            let mut b = bytes.clone();
            b[k] = b[k].wrapping_add(0x5a);
            inputs.push(b);
        }
    }
    for b in &inputs {
        for f in [MeshFormat::Obj, MeshFormat::Stl, MeshFormat::Ply] {
            if let Ok(mesh) = decode_mesh(b, f, "g") {
                mesh.validate().unwrap();
            }
        }
    }
}

/// Issue 17: a long token of a mesh file is quoted cut to 80 characters, not whole.
#[test]
fn long_tokens_are_quoted_cut() {
    let long = "z".repeat(50_000);
    for (text, format, name) in [
        (format!("v 0 0 {long}\n"), MeshFormat::Obj, "a.obj"),
        (
            format!("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 {long}\n"),
            MeshFormat::Obj,
            "a.obj",
        ),
        (format!("solid x\n{long}\n"), MeshFormat::Stl, "a.stl"),
        (
            format!("ply\nformat {long} 1.0\nend_header\n"),
            MeshFormat::Ply,
            "a.ply",
        ),
        (
            format!("ply\nformat ascii 1.0\n{long}\nend_header\n"),
            MeshFormat::Ply,
            "a.ply",
        ),
    ] {
        let msg = decode(&text, format, name).unwrap_err();
        assert!(msg.len() < 300, "{} characters: {}", msg.len(), &msg[..300]);
        assert!(msg.contains("...\" (50000 characters)"), "{msg}");
    }
}
