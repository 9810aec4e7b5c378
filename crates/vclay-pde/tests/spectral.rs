//! The Fourier-series and pseudospectral solvers (`dynamic-pde-surfaces.txt` section III,
//! eq 19-23, Fig 1(c)-(e)) and the comparison the paper reports (issue 22).

use crate::support;

use support::closed_form::{ClosedForm, Section3};
use vclay_pde::spec::SpecFile;
use vclay_pde::spectral::boundary_series;
use vclay_pde::surface::{GridWork, eval_grid, point, uniform};
use vclay_pde::{Method, PdeError, PdeModel};

const SPEC: &str = include_str!("../examples/specs/section3.json");

fn spec(solver: &str, terms: usize) -> SpecFile {
    let mut s: SpecFile = serde_json::from_str(SPEC).unwrap();
    if solver != "collocation" {
        s.solver = Some(solver.into());
        s.fourier_terms = Some(terms);
    }
    s
}

/// (largest deviation, largest deviation on u = 0 and u = 1), relative to the closed-form
/// surface's bounding-box diagonal, on a 101 x 101 grid.
fn deviation(s: &SpecFile, reference: &ClosedForm) -> (f64, f64) {
    let model = PdeModel::from_spec(s).unwrap();
    let sol = model.solve(0.0).unwrap();
    let (mut lo, mut hi, mut worst, mut bc) = ([f64::MAX; 3], [f64::MIN; 3], 0.0f64, 0.0f64);
    for a in 0..=100 {
        for b in 0..=100 {
            let (u, v) = (a as f64 / 100.0, std::f64::consts::TAU * b as f64 / 100.0);
            let r = reference.point(u, v);
            let p = point(&model.patches[0], &sol.patches[0], u, v);
            for i in 0..3 {
                lo[i] = lo[i].min(r[i]);
                hi[i] = hi[i].max(r[i]);
                worst = worst.max((p[i] - r[i]).abs());
                if a == 0 || a == 100 {
                    bc = bc.max((p[i] - r[i]).abs());
                }
            }
        }
    }
    let diag = (0..3).map(|i| (hi[i] - lo[i]).powi(2)).sum::<f64>().sqrt();
    (worst / diag, bc / diag)
}

#[test]
fn fourier_coefficients_are_eq_19_and_20() {
    // x's u = 0 condition is 4.763 + 0.017 sin v - 3.395 exp(0.1 v); y's is
    // 0.475 + 0.0159 v - 0.475 cos v. Their series follow from eq (19) (v) and (20) (exp).
    let model = PdeModel::from_spec(&spec("fourier", 30)).unwrap();
    let patch = &model.patches[0];
    let sx = boundary_series(patch, 0, 0.0, 30);
    let sy = boundary_series(patch, 1, 0.0, 30);
    let pi = std::f64::consts::PI;
    let e = ((0.2 * pi).exp() - 1.0) / pi;
    for n in 0..=30usize {
        let nf = n as f64;
        // eq (20): exp(0.1 v) = e [5 + sum (0.1 cos nv - n sin nv) / (0.01 + n^2)]
        let (ea, eb) = if n == 0 {
            (5.0 * e, 0.0)
        } else {
            (e * 0.1 / (0.01 + nf * nf), -e * nf / (0.01 + nf * nf))
        };
        // eq (19): v = pi - sum (2/n) sin nv
        let (va, vb) = if n == 0 { (pi, 0.0) } else { (0.0, -2.0 / nf) };
        let want_x = [
            (if n == 0 { 4.763 } else { 0.0 }) - 3.395 * ea,
            (if n == 1 { 0.017 } else { 0.0 }) - 3.395 * eb,
        ];
        let want_y = [
            (if n == 0 { 0.475 } else { 0.0 }) + 0.0159 * va - (if n == 1 { 0.475 } else { 0.0 }),
            0.0159 * vb,
        ];
        for k in 0..2 {
            assert!(
                (sx[n][0][k] - want_x[k]).abs() < 1e-12,
                "x mode {n} part {k}: {} vs {}",
                sx[n][0][k],
                want_x[k]
            );
            assert!(
                (sy[n][0][k] - want_y[k]).abs() < 1e-12,
                "y mode {n} part {k}: {} vs {}",
                sy[n][0][k],
                want_y[k]
            );
        }
    }
}

