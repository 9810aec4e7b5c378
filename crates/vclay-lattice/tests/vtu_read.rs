//! Reading `.vtu` lattices (issue 20): what `vtu::write` writes reads back (points exactly,
//! cells as the same point sets and faces), malformed files are located errors, and hostile
//! byte mutations give `Ok` or `Err`, never a panic or a hang.

use crate::common;

use std::time::{Duration, Instant};
use vclay_core::Vec3;
use vclay_lattice::formats::{FormatError, vtu};
use vclay_lattice::{BoundaryRule, CellId, Lattice, cells, primitives};

fn tet_and_pyramid() -> Lattice {
    let points = vec![
        Vec3::new(0.0, 0.0, 0.0),
        Vec3::new(1.0, 0.0, 0.0),
        Vec3::new(1.0, 1.0, 0.0),
        Vec3::new(0.0, 1.0, 0.0),
        Vec3::new(0.5, 0.5, 1.0),
        Vec3::new(0.5, -1.0, 0.8),
    ];
    Lattice::from_cells(
        points,
        &[
            cells::pyramid([0, 1, 2, 3, 4]),
            cells::tetrahedron([0, 1, 4, 5]),
        ],
    )
    .unwrap()
}

fn lattices() -> Vec<(&'static str, Lattice)> {
    vec![
        (
            "box",
            primitives::box_lattice([3, 2, 2], Vec3::zeros(), Vec3::new(2.0, 3.0, 1.0)),
        ),
        ("cylinder", primitives::cylinder(1.0, 2.0, 4, 2, 0)),
        ("gear", primitives::gear(1.0, 2.0, 2.6, 1.0)),
        ("cube-with-holes", primitives::cube_with_holes(1.0)),
        ("tet-pyramid", tet_and_pyramid()),
        (
            "subdivided-pyramid",
            common::solid(tet_and_pyramid(), BoundaryRule::Smooth, 1)
                .finest()
                .clone(),
        ),
    ]
}

/// The sorted point sets of each cell's faces: what a cell is, independent of ids.
fn cell_faces(l: &Lattice, c: usize) -> Vec<Vec<u32>> {
    let mut fs: Vec<Vec<u32>> = l
        .cell_faces(CellId::new(c))
        .iter()
        .map(|&f| {
            let mut v: Vec<u32> = l.face_vertices(f).iter().map(|v| v.0).collect();
            v.sort();
            v
        })
        .collect();
    fs.sort();
    fs
}

#[test]
fn written_lattices_read_back() {
    let mut poly = 0;
    for (name, l) in lattices() {
        let text = vtu::to_string(&l);
        poly += text.contains("faceoffsets") as usize;
        let back = vtu::parse(&text, name).unwrap_or_else(|e| panic!("{name}: {e}"));
        assert_eq!(back.counts(), l.counts(), "{name}");
        assert_eq!(back.points(), l.points(), "{name}");
        for c in 0..l.num_cells() {
            assert_eq!(cell_faces(&back, c), cell_faces(&l, c), "{name} cell {c}");
            let (a, b) = (
                back.cell_signed_volume(CellId::new(c)),
                l.cell_signed_volume(CellId::new(c)),
            );
            assert!((a - b).abs() <= 1e-12 * b.abs().max(1.0), "{name} {c}");
        }
        // Written again, the same VTK cell types.
        for c in 0..l.num_cells() {
            let c = CellId::new(c);
            assert_eq!(vtu::vtk_cell(&back, c).0, vtu::vtk_cell(&l, c).0, "{name}");
        }
    }
    assert!(poly >= 1, "no polyhedron exercised");
    // Point data (as `vclay run` writes) is skipped.
    let l = tet_and_pyramid();
    let mass = vec![1.5; l.num_points()];
    let mut buf = Vec::new();
    vtu::write_with_point_data_to(&l, &[vtu::PointData::Scalars("mass", &mass)], &mut buf).unwrap();
    let back = vtu::parse(&String::from_utf8(buf).unwrap(), "m.vtu").unwrap();
    assert_eq!(back.points(), l.points());
}

fn err(edit: impl Fn(String) -> String) -> String {
    let text = vtu::to_string(&tet_and_pyramid());
    let bad = edit(text.clone());
    assert_ne!(bad, text);
    vtu::parse(&bad, "t.vtu").unwrap_err().to_string()
}

