//! NurbsCurve: exact circle, partition of unity, affine invariance, derivatives vs finite
//! differences, Bezier vs de Casteljau, bad input.
use crate::common;
use common::*;
use vclay_core::Vec3;
use vclay_spline::{KnotError, KnotVector, NurbsCurve, ParametricCurve, SplineError};

#[test]
fn rational_quadratic_circle_is_exact() {
    let r = 3.7;
    let c = NurbsCurve::circle(Vec3::new(1., -2., 0.5), Vec3::x(), Vec3::y(), r).unwrap();
    for i in 0..=1000 {
        let u = i as f64 / 1000.0;
        let p = c.point(u).unwrap();
        let d = (p - Vec3::new(1., -2., 0.5)).norm();
        assert!((d - r).abs() <= 1e-14 * r, "u={u}: radius {d}");
        assert!((p.z - 0.5).abs() < 1e-15);
    }
    // Derivative is tangent: orthogonal to the radius vector.
    for i in 0..=97 {
        let u = i as f64 / 97.0;
        let d = c.derivatives(u, 1).unwrap();
        let radial = d[0] - Vec3::new(1., -2., 0.5);
        assert!(radial.dot(&d[1]).abs() < 1e-12 * d[1].norm() * r);
    }
}

#[test]
fn basis_is_a_partition_of_unity_and_non_negative() {
    let mut rng = Rng(7);
    for p in 0..=5 {
        let n = p + 1 + 6;
        let kv = KnotVector::new(random_knots(&mut rng, p, n), p, n).unwrap();
        let mut b = vec![0.0; p + 1];
        for u in samples(200) {
            let span = kv.find_span(u);
            kv.basis(span, u, &mut b);
            let s: f64 = b.iter().sum();
            assert!((s - 1.0).abs() < 1e-14, "p={p} u={u} sum={s}");
            assert!(b.iter().all(|&x| x >= -1e-16));
            // Derivatives of a partition of unity sum to zero.
            let d = kv.basis_derivatives_vec(span, u, p.min(3));
            for k in 1..=p.min(3) {
                let sk: f64 = d[k * (p + 1)..(k + 1) * (p + 1)].iter().sum();
                assert!(
                    sk.abs() < 1e-9 * (1.0 + d[k * (p + 1)..].iter().map(|x| x.abs()).sum::<f64>())
                );
            }
        }
    }
}

#[test]
fn unclamped_uniform_basis_is_also_a_partition_of_unity() {
    let kv = KnotVector::uniform(3, 8).unwrap();
    let mut b = [0.0; 4];
    for u in samples(50) {
        kv.basis(kv.find_span(u), u, &mut b);
        assert!((b.iter().sum::<f64>() - 1.0).abs() < 1e-14);
    }
}

#[test]
fn curves_are_affinely_invariant() {
    let mut rng = Rng(11);
    let c = random_curve(&mut rng, 3, 9);
    let m = nalgebra::Matrix3::new(1.2, 0.3, -0.4, 0.1, 0.9, 0.2, -0.5, 0.7, 1.1);
    let t = Vec3::new(0.3, -4.0, 2.5);
    let mut c2 = c.clone();
    c2.transform(&m, &t);
    for u in samples(77) {
        let a = m * c.point(u).unwrap() + t;
        let b = c2.point(u).unwrap();
        assert!((a - b).norm() < 1e-13 * (1.0 + a.norm()));
    }
}

fn assert_fd(c: &NurbsCurve, order: usize) {
    let h = 1e-5;
    let dom = c.domain();
    let (mut checked, mut skipped) = (0, 0);
    for u in samples(40) {
        let u = dom.min + (dom.max - dom.min) * (0.02 + 0.96 * u);
        let d = c.derivatives(u, order).unwrap();
        let dm = c.derivatives(u - h, order).unwrap();
        let dp = c.derivatives(u + h, order).unwrap();
        for k in 1..=order {
            // Central difference of the (k-1)-th derivative.
            let fd = (dp[k - 1] - dm[k - 1]) / (2.0 * h);
            let scale = 1.0 + d[k].norm() + dp[k].norm();
            // Skip parameters straddling a knot where d^k is discontinuous.
            if (dp[k] - dm[k]).norm() > 1e-2 * scale {
                skipped += 1;
                continue;
            }
            checked += 1;
            assert!(
                (fd - d[k]).norm() < 1e-5 * scale,
                "order {k} at u={u}: analytic {:?} fd {:?}",
                d[k],
                fd
            );
        }
    }
    assert!(
        checked > 4 * skipped,
        "too few points checked: {checked} vs {skipped} skipped"
    );
}

#[test]
fn derivatives_match_central_differences() {
    let mut rng = Rng(3);
    for p in 1..=5 {
        let c = random_curve(&mut rng, p, p + 6);
        assert_fd(&c, 4);
    }
    let circle = NurbsCurve::circle(Vec3::zeros(), Vec3::x(), Vec3::z(), 2.0).unwrap();
    assert_fd(&circle, 3);
}

#[test]
fn derivatives_above_the_degree_vanish_for_polynomials() {
    let c = NurbsCurve::clamped_uniform(2, vec![Vec3::zeros(), Vec3::x(), Vec3::y(), Vec3::z()])
        .unwrap();
    let d = c.derivatives(0.3, 5).unwrap();
    assert_eq!(d.len(), 6);
    for dk in &d[3..] {
        assert_eq!(*dk, Vec3::zeros());
    }
}

