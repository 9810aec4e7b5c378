//! D-NURBS fitting (d-nurbs.txt section 7.3, Fig 6 and Fig 7c) with the parameters of Table 1.
use vclay_core::Vec3;
use vclay_dynamics::dnurbs::{ClosedCurve, Preset, TABLE_1, Target};
use vclay_dynamics::{DnurbsClosedCurve, DnurbsSurface, ElasticReference, Force, Integrator};
use vclay_spline::{NurbsSurface, ParametricSurface};

fn fig6_data() -> Vec<Vec3> {
    // Six points on an ellipse (the paper does not list its data).
    (0..6)
        .map(|k| {
            let t = std::f64::consts::TAU * k as f64 / 6.0 + 0.3;
            Vec3::new(2.0 * t.cos(), 1.2 * t.sin(), 0.0)
        })
        .collect()
}

#[test]
fn table_1_is_complete_and_searchable() {
    assert_eq!(TABLE_1.len(), 11);
    let p = Preset::by_name("curve-fitting").unwrap();
    assert_eq!(
        (p.gamma, p.alpha[0], p.beta[0], p.dt, p.k),
        (50.0, 20.0, 60.0, 0.001, 1000.0)
    );
    assert!(Preset::by_name("glass sculpting").is_some());
    assert!(Preset::by_name("no such thing").is_none());
}

#[test]
fn fig6_closed_curve_fits_six_data_points() {
    let preset = Preset::by_name("Curve fitting").unwrap();
    let ring: Vec<Vec3> = (0..11)
        .map(|k| {
            let t = std::f64::consts::TAU * k as f64 / 11.0;
            Vec3::new(1.3 * t.cos(), 1.3 * t.sin(), 0.0)
        })
        .collect();
    let geometry = ClosedCurve::new(3, ring).unwrap();
    let mut d = DnurbsClosedCurve::new(geometry, preset.curve_material()).unwrap();
    d.set_elastic_reference(ElasticReference::Absolute);
    for p in fig6_data() {
        d.forces_mut().push(Force::DataPoint {
            point: p,
            stiffness: preset.k,
        });
    }
    let before = d.data_distances().unwrap().into_iter().fold(0.0, f64::max);
    let mut last = f64::INFINITY;
    for _ in 0..40 {
        d.run(preset.dt, 25).unwrap();
        let e = d.data_distances().unwrap().into_iter().fold(0.0, f64::max);
        last = e;
    }
    // Springs (k = 1000) balance tension and bending (alpha = 20, beta = 60): the data are
    // approximated, not interpolated. Measured: 0.71 -> 0.060 on a curve of size 4.
    assert!(before > 0.5, "initial error {before}");
    assert!(
        last < 0.15 * before,
        "final error {last} vs initial {before}"
    );
    // The curve stays closed and its control points stay shared across the seam.
    let c = d.geometry().curve();
    use vclay_spline::ParametricCurve;
    assert!((c.point(0.0).unwrap() - c.point(11.0).unwrap()).norm() < 1e-12);
}

#[test]
fn fig7c_sinusoid_with_fixed_attachments_approaches_the_data() {
    // 25 samples of a sinusoid pulled onto a quadratic 5x5 surface with springs at fixed
    // material points (Table 1, "Sinusoidal fitting").
    let preset = Preset::by_name("Sinusoidal fitting").unwrap();
    let n = 5;
    // Unit knot spacing, as Table 1's parameters assume: domain [0, 3]^2.
    let knots = vec![0., 0., 0., 1., 2., 3., 3., 3.];
    let kv = vclay_spline::KnotVector::new(knots.clone(), 2, n).unwrap();
    let g = kv.greville();
    let mut pts = Vec::new();
    for i in 0..n {
        for j in 0..n {
            pts.push(Vec3::new(g[i], g[j], 0.0));
        }
    }
    let s = NurbsSurface::from_flat([kv.clone(), kv], pts, vec![1.0; n * n]).unwrap();
    let mut d = DnurbsSurface::new(s, preset.surface_material()).unwrap();
    d.set_elastic_reference(ElasticReference::Absolute);
    let f = |u: f64, v: f64| {
        0.6 * (std::f64::consts::TAU * u / 3.0).sin() * (std::f64::consts::PI * v / 3.0).cos()
    };
    for i in 0..5 {
        for j in 0..5 {
            let (u, v) = (0.3 + 0.6 * i as f64, 0.3 + 0.6 * j as f64);
            d.forces_mut().push(Force::Spring {
                param: [u, v],
                target: Target::Fixed(Vec3::new(u, v, f(u, v))),
                stiffness: preset.k,
                kernel: None,
            });
        }
    }
    for _ in 0..400 {
        d.step(Integrator::Implicit { dt: preset.dt }).unwrap();
    }
    let mut err: f64 = 0.0;
    for i in 0..5 {
        for j in 0..5 {
            let (u, v) = (0.3 + 0.6 * i as f64, 0.3 + 0.6 * j as f64);
            err = err.max((d.geometry().point(u, v).unwrap().z - f(u, v)).abs());
        }
    }
    // A 5x5 quadratic with bending rigidity 10 approximates the sinusoid; measured 0.054 on an
    // amplitude of 0.6. Allow 10 % of the amplitude.
    assert!(err < 0.1 * 0.6, "largest height error {err}");
}

#[test]
fn fig7a_hemisphere_fit_with_dynamic_weights() {
    // 19 hemisphere points, quadratic 7x7 surface (49 control points, weights dynamic), Table 1
    // "Hemisphere fitting" parameters, springs on the nearest points.
    use vclay_dynamics::dnurbs::{GeneralizedDnurbs, RationalGeometry, figures};
    let p = Preset::by_name("Hemisphere fitting").unwrap();
    let sheet = figures::flat_sheet(7, 2, 2.4).unwrap();
    let mut d =
        GeneralizedDnurbs::new(RationalGeometry::from_surface(&sheet), p.surface_material())
            .unwrap();
    d.set_elastic_reference(ElasticReference::Absolute);
    let data = figures::hemisphere_points();
    for x in data {
        d.forces_mut().push(Force::DataPoint {
            point: x,
            stiffness: p.k,
        });
    }
    let rms = |v: Vec<f64>| (v.iter().map(|x| x * x).sum::<f64>() / v.len() as f64).sqrt();
    let before = rms(d.data_distances().unwrap());
    for _ in 0..120 {
        d.step(Integrator::Implicit { dt: p.dt }).unwrap();
    }
    let after = rms(d.data_distances().unwrap());
    // Measured (300 steps, example fig7_surface_fit): 0.70 -> 0.0078.
    assert!(before > 0.6, "{before}");
    assert!(after < 0.03, "RMS distance after fitting {after}");
    assert!(d.geometry().weights().iter().all(|&w| w > 0.0));
    let w = d.geometry().weights();
    assert!(
        w.iter().any(|&x| (x - 1.0).abs() > 1e-3),
        "weights should take part in the fit"
    );
}
