//! The boundary limit surface (`vclay_lattice::limit_surface`, issues 19 and 20): limit masks
//! agree with the volume limit evaluator on the boundary; exact patches of regular regions equal
//! the Catmull-Clark limit; fitted patches report a small error; normals point outward.

use crate::common;

use common::{perturb, solid};
use vclay_core::{TriMesh, Vec3};
use vclay_lattice::limit::corner_parameters;
use vclay_lattice::{
    BoundaryRule, CellId, Features, LimitEvaluator, LimitParams, SubdivisionRules, boundary_limits,
    boundary_patches, primitives, write_limit_boundary,
};
use vclay_spline::ParametricSurface;

fn boxl() -> vclay_lattice::Lattice {
    let mut l = primitives::box_lattice([4, 4, 4], Vec3::zeros(), Vec3::repeat(3.0));
    perturb(&mut l, 12, 0.2);
    l
}

#[test]
fn limit_masks_agree_with_the_volume_evaluator_on_the_boundary() {
    // The limit position of a boundary vertex of the control lattice, by the surface mask, and
    // by local volume subdivision at the cell corner (tolerance 1e-7 of the diagonal).
    for rule in [BoundaryRule::Smooth, BoundaryRule::Sharp] {
        let l = boxl();
        let f = Features::none(&l);
        let lim = boundary_limits(&l, &f, rule).unwrap();
        let ev = LimitEvaluator::new(&l, &f, SubdivisionRules::new(rule), LimitParams::default())
            .unwrap();
        let mut checked = 0;
        for c in 0..l.num_cells() {
            let frame = ev.frame(CellId(c as u32)).unwrap();
            for (h, v) in frame.iter().enumerate() {
                let Some(s) = lim[v.index()] else { continue };
                let p = ev.evaluate(c, corner_parameters(h)).unwrap();
                assert!(
                    (p.position - s.position).norm() < 1e-6,
                    "{rule:?} cell {c} corner {h}: {} vs {}",
                    p.position,
                    s.position
                );
                checked += 1;
            }
        }
        assert!(checked > 100);
    }
}

#[test]
fn limit_boundary_mesh_has_outward_normals() {
    let s = solid(boxl(), BoundaryRule::Smooth, 2);
    let mut m = TriMesh::new();
    let n = write_limit_boundary(s.finest(), s.features(2), BoundaryRule::Smooth, &mut m).unwrap();
    assert_eq!(n, 2 * 6 * 9 * 16);
    m.validate().unwrap();
    let centre = Vec3::repeat(1.5);
    let mut outward = 0;
    for (p, nrm) in m.positions.iter().zip(&m.normals) {
        assert!((nrm.norm() - 1.0).abs() < 1e-9);
        if (p - centre).dot(nrm) > 0.0 {
            outward += 1;
        }
    }
    assert_eq!(outward, m.positions.len());
    // Limit points lie inside the control hull and away from the control points.
    let f = Features::none(s.lattice(0));
    assert!(boundary_limits(s.lattice(0), &f, BoundaryRule::Interior).is_err());
}

#[test]
fn patches_are_exact_in_regular_regions_and_fitted_elsewhere() {
    let l = boxl();
    let f = Features::none(&l);
    let smooth = boundary_patches(&l, &f, SubdivisionRules::new(BoundaryRule::Smooth), 3).unwrap();
    assert_eq!(smooth.patches.len(), 54);
    // On each side of the 3x3x3 box, the 5 quads that avoid the box corners are regular.
    assert_eq!(smooth.exact.iter().filter(|&&e| e).count(), 30);
    assert!(smooth.max_error_exact < 1e-13, "{}", smooth.max_error_exact);
    assert!(smooth.max_error < 5e-3, "{}", smooth.max_error);
    assert!(smooth.mean_error < 1e-3, "{}", smooth.mean_error);
    let sharp = boundary_patches(&l, &f, SubdivisionRules::new(BoundaryRule::Sharp), 3).unwrap();
    assert_eq!(sharp.exact.iter().filter(|&&e| e).count(), 6);
    assert!(sharp.max_error_exact < 1e-13);
    // The patches' corners interpolate the limit; s x t points outward.
    let centre = Vec3::repeat(1.5);
    for p in &smooth.patches {
        let d = p.derivatives(0.5, 0.5, 1).unwrap();
        assert!(d[1][0].cross(&d[0][1]).dot(&(d[0][0] - centre)) > 0.0);
    }
    // The exact patches agree with the volume evaluator inside the face too.
    let ev = LimitEvaluator::new(
        &l,
        &f,
        SubdivisionRules::new(BoundaryRule::Smooth),
        LimitParams::default(),
    )
    .unwrap();
    let mut checked = 0;
    for (k, &face) in smooth.faces.iter().enumerate() {
        let cell = l.face_cells(face)[0].unwrap();
        let frame = ev.frame(cell).unwrap();
        let vs = l.face_vertices(face);
        let at = |v| corner_parameters(frame.iter().position(|x| *x == v).unwrap());
        let (c0, c1, c3) = (at(vs[0]), at(vs[1]), at(vs[3]));
        for (s, t) in [(0.3, 0.6), (0.8, 0.1)] {
            let uvw: [f64; 3] =
                std::array::from_fn(|a| c0[a] + s * (c1[a] - c0[a]) + t * (c3[a] - c0[a]));
            let x = ev.evaluate(cell.index(), uvw).unwrap().position;
            let y = smooth.patches[k].point(s, t).unwrap();
            let tol = if smooth.exact[k] { 1e-6 } else { 2e-2 };
            assert!((x - y).norm() < tol, "patch {k} ({s}, {t}): {x} vs {y}");
            checked += 1;
        }
    }
    assert_eq!(checked, 108);
}
