//! Property tests (proptest, deterministic seed from proptest's config): invariants that must
//! hold for any valid knot vector and net.
use proptest::prelude::*;
use vclay_core::Vec3;
use vclay_spline::{KnotVector, NurbsCurve, ParametricCurve};

/// A clamped knot vector of degree `p` for `n` control points from sorted random interior knots.
fn knots_strategy() -> impl Strategy<Value = (usize, usize, Vec<f64>)> {
    (1usize..=5, 0usize..=6).prop_flat_map(|(p, extra)| {
        let n = p + 1 + extra;
        proptest::collection::vec(0.01f64..0.99, n - p - 1).prop_map(move |mut interior| {
            interior.sort_by(f64::total_cmp);
            let mut k = vec![0.0; p + 1];
            k.extend(interior);
            k.extend(vec![1.0; p + 1]);
            (p, n, k)
        })
    })
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 128, ..ProptestConfig::default() })]

    #[test]
    fn partition_of_unity((p, n, k) in knots_strategy(), u in 0.0f64..=1.0) {
        // Interior knots may repeat more than p + 1 times only by chance; skip those.
        let Ok(kv) = KnotVector::new(k, p, n) else { return Ok(()); };
        let mut b = vec![0.0; p + 1];
        let span = kv.find_span(u);
        kv.basis(span, u, &mut b);
        prop_assert!((b.iter().sum::<f64>() - 1.0).abs() < 1e-13);
        prop_assert!(b.iter().all(|&x| x >= -1e-15));
        let d = kv.basis_derivatives_vec(span, u, 0);
        for j in 0..=p {
            prop_assert!((d[j] - b[j]).abs() < 1e-14);
        }
    }

    #[test]
    fn affine_invariance_and_convex_hull(
        (p, n, k) in knots_strategy(),
        seed in proptest::collection::vec(-5.0f64..5.0, 3 * 12),
        wseed in proptest::collection::vec(0.1f64..10.0, 12),
        u in 0.0f64..=1.0,
        t in proptest::collection::vec(-3.0f64..3.0, 3),
    ) {
        let pts: Vec<Vec3> = (0..n).map(|i| Vec3::new(seed[3 * i], seed[3 * i + 1], seed[3 * i + 2])).collect();
        let Ok(c) = NurbsCurve::new(p, k, pts.clone(), Some(wseed[..n].to_vec())) else { return Ok(()); };
        let x = c.point(u).unwrap();
        // Strong convex hull: inside the bounding box of the control points.
        let lo = pts.iter().fold(pts[0], |a, b| a.inf(b));
        let hi = pts.iter().fold(pts[0], |a, b| a.sup(b));
        prop_assert!(x.iter().zip(lo.iter()).all(|(a, b)| *a >= b - 1e-12));
        prop_assert!(x.iter().zip(hi.iter()).all(|(a, b)| *a <= b + 1e-12));
        let m = nalgebra::Matrix3::new(0.5, 2.0, 0.0, -1.0, 0.3, 0.2, 0.0, 0.4, 1.5);
        let tv = Vec3::new(t[0], t[1], t[2]);
        let mut c2 = c.clone();
        c2.transform(&m, &tv);
        let y = c2.point(u).unwrap();
        prop_assert!((m * x + tv - y).norm() < 1e-12 * (1.0 + y.norm()));
    }
}
