//! Three-, four- and five-sided patches (`dynamic-pde-surfaces.txt` section VI-B, eq 33-37,
//! Fig 8): side conditions hold exactly, contradictions are reported.

use vclay_pde::surface::point;
use vclay_pde::{PatchKind, PdeError, PdeModel};

const FIG8: &str = include_str!("../examples/specs/fig8.json");

#[test]
fn four_sided_patch_meets_all_four_sides() {
    let model = PdeModel::from_json(FIG8, "fig8.json").unwrap();
    let sq = &model.patches[0];
    assert_eq!(sq.kind(), PatchKind::TwoEnds);
    let sol = model.solve(0.0).unwrap();
    let s = &sol.patches[0];
    let pi = std::f64::consts::PI;
    let h = 1e-6;
    for k in 0..=10 {
        let u = k as f64 / 10.0;
        let (p0, p1) = (point(sq, s, u, 0.0), point(sq, s, u, 1.0));
        // Positions on v = 0 and v = 1 (eq 33).
        for (p, y) in [(p0, 0.0), (p1, 1.0)] {
            assert!(
                (p.x - u).abs() < 1e-12 && (p.y - y).abs() < 1e-12 && p.z.abs() < 1e-12,
                "{p:?}"
            );
        }
        // Cross tangents dz/dv on both sides, by one-sided differences.
        let dv0 = (point(sq, s, u, h).z - p0.z) / h;
        let dv1 = (p1.z - point(sq, s, u, 1.0 - h).z) / h;
        let h1 = 1.0 - 3.0 * u * u + 2.0 * u * u * u;
        let want0 = 0.5 * pi * h1 + 2.0 * (u * u - 2.0 * u.powi(3) + u.powi(4));
        let want1 = -0.5 * pi * h1;
        assert!(
            (dv0 - want0).abs() < 1e-4,
            "u={u}: dz/dv(v=0) {dv0} vs {want0}"
        );
        assert!(
            (dv1 - want1).abs() < 1e-4,
            "u={u}: dz/dv(v=1) {dv1} vs {want1}"
        );
        // And the u = 0 boundary curve.
        let v = u;
        let b = point(sq, s, 0.0, v);
        assert!((b.z - 0.5 * (pi * v).sin()).abs() < 1e-12);
    }
    // The sides fix 2 of the 3 constants per trial power of z; the PDE residual chose the rest.
    assert_eq!(s.stats.unknowns[2], 12);
    assert!(s.stats.residual_rms.is_finite());
}

#[test]
fn three_sided_patch_and_five_sided_assembly() {
    let model = PdeModel::from_json(FIG8, "fig8.json").unwrap();
    let tri = &model.patches[1];
    assert_eq!(tri.kind(), PatchKind::OneEnd);
    let sol = model.solve(0.0).unwrap();
    let (sq, ss, ts) = (&model.patches[0], &sol.patches[0], &sol.patches[1]);
    for k in 0..=10 {
        let u = k as f64 / 10.0;
        let p0 = point(tri, ts, u, 0.0);
        let p1 = point(tri, ts, u, 1.0);
        let y0 = 0.5 * u + 0.4 * u * u - 0.4 * u.powi(3);
        assert!((p0.x - (1.0 + 0.8 * u)).abs() < 1e-12 && (p0.y - y0).abs() < 1e-12);
        assert!((p1.x - (1.0 + 0.8 * u)).abs() < 1e-12 && (p1.y - (1.0 - y0)).abs() < 1e-12);
        // The shared edge: triangle u = 0 is the square's u = 1.
        let v = u;
        assert!((point(tri, ts, 0.0, v) - point(sq, ss, 1.0, v)).norm() < 1e-12);
    }
    // The two sides meet at the apex.
    assert!((point(tri, ts, 1.0, 0.0) - point(tri, ts, 1.0, 1.0)).norm() < 1e-12);
}

#[test]
fn contradicting_side_is_reported() {
    // z on v = 0 must start at the u = 0 curve's value there (0.5 sin 0 = 0); 0.3 contradicts it.
    let bad = FIG8.replacen("\"z\": { \"v0\": 0,", "\"z\": { \"v0\": 0.3,", 1);
    assert_ne!(bad, FIG8);
    let e = PdeModel::from_json(&bad, "fig8.json")
        .unwrap()
        .solve(0.0)
        .unwrap_err();
    match &e {
        PdeError::InconsistentSides {
            component, message, ..
        } => {
            assert_eq!(*component, 'z');
            assert!(
                message.contains("sides.z.v0") && message.contains("u^0"),
                "{message}"
            );
        }
        other => panic!("{other:?}"),
    }
}

#[test]
fn side_must_be_polynomial_in_u() {
    let bad = FIG8.replacen("\"v0\": \"u\"", "\"v0\": \"sin(u)\"", 1);
    let e = PdeModel::from_json(&bad, "fig8.json").unwrap_err();
    assert!(e.to_string().contains("polynomials in u"), "{e}");
}
