//! Knot insertion, clamping and degree elevation leave the shape unchanged.
use crate::common;
use common::*;
use vclay_core::Vec3;
use vclay_spline::{
    KnotVector, NurbsCurve, NurbsSurface, ParametricCurve, ParametricSurface, ParametricVolume,
    SplineError,
};

fn same_curve(a: &NurbsCurve, b: &NurbsCurve) {
    for u in samples(300) {
        let (pa, pb) = (a.point(u).unwrap(), b.point(u).unwrap());
        assert!(
            (pa - pb).norm() < 1e-13 * (1.0 + pa.norm()),
            "u={u}: {pa:?} vs {pb:?}"
        );
    }
}

#[test]
fn knot_insertion_keeps_the_curve() {
    let mut rng = Rng(10);
    for p in 1..=5 {
        let c = random_curve(&mut rng, p, p + 5);
        let c1 = c.insert_knot(0.41, 1).unwrap();
        assert_eq!(c1.control_points().len(), c.control_points().len() + 1);
        same_curve(&c, &c1);
        let c2 = c.insert_knot(0.77, p).unwrap();
        assert_eq!(c2.knots().multiplicity(0.77), p);
        same_curve(&c, &c2);
        // Insert at an existing knot.
        let existing = c.knots().as_slice()[p + 1];
        let m = c.knots().multiplicity(existing);
        if m < p {
            let c3 = c.insert_knot(existing, 1).unwrap();
            same_curve(&c, &c3);
        }
        let too_many = c.insert_knot(0.77, p + 1).unwrap_err();
        assert!(matches!(
            too_many,
            SplineError::InsertionMultiplicity { .. }
        ));
        let refined = c.refine(&[0.1, 0.2, 0.3, 0.9]).unwrap();
        same_curve(&c, &refined);
    }
    let circle = NurbsCurve::circle(Vec3::zeros(), Vec3::x(), Vec3::y(), 1.0).unwrap();
    same_curve(&circle, &circle.insert_knot(0.1, 2).unwrap());
}

#[test]
fn degree_elevation_keeps_the_curve() {
    let mut rng = Rng(20);
    for p in 1..=4 {
        for t in 1..=3 {
            let c = random_curve(&mut rng, p, p + 6);
            let e = c.elevate_degree(t).unwrap();
            assert_eq!(e.degree(), p + t);
            // Each distinct interior knot gains t in multiplicity.
            let distinct = c.knots().distinct().len() - 2;
            assert_eq!(
                e.control_points().len(),
                c.control_points().len() + t * (distinct + 1)
            );
            same_curve(&c, &e);
        }
    }
    let circle = NurbsCurve::circle(Vec3::zeros(), Vec3::x(), Vec3::y(), 1.0).unwrap();
    let e = circle.elevate_degree(2).unwrap();
    for u in samples(200) {
        assert!((e.point(u).unwrap().norm() - 1.0).abs() < 1e-14);
    }
}

#[test]
fn unclamped_curves_are_clamped_then_elevated_without_change() {
    let kv = KnotVector::uniform(3, 8).unwrap();
    let mut rng = Rng(30);
    let pts: Vec<Vec3> = (0..8).map(|_| rng.vec3(1.0)).collect();
    let w: Vec<f64> = (0..8).map(|_| rng.range(0.5, 2.0)).collect();
    let c = NurbsCurve::from_knot_vector(kv, pts, w).unwrap();
    assert!(!c.knots().is_clamped());
    let cl = c.clamped().unwrap();
    assert!(cl.knots().is_clamped());
    assert_eq!(cl.domain(), c.domain());
    same_curve(&c, &cl);
    let e = c.elevate_degree(1).unwrap();
    same_curve(&c, &e);
}

#[test]
fn surface_and_volume_refinement_keep_the_shape() {
    let mut rng = Rng(40);
    let s = random_surface(&mut rng, [3, 2], [6, 5]);
    let cases = [
        s.insert_knot(0, 0.33, 2).unwrap(),
        s.insert_knot(1, 0.6, 1).unwrap(),
        s.elevate_degree(0, 1).unwrap(),
        s.elevate_degree(1, 2).unwrap(),
        NurbsSurface::torus(2.0, 0.5)
            .unwrap()
            .elevate_degree(1, 1)
            .unwrap(),
    ];
    for (n, r) in cases.iter().enumerate() {
        let base = if n == 4 {
            NurbsSurface::torus(2.0, 0.5).unwrap()
        } else {
            s.clone()
        };
        for u in samples(23) {
            for v in samples(19) {
                let (a, b) = (base.point(u, v).unwrap(), r.point(u, v).unwrap());
                assert!((a - b).norm() < 1e-13 * (1.0 + a.norm()), "case {n}");
            }
        }
    }
    assert!(matches!(
        s.insert_knot(2, 0.5, 1),
        Err(SplineError::NoSuchAxis { axis: 2, dims: 2 })
    ));
    let vol = random_volume(&mut rng, [2, 2, 2], [4, 4, 5]);
    for r in [
        vol.insert_knot(2, 0.45, 1).unwrap(),
        vol.elevate_degree(1, 1).unwrap(),
        vol.elevate_degree(0, 2).unwrap(),
    ] {
        for u in samples(6) {
            for v in samples(5) {
                for w in samples(7) {
                    let (a, b) = (vol.point(u, v, w).unwrap(), r.point(u, v, w).unwrap());
                    assert!((a - b).norm() < 1e-13 * (1.0 + a.norm()));
                }
            }
        }
    }
}
