//! Construction, validation errors and adjacency of `Lattice`.

use crate::common;

use vclay_core::Vec3;
use vclay_lattice::{
    BoundaryRule, CellId, EdgeId, FaceId, Lattice, LatticeError, VertexId, cells, primitives,
};

fn unit_cube_points() -> Vec<Vec3> {
    let mut pts = Vec::new();
    for z in [0.0, 1.0] {
        for (x, y) in [(0.0, 0.0), (1.0, 0.0), (1.0, 1.0), (0.0, 1.0)] {
            pts.push(Vec3::new(x, y, z));
        }
    }
    pts
}

fn hex() -> Vec<Vec<u32>> {
    cells::hexahedron([0, 1, 2, 3, 4, 5, 6, 7])
}

#[test]
fn single_hexahedron_adjacency() {
    let l = Lattice::from_cells(unit_cube_points(), &[hex()]).unwrap();
    assert_eq!(l.counts().to_array(), [8, 12, 6, 1]);
    l.validate().unwrap();
    for v in 0..8 {
        let v = VertexId(v);
        assert_eq!(l.vertex_edges(v).len(), 3);
        assert_eq!(l.vertex_faces(v).len(), 3);
        assert_eq!(l.vertex_cells(v), &[CellId(0)]);
    }
    for e in 0..12 {
        let e = EdgeId(e);
        assert_eq!(l.edge_faces(e).len(), 2);
        assert_eq!(l.edge_cells(e), &[CellId(0)]);
        assert!(l.is_boundary_edge(e));
    }
    assert!((l.cell_signed_volume(CellId(0)) - 1.0).abs() < 1e-14);
    assert_eq!(l.boundary_faces().count(), 6);
    assert_eq!(l.cell_vertices(CellId(0)).len(), 8);
    assert_eq!(l.cell_edges(CellId(0)).len(), 12);
    assert!(l.edge_between(VertexId(0), VertexId(6)).is_none());
    let e = l.edge_between(VertexId(5), VertexId(1)).unwrap();
    assert_eq!(l.edge_vertices(e), [VertexId(1), VertexId(5)]);
    assert!(
        l.face_with_vertices(&[VertexId(3), VertexId(2), VertexId(1), VertexId(0)])
            .is_some()
    );
}

#[test]
fn inside_out_input_is_flipped() {
    let flipped: Vec<Vec<u32>> = hex()
        .into_iter()
        .map(|mut f| {
            f.reverse();
            f
        })
        .collect();
    let l = Lattice::from_cells(unit_cube_points(), &[flipped]).unwrap();
    assert!(l.cell_signed_volume(CellId(0)) > 0.0);
    l.validate().unwrap();
}

#[test]
fn radial_order_around_an_interior_edge() {
    // 2 x 2 x 1 cells: the vertical edge through the middle has 4 faces and 4 cells.
    let l = primitives::box_lattice([3, 3, 2], Vec3::zeros(), Vec3::new(2.0, 2.0, 1.0));
    let a = l
        .points()
        .iter()
        .position(|p| (p - Vec3::new(1.0, 1.0, 0.0)).norm() < 1e-12)
        .unwrap();
    let b = l
        .points()
        .iter()
        .position(|p| (p - Vec3::new(1.0, 1.0, 1.0)).norm() < 1e-12)
        .unwrap();
    let e = l
        .edge_between(VertexId(a as u32), VertexId(b as u32))
        .unwrap();
    let faces = l.edge_faces(e);
    let cells = l.edge_cells(e);
    assert_eq!((faces.len(), cells.len()), (4, 4));
    // Counter-clockwise about +z (a is below b, a < b): face angles increase.
    let angle = |f: FaceId| {
        let c = l.face_centroid(f) - Vec3::new(1.0, 1.0, 0.5);
        c.y.atan2(c.x)
    };
    let mut angles: Vec<f64> = faces.iter().map(|&f| angle(f)).collect();
    let start = angles[0];
    for x in &mut angles {
        *x = (*x - start).rem_euclid(std::f64::consts::TAU);
    }
    assert!(angles.windows(2).all(|w| w[0] < w[1]), "{angles:?}");
    // Cell k lies between faces k and k+1.
    for k in 0..4 {
        let c = cells[k];
        assert!(l.cell_faces(c).contains(&faces[k]));
        assert!(l.cell_faces(c).contains(&faces[(k + 1) % 4]));
    }
    // Face sides: interior faces have two cells, and each cell's use is outward.
    for &f in faces {
        let [front, back] = l.face_cells(f);
        assert!(front.is_some() && back.is_some());
        assert!(l.cell_uses_face_reversed(back.unwrap(), f));
    }
}

