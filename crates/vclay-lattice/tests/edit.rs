//! Editing: face extrusion, cell deletion, feature tags across edits.

use vclay_core::Vec3;
use vclay_lattice::{
    CellId, EdgeId, ExtrudeParams, FaceId, Features, LatticeError, VertexId, delete_cell,
    extrude_face, primitives,
};

fn unit_box(n: usize) -> vclay_lattice::Lattice {
    primitives::box_lattice([n; 3], Vec3::zeros(), Vec3::repeat((n - 1) as f64))
}

/// The boundary face of `l` whose centroid is nearest `p`.
fn face_near(l: &vclay_lattice::Lattice, p: Vec3) -> FaceId {
    l.boundary_faces()
        .min_by(|&a, &b| {
            let da = (l.face_centroid(a) - p).norm();
            let db = (l.face_centroid(b) - p).norm();
            da.total_cmp(&db)
        })
        .unwrap()
}

#[test]
fn extrude_top_of_a_unit_cube_grows_a_unit_cube_upward() {
    let cube = unit_box(2);
    let top = face_near(&cube, Vec3::new(0.5, 0.5, 1.0));
    let edit = extrude_face(&cube, top, &ExtrudeParams::default()).unwrap();
    let l = &edit.lattice;
    l.validate().unwrap();
    assert_eq!(l.counts().to_array(), [12, 20, 11, 2]);
    // Every old id is kept, in place.
    for v in 0..8 {
        assert_eq!(edit.point_map[v], Some(VertexId::new(v)));
        assert_eq!(l.points()[v], cube.points()[v]);
    }
    for e in 0..cube.num_edges() {
        assert_eq!(edit.edge_map[e], Some(EdgeId::new(e)));
        assert_eq!(l.edges()[e], cube.edges()[e]);
    }
    for f in 0..cube.num_faces() {
        let id = FaceId::new(f);
        assert_eq!(edit.face_map[f], Some(id));
        assert_eq!(l.face_vertices(id), cube.face_vertices(id));
    }
    assert_eq!(edit.cell_map, vec![Some(CellId(0))]);
    // The extruded face is interior now; the new points are the face's, one unit higher.
    assert!(!l.is_boundary_face(top));
    for (i, &v) in cube.face_vertices(top).iter().enumerate() {
        let q = l.points()[8 + i];
        assert!((q - (cube.point(v) + Vec3::z())).norm() < 1e-12);
    }
    assert!((l.cell_signed_volume(CellId(1)) - 1.0).abs() < 1e-12);
}

#[test]
fn extrude_factor_scales_the_height_with_the_cell_size() {
    let big = primitives::box_lattice([2; 3], Vec3::zeros(), Vec3::repeat(2.0)); // volume 8
    let side = face_near(&big, Vec3::new(2.0, 1.0, 1.0));
    let edit = extrude_face(&big, side, &ExtrudeParams { factor: 0.25 }).unwrap();
    let xs: Vec<f64> = edit.lattice.points()[8..].iter().map(|p| p.x).collect();
    // h = 0.25 * cbrt(8) = 0.5, along +x.
    assert!(xs.iter().all(|&x| (x - 2.5).abs() < 1e-12), "{xs:?}");
}

#[test]
fn extrude_a_triangle_gives_a_wedge_and_twice_is_consistent() {
    let cyl = primitives::cylinder(1.0, 1.0, 3, 1, 0); // 3 wedges
    let top = face_near(&cyl, Vec3::new(0.3, 0.3, 1.0));
    assert_eq!(cyl.face_vertices(top).len(), 3);
    let e1 = extrude_face(&cyl, top, &ExtrudeParams::default()).unwrap();
    let new_cell = CellId::new(cyl.num_cells());
    assert_eq!(e1.lattice.cell_faces(new_cell).len(), 5);
    assert!(e1.lattice.cell_signed_volume(new_cell) > 0.0);
    // Extrude the new cell's top again.
    let l = &e1.lattice;
    let next = l
        .cell_faces(new_cell)
        .iter()
        .copied()
        .find(|&f| l.is_boundary_face(f) && l.face_vertices(f).len() == 3)
        .unwrap();
    let e2 = extrude_face(l, next, &ExtrudeParams::default()).unwrap();
    e2.lattice.validate().unwrap();
    assert_eq!(e2.lattice.num_cells(), cyl.num_cells() + 2);
}

