//! NurbsSurface and NurbsVolume: exact primitives, partition of unity (via constant
//! reproduction), affine invariance, mixed partial derivatives vs finite differences, grids.
use crate::common;
use common::*;
use vclay_core::{Parallelism, Vec3};
use vclay_spline::{NurbsSurface, NurbsVolume, ParametricSurface, ParametricVolume, SplineError};

#[test]
fn torus_and_sphere_are_exact() {
    let t = NurbsSurface::torus(3.0, 1.0).unwrap();
    let s = NurbsSurface::sphere(2.5).unwrap();
    for u in samples(40) {
        for v in samples(40) {
            let p = t.point(u, v).unwrap();
            let rho = (p.x * p.x + p.y * p.y).sqrt();
            let tube = ((rho - 3.0).powi(2) + p.z * p.z).sqrt();
            assert!((tube - 1.0).abs() < 1e-14, "torus tube radius {tube}");
            let q = s.point(u, v).unwrap();
            assert!(
                (q.norm() - 2.5).abs() < 2.5e-14 * 2.0,
                "sphere radius {}",
                q.norm()
            );
        }
    }
}

#[test]
fn constant_control_points_are_reproduced() {
    // Partition of unity of the rational basis R_ij: equal control points give that point.
    let mut rng = Rng(21);
    let mut s = random_surface(&mut rng, [3, 2], [7, 6]);
    let c = Vec3::new(0.25, -1.5, 4.0);
    s.set_control_points(vec![c; 42]).unwrap();
    for u in samples(17) {
        for v in samples(13) {
            assert!((s.point(u, v).unwrap() - c).norm() < 1e-14 * 4.0);
        }
    }
}

#[test]
fn surfaces_are_affinely_invariant() {
    let mut rng = Rng(4);
    let s = random_surface(&mut rng, [3, 3], [6, 7]);
    let m = nalgebra::Matrix3::new(0.2, 1.3, -0.4, 1.1, 0.9, 0.2, -0.5, 0.7, 2.1);
    let t = Vec3::new(10.0, -4.0, 2.5);
    let mut s2 = s.clone();
    s2.transform(&m, &t);
    for u in samples(11) {
        for v in samples(9) {
            let a = m * s.point(u, v).unwrap() + t;
            let b = s2.point(u, v).unwrap();
            assert!((a - b).norm() < 1e-13 * (1.0 + a.norm()));
        }
    }
}

#[test]
fn surface_partials_match_central_differences() {
    let mut rng = Rng(8);
    let h = 1e-5;
    for (deg, dims) in [([3, 3], [6, 7]), ([2, 4], [5, 6]), ([1, 2], [4, 5])] {
        let s = random_surface(&mut rng, deg, dims);
        let order = 3;
        let mut checked = 0;
        for i in 1..12 {
            for j in 1..12 {
                let (u, v) = (i as f64 / 12.0 + 0.013, j as f64 / 12.0 - 0.007);
                let d = s.derivatives(u, v, order).unwrap();
                let du_p = s.derivatives(u + h, v, order).unwrap();
                let du_m = s.derivatives(u - h, v, order).unwrap();
                let dv_p = s.derivatives(u, v + h, order).unwrap();
                let dv_m = s.derivatives(u, v - h, order).unwrap();
                for a in 0..=order {
                    for b in 0..=order - a {
                        let scale = 1.0 + d[a][b].norm();
                        if a + b < order {
                            let fd = (du_p[a][b] - du_m[a][b]) / (2.0 * h);
                            let jump = (du_p[a + 1][b] - du_m[a + 1][b]).norm();
                            if jump < 1e-2 * (1.0 + d[a + 1][b].norm()) {
                                assert!(
                                    (fd - d[a + 1][b]).norm() < 2e-5 * (scale + d[a + 1][b].norm()),
                                    "d[{}][{b}] at ({u},{v}) deg {deg:?}",
                                    a + 1
                                );
                                checked += 1;
                            }
                        }
                        if a + b < order {
                            let fd = (dv_p[a][b] - dv_m[a][b]) / (2.0 * h);
                            let jump = (dv_p[a][b + 1] - dv_m[a][b + 1]).norm();
                            if jump < 1e-2 * (1.0 + d[a][b + 1].norm()) {
                                assert!(
                                    (fd - d[a][b + 1]).norm() < 2e-5 * (scale + d[a][b + 1].norm()),
                                    "d[{a}][{}] at ({u},{v}) deg {deg:?}",
                                    b + 1
                                );
                                checked += 1;
                            }
                        }
                    }
                }
            }
        }
        assert!(
            checked > 1000,
            "only {checked} finite-difference checks ran"
        );
    }
}