#[test]
fn non_convex_many_faced_cell() {
    // An L-shaped prism (hexagon caps): one non-convex cell with 8 faces.
    let prof = [
        [0.0, 0.0],
        [2.0, 0.0],
        [2.0, 1.0],
        [1.0, 1.0],
        [1.0, 2.0],
        [0.0, 2.0],
    ];
    let l = primitives::extrude(&prof, &[vec![0, 1, 2, 3, 4, 5]], &[0.0, 1.0]).unwrap();
    assert_eq!(l.counts().to_array(), [12, 18, 8, 1]);
    assert!((l.cell_signed_volume(CellId(0)) - 3.0).abs() < 1e-12);
    let s = common::solid(l, BoundaryRule::Sharp, 2);
    s.finest().validate().unwrap();
    assert_eq!(s.lattice(1).num_cells(), 12);
}

fn err(points: Vec<Vec3>, cells: &[Vec<Vec<u32>>]) -> LatticeError {
    Lattice::from_cells(points, cells).unwrap_err()
}

#[test]
fn rejects_bad_input_and_names_the_element() {
    let pts = unit_cube_points();
    // Non-finite coordinates.
    let mut bad = pts.clone();
    bad[3].y = f64::NAN;
    assert_eq!(
        err(bad, &[hex()]),
        LatticeError::NonFinitePoint { point: VertexId(3) }
    );
    // No cells.
    assert_eq!(err(pts.clone(), &[]), LatticeError::Empty);
    // Index out of range.
    let mut c = hex();
    c[2][1] = 42;
    assert!(matches!(
        err(pts.clone(), &[c]),
        LatticeError::VertexOutOfRange {
            cell: 0,
            face_in_cell: 2,
            index: 42,
            ..
        }
    ));
    // Degenerate face and repeated vertex.
    let mut c = hex();
    c[0] = vec![0, 3];
    assert!(matches!(
        err(pts.clone(), &[c]),
        LatticeError::DegenerateFace {
            face_in_cell: 0,
            ..
        }
    ));
    let mut c = hex();
    c[1] = vec![4, 5, 6, 4];
    assert!(matches!(
        err(pts.clone(), &[c]),
        LatticeError::RepeatedVertex { vertex: 4, .. }
    ));
    // Open cell: drop the top face.
    let mut c = hex();
    c.remove(1);
    assert!(matches!(
        err(pts.clone(), &[c]),
        LatticeError::OpenCell {
            cell: 0,
            uses: 1,
            ..
        }
    ));
    // Inconsistent orientation: one face reversed.
    let mut c = hex();
    c[3].reverse();
    assert!(matches!(
        err(pts.clone(), &[c]),
        LatticeError::InconsistentOrientation { cell: 0, .. }
    ));
    // Unused point.
    let mut more = pts.clone();
    more.push(Vec3::new(5.0, 5.0, 5.0));
    assert_eq!(
        err(more, &[hex()]),
        LatticeError::UnusedPoint { point: VertexId(8) }
    );
    // Duplicate point.
    let mut dup = pts.clone();
    dup.push(pts[6]);
    let tet = cells::tetrahedron([0, 1, 2, 8]);
    let e = err(dup, &[hex(), tet]);
    assert!(
        matches!(
            e,
            LatticeError::DuplicatePoint {
                a: VertexId(6),
                b: VertexId(8),
                ..
            }
        ) || matches!(e, LatticeError::DegenerateEdge { .. }),
        "{e:?}"
    );
    // Zero-length edge.
    let mut z = pts.clone();
    z[5] = z[4];
    assert!(matches!(
        err(z, &[hex()]),
        LatticeError::DegenerateEdge { .. }
    ));
    // A face used twice by one cell.
    let mut c = hex();
    c.push(c[0].clone());
    assert!(matches!(
        err(pts.clone(), &[c]),
        LatticeError::RepeatedFaceInCell { cell: 0, .. }
    ));
    // Same vertex set, different loop.
    let mut pts2 = pts.clone();
    pts2.push(Vec3::new(0.5, 0.5, -1.0));
    let pyr = vec![
        vec![0, 2, 1, 3],
        vec![0, 1, 8],
        vec![1, 2, 8],
        vec![2, 3, 8],
        vec![3, 0, 8],
    ];
    assert!(matches!(
        err(pts2.clone(), &[hex(), pyr]),
        LatticeError::FaceLoopMismatch { .. }
    ));
    // Two cells using a shared face in the same direction.
    let pyr = cells::pyramid([0, 1, 2, 3, 8]);
    assert!(matches!(
        err(pts2.clone(), &[hex(), pyr]),
        LatticeError::FaceOrientationConflict { cells: [0, 1], .. }
    ));
    // The correctly oriented pyramid below the cube is fine.
    let pyr = cells::pyramid([0, 3, 2, 1, 8]);
    let l = Lattice::from_cells(pts2.clone(), &[hex(), pyr.clone()]).unwrap();
    l.validate().unwrap();
    // Three cells on one face.
    let mut pts3 = pts2.clone();
    pts3.push(Vec3::new(0.5, 0.5, -2.0));
    let pyr2 = cells::pyramid([0, 3, 2, 1, 9]);
    assert!(matches!(
        err(pts3, &[hex(), pyr, pyr2]),
        LatticeError::FaceUsedByMoreThanTwoCells { .. }
            | LatticeError::FaceOrientationConflict { .. }
    ));
    // A cell pinched at a vertex: two tetrahedra sharing only vertex 0, listed as one cell.
    let pts4 = vec![
        Vec3::new(0.0, 0.0, 0.0),
        Vec3::new(1.0, 0.0, 0.0),
        Vec3::new(0.0, 1.0, 0.0),
        Vec3::new(0.0, 0.0, 1.0),
        Vec3::new(-1.0, 0.0, 0.0),
        Vec3::new(0.0, -1.0, 0.0),
        Vec3::new(0.0, 0.0, -1.0),
    ];
    let mut pinched = cells::tetrahedron([0, 1, 2, 3]);
    pinched.extend(cells::tetrahedron([0, 5, 4, 6]));
    assert!(matches!(
        err(pts4, &[pinched]),
        LatticeError::NonManifoldCellVertex {
            cell: 0,
            vertex: VertexId(0)
        }
    ));
}