/// Section III's problem with only periodic basic functions (c = e = h1 = 0): the Fourier
/// series is then exact, and so is the pseudospectral solution (its remainder vanishes).
fn periodic() -> (SpecFile, Section3) {
    let mut p = Section3::paper();
    (p.c, p.cp, p.e, p.ep, p.h1, p.h1p) = (0.0, 0.0, 0.0, 0.0, 0.0, 0.0);
    let mut s: SpecFile = serde_json::from_str(SPEC).unwrap();
    for key in ["c", "cp", "e", "ep", "h1", "h1p"] {
        s.params.insert(key.into(), 0.0);
    }
    (s, p)
}

#[test]
fn periodic_data_are_solved_exactly_double_roots() {
    // b = 1, c = 2 a^2, d = a^4: double roots +-a n (eq 17); mode 0 a cubic (eq 15).
    let (base, p) = periodic();
    let reference = ClosedForm::new(&p);
    for (solver, terms) in [("fourier", 3), ("fourier", 20), ("pseudospectral", 5)] {
        let mut s = base.clone();
        s.solver = Some(solver.into());
        s.fourier_terms = Some(terms);
        let (dev, bc) = deviation(&s, &reference);
        assert!(
            dev < 1e-11 && bc < 1e-11,
            "{solver} N = {terms}: {dev:e} {bc:e}"
        );
    }
}

#[test]
fn distinct_and_complex_roots_agree_with_converged_collocation() {
    // b s^4 - c n^2 s^2 + d n^4 = 0 with distinct real roots (b, c, d) = (1, 5, 4) and complex
    // ones (1, 1, 1): the Fourier series of periodic data against collocation with N = 15.
    let (base, _) = periodic();
    for shape in [[1.0, 5.0, 4.0], [1.0, 1.0, 1.0], [2.0, 0.0, 0.5]] {
        let mut s = base.clone();
        s.shape = Some(
            serde_json::from_value(
                serde_json::json!({"b": shape[0], "c": shape[1], "d": shape[2]}),
            )
            .unwrap(),
        );
        let mut f = s.clone();
        f.solver = Some("fourier".into());
        f.fourier_terms = Some(4);
        s.trial_terms = Some(15);
        s.collocation = Some(vclay_pde::spec::CollocationSpec::Grid([30, 8]));
        let (m1, m2) = (
            PdeModel::from_spec(&s).unwrap(),
            PdeModel::from_spec(&f).unwrap(),
        );
        let (s1, s2) = (m1.solve(0.0).unwrap(), m2.solve(0.0).unwrap());
        let mut worst: f64 = 0.0;
        for a in 0..=20 {
            for b in 0..=20 {
                let (u, v) = (a as f64 / 20.0, 0.3 * b as f64);
                let d = point(&m1.patches[0], &s1.patches[0], u, v)
                    - point(&m2.patches[0], &s2.patches[0], u, v);
                worst = worst.max(d.norm());
            }
        }
        assert!(
            worst < 1e-6,
            "shape {shape:?}: collocation and Fourier differ by {worst:e}"
        );
    }
}

