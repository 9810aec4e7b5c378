//! File formats: OVM round trips and malformed input, VTU structure, surface writers, atomic
//! writes, and the `subdivide` command logic.

use crate::common;

use std::path::{Path, PathBuf};

use vclay_core::Vec3;
use vclay_lattice::command::{
    CommandError, DEFAULT_MAX_MEMORY, LatticeSource, OutputFormat, SubdivideOptions, primitive,
    subdivide_command,
};
use vclay_lattice::formats::{FormatError, ovm, surface, vtu};
use vclay_lattice::{
    BoundaryRule, CellId, FaceId, Lattice, LatticeError, boundary_mesh, cells, primitives,
};

/// A fresh empty directory under the target's temp dir.
fn scratch(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("vclay-lattice-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

fn all_primitives() -> Vec<(&'static str, Lattice)> {
    vec![
        (
            "box",
            primitives::box_lattice([3, 4, 2], Vec3::zeros(), Vec3::new(2.0, 3.0, 1.0)),
        ),
        ("cylinder", primitives::cylinder(1.0, 2.0, 4, 2, 0)),
        ("cylinder-rings", primitives::cylinder(1.0, 1.0, 6, 1, 2)),
        ("torus", primitives::torus(2.0, 0.5, 6, 2)),
        ("paper-torus", primitives::paper_torus(1.0, 2.0, 1.0)),
        ("gear", primitives::gear(1.0, 2.0, 2.6, 1.0)),
        ("cube-with-holes", primitives::cube_with_holes(1.0)),
        ("l", primitives::l_solid(2, 1, 1.0)),
        ("t", primitives::t_solid(1, 1, 1.0)),
        (
            "subdivided",
            common::solid(
                primitives::paper_torus(1.0, 2.0, 1.0),
                BoundaryRule::Smooth,
                1,
            )
            .finest()
            .clone(),
        ),
        ("tet-pyramid", tet_and_pyramid()),
    ]
}

/// A pyramid on a unit square with a tetrahedron on one of its triangles.
fn tet_and_pyramid() -> Lattice {
    let points = vec![
        Vec3::new(0.0, 0.0, 0.0),
        Vec3::new(1.0, 0.0, 0.0),
        Vec3::new(1.0, 1.0, 0.0),
        Vec3::new(0.0, 1.0, 0.0),
        Vec3::new(0.5, 0.5, 1.0),
        Vec3::new(0.5, -1.0, 0.8),
    ];
    let pyr = cells::pyramid([0, 1, 2, 3, 4]);
    // Tetrahedron on the pyramid face (0, 1, 4), apex 5 outside it (towards -y).
    let tet = cells::tetrahedron([0, 1, 4, 5]);
    Lattice::from_cells(points, &[pyr, tet]).unwrap()
}

/// Asserts that two lattices are identical element for element.
fn assert_same(a: &Lattice, b: &Lattice, what: &str) {
    assert_eq!(a.counts(), b.counts(), "{what}");
    assert_eq!(a.points(), b.points(), "{what}");
    assert_eq!(a.edges(), b.edges(), "{what}");
    for f in 0..a.num_faces() {
        let f = FaceId::new(f);
        assert_eq!(a.face_vertices(f), b.face_vertices(f), "{what} {f}");
        assert_eq!(a.face_cells(f), b.face_cells(f), "{what} {f}");
    }
    for c in 0..a.num_cells() {
        let c = CellId::new(c);
        assert_eq!(a.cell_faces(c), b.cell_faces(c), "{what} {c}");
    }
}

#[test]
fn ovm_round_trips_every_primitive_exactly() {
    for (name, l) in all_primitives() {
        let text = ovm::to_string(&l);
        let back = ovm::parse(&text, name).unwrap_or_else(|e| panic!("{name}: {e}"));
        back.validate().unwrap();
        assert_same(&l, &back, name);
        // Writing again gives the same text.
        assert_eq!(ovm::to_string(&back), text, "{name}");
    }
}

#[test]
fn ovm_layout_of_a_single_hexahedron() {
    let l = primitives::box_lattice([2; 3], Vec3::zeros(), Vec3::repeat(1.0));
    let text = ovm::to_string(&l);
    let lines: Vec<&str> = text.lines().collect();
    assert_eq!(lines[0], "OVM ASCII");
    assert_eq!(lines[1], "Vertices");
    assert_eq!(lines[2], "8");
    assert_eq!(lines[11], "Edges");
    assert_eq!(lines[12], "12");
    assert_eq!(lines[25], "Faces");
    assert_eq!(lines[26], "6");
    assert!(lines[27].starts_with("4 "));
    assert_eq!(lines[33], "Polyhedra");
    assert_eq!(lines[34], "1");
    // The cell's half-faces point into it: all odd (the faces are stored outward).
    let hfs: Vec<u64> = lines[35]
        .split(' ')
        .skip(1)
        .map(|t| t.parse().unwrap())
        .collect();
    assert_eq!(hfs.len(), 6);
    assert!(hfs.iter().all(|h| h % 2 == 1), "{hfs:?}");
}

#[test]
fn ovm_reader_accepts_comments_case_and_outward_half_faces() {
    let l = primitives::box_lattice([2; 3], Vec3::zeros(), Vec3::repeat(1.0));
    let text = ovm::to_string(&l);
    // Flip every half-face (outward instead of inward), lower-case keywords, add comments.
    let mut out = String::from("# a comment\n");
    let mut in_cells = false;
    for line in text.lines() {
        if line == "Polyhedra" {
            in_cells = true;
        }
        let line = if in_cells && line.starts_with("6 ") {
            let hf: Vec<String> = line
                .split(' ')
                .skip(1)
                .map(|t| (t.parse::<u64>().unwrap() ^ 1).to_string())
                .collect();
            format!("6 {}", hf.join(" "))
        } else if line.chars().all(|c| c.is_ascii_alphabetic()) {
            line.to_lowercase()
        } else {
            line.to_string()
        };
        out.push_str(&line);
        out.push_str("   # trailing\n\n");
    }
    out = out.replacen("ovm ascii", "OVM ASCII", 1);
    let back = ovm::parse(&out, "flipped.ovm").unwrap();
    back.validate().unwrap();
    assert!((back.cell_signed_volume(CellId(0)) - 1.0).abs() < 1e-12);
}

/// The error of parsing `text` (a hexahedron file with one line replaced).
fn ovm_err(edit: impl Fn(&mut Vec<String>)) -> FormatError {
    let l = primitives::box_lattice([2; 3], Vec3::zeros(), Vec3::repeat(1.0));
    let mut lines: Vec<String> = ovm::to_string(&l).lines().map(String::from).collect();
    edit(&mut lines);
    ovm::parse(&lines.join("\n"), "cube.ovm").unwrap_err()
}

/// An edit of the lines of a file.
type LineEdit = Box<dyn Fn(&mut Vec<String>)>;

#[test]
fn ovm_malformed_inputs_name_file_line_and_element() {
    // Lines (1-based): 1 header, 2 Vertices, 3 count, 4-11 points, 12 Edges, 13 count, 14-25
    // edges, 26 Faces, 27 count, 28-33 faces, 34 Polyhedra, 35 count, 36 cell.
    let cases: Vec<(LineEdit, &str)> = vec![
        (
            Box::new(|l| l[0] = "OFF".into()),
            "cube.ovm:1: expected the header \"OVM ASCII\", found \"OFF\"",
        ),
        (
            Box::new(|l| l[0] = "OVM BINARY".into()),
            "cube.ovm: the binary OVM format is not supported",
        ),
        (
            Box::new(|l| l[1] = "Points".into()),
            "cube.ovm:2: expected the section keyword \"Vertices\", found \"Points\"",
        ),
        (
            Box::new(|l| l[2] = "-3".into()),
            "cube.ovm:3: expected the number of vertices (a non-negative integer), found \"-3\"",
        ),
        (
            Box::new(|l| l[4] = "1 2".into()),
            "cube.ovm:5: expected vertex 1 as three finite numbers, found \"1 2\"",
        ),
        (
            Box::new(|l| l[4] = "1 x 2".into()),
            "cube.ovm:5: expected vertex 1 as three numbers, found \"1 x 2\"",
        ),
        (
            Box::new(|l| l[4] = "1 inf 2".into()),
            "cube.ovm:5: expected vertex 1 as three finite numbers",
        ),
        (
            Box::new(|l| l[14] = "0 8".into()),
            "cube.ovm:15: edge 1 references vertex 8 but there are 8 vertices",
        ),
        (
            Box::new(|l| l[14] = "3 3".into()),
            "cube.ovm:15: edge 1: both ends are vertex 3",
        ),
        (
            Box::new(|l| l[14] = "3".into()),
            "cube.ovm:15: expected edge 1 as 2 non-negative integers, found \"3\"",
        ),
        (
            Box::new(|l| l[31] = "4 0 2 99 6".into()),
            "cube.ovm:32: face 4 references half-edge 99 but there are 12 edges",
        ),
        (
            Box::new(|l| l[31] = "4 0 2 6".into()),
            "cube.ovm:32: face 4: declares 4 indices but lists 3",
        ),
        (
            Box::new(|l| l[31] = "2 0 1".into()),
            "cube.ovm:32: face 4: has 2 half-edges, a face needs at least 3",
        ),
        (
            Box::new(|l| l[31] = "4 0 1 2 3".into()),
            "cube.ovm:32: face 4: half-edge 1 ends at vertex 0 but the next one, 2, starts at vertex 2",
        ),
        (
            Box::new(|l| l[35] = "6 1 3 5 7 9 13".into()),
            "cube.ovm:36: polyhedron 0 references half-face 13 but there are 6 faces",
        ),
        (
            Box::new(|l| l[35] = "3 1 3 5".into()),
            "cube.ovm:36: polyhedron 0: has 3 half-faces, a polyhedron needs at least 4",
        ),
        (
            Box::new(|l| l[35] = "5 1 3 5 7 9".into()),
            "cube.ovm: cell 0 is not closed",
        ),
        (
            Box::new(|l| {
                l.truncate(35);
            }),
            "cube.ovm:36: expected polyhedron 0 as a count followed by that many indices, found end of file",
        ),
        (
            Box::new(|l| {
                l.truncate(20);
            }),
            "cube.ovm:21: expected edge 7 as 2 non-negative integers, found end of file",
        ),
    ];
    for (i, (edit, want)) in cases.iter().enumerate() {
        let msg = ovm_err(edit).to_string();
        assert!(
            msg.starts_with(want),
            "case {i}: got {msg:?}, want {want:?}"
        );
    }
    // Typed data in the variants.
    match ovm_err(|l| l[31] = "4 0 2 99 6".into()) {
        FormatError::BadReference {
            line,
            index,
            count,
            kind,
            ..
        } => {
            assert_eq!((line, index, count, kind), (32, 99, 12, "half-edge"));
        }
        e => panic!("{e:?}"),
    }
    match ovm_err(|l| l[35] = "5 1 3 5 7 9".into()) {
        FormatError::Lattice {
            source: LatticeError::OpenCell { .. },
            ..
        } => {}
        e => panic!("{e:?}"),
    }
}

#[test]
fn ovm_read_and_write_files_atomically() {
    let dir = scratch("ovm");
    let path = dir.join("torus.ovm");
    let l = primitives::paper_torus(1.0, 2.0, 1.0);
    ovm::write(&l, &path).unwrap();
    let back = ovm::read(&path).unwrap();
    assert_same(&l, &back, "file");
    // A failing write leaves the old file alone and no temporary behind.
    let before = std::fs::read_to_string(&path).unwrap();
    let err = vclay_lattice::formats::write_atomic(&path, |w| {
        w.write_all(b"partial")?;
        Err(std::io::Error::other("disk full"))
    })
    .unwrap_err();
    assert!(err.to_string().contains("torus.ovm: disk full"), "{err}");
    assert_eq!(std::fs::read_to_string(&path).unwrap(), before);
    assert_eq!(std::fs::read_dir(&dir).unwrap().count(), 1);
    // Missing files and directories are reported with their path.
    let err = ovm::read(&dir.join("missing.ovm")).unwrap_err();
    assert!(matches!(err, FormatError::Io { .. }) && err.to_string().contains("missing.ovm"));
    // A folder that does not exist yet is created (issue 17); a path through a file is an
    // error naming the file written.
    ovm::write(&l, &dir.join("no-such-dir").join("x.ovm")).unwrap();
    assert!(dir.join("no-such-dir").join("x.ovm").exists());
    let err = ovm::write(&l, &path.join("x.ovm")).unwrap_err();
    assert!(err.to_string().contains("x.ovm"), "{err}");
    let _ = std::fs::remove_dir_all(&dir);
}

/// The content of the named `DataArray` as numbers.
fn data_array(xml: &str, name: &str) -> Vec<f64> {
    let tag = format!("Name=\"{name}\"");
    let start = xml.find(&tag).unwrap_or_else(|| panic!("no array {name}"));
    let body = &xml[start..];
    let body = &body[body.find('>').unwrap() + 1..body.find("</DataArray>").unwrap()];
    body.split_whitespace()
        .map(|t| t.parse().unwrap())
        .collect()
}

fn signed_volume(points: &[Vec3], faces: &[Vec<usize>]) -> f64 {
    let o = points[faces[0][0]];
    let mut v = 0.0;
    for f in faces {
        let g = f.iter().map(|&i| points[i]).sum::<Vec3>() / f.len() as f64 - o;
        for i in 0..f.len() {
            let a = points[f[i]] - o;
            let b = points[f[(i + 1) % f.len()]] - o;
            v += g.dot(&a.cross(&b));
        }
    }
    v / 6.0
}

#[test]
fn vtu_structure_types_and_orientation() {
    for (name, l) in all_primitives() {
        let xml = vtu::to_string(&l);
        assert!(xml.starts_with("<?xml version=\"1.0\"?>\n<VTKFile type=\"UnstructuredGrid\""));
        assert!(xml.contains(&format!(
            "<Piece NumberOfPoints=\"{}\" NumberOfCells=\"{}\">",
            l.num_points(),
            l.num_cells()
        )));
        let pts = data_array(&xml, "Points");
        assert_eq!(pts.len(), 3 * l.num_points(), "{name}");
        let points: Vec<Vec3> = pts.chunks(3).map(|c| Vec3::new(c[0], c[1], c[2])).collect();
        assert_eq!(points, l.points(), "{name}");
        let conn: Vec<usize> = data_array(&xml, "connectivity")
            .iter()
            .map(|&x| x as usize)
            .collect();
        let offsets: Vec<usize> = data_array(&xml, "offsets")
            .iter()
            .map(|&x| x as usize)
            .collect();
        let types: Vec<u8> = data_array(&xml, "types").iter().map(|&x| x as u8).collect();
        assert_eq!(offsets.len(), l.num_cells());
        assert_eq!(types.len(), l.num_cells());
        assert_eq!(*offsets.last().unwrap(), conn.len());
        let has_poly = types.contains(&vtu::VTK_POLYHEDRON);
        assert_eq!(xml.contains("Name=\"faces\""), has_poly, "{name}");
        let (faces, faceoffsets) = if has_poly {
            (data_array(&xml, "faces"), data_array(&xml, "faceoffsets"))
        } else {
            (vec![], vec![])
        };
        let mut start = 0;
        for c in 0..l.num_cells() {
            let cid = CellId::new(c);
            let cp = &conn[start..offsets[c]];
            // Every cell's point set is the lattice cell's.
            let mut sorted: Vec<u32> = cp.iter().map(|&v| v as u32).collect();
            sorted.sort_unstable();
            let want: Vec<u32> = l.cell_vertices(cid).iter().map(|v| v.0).collect();
            assert_eq!(sorted, want, "{name} cell {c}");
            let expect_type = match (l.cell_faces(cid).len(), l.cell_vertices(cid).len()) {
                (6, 8) => vtu::VTK_HEXAHEDRON,
                (5, 6) => vtu::VTK_WEDGE,
                (4, 4) => vtu::VTK_TETRA,
                (5, 5) => vtu::VTK_PYRAMID,
                _ => vtu::VTK_POLYHEDRON,
            };
            assert_eq!(types[c], expect_type, "{name} cell {c}");
            // The reference faces over the written points enclose positive volume.
            let faces_of: Vec<Vec<usize>> = if types[c] == vtu::VTK_POLYHEDRON {
                let end = faceoffsets[c] as usize;
                let prev = (0..c)
                    .rev()
                    .find_map(|k| (faceoffsets[k] >= 0.0).then(|| faceoffsets[k] as usize))
                    .unwrap_or(0);
                let run: Vec<usize> = faces[prev..end].iter().map(|&x| x as usize).collect();
                let mut out = Vec::new();
                let mut i = 1;
                for _ in 0..run[0] {
                    out.push(run[i + 1..i + 1 + run[i]].to_vec());
                    i += 1 + run[i];
                }
                assert_eq!(i, run.len());
                out
            } else {
                assert_eq!(faceoffsets.get(c).copied().unwrap_or(-1.0), -1.0);
                vtu::reference_faces(types[c])
                    .iter()
                    .map(|f| f.iter().map(|&i| cp[i]).collect())
                    .collect()
            };
            // VTK's convention, the one its code computes positive volumes for (VTK 9.7's
            // vtkCellSizeFilter; the vtkWedge documentation says the opposite for wedges): the
            // base's right-hand normal points into the cell, towards its other points.
            let base_len = match types[c] {
                vtu::VTK_TETRA | vtu::VTK_WEDGE => 3,
                vtu::VTK_PYRAMID | vtu::VTK_HEXAHEDRON => 4,
                _ => 0,
            };
            if base_len > 0 {
                let b: Vec<Vec3> = cp[..base_len].iter().map(|&i| points[i]).collect();
                let normal: Vec3 = (0..base_len)
                    .map(|k| b[k].cross(&b[(k + 1) % base_len]))
                    .sum();
                let centre = b.iter().sum::<Vec3>() / base_len as f64;
                let rest = cp[base_len..].iter().map(|&i| points[i]).sum::<Vec3>()
                    / (cp.len() - base_len) as f64;
                assert!(
                    normal.dot(&(rest - centre)) > 0.0,
                    "{name} cell {c} (type {}): the base's normal points out of the cell",
                    types[c]
                );
            }
            let vol = signed_volume(&points, &faces_of);
            let want = l.cell_signed_volume(cid);
            assert!(
                (vol - want).abs() < 1e-9 * want.abs().max(1.0) && vol > 0.0,
                "{name} cell {c}: {vol} vs {want}"
            );
            start = offsets[c];
        }
        let ids = data_array(&xml, "cell_id");
        assert_eq!(ids.len(), l.num_cells());
    }
}

#[test]
fn vtu_detects_every_linear_type_and_polyhedra() {
    let l = tet_and_pyramid();
    assert_eq!(vtu::vtk_cell(&l, CellId(0)).0, vtu::VTK_PYRAMID);
    assert_eq!(vtu::vtk_cell(&l, CellId(1)).0, vtu::VTK_TETRA);
    let s = common::solid(
        primitives::paper_torus(1.0, 2.0, 1.0),
        BoundaryRule::Smooth,
        1,
    );
    let types: Vec<u8> = (0..s.finest().num_cells())
        .map(|c| vtu::vtk_cell(s.finest(), CellId::new(c)).0)
        .collect();
    assert!(types.iter().all(|&t| t == vtu::VTK_HEXAHEDRON));
    // A pyramid's subdivided apex cell has 8 faces: a polyhedron.
    let p = common::solid(tet_and_pyramid(), BoundaryRule::Smooth, 1);
    let types: Vec<u8> = (0..p.finest().num_cells())
        .map(|c| vtu::vtk_cell(p.finest(), CellId::new(c)).0)
        .collect();
    assert!(types.contains(&vtu::VTK_POLYHEDRON) && types.contains(&vtu::VTK_HEXAHEDRON));
}

#[test]
fn surface_writers() {
    let l = primitives::box_lattice([2; 3], Vec3::zeros(), Vec3::repeat(1.0));
    let m = boundary_mesh(&l);
    let mut buf = Vec::new();
    surface::write_obj_to(&m, &mut buf).unwrap();
    let obj = String::from_utf8(buf).unwrap();
    assert_eq!(obj.lines().filter(|l| l.starts_with("v ")).count(), 8);
    assert_eq!(obj.lines().filter(|l| l.starts_with("f ")).count(), 12);
    assert!(obj.lines().filter(|l| l.starts_with("f ")).all(|l| {
        l.split(' ')
            .skip(1)
            .all(|i| (1..=8).contains(&i.parse::<u32>().unwrap()))
    }));
    let mut buf = Vec::new();
    surface::write_stl_to(&m, "cube", &mut buf).unwrap();
    let stl = String::from_utf8(buf).unwrap();
    assert!(stl.starts_with("solid cube\n") && stl.ends_with("endsolid cube\n"));
    assert_eq!(stl.matches("facet normal").count(), 12);
    assert_eq!(stl.matches("      vertex ").count(), 36);
    // Normals point outward: away from the cube's centre.
    for chunk in stl.split("facet normal ").skip(1) {
        let nums: Vec<f64> = chunk
            .split_whitespace()
            .take(3)
            .map(|t| t.parse().unwrap())
            .collect();
        let vs: Vec<f64> = chunk
            .split("vertex ")
            .nth(1)
            .unwrap()
            .split_whitespace()
            .take(3)
            .map(|t| t.parse().unwrap())
            .collect();
        let d = (vs[0] - 0.5) * nums[0] + (vs[1] - 0.5) * nums[1] + (vs[2] - 0.5) * nums[2];
        assert!(d > 0.0);
    }
    let mut buf = Vec::new();
    surface::write_ply_to(&m, &mut buf).unwrap();
    let ply = String::from_utf8(buf).unwrap();
    assert!(ply.starts_with("ply\nformat ascii 1.0\n"));
    assert!(ply.contains("element vertex 8\n") && ply.contains("element face 12\n"));
    let body = ply.split("end_header\n").nth(1).unwrap();
    assert_eq!(body.lines().count(), 20);
    assert!(body.lines().skip(8).all(|l| l.starts_with("3 ")));
}

fn opts(source: LatticeSource, levels: usize, out: Option<&Path>) -> SubdivideOptions {
    SubdivideOptions {
        source,
        levels,
        boundary: BoundaryRule::Smooth,
        out: out.map(Path::to_path_buf),
        max_memory: DEFAULT_MAX_MEMORY,
    }
}

#[test]
fn command_subdivides_primitives_and_files_and_writes_every_format() {
    // Conference paper, Table 1, "Cube (4^3)", level 2.
    let r =
        subdivide_command(&opts(LatticeSource::Primitive("box:4x4x4".into()), 2, None)).unwrap();
    assert_eq!(r.counts.to_array(), [2197, 6084, 5616, 1728]);
    assert_eq!(
        r.stats_json(),
        "{\"points\": 2197, \"edges\": 6084, \"faces\": 5616, \"cells\": 1728, \"inverted_cells\": 0}"
    );
    // The paper's single-cell tetrahedron with holes folds when subdivided (docs/formats.md):
    // 12 of its 16 level-1 cells have negative volume (VTK's vtkCellSizeFilter agrees,
    // bench/check_vtk.sh); the default one, split into convex cells (issue 19), does not.
    let t = subdivide_command(&opts(
        LatticeSource::Primitive("tetrahedron-with-holes-paper".into()),
        1,
        None,
    ))
    .unwrap();
    assert_eq!((t.counts.cells, t.inverted_cells), (16, 12));
    let t = subdivide_command(&opts(
        LatticeSource::Primitive("tetrahedron-with-holes".into()),
        2,
        None,
    ))
    .unwrap();
    assert_eq!((t.counts.cells, t.inverted_cells), (416, 0));
    assert_eq!(r.control.cells, 27);
    let dir = scratch("command");
    let input = dir.join("gear.ovm");
    ovm::write(&primitive("gear").unwrap(), &input).unwrap();
    for ext in ["ovm", "vtu", "obj", "ply", "stl", "OBJ"] {
        let out = dir.join(format!("out.{ext}"));
        let r =
            subdivide_command(&opts(LatticeSource::File(input.clone()), 1, Some(&out))).unwrap();
        assert_eq!(r.counts.cells, 12 * 8 + 4 * 6, "{ext}");
        assert!(std::fs::metadata(&out).unwrap().len() > 0);
        assert_eq!(
            r.written.as_ref().unwrap().1,
            OutputFormat::from_path(&out).unwrap()
        );
    }
    // The written .ovm reads back with the reported counts.
    let back = ovm::read(&dir.join("out.ovm")).unwrap();
    assert_eq!(back.num_cells(), 12 * 8 + 4 * 6);
    // Errors.
    let err = subdivide_command(&opts(
        LatticeSource::File(input.clone()),
        1,
        Some(&dir.join("x.vtk")),
    ))
    .unwrap_err();
    assert!(
        matches!(err, CommandError::UnknownOutputFormat { .. }),
        "{err}"
    );
    let err =
        subdivide_command(&opts(LatticeSource::File(dir.join("x.msh")), 1, None)).unwrap_err();
    assert!(
        err.to_string().contains("x.msh: unknown input format"),
        "{err}"
    );
    std::fs::write(dir.join("bad.ovm"), "OVM ASCII\nVertices\n1\n0 0\n").unwrap();
    let err =
        subdivide_command(&opts(LatticeSource::File(dir.join("bad.ovm")), 1, None)).unwrap_err();
    assert!(
        err.to_string().contains("bad.ovm:4: expected vertex 0"),
        "{err}"
    );
    let err =
        subdivide_command(&opts(LatticeSource::Primitive("box".into()), 12, None)).unwrap_err();
    assert!(matches!(err, CommandError::TooManyLevels { .. }), "{err}");
    // Issue 17: the default box at level 6 (7 million cells, 4.7 GB measured) is over the default
    // memory limit and refused before anything is subdivided; a small limit refuses level 2.
    let err =
        subdivide_command(&opts(LatticeSource::Primitive("box".into()), 6, None)).unwrap_err();
    assert!(
        matches!(
            err,
            CommandError::TooMuchMemory {
                levels: 6,
                predicted: 7_077_888,
                ..
            }
        ),
        "{err}"
    );
    // Issue 29 item 3: the default limit reads as given, 4G (not "4.3 GB").
    assert!(
        err.to_string()
            .contains("GB of memory, more than the limit of 4G"),
        "{err}"
    );
    let mut small = opts(LatticeSource::Primitive("box".into()), 2, None);
    small.max_memory = 1 << 20;
    let err = subdivide_command(&small).unwrap_err();
    assert!(matches!(err, CommandError::TooMuchMemory { .. }), "{err}");
    small.max_memory = 1 << 30;
    assert!(subdivide_command(&small).is_ok());
    let _ = std::fs::remove_dir_all(&dir);
}

/// Issue 17: a hole so small that its points coincide was an `expect`.
#[test]
fn degenerate_primitive_is_an_error() {
    let err = primitive("tetrahedron-with-holes:1e-300").unwrap_err();
    assert!(
        matches!(err, CommandError::DegeneratePrimitive { .. }),
        "{err}"
    );
    assert!(err.to_string().contains("degenerate"), "{err}");
    assert!(primitive("tetrahedron-with-holes:0.01").is_ok());
    let err = primitive("tetrahedron-with-holes-paper:1e-300").unwrap_err();
    assert!(
        matches!(err, CommandError::DegeneratePrimitive { .. }),
        "{err}"
    );
}

#[test]
fn command_primitive_specs() {
    let counts = |s: &str| primitive(s).unwrap().counts().to_array();
    assert_eq!(counts("box"), [64, 144, 108, 27]);
    assert_eq!(counts("box:3"), [27, 54, 36, 8]);
    assert_eq!(counts("box:2x3x4").last(), Some(&6));
    assert_eq!(counts("cylinder"), [15, 34, 28, 8]);
    assert_eq!(counts("cylinder:8x1x1")[3], 16);
    assert_eq!(counts("paper-torus"), [24, 52, 36, 8]);
    // The same torus as a scenario's `primitive = "torus"`: 8 segments of 4 x 4 hexahedra.
    assert_eq!(counts("torus")[3], 128);
    // One registry: the scenario names and the short aliases build the same lattices.
    assert_eq!(counts("l-solid"), counts("l"));
    assert_eq!(counts("T-solid"), counts("t"));
    assert_eq!(counts("cube"), counts("box"));
    let e = primitive("donut").unwrap_err().to_string();
    assert!(e.contains("paper-torus") && e.contains("l-solid"), "{e}");
    assert_eq!(counts("torus:8x2")[3], 32);
    assert_eq!(counts("gear"), [56, 116, 76, 16]);
    assert_eq!(counts("cube-with-holes"), [64, 144, 96, 20]);
    assert_eq!(counts("tetrahedron-with-holes"), [16, 42, 34, 10]);
    assert_eq!(counts("tetrahedron-with-holes-paper"), [16, 42, 22, 1]);
    assert_eq!(counts("soccer-player"), [104, 200, 122, 24]);
    assert_eq!(counts("cactus"), [108, 212, 131, 26]);
    assert_eq!(counts("spiked-object")[3], 75);
    assert_eq!(counts("holed-object")[3], 135);
    assert_eq!(counts("l")[3], 5);
    assert_eq!(counts("T")[3], 4);
    assert_eq!(counts("t:2x1")[3], 7);
    for bad in [
        "sphere",
        "box:1",
        "box:2x2",
        "box:axb",
        "cylinder:2",
        "torus:2x1",
        "gear:3",
        "cactus:2",
        "soccer-player:1",
        "l:0",
        "box:2000",
    ] {
        let err = primitive(bad).unwrap_err();
        assert!(
            matches!(err, CommandError::BadPrimitive { .. }),
            "{bad}: {err}"
        );
        assert!(
            err.to_string().starts_with(&format!("primitive '{bad}'")),
            "{err}"
        );
    }
}

#[test]
fn vtu_point_data_is_written_and_checked() {
    use vtu::PointData;
    let l = primitives::box_lattice([2, 2, 3], Vec3::zeros(), Vec3::repeat(1.0));
    let n = l.num_points();
    let disp: Vec<Vec3> = (0..n).map(|i| Vec3::new(i as f64, 0.5, -0.25)).collect();
    let mass: Vec<f64> = (0..n).map(|i| 1.0 / (i + 1) as f64).collect();
    let mut buf = Vec::new();
    vtu::write_with_point_data_to(
        &l,
        &[
            PointData::Vectors("displacement", &disp),
            PointData::Scalars("mass", &mass),
        ],
        &mut buf,
    )
    .unwrap();
    let xml = String::from_utf8(buf).unwrap();
    assert!(xml.contains("<PointData>"));
    assert!(xml.contains("Name=\"displacement\" NumberOfComponents=\"3\""));
    let d = data_array(&xml, "displacement");
    assert_eq!(d.len(), 3 * n);
    assert_eq!((d[3], d[4], d[5]), (1.0, 0.5, -0.25));
    let m = data_array(&xml, "mass");
    assert_eq!(m, mass, "scalars round-trip exactly");
    // Without data arrays: no PointData element (the plain writer).
    assert!(!vtu::to_string(&l).contains("<PointData>"));
    // Wrong length, repeated name, bad name: InvalidInput naming the array; nothing written.
    let short = &mass[..n - 1];
    for (data, needle) in [
        (
            vec![PointData::Scalars("mass", short)],
            "11 values for 12 points",
        ),
        (
            vec![
                PointData::Scalars("mass", &mass),
                PointData::Scalars("mass", &mass),
            ],
            "used twice",
        ),
        (vec![PointData::Scalars("a b", &mass)], "name must be"),
    ] {
        let mut buf = Vec::new();
        let err = vtu::write_with_point_data_to(&l, &data, &mut buf).unwrap_err();
        assert_eq!(err.kind(), std::io::ErrorKind::InvalidInput);
        assert!(err.to_string().contains(needle), "{err}");
        assert!(buf.is_empty());
    }
}
