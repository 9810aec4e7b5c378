//! Tests of `FfdLattice`: identity at rest, linear parameters, validation, basis, rational
//! evaluation against the spline layer.

use crate::common;

use common::{Lcg, jiggle, lattice, rest_point, specs, test_box};
use vclay_core::Vec3;
use vclay_ffd::{FfdError, FfdLattice, LatticeSpec};
use vclay_spline::ParametricVolume;

#[test]
fn undeformed_lattice_is_the_identity() {
    let mut rng = Lcg::new(1);
    for spec in specs()
        .into_iter()
        .chain([LatticeSpec::uniform(1, 2), LatticeSpec::uniform(1, 5)])
    {
        let l = lattice(spec);
        let tol = 1e-12 * l.size();
        let (lo, hi) = l.bounds();
        for _ in 0..500 {
            let x = lo + (hi - lo).component_mul(&Vec3::from(rng.params()));
            let y = l.deform_point(&x);
            assert!((y - x).norm() < tol, "{spec:?}: {x} -> {y}");
        }
        // Corners and faces too.
        for c in 0..8 {
            let t = [(c & 1) as f64, ((c >> 1) & 1) as f64, ((c >> 2) & 1) as f64];
            let x = rest_point(&l, t);
            assert!((l.deform_point(&x) - x).norm() < tol);
        }
    }
}

#[test]
fn parameters_are_the_linear_map_and_outside_is_none() {
    let l = lattice(LatticeSpec::default());
    let (lo, hi) = test_box();
    let x = Vec3::new(0.5, 2.25, 12.0);
    let t = l.parameters(&x).unwrap();
    for a in 0..3 {
        assert!((t[a] - (x[a] - lo[a]) / (hi[a] - lo[a])).abs() < 1e-15);
    }
    // On the faces (and within round-off of them): embedded, clamped.
    assert_eq!(l.parameters(&lo), Some([0.0; 3]));
    assert_eq!(l.parameters(&hi), Some([1.0; 3]));
    let just = Vec3::new(hi.x + 1e-14, 2.5, 11.0);
    assert_eq!(l.parameters(&just).unwrap()[0], 1.0);
    // Outside.
    assert!(l.parameters(&Vec3::new(hi.x + 1e-6, 2.5, 11.0)).is_none());
    assert!(l.parameters(&Vec3::new(0.0, lo.y - 0.1, 11.0)).is_none());
    assert!(l.parameters(&Vec3::new(f64::NAN, 2.5, 11.0)).is_none());
    // Outside points are not moved by a deformed lattice.
    let mut d = l.clone();
    jiggle(&mut d, &mut Lcg::new(3), 0.3);
    let out = Vec3::new(100.0, 0.0, 0.0);
    assert_eq!(d.deform_point(&out), out);
}

#[test]
fn constructors_validate_their_inputs() {
    let (lo, hi) = test_box();
    assert_eq!(
        FfdLattice::new(
            LatticeSpec {
                degree: [3, 0, 3],
                control_points: [4; 3]
            },
            lo,
            hi
        ),
        Err(FfdError::Degree { axis: 1, degree: 0 })
    );
    assert_eq!(
        FfdLattice::new(
            LatticeSpec {
                degree: [3; 3],
                control_points: [4, 4, 3]
            },
            lo,
            hi
        ),
        Err(FfdError::TooFewControlPoints {
            axis: 2,
            degree: 3,
            count: 3
        })
    );
    assert!(matches!(
        FfdLattice::new(LatticeSpec::default(), hi, lo),
        Err(FfdError::InvalidBox { axis: 0, .. })
    ));
    assert!(matches!(
        FfdLattice::new(LatticeSpec::default(), lo, Vec3::new(hi.x, lo.y, hi.z)),
        Err(FfdError::InvalidBox { axis: 1, .. })
    ));
    assert!(matches!(
        FfdLattice::new(
            LatticeSpec::default(),
            lo,
            Vec3::new(hi.x, hi.y, f64::INFINITY)
        ),
        Err(FfdError::InvalidBox { axis: 2, .. })
    ));
    assert!(matches!(
        FfdLattice::new(LatticeSpec::uniform(40, 50), lo, hi),
        Err(FfdError::Spline(_))
    ));
    assert_eq!(
        FfdLattice::enclosing(&[], LatticeSpec::default(), 0.1),
        Err(FfdError::NoPoints)
    );
    assert_eq!(
        FfdLattice::enclosing(&[lo, hi], LatticeSpec::default(), -0.1),
        Err(FfdError::InvalidMargin { margin: -0.1 })
    );
    assert_eq!(
        FfdLattice::enclosing(
            &[lo, Vec3::new(0.0, f64::NAN, 0.0)],
            LatticeSpec::default(),
            0.1
        ),
        Err(FfdError::NonFinitePoint { index: 1 })
    );
    // Messages name what is wrong.
    let e = FfdLattice::new(
        LatticeSpec {
            degree: [3; 3],
            control_points: [4, 2, 4],
        },
        lo,
        hi,
    )
    .unwrap_err();
    assert!(e.to_string().contains("2 control points along v"), "{e}");
}

