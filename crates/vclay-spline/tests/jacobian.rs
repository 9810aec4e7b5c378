//! D-NURBS Jacobians (d-nurbs.txt eqs 3-6): s = J p, and J against finite differences of the
//! point with respect to each control point and weight.
use crate::common;
use common::*;
use vclay_core::Vec3;
use vclay_spline::{ParametricCurve, ParametricSurface, ParametricVolume, generalized_coordinates};

#[test]
fn curve_point_equals_j_times_p() {
    let mut rng = Rng(1);
    let c = random_curve(&mut rng, 3, 9);
    let p = generalized_coordinates(c.control_points(), c.weights());
    for u in samples(50) {
        let j = c.jacobian(u).unwrap();
        let s = c.point(u).unwrap();
        let dense = j.to_dense(9) * &p;
        let dense = Vec3::new(dense[0], dense[1], dense[2]);
        assert!(
            (dense - s).norm() < 1e-14 * (1.0 + s.norm()),
            "eq 4 at u={u}"
        );
        assert!((j.apply(c.control_points(), c.weights()) - s).norm() < 1e-14 * (1.0 + s.norm()));
        assert!((j.point - s).norm() < 1e-15 * (1.0 + s.norm()));
    }
}

#[test]
fn curve_jacobian_matches_finite_differences_of_the_paper_formula() {
    let mut rng = Rng(2);
    let c = random_curve(&mut rng, 2, 6);
    let h = 1e-6;
    for u in [0.1, 0.37, 0.5, 0.93] {
        let j = c.jacobian(u).unwrap().to_dense(6);
        for i in 0..6 {
            // Weight column.
            let mut w = c.weights().to_vec();
            w[i] += h;
            let mut cp = c.clone();
            cp.set_weights(w.clone()).unwrap();
            let sp = cp.point(u).unwrap();
            w[i] -= 2.0 * h;
            cp.set_weights(w).unwrap();
            let sm = cp.point(u).unwrap();
            let fd = (sp - sm) / (2.0 * h);
            for r in 0..3 {
                assert!((j[(r, 4 * i + 3)] - fd[r]).abs() < 1e-7, "dc/dw_{i}");
            }
            // Point columns: the curve is linear in p, the FD is exact up to rounding.
            let mut pts = c.control_points().to_vec();
            pts[i].y += 1.0;
            let mut cp = c.clone();
            cp.set_control_points(pts).unwrap();
            let d = cp.point(u).unwrap() - c.point(u).unwrap();
            assert!((j[(1, 4 * i + 1)] - d.y).abs() < 1e-13);
            assert!(j[(0, 4 * i + 1)] == 0.0 && d.x.abs() < 1e-15);
        }
    }
}

#[test]
fn surface_and_volume_points_equal_j_times_p() {
    let mut rng = Rng(3);
    let s = random_surface(&mut rng, [3, 2], [6, 5]);
    let p = generalized_coordinates(s.control_points(), s.weights());
    for u in samples(9) {
        for v in samples(11) {
            let j = s.jacobian(u, v).unwrap();
            assert_eq!(j.indices.len(), 4 * 3);
            let x = s.point(u, v).unwrap();
            let jp = j.to_dense(30) * &p;
            assert!((Vec3::new(jp[0], jp[1], jp[2]) - x).norm() < 1e-14 * (1.0 + x.norm()));
            // Rational basis sums to one.
            let sum: f64 = j.point_derivatives.iter().sum();
            assert!((sum - 1.0).abs() < 1e-14);
        }
    }
    let vol = random_volume(&mut rng, [2, 2, 3], [4, 5, 5]);
    let p = generalized_coordinates(vol.control_points(), vol.weights());
    for u in samples(5) {
        for v in samples(4) {
            for w in samples(6) {
                let j = vol.jacobian(u, v, w).unwrap();
                let x = vol.point(u, v, w).unwrap();
                let jp = j.to_dense(100) * &p;
                assert!((Vec3::new(jp[0], jp[1], jp[2]) - x).norm() < 1e-14 * (1.0 + x.norm()));
            }
        }
    }
}

#[test]
fn transpose_is_the_adjoint() {
    // <J^T f, q> == <f, J q> for random generalized coordinates q.
    let mut rng = Rng(4);
    let s = random_surface(&mut rng, [3, 3], [5, 5]);
    let j = s.jacobian(0.3, 0.8).unwrap();
    let f = rng.vec3(1.0);
    let mut pf = vec![Vec3::zeros(); 25];
    let mut wf = vec![0.0; 25];
    j.apply_transpose(&f, &mut pf, &mut wf);
    let qp: Vec<Vec3> = (0..25).map(|_| rng.vec3(1.0)).collect();
    let qw: Vec<f64> = (0..25).map(|_| rng.range(-1.0, 1.0)).collect();
    let lhs: f64 = pf.iter().zip(&qp).map(|(a, b)| a.dot(b)).sum::<f64>()
        + wf.iter().zip(&qw).map(|(a, b)| a * b).sum::<f64>();
    let rhs = f.dot(&j.apply(&qp, &qw));
    assert!((lhs - rhs).abs() < 1e-13);
}