#[test]
fn extrude_refuses_bad_requests() {
    let l = unit_box(3);
    let interior = (0..l.num_faces())
        .map(FaceId::new)
        .find(|&f| !l.is_boundary_face(f))
        .unwrap();
    let err = extrude_face(&l, interior, &ExtrudeParams::default()).unwrap_err();
    assert!(matches!(err, LatticeError::CannotExtrude { .. }), "{err}");
    assert!(err.to_string().contains("interior face"), "{err}");
    let f = l.boundary_faces().next().unwrap();
    for factor in [0.0, -1.0, f64::NAN, f64::INFINITY] {
        let err = extrude_face(&l, f, &ExtrudeParams { factor }).unwrap_err();
        assert!(err.to_string().contains("factor"), "{err}");
    }
    let err = extrude_face(&l, FaceId(9999), &ExtrudeParams::default()).unwrap_err();
    assert_eq!(err, LatticeError::NoSuchFace { face: FaceId(9999) });
}

#[test]
fn extrude_into_an_existing_point_is_refused() {
    // A 2x2x1 slab minus one corner: extruding a face into the notch lands on existing points.
    let l = primitives::voxel_lattice([2, 2, 1], Vec3::zeros(), Vec3::repeat(1.0), |i, j, _| {
        !(i == 1 && j == 1)
    })
    .unwrap();
    let f = face_near(&l, Vec3::new(1.0, 1.5, 0.5)); // faces +x into the missing corner
    let err = extrude_face(&l, f, &ExtrudeParams::default()).unwrap_err();
    assert!(matches!(err, LatticeError::DuplicatePoint { .. }), "{err}");
}

#[test]
fn delete_a_corner_cell_of_a_box() {
    let l = unit_box(3); // 8 cells
    let edit = delete_cell(&l, CellId(0)).unwrap();
    let n = &edit.lattice;
    n.validate().unwrap();
    // The corner cell owned one point, 3 edges, 3 faces.
    assert_eq!(n.counts().to_array(), [26, 51, 33, 7]);
    assert_eq!(edit.cell_map[0], None);
    for c in 1..8 {
        assert_eq!(edit.cell_map[c], Some(CellId::new(c - 1)));
    }
    // Surviving points keep their order and positions.
    let mut next = 0;
    for (v, m) in edit.point_map.iter().enumerate() {
        if let Some(m) = m {
            assert_eq!(m.index(), next);
            assert_eq!(n.point(*m), l.points()[v]);
            next += 1;
        }
    }
    assert_eq!(edit.point_map.iter().filter(|m| m.is_none()).count(), 1);
    // Surviving edges and faces keep their relative order; kept interior faces keep their loop.
    let kept: Vec<usize> = edit.edge_map.iter().flatten().map(|e| e.index()).collect();
    assert!(kept.windows(2).all(|w| w[0] + 1 == w[1]));
    for (f, m) in edit.face_map.iter().enumerate() {
        if let Some(m) = m {
            let old = l.face_vertices(FaceId::new(f));
            let mapped: Vec<VertexId> = old
                .iter()
                .map(|v| edit.point_map[v.index()].unwrap())
                .collect();
            if n.is_boundary_face(*m) == l.is_boundary_face(FaceId::new(f)) {
                assert_eq!(n.face_vertices(*m), &mapped[..]);
            }
        }
    }
    // Volume drops by one cell.
    let vol: f64 = (0..n.num_cells())
        .map(|c| n.cell_signed_volume(CellId::new(c)))
        .sum();
    assert!((vol - 7.0).abs() < 1e-12);
}

#[test]
fn delete_refuses_invalid_results() {
    let one = unit_box(2);
    assert_eq!(
        delete_cell(&one, CellId(0)).unwrap_err(),
        LatticeError::LastCell { cell: CellId(0) }
    );
    assert_eq!(
        delete_cell(&one, CellId(5)).unwrap_err(),
        LatticeError::NoSuchCell { cell: CellId(5) }
    );
    // A row of three: deleting the middle disconnects.
    let row = primitives::box_lattice([4, 2, 2], Vec3::zeros(), Vec3::new(3.0, 1.0, 1.0));
    let err = delete_cell(&row, CellId(1)).unwrap_err();
    assert!(
        matches!(
            err,
            LatticeError::WouldDisconnect {
                before: 1,
                after: 2,
                ..
            }
        ),
        "{err}"
    );
    assert!(err.to_string().contains("fall apart"), "{err}");
    // Two cells that would share only an edge while staying connected through others:
    // (0,0,0) and (1,1,0) in a 2x2x2 grid, joined over the top layer; (1,0,0) covers the edge.
    let l = primitives::voxel_lattice([2, 2, 2], Vec3::zeros(), Vec3::repeat(1.0), |i, j, k| {
        matches!(
            (i, j, k),
            (0, 0, 0) | (1, 0, 0) | (1, 1, 0) | (0, 0, 1) | (1, 0, 1) | (1, 1, 1)
        )
    })
    .unwrap();
    let c100 = cell_at(&l, Vec3::new(1.5, 0.5, 0.5));
    let err = delete_cell(&l, c100).unwrap_err();
    assert!(
        matches!(
            err,
            LatticeError::WouldCreateNonManifoldEdge {
                boundary_faces: 4,
                ..
            }
        ),
        "{err}"
    );
    assert!(err.to_string().contains("non-manifold edge"), "{err}");
    // Deleting a cell of the top layer's end is fine.
    let c000 = cell_at(&l, Vec3::repeat(0.5));
    delete_cell(&l, c000).unwrap().lattice.validate().unwrap();
}

