//! Tests of multi-point direct manipulation (eq 12 of `ffd-direct-manipulation.txt`): targets met,
//! least norm against a dense pseudo-inverse, locality, conflicting constraints named,
//! least-squares mode.

use crate::common;

use common::{
    Lcg, dense_normal_equations_solution, dense_pinv_solution, dense_r, jiggle, lattice, specs,
};
use vclay_core::Vec3;
use vclay_ffd::{
    FfdError, FfdLattice, LatticeSpec, Manipulation, PointConstraint, SolveMode, SolveOptions,
};

/// `m` random constraints with displacements up to `scale`.
fn random_constraints(l: &FfdLattice, rng: &mut Lcg, m: usize, scale: f64) -> Vec<PointConstraint> {
    (0..m)
        .map(|_| {
            let t = rng.params();
            PointConstraint::new(t, l.point_at(t).unwrap() + rng.vec(scale))
        })
        .collect()
}

fn assert_targets_met(l: &FfdLattice, m: &Manipulation, cs: &[PointConstraint], tol: f64) {
    let mut moved = l.clone();
    moved.apply(m);
    for (f, c) in cs.iter().enumerate() {
        let got = moved.point_at(c.params).unwrap();
        assert!(
            (got - c.target).norm() < tol,
            "constraint {f}: {got} vs {}",
            c.target
        );
    }
}

#[test]
fn multi_point_constraints_are_met() {
    let mut rng = Lcg::new(21);
    for spec in specs() {
        for deformed in [false, true] {
            let mut l = lattice(spec);
            if deformed {
                jiggle(&mut l, &mut rng, 0.05);
            }
            let tol = 1e-12 * l.size();
            // Few enough, well enough spread constraints that R has full rank.
            let max_m = if l.control_point_count() >= 100 { 8 } else { 3 };
            for m in 1..=max_m {
                let cs = random_constraints(&l, &mut rng, m, 0.3);
                let manip = Manipulation::multi(&l, &cs, &SolveOptions::default())
                    .unwrap_or_else(|e| panic!("{spec:?} m = {m}: {e}"));
                assert_targets_met(&l, &manip, &cs, tol);
            }
        }
    }
}

#[test]
fn one_constraint_equals_the_single_point_solution() {
    let mut rng = Lcg::new(22);
    let l = lattice(LatticeSpec::uniform(3, 6));
    let cs = random_constraints(&l, &mut rng, 1, 0.3);
    let a = Manipulation::multi(&l, &cs, &SolveOptions::default()).unwrap();
    let b = Manipulation::single(&l, &cs[0]).unwrap();
    assert_eq!(a.indices(), b.indices());
    for (x, y) in a.displacements().iter().zip(b.displacements()) {
        assert!((x - y).norm() < 1e-14);
    }
}

#[test]
fn multi_point_solution_is_the_least_norm_one() {
    let mut rng = Lcg::new(23);
    for spec in [
        LatticeSpec::uniform(2, 4),
        LatticeSpec::uniform(3, 5),
        LatticeSpec::uniform(3, 7),
    ] {
        let l = lattice(spec);
        for m in [2, 3, 5] {
            let cs = random_constraints(&l, &mut rng, m, 0.3);
            let params: Vec<[f64; 3]> = cs.iter().map(|c| c.params).collect();
            let d: Vec<Vec3> = cs
                .iter()
                .map(|c| c.target - l.point_at(c.params).unwrap())
                .collect();
            let ours = Manipulation::multi(&l, &cs, &SolveOptions::default())
                .unwrap()
                .to_dense();
            let r = dense_r(&l, &params);
            let mut references = vec![dense_normal_equations_solution(&r, &d)];
            if l.control_point_count() <= 125 {
                // nalgebra's SVD pseudo-inverse on the small cases (on larger ones it was seen to
                // lose accuracy: residual 1e-9 for a 343 x 2 matrix with singular values 0.35, 0.30).
                references.push(dense_pinv_solution(&r, &d));
            }
            for dense in references {
                let scale = dense.amax().max(1.0);
                for (i, x) in ours.iter().enumerate() {
                    let e = Vec3::new(dense[(i, 0)], dense[(i, 1)], dense[(i, 2)]);
                    assert!(
                        (x - e).norm() < 1e-12 * scale,
                        "{spec:?} m={m} cp {i}: {x} vs {e}"
                    );
                }
            }
            // Same with displacements given directly.
            let direct =
                Manipulation::multi_displacements(&l, &params, &d, &SolveOptions::default())
                    .unwrap()
                    .to_dense();
            for (x, y) in ours.iter().zip(&direct) {
                assert!((x - y).norm() < 1e-14 * x.norm().max(1.0));
            }
        }
    }
}