#[test]
fn volume_partials_match_central_differences_and_metric_is_gram() {
    let mut rng = Rng(12);
    let vol = random_volume(&mut rng, [3, 2, 2], [5, 4, 5]);
    let h = 1e-5;
    for i in 1..6 {
        for j in 1..6 {
            for k in 1..6 {
                let t = [
                    i as f64 / 6.0 + 0.01,
                    j as f64 / 6.0 - 0.02,
                    k as f64 / 6.0 + 0.005,
                ];
                let d = vol.derivatives(t[0], t[1], t[2], 2).unwrap();
                assert!((d[0][0][0] - vol.point(t[0], t[1], t[2]).unwrap()).norm() < 1e-13);
                for axis in 0..3 {
                    let mut tp = t;
                    let mut tm = t;
                    tp[axis] += h;
                    tm[axis] -= h;
                    let dp = vol.derivatives(tp[0], tp[1], tp[2], 2).unwrap();
                    let dm = vol.derivatives(tm[0], tm[1], tm[2], 2).unwrap();
                    let fd = (dp[0][0][0] - dm[0][0][0]) / (2.0 * h);
                    let an = [d[1][0][0], d[0][1][0], d[0][0][1]][axis];
                    assert!((fd - an).norm() < 1e-6 * (1.0 + an.norm()), "axis {axis}");
                    // Second derivatives from first: d/du of V_v is V_uv.
                    let fd2 = ([dp[0][1][0], dp[0][0][1], dp[1][0][0]][axis]
                        - [dm[0][1][0], dm[0][0][1], dm[1][0][0]][axis])
                        / (2.0 * h);
                    let an2 = [d[1][1][0], d[0][1][1], d[1][0][1]][axis];
                    assert!(
                        (fd2 - an2).norm() < 1e-5 * (1.0 + an2.norm()),
                        "mixed {axis}"
                    );
                }
                let jm = vol.jacobian_matrix(t[0], t[1], t[2]).unwrap();
                assert_eq!(jm.column(0).into_owned(), d[1][0][0]);
            }
        }
    }
}

#[test]
fn box_lattice_is_the_identity_map() {
    let lo = Vec3::new(-1.0, 2.0, 0.5);
    let hi = Vec3::new(3.0, 2.5, 7.0);
    let vol = NurbsVolume::box_lattice([3, 2, 3], [5, 4, 7], lo, hi).unwrap();
    for u in samples(7) {
        for v in samples(5) {
            for w in samples(6) {
                let p = vol.point(u, v, w).unwrap();
                let e = lo + (hi - lo).component_mul(&Vec3::new(u, v, w));
                assert!((p - e).norm() < 1e-14 * 8.0, "{p:?} vs {e:?}");
            }
        }
    }
}

