//! Tests of `WeightChange`: direct manipulation through the weights (section 3, last paragraph of
//! `ffd-direct-manipulation.txt`; derivation in `src/weights.rs`).

use crate::common;

use common::{Lcg, lattice, specs};
use nalgebra::{DMatrix, DVector};
use vclay_core::Vec3;
use vclay_ffd::{FfdError, FfdLattice, LatticeSpec, PointConstraint, WeightChange, WeightOptions};

/// The 3 x n weight Jacobian `J_i = B_i (P_i - Q) / sum W B` on the support of `t`.
fn weight_jacobian(l: &FfdLattice, t: [f64; 3], indices: &[usize]) -> DMatrix<f64> {
    let jac = l.volume().jacobian(t[0], t[1], t[2]).unwrap();
    let mut out = DMatrix::zeros(3, indices.len());
    for (c, &i) in indices.iter().enumerate() {
        let k = jac.indices.iter().position(|&j| j == i).unwrap();
        for r in 0..3 {
            out[(r, c)] = jac.weight_derivatives[k][r];
        }
    }
    out
}

#[test]
fn weight_change_moves_the_source_onto_the_target() {
    let mut rng = Lcg::new(51);
    for spec in specs() {
        let l0 = lattice(spec);
        for _ in 0..10 {
            let t = [
                rng.range(0.1, 0.9),
                rng.range(0.1, 0.9),
                rng.range(0.1, 0.9),
            ];
            let s = l0.point_at(t).unwrap();
            // Small enough moves that the target stays well inside the support's hull.
            let target = s + rng.vec(0.02);
            let c = PointConstraint::new(t, target);
            let w = WeightChange::single(&l0, &c, &WeightOptions::default()).unwrap();
            let mut l = l0.clone();
            w.apply(&mut l).unwrap();
            assert!(l.weights().iter().all(|&x| x > 0.0));
            let got = l.point_at(t).unwrap();
            assert!(
                (got - target).norm() < 1e-12 * l.size(),
                "{spec:?}: {}",
                (got - target).norm()
            );
            assert!(w.iterations() <= 10, "{}", w.iterations());
            assert!(w.residual() <= 1e-12 * l.size());
            // Locality: only the support's weights change.
            assert_eq!(w.indices(), &l0.basis(t).unwrap().indices[..]);
            // Control points are untouched.
            assert_eq!(l.control_points(), l0.control_points());
        }
    }
}

/// First-order optimality of `min ||Delta||^2 s.t. Q(W + Delta) = T`: `Delta` lies in the row
/// space of the weight Jacobian at the solution (`Delta = J^T mu`).
#[test]
fn weight_change_is_a_least_norm_stationary_point() {
    let mut rng = Lcg::new(52);
    for spec in [LatticeSpec::uniform(2, 4), LatticeSpec::uniform(3, 6)] {
        let l0 = lattice(spec);
        let t = [0.4, 0.55, 0.3];
        let target = l0.point_at(t).unwrap() + rng.vec(0.05);
        let w = WeightChange::single(
            &l0,
            &PointConstraint::new(t, target),
            &WeightOptions::default(),
        )
        .unwrap();
        let mut l = l0.clone();
        w.apply(&mut l).unwrap();
        let j = weight_jacobian(&l, t, w.indices());
        let delta = DVector::from_column_slice(w.deltas());
        // Projection of Delta onto the row space of J.
        let mu = (&j * j.transpose())
            .cholesky()
            .unwrap()
            .solve(&(&j * &delta));
        let proj = j.transpose() * mu;
        assert!(
            (&proj - &delta).norm() < 1e-9 * delta.norm(),
            "{}",
            (&proj - &delta).norm()
        );
        // For a small move the change is, to first order, J^T (J J^T)^{-1} (T - S) at the start
        // (the weight analogue of eq 7).
        let small = l0.point_at(t).unwrap() + Vec3::new(1e-6, -2e-6, 1.5e-6);
        let w = WeightChange::single(
            &l0,
            &PointConstraint::new(t, small),
            &WeightOptions::default(),
        )
        .unwrap();
        let j0 = weight_jacobian(&l0, t, w.indices());
        let rhs = DVector::from_column_slice((small - l0.point_at(t).unwrap()).as_slice());
        let lin = j0.transpose() * (&j0 * j0.transpose()).cholesky().unwrap().solve(&rhs);
        let got = DVector::from_column_slice(w.deltas());
        assert!(
            (&got - &lin).norm() < 1e-4 * lin.norm(),
            "{} vs {}",
            got.norm(),
            lin.norm()
        );
    }
}

#[test]
fn unreachable_targets_are_reported() {
    // Q is a convex combination of the support control points: a target far outside cannot be
    // reached with positive weights.
    let l = lattice(LatticeSpec::uniform(3, 8));
    let t = [0.5, 0.5, 0.5];
    let far = l.point_at(t).unwrap() + Vec3::new(10.0, 0.0, 0.0);
    let err = WeightChange::single(&l, &PointConstraint::new(t, far), &WeightOptions::default())
        .unwrap_err();
    assert!(
        matches!(
            err,
            FfdError::NonPositiveWeight { .. } | FfdError::WeightNoConvergence { .. }
        ),
        "{err}"
    );
    // The already-reached target takes no step.
    let here = l.point_at(t).unwrap();
    let w = WeightChange::single(
        &l,
        &PointConstraint::new(t, here),
        &WeightOptions::default(),
    )
    .unwrap();
    assert_eq!(w.iterations(), 0);
    assert_eq!(w.norm_squared(), 0.0);
}

#[test]
fn works_on_rational_lattices() {
    let mut rng = Lcg::new(53);
    let mut l = lattice(specs()[3]);
    let w0: Vec<f64> = (0..l.control_point_count())
        .map(|_| rng.range(0.7, 1.4))
        .collect();
    l.set_weights(w0).unwrap();
    let t = rng.params();
    let target = l.point_at(t).unwrap() + rng.vec(0.01);
    let w = WeightChange::single(
        &l,
        &PointConstraint::new(t, target),
        &WeightOptions::default(),
    )
    .unwrap();
    w.apply(&mut l).unwrap();
    assert!((l.point_at(t).unwrap() - target).norm() < 1e-12 * l.size());
}