#[test]
fn only_the_union_of_supports_moves() {
    let mut rng = Lcg::new(24);
    let l = lattice(LatticeSpec::uniform(3, 10));
    let cs = random_constraints(&l, &mut rng, 4, 0.3);
    let m = Manipulation::multi(&l, &cs, &SolveOptions::default()).unwrap();
    let mut union: Vec<usize> = cs
        .iter()
        .flat_map(|c| l.basis(c.params).unwrap().indices)
        .collect();
    union.sort_unstable();
    union.dedup();
    assert_eq!(m.indices(), &union[..]);
    let mut moved = l.clone();
    moved.apply(&m);
    for (f, (p, q)) in l
        .control_points()
        .iter()
        .zip(moved.control_points())
        .enumerate()
    {
        if union.binary_search(&f).is_err() {
            assert_eq!(p, q);
        }
    }
}

#[test]
fn same_source_with_two_targets_names_the_conflict() {
    let mut rng = Lcg::new(25);
    let l = lattice(LatticeSpec::uniform(3, 6));
    let mut cs = random_constraints(&l, &mut rng, 4, 0.3);
    cs.push(PointConstraint::new(
        cs[1].params,
        cs[1].target + Vec3::new(0.1, 0.0, 0.0),
    ));
    let err = Manipulation::multi(&l, &cs, &SolveOptions::default()).unwrap_err();
    match &err {
        FfdError::ConflictingConstraints {
            rank,
            count,
            conflicts,
        } => {
            assert_eq!((*rank, *count), (4, 5));
            assert_eq!(conflicts.len(), 1);
            assert_eq!(conflicts[0].involved(), vec![1, 4]);
            assert!((conflicts[0].mismatch - 0.1).abs() < 1e-12);
        }
        e => panic!("{e}"),
    }
    let msg = err.to_string();
    assert!(msg.contains("only 4 of 5"), "{msg}");
    // Least squares meets the others and splits the difference between 1 and 4.
    let m = Manipulation::multi(&l, &cs, &SolveOptions::least_squares()).unwrap();
    let mut moved = l.clone();
    moved.apply(&m);
    let tol = 1e-12 * l.size();
    for f in [0, 2, 3] {
        assert!((moved.point_at(cs[f].params).unwrap() - cs[f].target).norm() < tol);
    }
    let mid = 0.5 * (cs[1].target + cs[4].target);
    assert!((moved.point_at(cs[1].params).unwrap() - mid).norm() < tol);
}

#[test]
fn repeated_identical_constraints_are_redundant_not_conflicting() {
    let mut rng = Lcg::new(26);
    let l = lattice(LatticeSpec::uniform(2, 5));
    let mut cs = random_constraints(&l, &mut rng, 3, 0.3);
    cs.push(cs[0]);
    cs.push(cs[2]);
    let tol = 1e-12 * l.size();
    for opts in [SolveOptions::default(), SolveOptions::least_squares()] {
        let m = Manipulation::multi(&l, &cs, &opts).unwrap();
        assert_targets_met(&l, &m, &cs, tol);
        // And it is the same field as without the repeats.
        let plain = Manipulation::multi(&l, &cs[..3], &opts).unwrap();
        for (x, y) in m.to_dense().iter().zip(plain.to_dense()) {
            assert!((x - y).norm() < 1e-12);
        }
    }
}

