//! Tests of `Manipulation`: single-point direct manipulation (eq 7), locality, least norm, and the
//! commutative group laws of section 4 of `ffd-direct-manipulation.txt`.

use crate::common;

use common::{Lcg, dense_pinv_solution, dense_r, jiggle, lattice, rest_point, specs};
use vclay_core::Vec3;
use vclay_ffd::{FfdError, FfdLattice, LatticeSpec, Manipulation, PointConstraint};

fn max_diff(a: &[Vec3], b: &[Vec3]) -> f64 {
    a.iter()
        .zip(b)
        .map(|(x, y)| (x - y).norm())
        .fold(0.0, f64::max)
}

#[test]
fn single_point_reaches_its_target() {
    let mut rng = Lcg::new(11);
    for spec in specs() {
        for deformed in [false, true] {
            let mut l = lattice(spec);
            if deformed {
                jiggle(&mut l, &mut rng, 0.1);
            }
            let tol = 1e-12 * l.size();
            for _ in 0..40 {
                let t = rng.params();
                let target = l.point_at(t).unwrap() + rng.vec(0.3);
                let m = Manipulation::single(&l, &PointConstraint::new(t, target)).unwrap();
                let mut moved = l.clone();
                moved.apply(&m);
                let got = moved.point_at(t).unwrap();
                assert!((got - target).norm() < tol, "{spec:?}: {got} vs {target}");
            }
        }
    }
}

#[test]
fn single_point_from_a_rest_position_moves_the_embedded_point() {
    let mut l = lattice(LatticeSpec::uniform(3, 5));
    let s = rest_point(&l, [0.2, 0.7, 0.4]);
    let t = s + Vec3::new(0.1, -0.2, 0.3);
    let c = PointConstraint::from_rest_point(&l, s, t).unwrap();
    l.apply(&Manipulation::single(&l, &c).unwrap());
    assert!((l.deform_point(&s) - t).norm() < 1e-12 * l.size());
    let far = Vec3::new(100.0, 0.0, 0.0);
    assert_eq!(
        PointConstraint::from_rest_point(&l, far, t),
        Err(FfdError::OutsideLattice { point: far })
    );
    assert!(matches!(
        Manipulation::single(
            &l,
            &PointConstraint::new([0.5, 0.5, 0.5], Vec3::new(f64::NAN, 0.0, 0.0))
        ),
        Err(FfdError::NonFiniteTarget { index: 0 })
    ));
}

#[test]
fn only_the_support_moves() {
    let mut rng = Lcg::new(12);
    for spec in specs() {
        let l = lattice(spec);
        let support: usize = spec.degree.iter().map(|d| d + 1).product();
        for _ in 0..20 {
            let t = rng.params();
            let m = Manipulation::single_displacement(&l, t, rng.vec(0.5)).unwrap();
            assert_eq!(m.len(), support);
            let b = l.basis(t).unwrap();
            assert_eq!(m.indices(), &b.indices[..]);
            let mut moved = l.clone();
            moved.apply(&m);
            for (f, (p, q)) in l
                .control_points()
                .iter()
                .zip(moved.control_points())
                .enumerate()
            {
                if b.indices.binary_search(&f).is_err() {
                    assert_eq!(p, q, "control point {f} outside the support moved");
                }
            }
            // The support is that of section 3: span - p ..= span on each axis.
            for &f in m.indices() {
                let ijk = l.multi_index(f);
                for a in 0..3 {
                    let kv = &l.knots()[a];
                    let span = kv.find_span(t[a]);
                    assert!(ijk[a] + kv.degree() >= span && ijk[a] <= span);
                }
            }
        }
    }
}

#[test]
fn explicit_solution_is_the_least_norm_one() {
    // Eq (7) against the pseudo-inverse of the 1 x N row R (Hsu et al.'s formulation).
    let mut rng = Lcg::new(13);
    for spec in [LatticeSpec::uniform(2, 4), LatticeSpec::uniform(3, 5)] {
        let mut l = lattice(spec);
        jiggle(&mut l, &mut rng, 0.05);
        for _ in 0..10 {
            let t = rng.params();
            let rho = rng.vec(0.4);
            let m = Manipulation::single_displacement(&l, t, rho).unwrap();
            let dense = dense_pinv_solution(&dense_r(&l, &[t]), &[rho]);
            let ours = m.to_dense();
            for (i, d) in ours.iter().enumerate() {
                let e = Vec3::new(dense[(i, 0)], dense[(i, 1)], dense[(i, 2)]);
                assert!((d - e).norm() < 1e-13, "{d} vs {e}");
            }
        }
    }
}