#[test]
fn comparison_ordering_of_section_3() {
    // The paper (Fig 1(b)-(e)): collocation with M = 36, N = 7 is indistinguishable from the
    // closed form; the pseudospectral solution (N = 5) is "slightly improved" over the Fourier
    // series (N = 20) but still different; N = 50 does not improve the series; N = 10 makes the
    // pseudospectral solution "poorer" than N = 5. The series misses the boundary condition
    // at the seam v = 0 = 2 pi (the Gibbs gap of Fig 1(c)); the remainder meets it exactly.
    let reference = ClosedForm::new(&Section3::paper());
    let (col, col_bc) = deviation(&spec("collocation", 0), &reference);
    let (f20, f20_bc) = deviation(&spec("fourier", 20), &reference);
    let (f50, _) = deviation(&spec("fourier", 50), &reference);
    let (p5, p5_bc) = deviation(&spec("pseudospectral", 5), &reference);
    let (p10, _) = deviation(&spec("pseudospectral", 10), &reference);
    eprintln!(
        "collocation {col:.2e}, fourier 20 {f20:.2e}, 50 {f50:.2e}, pseudospectral 5 {p5:.2e}, 10 {p10:.2e}"
    );
    assert!(col < 1e-3, "collocation {col}");
    assert!(
        100.0 * col < p5,
        "collocation far closer than pseudospectral: {col} {p5}"
    );
    assert!(
        p5 < f20,
        "pseudospectral N = 5 better than Fourier N = 20: {p5} {f20}"
    );
    assert!(
        f50 > 0.9 * f20,
        "more terms do not improve the series: {f50} {f20}"
    );
    assert!(
        p10 > p5,
        "pseudospectral N = 10 poorer than N = 5: {p10} {p5}"
    );
    assert!(
        f20_bc > 0.1,
        "the series misses the boundary at the seam: {f20_bc}"
    );
    assert!(
        col_bc < 1e-12 && p5_bc < 1e-12,
        "exact boundary conditions: {col_bc} {p5_bc}"
    );
}

#[test]
fn grid_evaluation_equals_points() {
    for solver in ["fourier", "pseudospectral"] {
        let model = PdeModel::from_spec(&spec(solver, 7)).unwrap();
        assert_eq!(model.patches[0].method.name(), solver);
        let sol = model.solve(0.0).unwrap();
        let (us, vs) = (uniform(0.0, 1.0, 9), uniform(0.0, 6.0, 11));
        let mut pts = Vec::new();
        eval_grid(
            &model.patches[0],
            &sol.patches[0],
            &us,
            &vs,
            &mut GridWork::default(),
            &mut pts,
        );
        for (r, &u) in us.iter().enumerate() {
            for (c, &v) in vs.iter().enumerate() {
                let p = point(&model.patches[0], &sol.patches[0], u, v);
                assert!(
                    (p - pts[r * vs.len() + c]).norm() < 1e-12,
                    "{solver} ({u}, {v})"
                );
            }
        }
        assert_eq!(sol.patches[0].stats.unknowns, [64, 64, 64]);
    }
}

fn invalid(s: &SpecFile) -> (String, String) {
    match PdeModel::from_spec(s) {
        Err(PdeError::InvalidValue { place, message }) => (place, message),
        other => panic!("expected InvalidValue, got {other:?}"),
    }
}

#[test]
fn spec_errors_name_the_field() {
    let mut s = spec("fourier", 20);
    s.solver = Some("spectral".into());
    let (place, msg) = invalid(&s);
    assert_eq!(place, "solver");
    assert!(
        msg.contains("collocation, fourier, pseudospectral"),
        "{msg}"
    );
    // Sizes are checked before anything is allocated.
    for n in [0, vclay_pde::spectral::MAX_FOURIER_TERMS + 1, usize::MAX] {
        let mut s = spec("pseudospectral", n);
        s.patches[0].fourier_terms = Some(n);
        let (place, _) = invalid(&s);
        assert_eq!(place, "patches[0].fourier_terms");
    }
    let mut s = spec("fourier", 20);
    s.shape =
        Some(serde_json::from_value(serde_json::json!({"b": "1 + u", "c": 2, "d": 1})).unwrap());
    assert_eq!(invalid(&s).0, "patches[0].shape.b");
    let mut s = spec("fourier", 20);
    s.rho = Some(1.0.into());
    assert_eq!(invalid(&s).0, "patches[0].rho");
    let mut s = spec("fourier", 20);
    s.patches[0].solver = Some("pseudospectral".into());
    let model = PdeModel::from_spec(&s).unwrap();
    assert_eq!(
        model.patches[0].method,
        Method::Pseudospectral { terms: 20 }
    );
}
