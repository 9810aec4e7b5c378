//! The fairness energy: the separable exact Gram assembly equals the D-NURBS engine's element
//! stiffness (d-nurbs.txt eq 17) on polynomial surfaces.

use crate::common;

use vclay_core::Vec3;
use vclay_fit::energy;
use vclay_spline::{KnotVector, NurbsSurface};

#[test]
fn separable_stiffness_matches_the_engine() {
    let mut rng = common::Rng(4);
    for (p, dims) in [(3usize, [7usize, 5usize]), (2, [4, 6])] {
        let knots = [
            KnotVector::clamped_uniform(p, dims[0]).unwrap(),
            KnotVector::clamped_uniform(p, dims[1]).unwrap(),
        ];
        let n = dims[0] * dims[1];
        let pts: Vec<Vec3> = (0..n)
            .map(|_| Vec3::new(rng.uniform(), rng.uniform(), rng.uniform()))
            .collect();
        let s = NurbsSurface::from_flat(knots.clone(), pts.clone(), vec![1.0; n]).unwrap();
        let (alpha, beta) = energy::densities(0.3, 0.7, [2.0, 0.5]);
        let bw = (2 * p + 1) * (2 * p + 1);
        let mut band = vec![0.0; n * bw];
        energy::add_separable(&mut band, &knots, alpha, beta).unwrap();
        let mine = vclay_fit::system::quadratic_form(&band, dims, [p, p], &pts);
        let mut engine = 0.0;
        for e in energy::engine_elements(&s, alpha, beta).unwrap() {
            let nd = e.dofs.len();
            for a in 0..nd {
                for b in 0..nd {
                    engine += e.stiffness[a * nd + b] * pts[e.dofs[a]].dot(&pts[e.dofs[b]]);
                }
            }
        }
        assert!(
            (mine - engine).abs() < 1e-10 * engine.abs(),
            "{mine} vs {engine}"
        );
    }
}

#[test]
fn densities_are_scale_free() {
    // A square base: alpha and beta unchanged; a 4:1 rectangle: u derivatives weigh less.
    let (a, b) = energy::densities(2.0, 3.0, [5.0, 5.0]);
    assert_eq!((a, b), ([2.0, 2.0], [3.0, 3.0, 3.0]));
    let (a, b) = energy::densities(1.0, 1.0, [4.0, 1.0]);
    // L = sqrt(4 x 1) = 2: (L/L_u)^2 = 1/4, (L/L_v)^2 = 4.
    assert!((a[0] - 0.25).abs() < 1e-15 && (a[1] - 4.0).abs() < 1e-15);
    assert!(
        (b[0] - 0.0625).abs() < 1e-15 && (b[1] - 1.0).abs() < 1e-15 && (b[2] - 16.0).abs() < 1e-15
    );
}