/// The cell whose centroid is at `p`.
fn cell_at(l: &vclay_lattice::Lattice, p: Vec3) -> CellId {
    (0..l.num_cells())
        .map(CellId::new)
        .find(|&c| (l.cell_centroid(c) - p).norm() < 1e-9)
        .unwrap()
}

#[test]
fn delete_refuses_a_pinched_vertex() {
    // Six cells of a 2x2x2 block.
    let l = primitives::voxel_lattice([2, 2, 2], Vec3::zeros(), Vec3::repeat(1.0), |i, j, k| {
        matches!(
            (i, j, k),
            (0, 0, 0) | (1, 0, 0) | (1, 1, 0) | (1, 0, 1) | (1, 1, 1) | (0, 1, 0)
        )
    })
    .unwrap();
    l.validate().unwrap();
    // Every deletion either validates or is refused with a reason.
    for c in 0..l.num_cells() {
        match delete_cell(&l, CellId::new(c)) {
            Ok(e) => e.lattice.validate().unwrap(),
            Err(err) => assert!(
                matches!(
                    err,
                    LatticeError::WouldDisconnect { .. }
                        | LatticeError::WouldCreateNonManifoldEdge { .. }
                        | LatticeError::WouldCreateNonManifoldVertex { .. }
                ),
                "{err}"
            ),
        }
    }
    // A 2x2x2 block without the cell at the origin.
    let l = primitives::voxel_lattice([2, 2, 2], Vec3::zeros(), Vec3::repeat(1.0), |i, j, k| {
        !matches!((i, j, k), (0, 0, 0))
    })
    .unwrap();
    // 7 cells; deleting (1,1,1) leaves the centre vertex where (0,0,0) and (1,1,1) are both
    // missing: the boundary around the centre vertex forms two fans (the vertex is pinched).
    let c111 = cell_at(&l, Vec3::repeat(1.5));
    let err = delete_cell(&l, c111).unwrap_err();
    assert!(
        matches!(
            err,
            LatticeError::WouldCreateNonManifoldVertex { fans: 2, .. }
        ),
        "{err}"
    );
    assert!(err.to_string().contains("pinched"), "{err}");
}

#[test]
fn features_survive_edits_and_untag() {
    let l = unit_box(3);
    let mut f = Features::none(&l);
    let last_edge = EdgeId::new(l.num_edges() - 1);
    let last_point = VertexId::new(l.num_points() - 1);
    f.tag_crease(last_edge).unwrap();
    f.tag_corner(last_point).unwrap();
    f.tag_corner(VertexId(0)).unwrap();
    let edit = delete_cell(&l, CellId(0)).unwrap();
    let g = edit.map_features(&f);
    // Point 0 belonged only to cell 0: its tag is gone; the others moved with their elements.
    assert_eq!(g.num_corners(), 1);
    assert!(g.is_corner(edit.point_map[last_point.index()].unwrap()));
    assert!(g.is_crease(edit.edge_map[last_edge.index()].unwrap()));
    let mut g = g;
    g.untag_crease(edit.edge_map[last_edge.index()].unwrap())
        .unwrap();
    assert_eq!(g.num_creases(), 0);
    g.untag_corner(VertexId(0)).unwrap();
    assert_eq!(g.num_corners(), 1);
    assert!(matches!(
        g.untag_corner(VertexId(10_000)).unwrap_err(),
        LatticeError::BadTag { .. }
    ));
    assert_eq!(g.corners().count(), 1);
    assert_eq!(f.creases().collect::<Vec<_>>(), vec![last_edge]);
}

#[test]
fn edited_lattices_subdivide() {
    use vclay_lattice::{BoundaryRule, SubdivisionRules, SubdivisionSolid};
    let l = unit_box(2);
    let f = face_near(&l, Vec3::new(1.0, 0.5, 0.5));
    let e = extrude_face(&l, f, &ExtrudeParams::default()).unwrap();
    let feats = Features::none(&e.lattice);
    let s = SubdivisionSolid::new(
        e.lattice,
        feats,
        SubdivisionRules::new(BoundaryRule::Sharp),
        2,
    )
    .unwrap();
    assert_eq!(s.finest().num_cells(), 2 * 64);
    s.finest().validate().unwrap();
}