#[test]
fn enclosing_adds_a_relative_margin_and_handles_flat_sets() {
    let pts = [Vec3::new(0.0, 0.0, 0.0), Vec3::new(2.0, 1.0, 0.0)];
    let l = FfdLattice::enclosing(&pts, LatticeSpec::default(), 0.1).unwrap();
    let (lo, hi) = l.bounds();
    assert!((lo - Vec3::new(-0.2, -0.1, -0.2)).norm() < 1e-15, "{lo}");
    assert!((hi - Vec3::new(2.2, 1.1, 0.2)).norm() < 1e-15, "{hi}");
    // A point set that is flat with zero margin has no volume.
    assert!(matches!(
        FfdLattice::enclosing(&pts, LatticeSpec::default(), 0.0),
        Err(FfdError::InvalidBox { axis: 2, .. })
    ));
}

#[test]
fn basis_is_a_sparse_partition_of_unity() {
    let mut rng = Lcg::new(5);
    for spec in specs() {
        let mut l = lattice(spec);
        let expected: usize = spec.degree.iter().map(|d| d + 1).product();
        for rational in [false, true] {
            if rational {
                let w = (0..l.control_point_count())
                    .map(|_| rng.range(0.5, 2.0))
                    .collect();
                l.set_weights(w).unwrap();
                assert!(l.is_rational());
            }
            for _ in 0..50 {
                let b = l.basis(rng.params()).unwrap();
                assert_eq!(b.len(), expected);
                assert!(b.indices.windows(2).all(|w| w[0] < w[1]));
                let s: f64 = b.values.iter().sum();
                assert!((s - 1.0).abs() < 1e-14);
                assert!(b.values.iter().all(|&r| r >= 0.0));
            }
        }
    }
    let l = lattice(LatticeSpec::default());
    assert!(matches!(
        l.basis([0.5, 1.5, 0.5]),
        Err(FfdError::ParametersOutOfDomain { .. })
    ));
}

#[test]
fn evaluation_matches_the_spline_layer_rational_or_not() {
    let mut rng = Lcg::new(7);
    for spec in specs() {
        let mut l = lattice(spec);
        jiggle(&mut l, &mut rng, 0.2);
        for rational in [false, true] {
            if rational {
                let w = (0..l.control_point_count())
                    .map(|_| rng.range(0.3, 3.0))
                    .collect();
                l.set_weights(w).unwrap();
            }
            for _ in 0..50 {
                let t = rng.params();
                let ours = l.point_at(t).unwrap();
                let theirs = l.volume().point(t[0], t[1], t[2]).unwrap();
                assert!(
                    (ours - theirs).norm() < 1e-13 * l.size(),
                    "{spec:?} {rational}"
                );
            }
        }
        l.reset();
        assert!(!l.is_rational());
        assert_eq!(l.control_points(), l.rest_control_points());
    }
}

#[test]
fn flat_and_multi_indices_agree() {
    let l = lattice(LatticeSpec {
        degree: [3, 2, 3],
        control_points: [4, 7, 5],
    });
    for f in 0..l.control_point_count() {
        let [i, j, k] = l.multi_index(f);
        assert_eq!(l.flat_index(i, j, k), f);
        assert_eq!(l.volume().control_point(i, j, k), l.control_points()[f]);
    }
}