fn de_casteljau(pw: &[nalgebra::Vector4<f64>], u: f64) -> Vec3 {
    let mut q = pw.to_vec();
    let n = q.len();
    for k in 1..n {
        for i in 0..n - k {
            q[i] = q[i] * (1.0 - u) + q[i + 1] * u;
        }
    }
    q[0].xyz() / q[0].w
}

#[test]
fn bezier_case_matches_de_casteljau() {
    let mut rng = Rng(5);
    for p in 1..=7 {
        let pts: Vec<Vec3> = (0..=p).map(|_| rng.vec3(3.0)).collect();
        let w: Vec<f64> = (0..=p).map(|_| rng.range(0.2, 4.0)).collect();
        let mut knots = vec![0.0; p + 1];
        knots.extend(vec![1.0; p + 1]);
        let c = NurbsCurve::new(p, knots, pts, Some(w)).unwrap();
        let pw = c.homogeneous_points();
        for u in samples(64) {
            let a = c.point(u).unwrap();
            let b = de_casteljau(&pw, u);
            assert!((a - b).norm() < 1e-13 * (1.0 + b.norm()), "p={p} u={u}");
        }
    }
}

#[test]
fn bad_inputs_are_reported_with_their_place() {
    let pts = vec![Vec3::zeros(), Vec3::x(), Vec3::y(), Vec3::z()];
    let e = NurbsCurve::new(2, vec![0., 0., 0., 1., 1., 1.], pts.clone(), None).unwrap_err();
    assert!(matches!(
        e,
        SplineError::Knots {
            axis: 0,
            source: KnotError::Count {
                found: 6,
                expected: 7,
                ..
            }
        }
    ));
    assert!(e.to_string().contains("6 knots given, expected 7"), "{e}");
    let e = NurbsCurve::new(2, vec![0., 0., 0., 0.6, 0.5, 1., 1.], pts.clone(), None).unwrap_err();
    assert!(e.to_string().contains("index 4"), "{e}");
    let e = NurbsCurve::new(
        2,
        vec![0., 0., 0., 0.5, 1., 1., 1.],
        pts.clone(),
        Some(vec![1., 1., 0., 1.]),
    )
    .unwrap_err();
    assert_eq!(
        e.to_string(),
        "weight [2] is 0, weights must be positive and finite"
    );
    let e = NurbsCurve::new(
        2,
        vec![0., 0., 0., 0.5, 1., 1., 1.],
        pts.clone(),
        Some(vec![1., 1., 1.]),
    )
    .unwrap_err();
    assert!(matches!(
        e,
        SplineError::Shape {
            found: 3,
            expected: 4,
            ..
        }
    ));
    let mut bad = pts.clone();
    bad[1].y = f64::INFINITY;
    let e = NurbsCurve::new(2, vec![0., 0., 0., 0.5, 1., 1., 1.], bad, None).unwrap_err();
    assert!(e.to_string().contains("control point [1]"), "{e}");
    let c = NurbsCurve::new(2, vec![0., 0., 0., 0.5, 1., 1., 1.], pts, None).unwrap();
    let e = c.point(1.5).unwrap_err();
    assert_eq!(
        e.to_string(),
        "parameter u = 1.5 lies outside the domain [0, 1]"
    );
    assert!(matches!(
        c.point(f64::NAN),
        Err(SplineError::NonFiniteParameter { .. })
    ));
    // Round-off just outside the domain is accepted and clamped.
    assert_eq!(c.point(1.0 + 1e-15).unwrap(), c.point(1.0).unwrap());
}

#[test]
fn end_points_are_interpolated_with_clamped_knots() {
    let mut rng = Rng(9);
    let c = random_curve(&mut rng, 3, 8);
    assert!((c.point(0.0).unwrap() - c.control_points()[0]).norm() < 1e-15);
    assert!((c.point(1.0).unwrap() - c.control_points()[7]).norm() < 1e-14);
}

/// Issue 17: `vclay eval --derivatives 18446744073709551615` overflowed an index, and 2^32
/// asked for 137 GB; orders above MAX_DERIVATIVE_ORDER are an error before any allocation.
#[test]
fn derivative_orders_above_the_limit_are_errors() {
    use vclay_spline::{MAX_DERIVATIVE_ORDER, NurbsVolume, ParametricVolume};
    let c = NurbsCurve::new(
        1,
        vec![0.0, 0.0, 1.0, 1.0],
        vec![Vec3::zeros(), Vec3::new(1.0, 0.0, 0.0)],
        None,
    )
    .unwrap();
    for k in [MAX_DERIVATIVE_ORDER + 1, 1 << 32, usize::MAX] {
        assert_eq!(
            c.derivatives(0.5, k).unwrap_err(),
            SplineError::DerivativeOrderTooHigh {
                order: k,
                max: MAX_DERIVATIVE_ORDER
            }
        );
    }
    let d = c.derivatives(0.5, MAX_DERIVATIVE_ORDER).unwrap();
    assert_eq!(d.len(), MAX_DERIVATIVE_ORDER + 1);
    assert_eq!(d[1], Vec3::new(1.0, 0.0, 0.0));
    let v = NurbsVolume::box_lattice(
        [1, 1, 1],
        [2, 2, 2],
        Vec3::zeros(),
        Vec3::new(1.0, 1.0, 1.0),
    )
    .unwrap();
    assert!(matches!(
        v.derivatives(0.5, 0.5, 0.5, usize::MAX),
        Err(SplineError::DerivativeOrderTooHigh { .. })
    ));
}