/// Section 4: omega(S, r1) o omega(S, r2) = omega(S, r1 + r2); commutative, associative, unit,
/// inverse — checked on the lattices the manipulations produce.
#[test]
fn direct_manipulations_form_a_commutative_group() {
    let mut rng = Lcg::new(14);
    for spec in specs() {
        let mut l = lattice(spec);
        jiggle(&mut l, &mut rng, 0.05);
        let tol = 1e-12 * l.size();
        let t = rng.params();
        let (r1, r2, r3) = (rng.vec(0.3), rng.vec(0.3), rng.vec(0.3));
        let w = |r: Vec3| Manipulation::single_displacement(&l, t, r).unwrap();
        let (w1, w2, w3) = (w(r1), w(r2), w(r3));
        let applied = |ms: &[&Manipulation]| {
            let mut x = l.clone();
            for m in ms {
                x.apply(m);
            }
            x.control_points().to_vec()
        };
        // Composition is the manipulation of the summed displacement.
        let sum = w(r1 + r2);
        assert!(max_diff(&applied(&[&w1, &w2]), &applied(&[&sum])) < tol);
        assert!(max_diff(&w1.compose(&w2).to_dense(), &sum.to_dense()) < tol);
        // Commutative.
        assert!(max_diff(&applied(&[&w1, &w2]), &applied(&[&w2, &w1])) < tol);
        // Associative.
        let a = w1.compose(&w2).compose(&w3);
        let b = w1.compose(&w2.compose(&w3));
        assert!(max_diff(&a.to_dense(), &b.to_dense()) < tol);
        assert!(max_diff(&applied(&[&a]), &applied(&[&b])) < tol);
        // Unit element.
        let id = Manipulation::identity(&l);
        assert!(id.is_empty());
        assert_eq!(applied(&[&id]), l.control_points());
        assert_eq!(w1.compose(&id), w1);
        // Inverse: undo restores the lattice, and the source returns to S.
        assert!(max_diff(&applied(&[&w1, &w1.inverse()]), l.control_points()) < tol);
        assert!(w1.compose(&w1.inverse()).norm_squared() == 0.0);
        let mut x = l.clone();
        let s = l.point_at(t).unwrap();
        x.apply(&w1);
        assert!((x.point_at(t).unwrap() - (s + r1)).norm() < tol);
        x.apply(&w1.inverse());
        assert!((x.point_at(t).unwrap() - s).norm() < tol);
    }
}

/// Section 4, property 1: the result depends only on S and the final target. Moving S to T1 and
/// then (on the deformed lattice) to T2 equals moving S directly to T2; moving T back to S undoes.
#[test]
fn consecutive_manipulations_depend_only_on_the_final_target() {
    let mut rng = Lcg::new(15);
    for spec in specs() {
        let l0 = lattice(spec);
        let tol = 1e-12 * l0.size();
        let t = rng.params();
        let s = l0.point_at(t).unwrap();
        let targets = [s + rng.vec(0.3), s + rng.vec(0.3), s + rng.vec(0.3)];
        let mut step = l0.clone();
        for tgt in &targets {
            let m = Manipulation::single(&step, &PointConstraint::new(t, *tgt)).unwrap();
            step.apply(&m);
        }
        let mut direct = l0.clone();
        direct.apply(&Manipulation::single(&l0, &PointConstraint::new(t, targets[2])).unwrap());
        assert!(max_diff(step.control_points(), direct.control_points()) < tol);
        // Undo by moving the target back to the source.
        let back = Manipulation::single(&step, &PointConstraint::new(t, s)).unwrap();
        step.apply(&back);
        assert!(max_diff(step.control_points(), l0.control_points()) < tol);
    }
}

#[test]
fn displacement_at_is_the_field_evaluated() {
    let l = lattice(LatticeSpec::uniform(3, 6));
    let t = [0.3, 0.6, 0.9];
    let rho = Vec3::new(0.1, 0.2, -0.3);
    let m = Manipulation::single_displacement(&l, t, rho).unwrap();
    assert!((m.displacement_at(&l, t).unwrap() - rho).norm() < 1e-15);
    // Far away (no common support): zero.
    assert_eq!(
        m.displacement_at(&l, [0.0, 0.0, 0.0]).unwrap(),
        Vec3::zeros()
    );
}

#[test]
#[should_panic(expected = "other dimensions")]
fn applying_to_another_lattice_shape_panics() {
    let a = lattice(LatticeSpec::uniform(3, 4));
    let mut b: FfdLattice = lattice(LatticeSpec::uniform(3, 5));
    let m = Manipulation::single_displacement(&a, [0.5; 3], Vec3::x()).unwrap();
    b.apply(&m);
}
