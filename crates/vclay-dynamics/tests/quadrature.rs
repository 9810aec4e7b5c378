//! Quadrature of rational D-NURBS elements (issue 18, "rational elements are under-integrated"):
//! with non-uniform weights the integrands of eqs (16)-(17) are rational, so the paper's fixed
//! Gauss rule misses; the weight-aware rule (vclay's default) meets its stated accuracy.
use vclay_core::Vec3;
use vclay_dynamics::dnurbs::{
    GeneralizedDnurbs, QuadratureRule, RationalGeometry, Target, denominator_radius,
};
use vclay_dynamics::{ElasticReference, Force, Integrator, Material};
use vclay_spline::NurbsCurve;

/// The test piece: a planar quartic with 8 control points and weights 0.6-1.8
/// (seeded pattern, both extremes present).
fn quartic() -> NurbsCurve {
    quartic_scaled(1.0)
}

/// [`quartic`] with the weights' deviation from 1 scaled by `a` (spread `(1 + 0.8 a) / (1 - 0.4 a)`).
fn quartic_scaled(a: f64) -> NurbsCurve {
    let n = 8;
    let pts: Vec<Vec3> = (0..n)
        .map(|i| {
            let x = i as f64 / (n - 1) as f64;
            Vec3::new(x, 0.15 * (5.0 * x).sin(), 0.0)
        })
        .collect();
    let w = [1.0, 1.8, 0.6, 1.3, 0.6, 1.8, 0.9, 1.0]
        .iter()
        .map(|w| 1.0 + a * (w - 1.0))
        .collect();
    let mut c = NurbsCurve::clamped_uniform(4, pts).unwrap();
    c.set_weights(w).unwrap();
    c
}

/// Static equilibrium (weights held, so the problem is linear and one Gauss-Newton step
/// solves it) of the quartic under tension, bending, gravity and a spring, with `rule`.
fn equilibrium(rule: QuadratureRule) -> (Vec<Vec3>, usize) {
    equilibrium_of(quartic(), rule)
}

fn equilibrium_of(c: NurbsCurve, rule: QuadratureRule) -> (Vec<Vec3>, usize) {
    let n = c.control_points().len();
    let mut m = GeneralizedDnurbs::new(
        RationalGeometry::from_curve(&c),
        Material::curve(1.0, 0.0, 2.0, 0.05),
    )
    .unwrap();
    m.set_quadrature_rule(rule).unwrap();
    m.set_elastic_reference(ElasticReference::Absolute);
    for i in [0, n - 1] {
        for k in 0..3 {
            m.set_fixed_coordinate(4 * i + k, true).unwrap();
        }
    }
    for i in (3..4 * n).step_by(4) {
        m.set_fixed_coordinate(i, true).unwrap();
    }
    m.forces_mut()
        .push(Force::Gravity(Vec3::new(0.0, -1.0, 0.0)));
    m.forces_mut().push(Force::Spring {
        param: [0.37, 0.0],
        target: Target::Fixed(Vec3::new(0.4, 0.5, 0.2)),
        stiffness: 5.0,
        kernel: None,
    });
    m.step(Integrator::Static).unwrap();
    (m.geometry().control_points(), m.quadrature_points())
}

fn max_diff(a: &[Vec3], b: &[Vec3]) -> f64 {
    a.iter()
        .zip(b)
        .map(|(x, y)| (x - y).norm())
        .fold(0.0, f64::max)
}

#[test]
fn weight_aware_rule_meets_its_accuracy_where_the_papers_fixed_rule_misses() {
    // Reference: 40 Gauss points per element (converged to rounding). Size of the model: 1.
    let (exact, _) = equilibrium(QuadratureRule::Points(40));
    let (fixed, n_fixed) = equilibrium(QuadratureRule::Fixed);
    let (aware, n_aware) = equilibrium(QuadratureRule::default());
    let e_fixed = max_diff(&fixed, &exact);
    let e_aware = max_diff(&aware, &exact);
    eprintln!(
        "fixed: {n_fixed} points, error {e_fixed:.3e}; weight-aware: {n_aware} points, error {e_aware:.3e}"
    );
    assert!(
        e_fixed > 1e-5,
        "the fixed rule should miss on this rational curve: {e_fixed:e}"
    );
    // The default tolerance is 1e-8 of the model size (size 1 here); measured 1.1e-8.
    assert!(e_aware < 3e-8, "weight-aware rule error {e_aware:e}");
    assert!(n_aware > n_fixed);
}