#[test]
fn error_messages_name_the_element() {
    let mut c = hex();
    c.remove(1);
    let msg = err(unit_cube_points(), &[c]).to_string();
    assert!(
        msg.contains("cell 0") && msg.contains("not closed"),
        "{msg}"
    );
    let mut bad = unit_cube_points();
    bad[2].x = f64::INFINITY;
    assert_eq!(
        err(bad, &[hex()]).to_string(),
        "point 2 has a non-finite coordinate"
    );
}

#[test]
fn subdivided_lattices_pass_validation() {
    for l in [
        primitives::torus(3.0, 1.0, 5, 2),
        primitives::t_solid(1, 1, 1.0),
        primitives::gear(1.0, 2.0, 2.5, 0.5),
    ] {
        let s = common::solid(l, BoundaryRule::Smooth, 2);
        for j in 0..=2 {
            s.lattice(j).validate().unwrap();
            // Every cell is positively oriented (valid, unperturbed shapes).
            for c in 0..s.lattice(j).num_cells() {
                assert!(s.lattice(j).cell_signed_volume(CellId(c as u32)) > 0.0);
            }
        }
    }
}

#[test]
fn adjacency_is_built_lazily() {
    let s = common::solid(
        primitives::box_lattice([3, 3, 3], Vec3::zeros(), Vec3::repeat(1.0)),
        BoundaryRule::Smooth,
        1,
    );
    let fine = s.finest();
    assert!(!fine.has_adjacency());
    assert_eq!(fine.vertex_cells(VertexId(0)).len(), 1);
    assert!(fine.has_adjacency());
}
