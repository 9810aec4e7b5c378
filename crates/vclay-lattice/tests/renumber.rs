//! `Lattice::renumber_points` and `Lattice::locality_order`.

use vclay_core::Vec3;
use vclay_lattice::{
    BoundaryRule, FaceId, Features, LatticeError, SubdivisionRules, SubdivisionSolid, primitives,
};

#[test]
fn renumbered_lattice_is_the_same_complex() {
    let cube = primitives::box_lattice([3, 4, 3], Vec3::zeros(), Vec3::new(1.0, 2.0, 1.5));
    let solid = SubdivisionSolid::new(
        cube.clone(),
        Features::none(&cube),
        SubdivisionRules::new(BoundaryRule::Sharp),
        2,
    )
    .unwrap();
    let fine = solid.finest();
    let order = fine.locality_order();
    let r = fine.renumber_points(&order).unwrap();
    r.validate().unwrap();
    assert_eq!(r.counts(), fine.counts());
    for (i, &o) in order.iter().enumerate() {
        assert_eq!(r.points()[i], fine.points()[o as usize]);
    }
    for f in 0..fine.num_faces() {
        let id = FaceId::new(f);
        assert_eq!(r.face_centroid(id), fine.face_centroid(id));
        assert_eq!(r.face_cells(id), fine.face_cells(id));
    }
    for c in 0..fine.num_cells() {
        let id = vclay_lattice::CellId::new(c);
        assert!((r.cell_signed_volume(id) - fine.cell_signed_volume(id)).abs() < 1e-15);
    }
    // Cuthill-McKee order: edge ends are close in id (the subdivision numbering puts vertex,
    // edge, face and cell points in separate blocks), and the order depends on topology only.
    let span = |l: &vclay_lattice::Lattice| {
        l.edges()
            .iter()
            .map(|[a, b]| (b.index() - a.index()) as f64)
            .sum::<f64>()
            / l.num_edges() as f64
    };
    let (after, before) = (span(&r), span(fine));
    assert!(after < 0.25 * before, "mean edge span {after} vs {before}");
    let mut moved = fine.clone();
    moved.set_points(
        fine.points()
            .iter()
            .map(|p| Vec3::new(-p.z, 2.0 * p.x, p.y + 3.0))
            .collect(),
    );
    assert_eq!(moved.locality_order(), order);
}

#[test]
fn bad_orders_are_rejected_with_the_entry() {
    let cube = primitives::box_lattice([2, 2, 2], Vec3::zeros(), Vec3::repeat(1.0));
    let n = cube.num_points() as u32;
    for (order, what) in [
        ((0..n - 1).collect::<Vec<u32>>(), "length"),
        (
            (0..n).map(|i| if i == 3 { 0 } else { i }).collect(),
            "order[3]",
        ),
        (
            (0..n).map(|i| if i == 5 { 99 } else { i }).collect(),
            "order[5]",
        ),
    ] {
        let e = cube.renumber_points(&order).unwrap_err();
        assert!(matches!(e, LatticeError::Invariant { .. }), "{e}");
        assert!(e.to_string().contains(what) || what == "length", "{e}");
    }
}