#[test]
fn uniform_weights_keep_the_fixed_rule_and_orders_follow_the_weights() {
    let pts: Vec<Vec3> = (0..6).map(|i| Vec3::new(i as f64, 0.0, 0.0)).collect();
    let c = NurbsCurve::clamped_uniform(3, pts).unwrap();
    let m = GeneralizedDnurbs::new(
        RationalGeometry::from_curve(&c),
        Material::curve(1.0, 0.0, 1.0, 0.0),
    )
    .unwrap();
    // 3 elements of 4 points: the paper's rule.
    assert_eq!(m.quadrature_points(), 3 * 4);
    let rule = QuadratureRule::default();
    assert_eq!(rule.order(3, f64::INFINITY, 1.0), 4);
    let mut last = 0;
    for (r, spread) in [
        (50.0, 1.001),
        (10.0, 1.1),
        (4.0, 1.5),
        (2.0, 3.0),
        (1.2, 10.0),
    ] {
        let n = rule.order(3, r, spread);
        assert!(n >= last && n <= vclay_dynamics::dnurbs::generalized::MAX_WEIGHT_AWARE_POINTS);
        last = n;
    }
    // The ellipse radius of a known zero: W(t) = t - 2 has r = 2 + sqrt(3).
    let nodes = [-0.5, 0.5];
    let (r, spread) = denominator_radius(&[-2.5, -1.5], &nodes);
    assert!((r - (2.0 + 3f64.sqrt())).abs() < 1e-12, "{r}");
    assert!((spread - 2.5 / 1.5).abs() < 1e-12);
    // W(t) = t^2 + 0.25: zeros at +-0.5i, r = 0.5 + sqrt(1.25).
    let nodes = [-0.8, 0.1, 0.9];
    let vals: Vec<f64> = nodes.iter().map(|t| t * t + 0.25).collect();
    let (r, _) = denominator_radius(&vals, &nodes);
    assert!((r - (0.5 + 1.25f64.sqrt())).abs() < 1e-10, "{r}");
    assert!(QuadratureRule::Points(0).validate().is_err());
    assert!(
        QuadratureRule::WeightAware { tolerance: 0.0 }
            .validate()
            .is_err()
    );
}

/// Measurement (run with `--ignored --nocapture`): equilibrium error against the 40-point
/// reference for the fixed rule, fixed orders 4..20 and the weight-aware rule at several
/// tolerances; the table in docs/performance.md comes from here.
#[test]
#[ignore]
fn measure_quadrature_error_table() {
    for a in [0.001, 0.01, 0.1, 0.5, 1.0] {
        let c = quartic_scaled(a);
        let (exact, _) = equilibrium_of(c.clone(), QuadratureRule::Points(40));
        let mut line = format!("a={a}:");
        for n in [5, 6, 7, 8, 10, 12, 14, 16, 20] {
            let (p, _) = equilibrium_of(c.clone(), QuadratureRule::Points(n));
            line += &format!(" {n}:{:.1e}", max_diff(&p, &exact));
        }
        println!("{line}");
        for tol in [1e-6, 1e-8, 1e-10, 1e-12] {
            let (p, pts) =
                equilibrium_of(c.clone(), QuadratureRule::WeightAware { tolerance: tol });
            println!(
                "  WeightAware({tol:e}): {pts} points, error {:.2e}",
                max_diff(&p, &exact)
            );
        }
    }
}

#[test]
fn frozen_engine_takes_the_weight_aware_order_for_its_weights() {
    // The frozen-weight engine with the quartic of the issue: the default (weight-aware) static
    // equilibrium agrees with the generalized engine's 40-point reference, the fixed rule not.
    use vclay_dynamics::DnurbsCurve;
    let (exact, _) = equilibrium(QuadratureRule::Points(40));
    let run = |rule: QuadratureRule| {
        let c = quartic();
        let n = c.control_points().len();
        let mut d =
            DnurbsCurve::with_quadrature(c, Material::curve(1.0, 0.0, 2.0, 0.05), rule).unwrap();
        d.set_elastic_reference(ElasticReference::Absolute);
        d.set_fixed(0, true).unwrap();
        d.set_fixed(n - 1, true).unwrap();
        d.forces_mut()
            .push(Force::Gravity(Vec3::new(0.0, -1.0, 0.0)));
        d.forces_mut().push(Force::Spring {
            param: [0.37, 0.0],
            target: Target::Fixed(Vec3::new(0.4, 0.5, 0.2)),
            stiffness: 5.0,
            kernel: None,
        });
        d.step(Integrator::Static).unwrap();
        d.geometry().control_points().to_vec()
    };
    let e_fixed = max_diff(&run(QuadratureRule::Fixed), &exact);
    let e_aware = max_diff(&run(QuadratureRule::default()), &exact);
    assert!(e_fixed > 1e-5, "{e_fixed:e}");
    assert!(e_aware < 3e-8, "{e_aware:e}");
}
