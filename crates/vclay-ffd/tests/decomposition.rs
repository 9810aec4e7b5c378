//! Tests of `decompose` (section 6 of `ffd-direct-manipulation.txt`, eqs 13-19): h single-point
//! steps reproduce the h-point manipulation.

use crate::common;

use common::{Lcg, jiggle, lattice, specs};
use vclay_core::Vec3;
use vclay_ffd::{FfdLattice, LatticeSpec, Manipulation, PointConstraint, SolveOptions, decompose};

fn constraints(l: &FfdLattice, rng: &mut Lcg, m: usize) -> Vec<PointConstraint> {
    (0..m)
        .map(|_| {
            let t = rng.params();
            PointConstraint::new(t, l.point_at(t).unwrap() + rng.vec(0.3))
        })
        .collect()
}

fn max_diff(a: &[Vec3], b: &[Vec3]) -> f64 {
    a.iter()
        .zip(b)
        .map(|(x, y)| (x - y).norm())
        .fold(0.0, f64::max)
}

/// Fig. 7: the user drags source q by D_q^(q) at step q, each a single-point manipulation (eq 7)
/// computed on the lattice as the previous steps left it; after h steps every source is on its
/// target and the lattice is that of the h-point manipulation (eq 18 = eq 12).
#[test]
fn single_point_steps_reproduce_the_multi_point_result() {
    let mut rng = Lcg::new(41);
    for spec in specs() {
        let mut l = lattice(spec);
        jiggle(&mut l, &mut rng, 0.05);
        let tol = 1e-12 * l.size();
        let m = if l.control_point_count() >= 100 { 4 } else { 2 };
        let cs = constraints(&l, &mut rng, m);
        let opts = SolveOptions::default();
        let multi = Manipulation::multi(&l, &cs, &opts).unwrap();
        let mut expected = l.clone();
        expected.apply(&multi);

        let steps = decompose(&l, &cs, &opts).unwrap();
        assert_eq!(steps.len(), m);
        let mut stepped = l.clone();
        for (q, step) in steps.iter().enumerate() {
            assert_eq!(step.constraint, q);
            let target = step.target(&stepped).unwrap();
            let single =
                Manipulation::single(&stepped, &PointConstraint::new(step.params, target)).unwrap();
            // The step's own field is eq (13).
            assert!(max_diff(&single.to_dense(), &step.manipulation.to_dense()) < tol);
            stepped.apply(&single);
        }
        assert!(
            max_diff(stepped.control_points(), expected.control_points()) < tol,
            "{spec:?}"
        );
        for c in &cs {
            assert!((stepped.point_at(c.params).unwrap() - c.target).norm() < tol);
        }
        // Any order gives the same result (the steps' fields commute, section 4).
        let mut reversed = l.clone();
        for step in steps.iter().rev() {
            reversed.apply(&step.manipulation);
        }
        assert!(max_diff(reversed.control_points(), expected.control_points()) < tol);
        // And the fields sum to the multi-point field (eq 17).
        let sum = steps.iter().fold(Manipulation::identity(&l), |acc, s| {
            acc.compose(&s.manipulation)
        });
        assert!(max_diff(&sum.to_dense(), &multi.to_dense()) < tol);
    }
}

/// Eq (19): D_q^(q) = delta^(q)_ijk sum R^2 / R_ijk for any non-zero term of step q.
#[test]
fn step_displacement_satisfies_eq_19() {
    let mut rng = Lcg::new(42);
    let l = lattice(LatticeSpec::uniform(3, 6));
    let cs = constraints(&l, &mut rng, 3);
    for step in decompose(&l, &cs, &SolveOptions::default()).unwrap() {
        let b = l.basis(step.params).unwrap();
        let s2 = b.sum_squares();
        for ((&i, &r), (j, d)) in b
            .indices
            .iter()
            .zip(&b.values)
            .zip(step.manipulation.iter())
        {
            assert_eq!(i, j);
            assert!((d * s2 / r - step.displacement).norm() < 1e-12);
        }
    }
}

#[test]
fn decomposition_of_a_least_squares_manipulation_adds_up() {
    // More constraints than a 2x2x2 trilinear lattice can meet: the steps still sum to the
    // least-squares field.
    let mut rng = Lcg::new(43);
    let l = lattice(LatticeSpec::uniform(1, 2));
    let cs = constraints(&l, &mut rng, 10);
    let opts = SolveOptions::least_squares();
    let multi = Manipulation::multi(&l, &cs, &opts).unwrap();
    let sum = decompose(&l, &cs, &opts)
        .unwrap()
        .iter()
        .fold(Manipulation::identity(&l), |acc, s| {
            acc.compose(&s.manipulation)
        });
    assert!(max_diff(&sum.to_dense(), &multi.to_dense()) < 1e-12 * l.size());
    assert!(decompose(&l, &cs, &SolveOptions::default()).is_err());
}
