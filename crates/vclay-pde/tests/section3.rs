//! `dynamic-pde-surfaces.txt` section III: the collocation solution (18) against the
//! closed-form solution (14)-(17) of the static problem (13), Fig 1(a)-(b).

use crate::support;

use support::closed_form::{ClosedForm, Section3};
use vclay_pde::spec::{CollocationSpec, SpecFile};
use vclay_pde::surface::point;
use vclay_pde::{PdeError, PdeModel};

const SPEC: &str = include_str!("../examples/specs/section3.json");

fn spec() -> SpecFile {
    serde_json::from_str(SPEC).expect("section3.json parses")
}

/// Largest deviation from the closed form on a 41 x 41 grid, relative to the diagonal of the
/// closed-form surface's bounding box.
fn deviation(model: &PdeModel) -> (f64, f64) {
    let sol = model.solve(0.0).expect("section III solves");
    let reference = ClosedForm::new(&Section3::paper());
    let patch = &model.patches[0];
    let n = 41;
    let (mut lo, mut hi) = ([f64::MAX; 3], [f64::MIN; 3]);
    let mut worst: f64 = 0.0;
    for a in 0..n {
        for b in 0..n {
            let u = a as f64 / (n - 1) as f64;
            let v = std::f64::consts::TAU * b as f64 / (n - 1) as f64;
            let r = reference.point(u, v);
            let p = point(patch, &sol.patches[0], u, v);
            for i in 0..3 {
                lo[i] = lo[i].min(r[i]);
                hi[i] = hi[i].max(r[i]);
                worst = worst.max((p[i] - r[i]).abs());
            }
        }
    }
    let diag = (0..3).map(|i| (hi[i] - lo[i]).powi(2)).sum::<f64>().sqrt();
    (worst / diag, sol.patches[0].stats.residual_rms)
}

#[test]
fn m36_n7_agrees_with_closed_form() {
    let model = PdeModel::from_spec(&spec()).unwrap();
    assert_eq!(model.patches[0].collocation.points(), 36);
    assert_eq!(model.patches[0].trial.n_max, 7);
    let (dev, res) = deviation(&model);
    eprintln!(
        "section III, M = 36, N = 7: max deviation / surface diagonal = {dev:.3e}, residual rms = {res:.3e}"
    );
    // Fig 1(b) shows no visible difference from Fig 1(a): well under a thousandth of the size.
    assert!(dev < 1e-3, "relative deviation {dev}");
}

#[test]
fn error_falls_as_n_grows() {
    let mut last = f64::INFINITY;
    let mut report = Vec::new();
    for n in [5usize, 7, 9, 11] {
        let mut s = spec();
        s.trial_terms = Some(n);
        // Enough rows along u for the N - 3 trial terms of each basic function.
        s.collocation = Some(CollocationSpec::Grid([(n - 1).max(6), 6]));
        let (dev, _) = deviation(&PdeModel::from_spec(&s).unwrap());
        report.push((n, dev));
        assert!(
            dev < last,
            "N = {n}: deviation {dev} did not fall below {last}: {report:?}"
        );
        last = dev;
    }
    eprintln!("section III deviation by N: {report:?}");
}

#[test]
fn direct_solve_with_m_equal_to_unknowns() {
    // M = J (N - 3) = 3 * 4 = 12 for x and y: eq (9) solved directly.
    let mut s = spec();
    s.collocation = Some(CollocationSpec::Grid([4, 3]));
    let model = PdeModel::from_spec(&s).unwrap();
    let sol = model.solve(0.0).unwrap();
    // Square system: the residual at the collocation points vanishes (up to rounding).
    let scale = 1e4; // residuals are of size b psi'''' ~ 10^3 times the coefficients
    assert!(
        sol.patches[0].stats.residual_norm[0] < 1e-9 * scale,
        "{:?}",
        sol.patches[0].stats
    );
    let (dev, _) = deviation(&model);
    assert!(dev < 1e-2, "direct solve deviation {dev}");
}

#[test]
fn too_few_collocation_points_is_reported() {
    let mut s = spec();
    s.collocation = Some(CollocationSpec::Grid([3, 3]));
    match PdeModel::from_spec(&s) {
        Err(PdeError::TooFewCollocationPoints {
            unknowns, points, ..
        }) => {
            assert_eq!((unknowns, points), (12, 9));
        }
        other => panic!("expected TooFewCollocationPoints, got {other:?}"),
    }
}

#[test]
fn boundary_conditions_hold_exactly() {
    let model = PdeModel::from_spec(&spec()).unwrap();
    let sol = model.solve(0.0).unwrap();
    let p = Section3::paper();
    for k in 0..13 {
        let v = k as f64 * 0.5;
        let x0 = point(&model.patches[0], &sol.patches[0], 0.0, v);
        let x1 = point(&model.patches[0], &sol.patches[0], 1.0, v);
        let want0 = [
            p.a + p.b * v.sin() + p.c * (0.1 * v).exp(),
            p.d + p.e * v + p.f * v.cos(),
            p.h0 - p.h1 * v,
        ];
        let want1 = [p.r * v.sin(), -p.r * v.cos(), 0.0];
        for i in 0..3 {
            assert!((x0[i] - want0[i]).abs() < 1e-12, "u=0 v={v} comp {i}");
            assert!((x1[i] - want1[i]).abs() < 1e-12, "u=1 v={v} comp {i}");
        }
        // Tangent by a one-sided difference (second-order accurate).
        let h = 1e-5;
        let xa = point(&model.patches[0], &sol.patches[0], h, v);
        let xb = point(&model.patches[0], &sol.patches[0], 2.0 * h, v);
        let du0 = (-3.0 * x0 + 4.0 * xa - xb) / (2.0 * h);
        let want = [0.0, p.dp + p.ep * v + p.fp * v.cos(), p.h0p - p.h1p * v];
        for i in 0..3 {
            assert!(
                (du0[i] - want[i]).abs() < 1e-6,
                "du at u=0, v={v}, comp {i}: {} vs {}",
                du0[i],
                want[i]
            );
        }
    }
}