#[test]
fn grids_agree_with_pointwise_evaluation_sequential_and_parallel() {
    let mut rng = Rng(31);
    let s = random_surface(&mut rng, [3, 3], [9, 8]);
    let us: Vec<f64> = samples(150);
    let vs: Vec<f64> = samples(130);
    let seq = s.eval_grid(&us, &vs, Parallelism::Sequential).unwrap();
    let par = s.eval_grid(&us, &vs, Parallelism::Rayon).unwrap();
    assert_eq!(seq, par);
    let g = s
        .eval_grid_with_derivatives(&us, &vs, Parallelism::Auto)
        .unwrap();
    for (i, &u) in us.iter().enumerate().step_by(7) {
        for (j, &v) in vs.iter().enumerate().step_by(5) {
            let d = s.derivatives(u, v, 1).unwrap();
            let k = i * vs.len() + j;
            assert!((seq[k] - d[0][0]).norm() < 1e-13 * (1.0 + d[0][0].norm()));
            assert!((g.points[k] - d[0][0]).norm() < 1e-13 * (1.0 + d[0][0].norm()));
            assert!((g.du[k] - d[1][0]).norm() < 1e-12 * (1.0 + d[1][0].norm()));
            assert!((g.dv[k] - d[0][1]).norm() < 1e-12 * (1.0 + d[0][1].norm()));
        }
    }
    let vol = random_volume(&mut rng, [2, 3, 2], [4, 5, 6]);
    let (a, b, c) = (samples(9), samples(7), samples(8));
    let grid = vol.eval_grid(&a, &b, &c, Parallelism::Rayon).unwrap();
    for (i, &u) in a.iter().enumerate() {
        for (j, &v) in b.iter().enumerate() {
            for (k, &w) in c.iter().enumerate() {
                let p = vol.point(u, v, w).unwrap();
                assert!(
                    (grid[(i * b.len() + j) * c.len() + k] - p).norm() < 1e-13 * (1.0 + p.norm())
                );
            }
        }
    }
    assert!(matches!(
        s.eval_grid(&[0.5, 1.2], &[0.1], Parallelism::Auto),
        Err(SplineError::ParameterOutOfDomain { axis: 0, .. })
    ));
}

#[test]
fn flat_grid_agrees_bit_for_bit() {
    let mut rng = Rng(21);
    let s = random_surface(&mut rng, [3, 2], [9, 7]);
    let us: Vec<f64> = samples(150);
    let vs: Vec<f64> = samples(130);
    for par in [
        Parallelism::Sequential,
        Parallelism::Rayon,
        Parallelism::Auto,
    ] {
        let pts = s.eval_grid(&us, &vs, par).unwrap();
        let mut flat = vec![f64::NAN; 3 * us.len() * vs.len()];
        s.eval_grid_into_flat(&us, &vs, &mut flat, par).unwrap();
        for (p, f) in pts.iter().zip(flat.chunks_exact(3)) {
            let f: Vec<u64> = f.iter().map(|x| x.to_bits()).collect();
            assert_eq!([p.x.to_bits(), p.y.to_bits(), p.z.to_bits()], f[..]);
        }
    }
    let mut flat = vec![0.0; 6];
    assert!(matches!(
        s.eval_grid_into_flat(&[0.5, 1.2], &[0.1], &mut flat, Parallelism::Auto),
        Err(SplineError::ParameterOutOfDomain { axis: 0, .. })
    ));
    s.eval_grid_into_flat(&[], &[0.1], &mut [], Parallelism::Auto)
        .unwrap();
}

#[test]
fn ragged_and_bad_nets_are_named() {
    let p = Vec3::zeros();
    let k = vec![0., 0., 1., 1.];
    let e = NurbsSurface::new(
        [1, 1],
        [k.clone(), k.clone()],
        vec![vec![p, p], vec![p]],
        None,
    )
    .unwrap_err();
    assert_eq!(
        e.to_string(),
        "length of control_points[1]: found 1, expected 2"
    );
    let e = NurbsSurface::new(
        [1, 1],
        [k.clone(), k.clone()],
        vec![vec![p, p], vec![p, p]],
        Some(vec![vec![1.0, 1.0], vec![1.0, -2.0]]),
    )
    .unwrap_err();
    assert_eq!(
        e.to_string(),
        "weight [1][1] is -2, weights must be positive and finite"
    );
    let e = NurbsSurface::new(
        [1, 1],
        [k.clone(), vec![0., 0., 1.]],
        vec![vec![p, p], vec![p, p]],
        None,
    )
    .unwrap_err();
    assert!(
        e.to_string()
            .starts_with("knot vector along v: 3 knots given, expected 4"),
        "{e}"
    );
    let e = NurbsVolume::new(
        [1, 1, 1],
        [k.clone(), k.clone(), k.clone()],
        vec![vec![vec![p, p], vec![p, p]], vec![vec![p, p], vec![p]]],
        None,
    )
    .unwrap_err();
    assert_eq!(
        e.to_string(),
        "length of control_points[1][1]: found 1, expected 2"
    );
}
