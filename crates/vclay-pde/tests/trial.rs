//! Trial functions (eq 5, 36) and the collocation grid.

use vclay_pde::patch::Collocation;
use vclay_pde::trial::{PatchKind, TrialBasis, TrialTable, fill_powers, poly_dot};

fn eval(p: &[f64], u: f64) -> f64 {
    let mut pw = vec![0.0; p.len()];
    fill_powers(u, &mut pw);
    poly_dot(p, &pw)
}

fn deriv(p: &[f64]) -> Vec<f64> {
    vclay_pde::trial::poly_derivative(p)
}

#[test]
fn hermite_and_trial_functions_meet_the_end_conditions() {
    let b = TrialBasis::new(PatchKind::TwoEnds, 9).unwrap();
    assert_eq!(b.unknowns_per_basic(), 6);
    // h_k: value/slope at u = 0 and u = 1 form the identity (eq 5).
    for (k, h) in b.known.iter().enumerate() {
        let dh = deriv(h);
        let ends = [eval(h, 0.0), eval(&dh, 0.0), eval(h, 1.0), eval(&dh, 1.0)];
        for (q, e) in ends.iter().enumerate() {
            assert!(
                (e - if q == k { 1.0 } else { 0.0 }).abs() < 1e-14,
                "h{k}: {ends:?}"
            );
        }
    }
    // psi_n vanish with their slope at both ends and contain u^n.
    for (k, psi) in b.unknown.iter().enumerate() {
        let n = b.power_of_unknown(k);
        let d = deriv(psi);
        for e in [eval(psi, 0.0), eval(&d, 0.0), eval(psi, 1.0), eval(&d, 1.0)] {
            assert!(e.abs() < 1e-13, "psi_{n}");
        }
        assert_eq!(psi[n], 1.0);
    }
    let one = TrialBasis::new(PatchKind::OneEnd, 6).unwrap();
    assert_eq!(one.unknowns_per_basic(), 5);
    assert_eq!(
        one.known,
        vec![
            vec![1.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0],
            vec![0.0, 1.0, 0.0, 0.0, 0.0, 0.0, 0.0]
        ]
    );
}

#[test]
fn table_derivatives_match_finite_differences() {
    let b = TrialBasis::new(PatchKind::TwoEnds, 8).unwrap();
    let us = [0.13, 0.5, 0.91];
    let t = TrialTable::new(&b, &us);
    let h = 1e-3;
    let all: Vec<&Vec<f64>> = b.known.iter().chain(&b.unknown).collect();
    for (r, &u) in us.iter().enumerate() {
        for (k, p) in all.iter().enumerate() {
            let f = |x: f64| eval(p, x);
            let d1 = (f(u + h) - f(u - h)) / (2.0 * h);
            let d2 = (f(u + h) - 2.0 * f(u) + f(u - h)) / (h * h);
            let d4 = (f(u + 2.0 * h) - 4.0 * f(u + h) + 6.0 * f(u) - 4.0 * f(u - h)
                + f(u - 2.0 * h))
                / h.powi(4);
            let i = r * t.width + k;
            assert!((t.value[i] - f(u)).abs() < 1e-14);
            assert!((t.d1[i] - d1).abs() < 1e-4 * t.d1[i].abs().max(1.0));
            assert!((t.d2[i] - d2).abs() < 1e-4 * t.d2[i].abs().max(1.0));
            assert!(
                (t.d4[i] - d4).abs() < 1e-2 * t.d4[i].abs().max(1.0),
                "{} vs {d4}",
                t.d4[i]
            );
        }
    }
}

#[test]
fn too_few_trial_terms_is_an_error() {
    assert!(TrialBasis::new(PatchKind::TwoEnds, 3).is_err());
    assert!(TrialBasis::new(PatchKind::OneEnd, 0).is_err());
    assert!(TrialBasis::new(PatchKind::OneEnd, 2).is_ok());
}

#[test]
fn collocation_count_is_arranged_as_square_as_possible() {
    assert_eq!(Collocation::from_count(36), Collocation { nu: 6, nv: 6 });
    assert_eq!(Collocation::from_count(12), Collocation { nu: 4, nv: 3 });
    assert_eq!(Collocation::from_count(7), Collocation { nu: 7, nv: 1 });
    assert_eq!(Collocation::from_count(48).points(), 48);
}