#[test]
fn more_constraints_than_the_lattice_can_meet_are_reported() {
    // A trilinear 2x2x2 lattice has 8 control points: a ninth constraint anywhere depends on the
    // others (R has rank <= 8), and random targets disagree.
    let mut rng = Lcg::new(27);
    let l = lattice(LatticeSpec::uniform(1, 2));
    let cs = random_constraints(&l, &mut rng, 10, 0.3);
    match Manipulation::multi(&l, &cs, &SolveOptions::default()).unwrap_err() {
        FfdError::ConflictingConstraints {
            rank,
            count,
            conflicts,
        } => {
            assert_eq!((rank, count), (8, 10));
            assert_eq!(conflicts.len(), 2);
            for c in &conflicts {
                assert!(c.constraint < 10 && c.mismatch > 1e-6);
                assert!(!c.depends_on.is_empty() && c.depends_on.iter().all(|&i| i < 10));
            }
        }
        e => panic!("{e}"),
    }
    // Least squares agrees with the dense pseudo-inverse.
    let params: Vec<[f64; 3]> = cs.iter().map(|c| c.params).collect();
    let d: Vec<Vec3> = cs
        .iter()
        .map(|c| c.target - l.point_at(c.params).unwrap())
        .collect();
    let ours = Manipulation::multi(&l, &cs, &SolveOptions::least_squares())
        .unwrap()
        .to_dense();
    let dense = dense_pinv_solution(&dense_r(&l, &params), &d);
    for (i, x) in ours.iter().enumerate() {
        let e = Vec3::new(dense[(i, 0)], dense[(i, 1)], dense[(i, 2)]);
        assert!((x - e).norm() < 1e-10 * dense.amax().max(1.0), "{x} vs {e}");
    }
    // But if the targets come from one trilinear map they are consistent and met exactly.
    let mut target_lattice = l.clone();
    jiggle(&mut target_lattice, &mut rng, 0.3);
    let consistent: Vec<PointConstraint> = cs
        .iter()
        .map(|c| PointConstraint::new(c.params, target_lattice.point_at(c.params).unwrap()))
        .collect();
    let m = Manipulation::multi(&l, &consistent, &SolveOptions::default()).unwrap();
    assert_targets_met(&l, &m, &consistent, 1e-11 * l.size());
}

#[test]
fn constraints_dependent_within_one_span_are_named() {
    // Degree 1, 3 points per axis: within the cell [0, 1/2]^3 the basis is trilinear, so nine
    // constraints inside that cell are dependent (8 basis functions), and only they are named.
    let mut rng = Lcg::new(28);
    let l = lattice(LatticeSpec::uniform(1, 3));
    let mut cs: Vec<PointConstraint> = Vec::new();
    for _ in 0..9 {
        let t = [
            rng.range(0.0, 0.5),
            rng.range(0.0, 0.5),
            rng.range(0.0, 0.5),
        ];
        cs.push(PointConstraint::new(
            t,
            l.point_at(t).unwrap() + rng.vec(0.2),
        ));
    }
    // Plus one far away in the opposite cell.
    let t = [0.9, 0.9, 0.9];
    cs.insert(
        4,
        PointConstraint::new(t, l.point_at(t).unwrap() + rng.vec(0.2)),
    );
    match Manipulation::multi(&l, &cs, &SolveOptions::default()).unwrap_err() {
        FfdError::ConflictingConstraints {
            rank, conflicts, ..
        } => {
            assert_eq!(rank, 9);
            assert_eq!(conflicts.len(), 1);
            let involved = conflicts[0].involved();
            assert!(!involved.contains(&4), "{involved:?}");
            assert_eq!(involved.len(), 9);
        }
        e => panic!("{e}"),
    }
}

#[test]
fn degenerate_inputs_are_errors() {
    let l = lattice(LatticeSpec::default());
    assert_eq!(
        Manipulation::multi(&l, &[], &SolveOptions::default()),
        Err(FfdError::NoConstraints)
    );
    let bad = [
        PointConstraint::new([0.1, 0.2, 0.3], Vec3::zeros()),
        PointConstraint::new([0.5, 0.5, 0.5], Vec3::new(0.0, f64::INFINITY, 0.0)),
    ];
    assert_eq!(
        Manipulation::multi(&l, &bad, &SolveOptions::default()),
        Err(FfdError::NonFiniteTarget { index: 1 })
    );
    let out = [PointConstraint::new([0.1, 1.2, 0.3], Vec3::zeros())];
    assert!(matches!(
        Manipulation::multi(&l, &out, &SolveOptions::default()),
        Err(FfdError::ParametersOutOfDomain { .. })
    ));
    assert_eq!(SolveOptions::default().mode, SolveMode::Exact);
}