#[test]
fn malformed_vtu_is_a_located_error() {
    type Edit = Box<dyn Fn(String) -> String>;
    let cases: Vec<(Edit, &str)> = vec![
        (
            Box::new(|t| t.replace("UnstructuredGrid\"", "PolyData\"")),
            "t.vtu:2: expected a VTKFile of type=\"UnstructuredGrid\"",
        ),
        (
            Box::new(|t| t.replace("NumberOfPoints=\"6\"", "NumberOfPoints=\"7\"")),
            "t.vtu:6: points array \"Points\": 18 values",
        ),
        (
            Box::new(|t| t.replace("format=\"ascii\"", "format=\"binary\"")),
            "binary format of data array",
        ),
        (
            Box::new(|t| t.replacen("0.5 0.5 1.0", "0.5 x 1.0", 1)),
            "t.vtu:11: expected a number in data array \"Points\", found \"x\"",
        ),
        (
            Box::new(|t| t.replacen("          14 10", "          14 11", 1)),
            "cell 1: VTK cell type 11 is not read",
        ),
        (
            Box::new(|t| t.replacen("          5 9", "          5 8", 1)),
            "cell 1: VTK type 10 has 4 points, found 3",
        ),
        (
            Box::new(|t| t.replacen("0 1 2 3 4", "0 1 2 3 9", 1)),
            "data array \"connectivity\" value 4: 9 is not an integer from 0 to 5",
        ),
        (
            Box::new(|t| t.replacen("<Piece", "<Pi", 1)),
            "expected a <Piece> element",
        ),
    ];
    for (edit, want) in cases {
        let e = err(edit);
        assert!(e.contains(want), "{e}\n  wanted: {want}");
    }
    // A cell whose faces do not close is the lattice's error, naming the file.
    let e = err(|t| t.replacen("4 4 0 1 5", "4 4 0 1 4", 1));
    assert!(e.starts_with("t.vtu: "), "{e}");
    assert!(matches!(
        vtu::parse(
            "<VTKFile type=\"UnstructuredGrid\"><Piece NumberOfPoints=\"1\" NumberOfCells=\"0\"><AppendedData>",
            "a"
        ),
        Err(FormatError::Unsupported { .. })
    ));
}

/// Seeded byte mutations (replace, insert, delete, truncate, repeat a slice) of written files:
/// each is read to `Ok` or `Err` quickly, never a panic.
#[test]
fn hostile_vtu_never_panics() {
    let seeds: Vec<Vec<u8>> = [
        tet_and_pyramid(),
        common::solid(tet_and_pyramid(), BoundaryRule::Smooth, 1)
            .finest()
            .clone(),
    ]
    .iter()
    .map(|l| vtu::to_string(l).into_bytes())
    .collect();
    let mut rng = common::Rng(20);
    let bytes = b"0123456789-+.eE <>/=\"\n\t";
    let (mut ok, started) = (0, Instant::now());
    let cases = 1500;
    for _ in 0..cases {
        let mut b = seeds[(rng.next_u64() % 2) as usize].clone();
        for _ in 0..1 + rng.next_u64() % 5 {
            let n = b.len();
            let pos = rng.next_u64() as usize;
            let x = if rng.next_u64().is_multiple_of(4) {
                rng.next_u64() as u8
            } else {
                bytes[(rng.next_u64() % bytes.len() as u64) as usize]
            };
            match rng.next_u64() % 5 {
                0 if n > 0 => b[pos % n] = x,
                1 => b.insert(pos % (n + 1), x),
                2 if n > 0 => {
                    b.remove(pos % n);
                }
                3 => b.truncate(pos % (n + 1)),
                4 if n > 0 => {
                    let s = pos % n;
                    let e = (s + 1 + x as usize).min(n);
                    let slice = b[s..e].to_vec();
                    b.splice(e..e, slice);
                }
                _ => {}
            }
        }
        let t = Instant::now();
        ok += vtu::parse(&String::from_utf8_lossy(&b), "h.vtu").is_ok() as usize;
        assert!(t.elapsed() < Duration::from_secs(2));
    }
    eprintln!(
        "vtu: {cases} cases ({ok} accepted) in {:.2?}",
        started.elapsed()
    );
}
